// Radau IIA (runtime/src/time/radau.hpp, radau_tableau.hpp): the constants computed from the nodes
// against RADAU5's published ones (Hairer and Wanner) for three stages, and for five against the
// published nodes and the conditions that define them (the quadrature's order 2s − 1, the
// collocation's stage order s, the embedded estimate's order s, the dense output through the
// stages); and the integrator's order on a damped oscillator's closed form: the error falls as
// (steps)^−(2s−1), 5 for three stages and 9 for five.
#include "time/radau.hpp"
#include "time/radau_tableau.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using mbsgen::detail::Radau;
using mbsgen::detail::RadauTableau;

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

// Computed from the nodes for s = 3: RADAU5's constants (the literal ones of RadauTableau::of(3),
// from Hairer and Wanner's code), to rounding: A⁻¹ through a long-double inverse (100 ε of its
// largest entry), γ and μ through a double eigendecomposition and two products with T and T⁻¹
// (T's condition 8.6: 1e-14 relative, 45 ε), E and P through long-double solves (64 ε). T is not
// unique (any eigenvector scaling), so the check on it is that it block-diagonalizes A⁻¹ with the
// same γ and μ.
TEST(RadauTableau, ThreeStagesComputedAreRadau5s) {
  const RadauTableau computed = RadauTableau::compute(3);
  const RadauTableau& published = RadauTableau::of(3);
  EXPECT_LT((computed.c - published.c).cwiseAbs().maxCoeff(), 4 * kEpsilon);
  EXPECT_LT((computed.A_inv - published.A_inv).cwiseAbs().maxCoeff(), 100 * kEpsilon * published.A_inv.cwiseAbs().maxCoeff());
  EXPECT_NEAR(computed.gamma, published.gamma, 1e-14 * published.gamma);
  ASSERT_EQ(computed.mu.size(), 1u);
  EXPECT_LT(std::abs(computed.mu[0] - published.mu[0]), 1e-14 * std::abs(published.mu[0]));
  EXPECT_LT((computed.E - published.E).cwiseAbs().maxCoeff(), 64 * kEpsilon * published.E.cwiseAbs().maxCoeff());
  EXPECT_LT((computed.P - published.P).cwiseAbs().maxCoeff(), 64 * kEpsilon * published.P.cwiseAbs().maxCoeff());
  for (const RadauTableau* t : {&computed, &published}) {
    const MatrixXd Lambda = t->T_inv * t->A_inv * t->T;
    MatrixXd expected = MatrixXd::Zero(3, 3);
    expected(0, 0) = t->gamma;
    expected(1, 1) = expected(2, 2) = t->mu[0].real();
    expected(1, 2) = -t->mu[0].imag();
    expected(2, 1) = t->mu[0].imag();
    EXPECT_LT((Lambda - expected).cwiseAbs().maxCoeff(), 1e-13) << Lambda;
  }
}

// Five stages: the nodes of Radau IIA of order 9 as Hairer and Wanner's RADAU gives them (C1 … C4
// of its coefficient routine, to 20 digits); b, the last row of A, integrates c^k exactly for
// k ≤ 2s − 2 = 8 (Radau quadrature); A integrates the stage polynomials of degree < s (stage order
// s); the embedded weights b̂ = b + Aᵀ E / γ with b̂₀ = 1/γ make an order-s quadrature; P
// reproduces the stage values at the nodes; T block-diagonalizes A⁻¹.
TEST(RadauTableau, FiveStagesSatisfyTheirDefiningConditions) {
  const RadauTableau& t = RadauTableau::of(5);
  const double nodes[4] = {0.05710419611451768219, 0.27684301363812382768, 0.58359043236891682006, 0.86024013565621944785};
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(t.c[i], nodes[i], 4 * kEpsilon) << "node " << i;
  EXPECT_EQ(t.c[4], 1.0);
  const MatrixXd A = t.A_inv.inverse();
  const VectorXd b = A.row(4).transpose();
  for (int k = 0; k <= 8; ++k) {
    double sum = 0;
    for (int i = 0; i < 5; ++i) sum += b[i] * std::pow(t.c[i], k);
    EXPECT_NEAR(sum, 1.0 / (k + 1), 1e-14) << "quadrature of c^" << k;
  }
  for (int i = 0; i < 5; ++i)
    for (int k = 0; k < 5; ++k) {
      double sum = 0;
      for (int j = 0; j < 5; ++j) sum += A(i, j) * std::pow(t.c[j], k);
      EXPECT_NEAR(sum, std::pow(t.c[i], k + 1) / (k + 1), 1e-14) << "stage " << i << ", c^" << k;
    }
  const VectorXd b_hat = b + A.transpose() * t.E / t.gamma;
  for (int k = 0; k < 5; ++k) {
    double sum = k == 0 ? 1 / t.gamma : 0;
    for (int i = 0; i < 5; ++i) sum += b_hat[i] * std::pow(t.c[i], k);
    EXPECT_NEAR(sum, 1.0 / (k + 1), 1e-13) << "embedded quadrature of c^" << k;
  }
  double missing = 0;  // and not of order s + 1
  for (int i = 0; i < 5; ++i) missing += b_hat[i] * std::pow(t.c[i], 5);
  EXPECT_GT(std::abs(missing - 1.0 / 6), 1e-6);
  MatrixXd powers(5, 5);
  for (int i = 0; i < 5; ++i)
    for (int k = 0; k < 5; ++k) powers(k, i) = std::pow(t.c[i], k + 1);
  EXPECT_LT((t.P * powers - MatrixXd::Identity(5, 5)).cwiseAbs().maxCoeff(), 1e-11);
  const MatrixXd Lambda = t.T_inv * t.A_inv * t.T;
  ASSERT_EQ(t.mu.size(), 2u);
  MatrixXd expected = MatrixXd::Zero(5, 5);
  expected(0, 0) = t.gamma;
  for (int p = 0; p < 2; ++p) {
    const int r = 1 + 2 * p;
    expected(r, r) = expected(r + 1, r + 1) = t.mu[static_cast<std::size_t>(p)].real();
    expected(r, r + 1) = -t.mu[static_cast<std::size_t>(p)].imag();
    expected(r + 1, r) = t.mu[static_cast<std::size_t>(p)].imag();
  }
  EXPECT_LT((Lambda - expected).cwiseAbs().maxCoeff(), 1e-12) << Lambda;
  EXPECT_THROW(RadauTableau::compute(4), std::invalid_argument);
}

