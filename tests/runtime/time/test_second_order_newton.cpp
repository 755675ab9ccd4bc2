// BDF's Newton systems in n unknowns (runtime/src/time/second_order_newton.hpp) against the same
// 2n×2n systems solved densely: A = d·I + c·J with J = [0, I; −M⁻¹K_y, −M⁻¹K_v], as CVODE forms it
// (the Jacobian's parts, then copy and scale-add-identity), for random well-conditioned M, K_y,
// K_v; and a singular reduced matrix reported as a recoverable failure.
#include "time/second_order_newton.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using mbsgen::detail::parts;

struct Context {
  SUNContext context = nullptr;
  Context() { SUNContext_Create(nullptr, &context); }
  ~Context() { SUNContext_Free(&context); }
};

TEST(SecondOrderNewton, EqualsTheDenseSolve) {
  Context sun;
  const Eigen::Index n = 6;
  std::srand(7);
  const MatrixXd R = MatrixXd::Random(n, n);
  const MatrixXd M = R * R.transpose() + n * MatrixXd::Identity(n, n);  // SPD, κ below 10
  const MatrixXd Ky = 50 * MatrixXd::Random(n, n), Kv = 5 * MatrixXd::Random(n, n);
  SUNMatrix J = mbsgen::detail::new_second_order_matrix(n, sun.context);
  SUNMatrix A = SUNMatClone(J);
  SUNLinearSolver S = mbsgen::detail::new_second_order_solver(n, sun.context);
  ASSERT_TRUE(J && A && S);
  ASSERT_EQ(SUNMatZero(J), 0);
  parts(J).M = M, parts(J).Ky = Ky, parts(J).Kv = Kv, parts(J).c = 1, parts(J).d = 0;
  MatrixXd Jd = MatrixXd::Zero(2 * n, 2 * n);
  Jd.topRightCorner(n, n).setIdentity();
  Jd.bottomLeftCorner(n, n) = -M.lu().solve(Ky);
  Jd.bottomRightCorner(n, n) = -M.lu().solve(Kv);
  N_Vector x = N_VNew_Serial(2 * n, sun.context), b = N_VNew_Serial(2 * n, sun.context);
  for (double gamma : {1e-6, 1e-3, 0.05}) {
    ASSERT_EQ(SUNMatCopy(J, A), 0);
    ASSERT_EQ(SUNMatScaleAddI(-gamma, A), 0);  // A = I − γJ
    ASSERT_EQ(SUNLinSolSetup(S, A), SUNLS_SUCCESS);
    const VectorXd rhs = VectorXd::Random(2 * n);
    Eigen::Map<VectorXd>(N_VGetArrayPointer(b), 2 * n) = rhs;
    ASSERT_EQ(SUNLinSolSolve(S, A, x, b, 0.0), SUNLS_SUCCESS);
    const MatrixXd dense = MatrixXd::Identity(2 * n, 2 * n) - gamma * Jd;
    const VectorXd expected = dense.lu().solve(rhs);
    const VectorXd got = Eigen::Map<const VectorXd>(N_VGetArrayPointer(x), 2 * n);
    // Both are backward stable on systems with κ below 1e4 here: 1e-11 of the solution.
    EXPECT_LE((got - expected).norm(), 1e-11 * expected.norm()) << "gamma " << gamma;
    // In place (CVODE may pass b as x).
    ASSERT_EQ(SUNLinSolSolve(S, A, b, b, 0.0), SUNLS_SUCCESS);
    EXPECT_EQ((Eigen::Map<const VectorXd>(N_VGetArrayPointer(b), 2 * n) - got).norm(), 0.0);
  }
  // Units that spread M's diagonal over 18 decades (kg m² of a 0.1 mm part beside a tonne): the
  // reduced matrix is equilibrated as M is, so it is not taken for singular (unscaled, its pivots
  // span 1e-18 and setup failed), and the solution
  // satisfies both block rows, d·Δy + c·Δv = r₁ and −c·K_y Δy + (d·M − c·K_v) Δv = M r₂, each
  // scaled by S = diag(M)^(-1/2), to 1e-12 of the largest term.
  {
    VectorXd m(n);
    m << 1e-10, 1e8, 1.0, 3e-4, 2e2, 5e-7;
    const VectorXd h = m.cwiseSqrt();
    // Nearly decoupled (weak coupling leaves the tiny pivots where they are; strong coupling
    // would make the unscaled LU swap rows and hide the spread).
    const MatrixXd X = 1e-12 * MatrixXd::Random(n, n);
    const MatrixXd Ms = m.asDiagonal();
    const MatrixXd Kys = 1e4 * (h.asDiagonal() * X * h.asDiagonal()), Kvs = 10 * (h.asDiagonal() * X.transpose() * h.asDiagonal());
    parts(J).M = Ms, parts(J).Ky = Kys, parts(J).Kv = Kvs, parts(J).c = 1, parts(J).d = 0;
    const double gamma = 1e-3;
    ASSERT_EQ(SUNMatCopy(J, A), 0);
    ASSERT_EQ(SUNMatScaleAddI(-gamma, A), 0);
    ASSERT_EQ(SUNLinSolSetup(S, A), SUNLS_SUCCESS);
    VectorXd rhs(2 * n);
    rhs << VectorXd::Random(n), VectorXd::Random(n).cwiseProduct(h.cwiseInverse());
    Eigen::Map<VectorXd>(N_VGetArrayPointer(b), 2 * n) = rhs;
    ASSERT_EQ(SUNLinSolSolve(S, A, x, b, 0.0), SUNLS_SUCCESS);
    const VectorXd dy = Eigen::Map<const VectorXd>(N_VGetArrayPointer(x), n);
    const VectorXd dv = Eigen::Map<const VectorXd>(N_VGetArrayPointer(x) + n, n);
    const double c = -gamma;
    EXPECT_LE((dy + c * dv - rhs.head(n)).cwiseAbs().maxCoeff(),
              1e-12 * (rhs.head(n).cwiseAbs().maxCoeff() + std::abs(c) * dv.cwiseAbs().maxCoeff()));
    const VectorXd s = h.cwiseInverse();
    const VectorXd second = s.asDiagonal() * (-c * Kys * dy + (Ms - c * Kvs) * dv - Ms * rhs.tail(n));
    const double size = (s.asDiagonal() * (Ms * rhs.tail(n))).cwiseAbs().maxCoeff() +
                        (s.asDiagonal() * (Ms * dv)).cwiseAbs().maxCoeff();
    EXPECT_LE(second.cwiseAbs().maxCoeff(), 1e-12 * size);
  }
  // M + γK_v + γ²K_y singular: a recoverable failure (CVODE retries with a smaller step).
  parts(J).M = MatrixXd::Identity(n, n), parts(J).Kv.setZero(), parts(J).Ky = -MatrixXd::Identity(n, n);
  ASSERT_EQ(SUNMatCopy(J, A), 0);
  ASSERT_EQ(SUNMatScaleAddI(-1.0, A), 0);  // γ = 1: I − I = 0
  EXPECT_EQ(SUNLinSolSetup(S, A), SUNLS_LUFACT_FAIL);
  N_VDestroy(x);
  N_VDestroy(b);
  SUNLinSolFree(S);
  SUNMatDestroy(A);
  SUNMatDestroy(J);
}

}  // namespace
