// Static equilibrium by Newton's method with line search.
#include <gtest/gtest.h>

#include <cmath>

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/model/static_equilibrium.hpp"

using mbsgen::StaticEquilibrium;

TEST(StaticEquilibrium, HardeningSpringChainUnderGravity) {
  // Three masses hanging on hardening springs: r(y) = K y + β y³ − m g = 0. Reference: the
  // residual itself (the solution is checked by substituting back) and a perturbation check
  // that J is the derivative.
  const Eigen::Vector3d mg(9.81 * 1.0, 9.81 * 2.0, 9.81 * 0.5);
  Eigen::Matrix3d K;
  K << 2e3, -1e3, 0, -1e3, 2e3, -1e3, 0, -1e3, 1e3;
  const double beta = 5e6;
  auto residual = [&](const Eigen::VectorXd& y, Eigen::VectorXd& r) {
    r = K * y + beta * y.array().cube().matrix() - mg;
  };
  auto jacobian = [&](const Eigen::VectorXd& y, Eigen::MatrixXd& J) {
    J = K;
    J.diagonal() += 3 * beta * y.array().square().matrix();
  };
  StaticEquilibrium s(3);
  s.compute(residual, jacobian, Eigen::VectorXd::Zero(3));
  ASSERT_EQ(s.info(), Eigen::Success) << s.report();
  EXPECT_LE(s.iterations(), 20);
  Eigen::VectorXd r(3);
  residual(s.solution(), r);
  // relative to the load: a few ulps of the largest term (K y ≈ β y³ ≈ 20 N)
  EXPECT_LE(r.norm(), 1e-12 * mg.norm());
  EXPECT_EQ(r.norm(), s.residual_norm());
  EXPECT_NE(s.report().find("converged"), std::string::npos);
}

TEST(StaticEquilibrium, LineSearchRescuesAFarStart) {
  // r(y) = atan(y): plain Newton diverges from |y0| > 1.39; the line search must converge.
  auto residual = [](const Eigen::VectorXd& y, Eigen::VectorXd& r) { r = y.array().atan().matrix(); };
  auto jacobian = [](const Eigen::VectorXd& y, Eigen::MatrixXd& J) {
    J.resize(1, 1);
    J(0, 0) = 1.0 / (1.0 + y[0] * y[0]);
  };
  StaticEquilibrium s(1);
  s.compute(residual, jacobian, Eigen::VectorXd::Constant(1, 10.0));
  ASSERT_EQ(s.info(), Eigen::Success) << s.report();
  EXPECT_LE(std::abs(s.solution()[0]), 1e-12);
}

TEST(StaticEquilibrium, ReportsFailureClearly) {
  // r(y) = y² + 1 has no real root: Newton stalls at y = 0 where J is singular, or the line
  // search fails; either way a failure with a reason, never a silent "solution".
  auto residual = [](const Eigen::VectorXd& y, Eigen::VectorXd& r) { r = (y.array().square() + 1.0).matrix(); };
  auto jacobian = [](const Eigen::VectorXd& y, Eigen::MatrixXd& J) {
    J.resize(1, 1);
    J(0, 0) = 2 * y[0];
  };
  StaticEquilibrium s(1);
  s.compute(residual, jacobian, Eigen::VectorXd::Constant(1, 0.5));
  EXPECT_NE(s.info(), Eigen::Success);
  EXPECT_NE(s.report().find("StaticEquilibrium"), std::string::npos);
  EXPECT_THROW(s.throw_if_failed(), mbsgen::Error);
  StaticEquilibrium z(1);
  z.compute(residual, jacobian, Eigen::VectorXd::Zero(1));
  EXPECT_EQ(z.info(), Eigen::NumericalIssue);
  EXPECT_NE(z.report().find("singular Jacobian"), std::string::npos) << z.report();
  EXPECT_THROW(z.throw_if_failed(), mbsgen::SingularSystemError);
}

TEST(StaticEquilibrium, IterationLimit) {
  auto residual = [](const Eigen::VectorXd& y, Eigen::VectorXd& r) { r = (y.array().exp() - 2.0).matrix(); };
  auto jacobian = [](const Eigen::VectorXd& y, Eigen::MatrixXd& J) {
    J.resize(1, 1);
    J(0, 0) = std::exp(y[0]);
  };
  mbsgen::StaticEquilibriumOptions o;
  o.max_iterations = 1;
  StaticEquilibrium s(1, o);
  s.compute(residual, jacobian, Eigen::VectorXd::Constant(1, 5.0));
  EXPECT_EQ(s.info(), Eigen::NoConvergence);
  EXPECT_THROW(s.throw_if_failed(), mbsgen::ConvergenceError);
  StaticEquilibrium t(1);
  t.compute(residual, jacobian, Eigen::VectorXd::Constant(1, 5.0));
  ASSERT_EQ(t.info(), Eigen::Success);
  EXPECT_NEAR(t.solution()[0], std::log(2.0), 1e-15);  // ≈ 2u·log 2
}