// ÿ + 2ζω ẏ + ω² y = 0 (M = 1, K_y = ω², K_v = 2ζω), ω = 2π, ζ = 0.05, from y = 1.
class Oscillator : public mbsgen::detail::SecondOrderSystem {
 public:
  static constexpr double kOmega = 2 * 3.14159265358979323846, kZeta = 0.05;
  bool accelerations(double, const double* y, const double* v, VectorXd& a) override {
    a.resize(1);
    a[0] = -(kOmega * kOmega * y[0] + 2 * kZeta * kOmega * v[0]);
    return true;
  }
  bool has_jacobian() const override { return true; }
  bool jacobian(double, const double*, const double*, MatrixXd& M, MatrixXd& Ky, MatrixXd& Kv) override {
    M = MatrixXd::Ones(1, 1);
    Ky = MatrixXd::Constant(1, 1, kOmega * kOmega);
    Kv = MatrixXd::Constant(1, 1, 2 * kZeta * kOmega);
    return true;
  }
  bool jacobian_mass(double t, const double* y, const double* v, MatrixXd& M, VectorXd& a) override {
    M = MatrixXd::Ones(1, 1);
    return accelerations(t, y, v, a);
  }
  static double exact(double t) {
    const double wd = kOmega * std::sqrt(1 - kZeta * kZeta);
    return std::exp(-kZeta * kOmega * t) * (std::cos(wd * t) + kZeta * kOmega / wd * std::sin(wd * t));
  }
};

struct Trial {
  long steps;
  double error;
};

// Ten periods at rtol (atol = rtol): the steps and the largest error at the steps.
Trial oscillate(int stages, double rtol) {
  Oscillator system;
  const std::unique_ptr<Radau> radau = Radau::make(system, 1, rtol, VectorXd::Constant(2, rtol), stages);
  EXPECT_TRUE(radau->start(0, Eigen::Vector2d(1, 0)));
  double error = 0;
  while (radau->time() < 10) {
    if (radau->step(10) != Radau::Status::ok) {
      ADD_FAILURE() << stages << " stages: a step failed at t = " << radau->time();
      break;
    }
    if (radau->statistics().steps > 100000) {  // a hundred times what either method needs
      ADD_FAILURE() << stages << " stages: more than 100,000 steps, at t = " << radau->time();
      break;
    }
    error = std::max(error, std::abs(radau->state()[0] - Oscillator::exact(radau->time())));
  }
  return {radau->statistics().steps, error};
}

// The error against the steps, between two tolerances 100 apart: its log–log slope is the order
// 2s − 1 (5 and 9), within one for the step-size control's variation; the order of the other
// method is outside that band.
TEST(Radau, ErrorFallsWithTheStepsAtTheMethodsOrder) {
  for (const int stages : {3, 5}) {
    const Trial coarse = oscillate(stages, 1e-6), fine = oscillate(stages, 1e-8);
    const double order = std::log(coarse.error / fine.error) / std::log(static_cast<double>(fine.steps) / coarse.steps);
    EXPECT_NEAR(order, 2 * stages - 1, 1.0) << stages << " stages: " << coarse.steps << " steps, error " << coarse.error
                                            << "; " << fine.steps << " steps, error " << fine.error;
  }
}

}  // namespace
