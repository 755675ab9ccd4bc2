// BDF's Newton systems in n unknowns (runtime/src/second_order_newton.hpp) against the same
// 2n×2n systems solved densely: A = d·I + c·J with J = [0, I; −M⁻¹K_y, −M⁻¹K_v], as CVODE forms it
// (the Jacobian's parts, then copy and scale-add-identity), for random well-conditioned M, K_y,
// K_v; and a singular reduced matrix reported as a recoverable failure.
#include "second_order_newton.hpp"

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
