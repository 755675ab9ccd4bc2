// Exact structural zeros in the generated kernels (issue 14 §1), on two models written for it:
// a heavy symmetric top in steady precession (two cyclic coordinates; closed form from the
// Routhian) and a three-ossicle chain at middle-ear scales (263 entries that vanish at rest),
// whose frequency response by the automatic method must be as accurate as `direct` against a
// 266-bit reference solve.
#include "kernel_harness.hpp"

#include "../runtime/hp.hpp"
#include "mbsgen/runtime/model/linear_model.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

namespace mbsgen::test {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

const GeneratedModel& model(const std::string& name) {
  for (const auto& m : all_models())
    if (m.name == name) return m;
  throw std::runtime_error("no generated model " + name);
}

// The kernels at the model's own operating point and default parameters.
LinearModel linear_at_operating_point(const GeneratedModel& g) {
  VectorXd p = Eigen::Map<const VectorXd>(g.defaults, g.np), y0(g.n), yd0(g.n);
  EXPECT_EQ(g.operating_point(p.data(), y0.data(), yd0.data()), 0);
  MatrixXd M(g.n, g.n), Q(g.n, g.n), K(g.n, g.n), B(g.n, g.nu), Cy(g.nr, g.n), Cv(g.nr, g.n);
  EXPECT_EQ(g.linear(y0.data(), yd0.data(), p.data(), M.data(), Q.data(), K.data(), B.data(),
                     Cy.data(), Cv.data()),
            0);
  return LinearModel(M, Q, K, B, Cy, Cv);
}

// ---------------------------------------------------------------------------------------------
// Heavy top: psi and phi are cyclic, so ∂(k − q)/∂psi and ∂(k − q)/∂phi vanish for every state.

double nutation_frequency() {
  // models/textbook/heavy_top_precession.yaml: the Routhian's effective potential
  // V(θ) = u²/(2 I1 s²) + m g l c with u = b − a c, s = sin θ, c = cos θ, u' = a s; so
  // V'(θ) = (a u s² − u² c)/(I1 s³) − m g l s, differentiated once more by hand below.
  const double m = 0.01, l = 0.04, It = 0.0003, I3 = 0.0004, g = 9.81, t0 = 0.5, Om = 2;
  const double I1 = It + m * l * l, mgl = m * g * l;
  const double phid = (mgl / Om + I1 * Om * std::cos(t0)) / I3 - Om * std::cos(t0);
  const double a = I3 * (phid + Om * std::cos(t0)), b = I1 * Om * std::pow(std::sin(t0), 2) + a * std::cos(t0);
  auto dV = [&](double t) {
    const double s = std::sin(t), c = std::cos(t), u = b - a * c;
    return (a * u * s * s - u * u * c) / (I1 * s * s * s) - mgl * s;
  };
  auto d2V = [&](double t) {
    const double s = std::sin(t), c = std::cos(t), u = b - a * c, du = a * s;
    const double num = a * u * s * s - u * u * c, den = I1 * s * s * s;
    const double dnum = a * du * s * s + 2 * a * u * s * c - 2 * u * du * c + u * u * s;
    const double dden = 3 * I1 * s * s * c;
    return (dnum * den - num * dden) / (den * den) - mgl * c;
  };
  EXPECT_LE(std::abs(dV(t0)), 1e-12 * mgl) << "theta0 is a steady precession";
  return std::sqrt(d2V(t0) / I1);
}

TEST(StructuralZeros, CyclicCoordinatesHaveExactlyZeroStiffnessColumns) {
  const LinearModel L = linear_at_operating_point(model("heavy_top_precession"));
  for (Eigen::Index i = 0; i < 3; ++i) {
    EXPECT_EQ(L.K()(i, 0), 0.0) << "K(" << i << ", psi)";
    EXPECT_EQ(L.K()(i, 2), 0.0) << "K(" << i << ", phi)";
  }
  // M = [[I1 s² + I3 c², 0, I3 c], [0, I1, 0], [I3 c, 0, I3]] (Lagrangian of the top): its zeros.
  EXPECT_EQ(L.M()(0, 1), 0.0);
  EXPECT_EQ(L.M()(1, 0), 0.0);
  EXPECT_EQ(L.M()(1, 2), 0.0);
  EXPECT_EQ(L.M()(2, 1), 0.0);
}

TEST(StructuralZeros, HeavyTopHasFourExactZeroEigenvaluesAndTheNutationPair) {
  const LinearModel L = linear_at_operating_point(model("heavy_top_precession"));
  QuadraticEigenSolver solver;
  solver.compute(L);
  ASSERT_EQ(solver.info(), Eigen::Success);
  EXPECT_EQ(solver.num_zero(), 4) << "two cyclic coordinates, each a Jordan pair at 0";
  const double w = nutation_frequency();
  int nutation = 0;
  for (const Mode& mode : solver.modes()) {
    if (mode.kind != EigenvalueKind::finite) continue;
    // Relative 1e-10: a well-conditioned simple eigenvalue of a 3×3 problem (backward errors
    // ~1e-16) against a closed form evaluated in double.
    EXPECT_LE(std::abs(std::abs(mode.lambda) - w), 1e-10 * w) << mode.lambda;
    EXPECT_LE(std::abs(mode.lambda.real()), 1e-10 * w) << "undamped and conservative: on the axis";
    ++nutation;
  }
  EXPECT_EQ(nutation, 2);
}

// ---------------------------------------------------------------------------------------------
// Three ossicles: 18 coordinates, 263 entries that vanish at rest.

TEST(StructuralZeros, OssiclesZeroAtRestAreExactAtTheOperatingPointOnly) {
  const GeneratedModel& g = model("three_ossicles");
  const LinearModel L = linear_at_operating_point(g);
  // The stapes' translation-rotation coupling of M vanishes at rest (its centre of mass lies on
  // its rotation axis there) and, with the constant tilt of -0.4 rad, was 1.65e-24 as noise.
  EXPECT_EQ(L.M()(12, 15), 0.0);
  EXPECT_EQ(L.M()(14, 17), 0.0);
  // Away from the operating point the kernel keeps the general expressions (not zeros): a
  // rotated stapes couples translation and rotation.
  VectorXd p = Eigen::Map<const VectorXd>(g.defaults, g.np), y(g.n), yd(g.n);
  EXPECT_EQ(g.operating_point(p.data(), y.data(), yd.data()), 0);
  y[15] = 0.2, y[16] = 0.3, y[17] = 0.1;  // stapes rotations a3, b3, c3
  MatrixXd M(g.n, g.n), Q(g.n, g.n), K(g.n, g.n), B(g.n, g.nu), Cy(g.nr, g.n), Cv(g.nr, g.n);
  ASSERT_EQ(g.linear(y.data(), yd.data(), p.data(), M.data(), Q.data(), K.data(), B.data(), Cy.data(),
                     Cv.data()),
            0);
  MatrixXd Mref(g.n, g.n);
  ASSERT_EQ(g.mass_matrix(y.data(), p.data(), Mref.data()), 0);
  // The two kernels compute M(y) by differently shared subexpressions: equal to rounding.
  EXPECT_LE((M - Mref).cwiseAbs().maxCoeff(), 1e-14 * Mref.cwiseAbs().maxCoeff())
      << "the general mass matrix away from rest";
  EXPECT_GT(std::abs(M(12, 15)) + std::abs(M(14, 17)), 1e-12 * M.cwiseAbs().maxCoeff());
}

// error(auto) ≤ 10·error(direct) + 10·n·u at every frequency, errors relative to a 266-bit solve
// of (K − Ω²M + iΩQ) ŷ = B û on the same double matrices (the bar: no method chosen by
// auto is more than 10× less accurate than direct; the floor is the rounding level of a
// backward-stable solve of an n×n system, 10× for the reduction to Hessenberg form).
TEST(StructuralZeros, OssiclesAutomaticFrequencyResponseIsAsAccurateAsDirect) {
  const LinearModel L = linear_at_operating_point(model("three_ossicles"));
  const int F = 25;
  VectorXd omega(F);
  for (int k = 0; k < F; ++k) omega[k] = 2 * M_PI * 100 * std::pow(100.0, k / (F - 1.0));
  FrfOptions automatic, direct;
  direct.method = FrfMethod::direct;
  FrequencyResponse fa(L, automatic), fd(L, direct);
  fa.compute(omega, 0);
  fd.compute(omega, 0);
  const hp::Matrix M = hp::from(L.M()), Q = hp::from(L.Q()), K = hp::from(L.K());
  const hp::Vector b = hp::from(VectorXd(L.B().col(0)));
  const Eigen::Index n = L.size();
  for (int k = 0; k < F; ++k) {
    const hp::cl_R w = hp::real(omega[k]);
    const hp::cl_N iw = cln::complex(0, w);
    hp::Matrix A(n, n);
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::Index j = 0; j < n; ++j) A(i, j) = K(i, j) - w * w * M(i, j) + iw * Q(i, j);
    const hp::Vector x = hp::solve(A, b);
    hp::cl_N z = 0;
    for (Eigen::Index j = 0; j < n; ++j)
      z = z + hp::real(L.C_y()(0, j)) * x[static_cast<std::size_t>(j)] +
          hp::real(L.C_v()(0, j)) * iw * x[static_cast<std::size_t>(j)];
    const std::complex<double> ref = hp::to_double(z);
    const double ea = std::abs(fa.response()(0, k) - ref) / std::abs(ref);
    const double ed = std::abs(fd.response()(0, k) - ref) / std::abs(ref);
    EXPECT_LE(ea, 10 * ed + 10 * static_cast<double>(n) * 1.1102230246251565e-16) << "f = " << omega[k] / (2 * M_PI) << " Hz, method "
                                   << to_string(fa.method()) << ", direct " << ed;
    EXPECT_NE(fa.flags()[static_cast<std::size_t>(k)], FrfFlag::pole) << "a damped model has no pole on the axis";
  }
}

}  // namespace
}  // namespace mbsgen::test
