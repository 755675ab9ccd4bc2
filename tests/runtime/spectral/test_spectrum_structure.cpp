// What the zero pattern proves about a spectrum (issue 39 §1, "useless error bounds and verdicts
// with ignorable coordinates"): exact zeros from the structural rank, eigenvalues on the imaginary
// axis from a reversible sign pattern, and where neither may be claimed. References: closed-form
// characteristic polynomials of 2- and 3-state systems.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "mbsgen/runtime/spectral/descriptor_eigen.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

namespace {

using mbsgen::EigenvalueKind;
using mbsgen::Mode;
using mbsgen::Stability;

// A gyroscopically stabilized pair: ÿ + G ẏ + K y = 0 with G = [[0, g], [−g, 0]], K = diag(k1, k2),
// both k < 0 (each coordinate alone unstable). λ⁴ + (k1 + k2 + g²)λ² + k1k2 = 0; for k1 = −1.3,
// k2 = −0.7, g = 3.1: λ² = (−7.61 ± √(7.61² − 3.64))/2, both negative: four eigenvalues on the
// imaginary axis, stable only by the gyroscopic coupling (a sleeping top). The pattern
// (M, K diagonal, G off-diagonal) makes the spectrum symmetric about the axis for any values.
TEST(SpectrumStructure, GyroscopicPairIsMarginalNotUndecided) {
  const double k1 = -1.3, k2 = -0.7, g = 3.1;
  Eigen::MatrixXd M = Eigen::MatrixXd::Identity(2, 2), Q(2, 2), K(2, 2);
  Q << 0, g, -g, 0;
  K << k1, 0, 0, k2;
  mbsgen::QuadraticEigenSolver solver(2);
  solver.compute(M, Q, K);
  EXPECT_EQ(solver.stability(), Stability::marginal);
  const double b = k1 + k2 + g * g, disc = std::sqrt(b * b - 4 * k1 * k2);
  const double w[2] = {std::sqrt((b - disc) / 2), std::sqrt((b + disc) / 2)};
  ASSERT_EQ(solver.modes().size(), 4u);  // both members of each pair, by increasing |λ|
  for (std::size_t k = 0; k < 4; ++k) {
    const Mode& m = solver.modes()[k];
    const double wk = w[k / 2];
    EXPECT_EQ(m.lambda.real(), 0.0);
    EXPECT_EQ(m.damping_ratio, 0.0);
    // Within the bound (plus the closed form's rounding, a few ulps).
    EXPECT_NEAR(std::abs(m.lambda.imag()), wk, m.error_bound + 8e-16 * wk);
  }
}

// The same with a damper on the first coordinate of 1e-15 N·s/m: the pattern is no longer
// reversible (a diagonal entry of Q), the real parts −O(1e-16) lie within their bounds, and the
// honest verdict stays undecided: nothing may be snapped to the axis.
TEST(SpectrumStructure, DampedPatternIsNotClaimedOnTheAxis) {
  Eigen::MatrixXd M = Eigen::MatrixXd::Identity(2, 2), Q(2, 2), K(2, 2);
  Q << 1e-15, 3.1, -3.1, 0;
  K << -1.3, 0, 0, -0.7;
  mbsgen::QuadraticEigenSolver solver(2);
  solver.compute(M, Q, K);
  EXPECT_EQ(solver.stability(), Stability::undecided);
  for (const Mode& m : solver.modes()) EXPECT_NE(m.lambda.real(), 0.0);
}

// A rolling disk's lean subsystem (states lean φ, yaw rate, lean rate; m = r = g = 1, w = 1):
// E = diag(1, 1/4, 5/4), A = [[0, 0, 1], [0, 0, −1/2], [1, 3/2, 0]]; det(λE − A) =
// (5/16)λ(λ² + 8/5). A has structural rank 2 (two rows with one entry, in the same column), so
// λ = 0 is an eigenvalue for every value of the entries (the neighbouring steady turns): it is
// exact (kind zero, bound 0), and the pair ±i√1.6 is on the axis by the sign pattern
// (φ, yaw rate even, lean rate odd): marginal.
TEST(SpectrumStructure, StructurallySingularZeroIsExact) {
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(3, 3), A(3, 3);
  E.diagonal() << 1, 0.25, 1.25;
  A << 0, 0, 1, 0, 0, -0.5, 1, 1.5, 0;
  mbsgen::DescriptorEigenSolver solver;
  solver.compute(E, A);
  EXPECT_EQ(solver.num_zero(), 1);
  EXPECT_EQ(solver.num_structural_zero(), 1);
  EXPECT_EQ(solver.stability(), Stability::marginal);
  ASSERT_EQ(solver.modes().size(), 3u);
  EXPECT_EQ(solver.modes()[0].kind, EigenvalueKind::zero);
  EXPECT_EQ(solver.modes()[0].lambda, std::complex<double>(0, 0));
  for (std::size_t i = 1; i < 3; ++i) {
    const Mode& m = solver.modes()[i];
    EXPECT_EQ(m.lambda.real(), 0.0);
    EXPECT_NEAR(std::abs(m.lambda.imag()), std::sqrt(1.6), m.error_bound + 4e-16);
  }
}

// A numerically singular but structurally nonsingular A (every entry nonzero, det = 0 only by the
// values): the zero is not structural, stays a finite eigenvalue zero within its bound, and the
// verdict stays undecided. E = I, A = [[1, 2], [2, 4]]: eigenvalues 0 and 5.
TEST(SpectrumStructure, ValueSingularityIsNotStructural) {
  Eigen::MatrixXd E = Eigen::MatrixXd::Identity(2, 2), A(2, 2);
  A << 1, 2, 2, 4;
  mbsgen::DescriptorEigenSolver solver;
  solver.compute(E, A);
  EXPECT_EQ(solver.num_structural_zero(), 0);
  EXPECT_EQ(solver.stability(), Stability::unstable);  // λ = 5
  ASSERT_EQ(solver.modes().size(), 2u);
  EXPECT_EQ(solver.modes()[0].kind, EigenvalueKind::finite);
  EXPECT_TRUE(solver.modes()[0].zero_within_bound);
}

}  // namespace
