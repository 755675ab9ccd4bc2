// Descriptor models E ẋ = A x + B u (descriptor_eigen.hpp): modes and frequency response, each
// against an independent route — the second-order solvers on the same system, closed forms, and
// the Whipple bicycle's published eigenvalues recomputed at 40 digits.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

#include "mbsgen/runtime/spectral/descriptor_eigen.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"
#include "models.hpp"

using mbsgen::DescriptorEigenOptions;
using mbsgen::DescriptorEigenSolver;
using mbsgen::DescriptorModel;
using mbsgen::EigenvalueKind;
using mbsgen::FrfFlag;
using mbsgen::Mode;
using mbsgen::Stability;
using testmodels::u;
using cd = std::complex<double>;
using Eigen::Index;
using Eigen::MatrixXd;

namespace {

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const mbsgen::Error& e) {
    return e.what();
  }
  return "(no error)";
}

/// E = blkdiag(I, M), A = [[0, I], [−K, −Q]]: M ÿ + Q ẏ + K y = B u with x = [y; ẏ].
struct Descriptor {
  MatrixXd E, A;
};
Descriptor first_order(const MatrixXd& M, const MatrixXd& Q, const MatrixXd& K) {
  const Index f = M.rows();
  Descriptor d{MatrixXd::Zero(2 * f, 2 * f), MatrixXd::Zero(2 * f, 2 * f)};
  d.E.topLeftCorner(f, f).setIdentity();
  d.E.bottomRightCorner(f, f) = M;
  d.A.topRightCorner(f, f).setIdentity();
  d.A.bottomLeftCorner(f, f) = -K;
  d.A.bottomRightCorner(f, f) = -Q;
  return d;
}

int count(const DescriptorEigenSolver& s, EigenvalueKind k) {
  return static_cast<int>(std::count_if(s.modes().begin(), s.modes().end(),
                                        [k](const Mode& m) { return m.kind == k; }));
}

/// Every finite computed eigenvalue matched to a distinct reference (nearest first), |Δλ| ≤ tol.
void expect_eigenvalues(const DescriptorEigenSolver& s, std::vector<cd> ref, double tol) {
  for (const Mode& m : s.modes()) {
    if (m.kind != EigenvalueKind::finite) continue;
    ASSERT_FALSE(ref.empty()) << "extra eigenvalue " << m.lambda;
    const auto it = std::min_element(ref.begin(), ref.end(), [&](cd a, cd b) {
      return std::abs(a - m.lambda) < std::abs(b - m.lambda);
    });
    EXPECT_LE(std::abs(*it - m.lambda), tol) << "lambda " << m.lambda << " reference " << *it;
    ref.erase(it);
  }
  EXPECT_TRUE(ref.empty()) << ref.size() << " reference eigenvalues not found";
}

/// The planar mass with two ignorable coordinates (test IgnorableCoordinatesGiveExactZeros):
/// x = [q_x, q_y, ψ, s, u_x, u_y], q̇ = u, ψ̇ = (u_x − u_y)/r and ṡ = u_x (kinematic rows: the
/// heading and the travelled distance follow the speeds and enter no equation, so their columns
/// of A are exactly zero), m u̇_x = −k_x q_x − d_x u_x + F, m u̇_y = −k_y q_y − d_y u_y.
struct PlanarMass {
  double m = 2.0, kx = 50.0, ky = 18.0, dx = 0.4, dy = 0.3, r = 0.5;
  DescriptorModel model() const {
    MatrixXd E = MatrixXd::Identity(6, 6), A = MatrixXd::Zero(6, 6), B = MatrixXd::Zero(6, 1);
    E(4, 4) = E(5, 5) = m;
    A(0, 4) = A(1, 5) = 1.0;
    A(2, 4) = 1.0 / r;
    A(2, 5) = -1.0 / r;
    A(3, 4) = 1.0;
    A(4, 0) = -kx;
    A(4, 4) = -dx;
    A(5, 1) = -ky;
    A(5, 5) = -dy;
    B(4, 0) = 1.0;
    const MatrixXd C = MatrixXd::Identity(6, 6);
    return DescriptorModel(E, A, B, C, {}, {"q_x", "q_y", "psi", "s", "u_x", "u_y"}, {"F"});
  }
  /// Roots of m λ² + d λ + k (both underdamped here): −d/2m ± i√(4mk − d²)/2m.
  static std::vector<cd> roots(double m, double d, double k) {
    const double re = -d / (2 * m), im = std::sqrt(4 * m * k - d * d) / (2 * m);
    return {cd(re, im), cd(re, -im)};
  }
};

/// The Whipple bicycle's lean-steer model at speed v (Meijaard, Papadopoulos, Ruina & Schwab
/// 2007), M q̈ + v C1 q̇ + (g K0 + v² K2) q = 0, q = [φ, δ], at 17 digits from
/// docs/test-references.md, "The Whipple bicycle" (recomputed at 40 digits from the paper's
/// Table 1).
struct Bicycle {
  MatrixXd M{2, 2}, C1{2, 2}, K0{2, 2}, K2{2, 2};
  double g = 9.81;
  Bicycle() {
    M << 80.81722, 2.3194133220870913, 2.3194133220870913, 0.29784188199685553;
    C1 << 0, 33.866413914924944, -0.85035641456978437, 1.6854039739755967;
    K0 << -80.95, -2.5995168524987164, -2.5995168524987164, -0.80329488458617688;
    K2 << 0, 76.597345895732222, 0, 2.6543152379460403;
  }
  Descriptor at(double v) const { return first_order(M, v * C1, g * K0 + v * v * K2); }
  /// Paper Table 2 at v = 5 m/s, recomputed at 40 digits (docs/test-references.md).
  static std::vector<cd> eigenvalues_at_5() {
    return {cd(-14.07838969279825, 0.0), cd(-0.3228664290040871, 0.0),
            cd(-0.7753418821958419, 4.464867713788225),
            cd(-0.7753418821958419, -4.464867713788225)};
  }
};

}  // namespace

TEST(DescriptorModel, ValidatesDimensionsAndFiniteness) {
  const MatrixXd I3 = MatrixXd::Identity(3, 3);
  EXPECT_EQ(message_of([&] { DescriptorModel(I3, MatrixXd::Zero(3, 2), MatrixXd(), MatrixXd()); }),
            "DescriptorModel: A is 3x2 but must be 3x3 (same size as E)");
  EXPECT_EQ(message_of([&] { DescriptorModel(MatrixXd::Zero(3, 2), I3, MatrixXd(), MatrixXd()); }),
            "DescriptorModel: E is 3x2 but must be 3x3 (square)");
  EXPECT_EQ(message_of([&] { DescriptorModel(I3, I3, MatrixXd::Ones(2, 1), MatrixXd()); }),
            "DescriptorModel: B is 2x1 but must be 3x1 (n rows, one column per input)");
  EXPECT_EQ(message_of([&] { DescriptorModel(I3, I3, MatrixXd(), MatrixXd::Ones(2, 4)); }),
            "DescriptorModel: C is 2x4 but must be 2x3 (one column per state)");
  EXPECT_EQ(message_of([&] {
              DescriptorModel(I3, I3, MatrixXd::Ones(3, 2), MatrixXd::Ones(1, 3),
                              MatrixXd::Ones(2, 1));
            }),
            "DescriptorModel: D is 2x1 but must be 1x2 (p x m, one row per output, one column "
            "per input)");
  MatrixXd B = MatrixXd::Ones(3, 1);
  B(1, 0) = std::nan("");
  EXPECT_EQ(message_of([&] { DescriptorModel(I3, I3, B, MatrixXd()); }),
            "DescriptorModel: B (3x1) has a non-finite entry nan at (2,1)");
  EXPECT_THROW(DescriptorModel(I3, I3, B, MatrixXd()), mbsgen::NonFiniteError);
  EXPECT_THROW(DescriptorModel(I3, MatrixXd::Zero(3, 2), MatrixXd(), MatrixXd()),
               mbsgen::DimensionError);
  EXPECT_THROW(DescriptorModel(I3, I3, MatrixXd(), MatrixXd(), MatrixXd(), {"a", "b"}),
               mbsgen::DimensionError);
  // Defaults: D zero p×m, names x1.., u1.., z1...
  const DescriptorModel d(I3, I3, MatrixXd::Ones(3, 2), MatrixXd::Ones(1, 3));
  EXPECT_EQ(d.D(), MatrixXd::Zero(1, 2));
  EXPECT_EQ(d.state_names(), (std::vector<std::string>{"x1", "x2", "x3"}));
  EXPECT_EQ(d.input_names(), (std::vector<std::string>{"u1", "u2"}));
  EXPECT_EQ(d.output_names(), (std::vector<std::string>{"z1"}));
  EXPECT_EQ(d.output_units(), (std::vector<std::string>{""}));
  // The solver's raw-matrix entry point validates the same way.
  DescriptorEigenSolver s;
  EXPECT_THROW(s.compute(I3, MatrixXd::Zero(3, 2)), mbsgen::DimensionError);
}

TEST(DescriptorModes, SecondOrderChainMatchesQuadraticSolverAndFrf) {
  // Damped 3-dof chain, grounded at both ends.
  const testmodels::Qep p = testmodels::chain({1.0, 2.0, 1.5}, {100.0, 200.0, 150.0, 50.0},
                                              {0.5, 1.0, 0.3, 0.2});
  const Descriptor d = first_order(p.M, p.Q, p.K);
  DescriptorEigenSolver ds;
  ds.compute(d.E, d.A);
  mbsgen::QuadraticEigenSolver qs(3);
  qs.compute(p.M, p.Q, p.K);
  ASSERT_EQ(ds.modes().size(), 6u);
  ASSERT_EQ(qs.modes().size(), 6u);
  EXPECT_EQ(ds.num_zero(), 0);
  EXPECT_EQ(ds.num_infinite(), 0);
  for (std::size_t k = 0; k < 6; ++k) {
    const Mode &a = ds.modes()[k], &b = qs.modes()[k];
    // Both are first-order bounds on the distance to the exact eigenvalue (κ·max(η, 100·n·u)),
    // so their sum bounds the distance between the two (same sort order: same eigenvalue).
    EXPECT_LE(std::abs(a.lambda - b.lambda), a.error_bound + b.error_bound)
        << a.lambda << " vs " << b.lambda;
    EXPECT_EQ(a.kind, EigenvalueKind::finite);
    // The bar of the quadratic solver's tests: backward error ≤ 100·n·u.
    EXPECT_LE(a.backward_error, 100.0 * 6 * u);
  }
  EXPECT_LE(ds.max_backward_error(), 100.0 * 6 * u);
  EXPECT_EQ(ds.stability(), Stability::stable);
  EXPECT_EQ(qs.stability(), Stability::stable);

  // Frequency response, one input per coordinate, outputs the coordinates.
  const mbsgen::LinearModel lm(p.M, p.Q, p.K);
  MatrixXd B = MatrixXd::Zero(6, 3), C = MatrixXd::Zero(3, 6);
  B.bottomRows(3).setIdentity();
  C.leftCols(3).setIdentity();
  const DescriptorModel dm(d.E, d.A, B, C);
  const Eigen::VectorXd omega = testmodels::log_omegas(0.1, 10.0, 40);
  mbsgen::FrequencyResponse fr(lm, testmodels::with(mbsgen::FrfMethod::direct));
  for (Index j = 0; j < 3; ++j) {
    fr.compute(omega, j);
    const mbsgen::DescriptorFrf df = mbsgen::descriptor_frequency_response(dm, omega, j);
    ASSERT_EQ(df.response.rows(), 3);
    ASSERT_EQ(df.response.cols(), omega.size());
    for (Index k = 0; k < omega.size(); ++k) {
      EXPECT_EQ(df.flags[static_cast<std::size_t>(k)], FrfFlag::ok);
      // Both are backward-stable LU solves of equivalent systems: each forward error is about
      // n·u/rcond relative (n = 6 states, rcond from zgecon), ×10 for the estimates.
      const double rc = std::min(df.rcond[k], fr.rcond()[k]);
      const double tol = 10.0 * 6 * u / rc;
      const double diff = (df.response.col(k) - fr.response().col(k)).norm();
      EXPECT_LE(diff, tol * fr.response().col(k).norm()) << "input " << j << " omega " << omega[k];
    }
  }
}

TEST(DescriptorModes, IgnorableCoordinatesGiveExactZeros) {
  const PlanarMass pm;
  const DescriptorModel model = pm.model();
  DescriptorEigenSolver s;
  s.compute(model);
  ASSERT_EQ(s.info(), Eigen::Success);
  ASSERT_EQ(s.modes().size(), 6u);
  EXPECT_EQ(s.num_zero(), 2);
  EXPECT_EQ(s.zero_columns(), (std::vector<Index>{2, 3}));
  for (std::size_t j = 0; j < 2; ++j) {
    const Mode& m = s.modes()[j];
    EXPECT_EQ(m.kind, EigenvalueKind::zero);
    EXPECT_EQ(m.lambda, cd(0.0, 0.0));  // exactly, not within a tolerance
    EXPECT_EQ(m.alpha, cd(0.0, 0.0));
    EXPECT_EQ(m.beta, 1.0);
    EXPECT_EQ(m.error_bound, 0.0);
    EXPECT_EQ(m.shape, Eigen::VectorXcd::Unit(6, static_cast<Index>(j) + 2));
    EXPECT_FALSE(m.defective);
    // The left eigenvector annihilates A exactly up to rounding in its computation (n·u·‖A‖).
    EXPECT_LE((m.left_shape.adjoint() * model.A().cast<cd>()).norm(), 10.0 * 6 * u * 50.0);
  }
  std::vector<cd> ref = PlanarMass::roots(pm.m, pm.dx, pm.kx);
  const std::vector<cd> ry = PlanarMass::roots(pm.m, pm.dy, pm.ky);
  ref.insert(ref.end(), ry.begin(), ry.end());
  // The closed form rounds to a few u·|λ| (|λ| ≤ 5); QZ on the reduced 4×4 pencil adds
  // κ·η ≈ 10·u·|λ|: 1e-14 absolute is ≈ 20 u·|λ| (measured 8.9e-16).
  expect_eigenvalues(s, ref, 1e-14);
  // Left eigenvectors of the zeros are biorthogonal to the other zero's e_k: y_jᴴE e_k = 0 for
  // j ≠ k up to the rounding of W (WᵀE_Z)⁻ᵀ, a few u for this well-conditioned 2×2 (measured
  // 7.4e-17).
  EXPECT_LE(std::abs(s.modes()[0].left_shape.dot(model.E().cast<cd>() * s.modes()[1].shape)),
            10 * u);
  EXPECT_LE(std::abs(s.modes()[1].left_shape.dot(model.E().cast<cd>() * s.modes()[0].shape)),
            10 * u);
  for (const Mode& m : s.modes())
    if (m.kind == EigenvalueKind::finite) {
      EXPECT_FALSE(m.zero_within_bound);
      EXPECT_LE(m.backward_error, 100.0 * 6 * u);  // the quadratic solver's bar
    }
  // Rigid-body zeros (exact) and decaying oscillations: marginal, not stable.
  EXPECT_EQ(s.stability(), Stability::marginal);

  // Conjugate pairs once: 2 zeros + 2 pairs.
  DescriptorEigenOptions once;
  once.one_per_conjugate_pair = true;
  DescriptorEigenSolver s1(once);
  s1.compute(model);
  EXPECT_EQ(s1.modes().size(), 4u);
  for (const Mode& m : s1.modes()) EXPECT_GE(m.lambda.imag(), 0.0);
}

TEST(DescriptorModes, SingularPencilNamesTheState) {
  const PlanarMass pm;
  const DescriptorModel good = pm.model();
  MatrixXd E = good.E();
  E.col(3).setZero();  // s: zero column in both E and A
  const DescriptorModel bad(E, good.A(), good.B(), good.C(), {}, good.state_names());
  DescriptorEigenSolver s;
  EXPECT_THROW(s.compute(bad), mbsgen::SingularSystemError);
  EXPECT_NE(message_of([&] { s.compute(bad); }).find("state 's'"), std::string::npos)
      << message_of([&] { s.compute(bad); });
  // Two zero columns of A whose columns of E are equal: E_Z has rank 1 of 2, det(λE − A) ≡ 0.
  E = good.E();
  E.col(3) = E.col(2);
  const DescriptorModel dep(E, good.A(), good.B(), good.C(), {}, good.state_names());
  EXPECT_NE(message_of([&] { s.compute(dep); }).find("(psi, s) have linearly dependent columns"),
            std::string::npos)
      << message_of([&] { s.compute(dep); });
  // The second equation is 0 = 0 in both E and A: det(λE − A) ≡ 0, named before any deflation.
  MatrixXd E2(2, 2), A2(2, 2);
  E2 << 1, 0, 0, 0;
  A2 << 0, 1, 0, 0;
  EXPECT_NE(message_of([&] { s.compute(E2, A2); }).find("equation 2 (the row of state 'x2') is zero in both E and A"),
            std::string::npos)
      << message_of([&] { s.compute(E2, A2); });
  // Two equal equations, no zero row or column: det ≡ 0, which QZ reports as α = β = 0.
  E2 << 1, 1, 1, 1;
  A2 << 2, 1, 2, 1;
  EXPECT_NE(message_of([&] { s.compute(E2, A2); }).find("α = β = 0"), std::string::npos)
      << message_of([&] { s.compute(E2, A2); });
}

TEST(DescriptorModes, DefectiveZeroIsZeroWithinBound) {
  // A = R N Rᵀ with N = [[0, 1], [0, 0]] (a 2×2 Jordan block at 0) and R a rotation by 0.3 rad,
  // rounded: no column is exactly zero, so nothing is deflated, and QZ splits the double zero
  // by O(√u) ≈ 1e-8. The bound κ·η with κ = O(1/√u) must cover it.
  const double c = std::cos(0.3), sn = std::sin(0.3);
  MatrixXd R(2, 2), N = MatrixXd::Zero(2, 2);
  R << c, -sn, sn, c;
  N(0, 1) = 1.0;
  const MatrixXd A = R * N * R.transpose();
  ASSERT_TRUE((A.array() != 0.0).all());
  DescriptorEigenSolver s;
  s.compute(MatrixXd::Identity(2, 2), A);
  EXPECT_EQ(s.num_zero(), 0);
  ASSERT_EQ(s.modes().size(), 2u);
  for (const Mode& m : s.modes()) {
    EXPECT_EQ(m.kind, EigenvalueKind::finite);
    EXPECT_TRUE(m.zero_within_bound) << m.lambda << " bound " << m.error_bound;
    EXPECT_STREQ(mbsgen::kind_label(m), "zero_within_bound");
    EXPECT_TRUE(std::isnan(m.damping_ratio));
    EXPECT_LE(std::abs(m.lambda), 1e-7);  // O(√u·‖A‖), √u ≈ 1.1e-8
  }
  EXPECT_EQ(s.stability(), Stability::undecided);
}

TEST(DescriptorModes, UnstableRealEigenvalue) {
  // det(λE − A) = (2λ − 2)(λ + 1) − 1 = 2λ² − 3: λ = ±√1.5.
  MatrixXd E(2, 2), A(2, 2);
  E << 2, 0, 0, 1;
  A << 2, 1, 1, -1;
  DescriptorEigenSolver s;
  s.compute(E, A);
  // √1.5 rounds to u·1.22; QZ adds κ·η of a few u (κ = O(1), 2×2): 1e-15 ≈ 4 u·|λ|.
  expect_eigenvalues(s, {cd(std::sqrt(1.5), 0.0), cd(-std::sqrt(1.5), 0.0)}, 1e-15);
  EXPECT_EQ(s.stability(), Stability::unstable);
}

TEST(DescriptorModes, SingularEGivesInfiniteEigenvalues) {
  // Index 1: det(λE − A) = 2λ + 1 for E = diag(1, 0), A = [[−1, 1], [1, −2]].
  MatrixXd E = MatrixXd::Zero(2, 2), A(2, 2);
  E(0, 0) = 1.0;
  A << -1, 1, 1, -2;
  DescriptorEigenSolver s;
  s.compute(E, A);
  ASSERT_EQ(s.modes().size(), 2u);
  EXPECT_EQ(s.num_infinite(), 1);
  EXPECT_EQ(count(s, EigenvalueKind::infinite), 1);
  EXPECT_EQ(s.modes().back().kind, EigenvalueKind::infinite);  // infinite last
  EXPECT_EQ(std::string(mbsgen::kind_label(s.modes().back())), "infinite");
  EXPECT_TRUE(std::isinf(s.modes().back().lambda.real()));
  // −0.5 is exact in binary; QZ on a 2×2 pencil errs by a few u.
  expect_eigenvalues(s, {cd(-0.5, 0.0)}, 4 * u);
  EXPECT_EQ(s.stability(), Stability::stable);  // the infinite eigenvalue does not count

  // Index 2 (a Jordan chain at ∞): det(λE − A) = 1 for E = [[0, 1], [0, 0]], A = I — no finite
  // eigenvalue at all.
  MatrixXd E2 = MatrixXd::Zero(2, 2);
  E2(0, 1) = 1.0;
  s.compute(E2, MatrixXd::Identity(2, 2));
  EXPECT_EQ(s.num_infinite(), 2);
  EXPECT_EQ(count(s, EigenvalueKind::finite), 0);
}

TEST(DescriptorFrequencyResponse, ClosedFormAndPoleAtZero) {
  const PlanarMass pm;
  const DescriptorModel model = pm.model();
  Eigen::VectorXd omega(4);
  omega << 0.0, 1.0, 5.0, 20.0;
  const mbsgen::DescriptorFrf r = mbsgen::descriptor_frequency_response(model, omega, 0);
  // Ω = 0: −A has the zero columns of ψ and s, an exactly singular matrix (λ = 0 is an
  // eigenvalue): zgetrf meets a zero pivot.
  EXPECT_EQ(r.flags[0], FrfFlag::pole);
  EXPECT_EQ(r.rcond[0], 0.0);
  EXPECT_TRUE(std::isnan(r.response(0, 0).real()));
  for (Index k = 1; k < omega.size(); ++k) {
    EXPECT_NE(r.flags[static_cast<std::size_t>(k)], FrfFlag::pole);
    const double w = omega[k];
    // Closed forms: q̂_x = 1/(k_x − mΩ² + iΩd_x), q̂_y = 0, ψ̂ = q̂_x/r, ŝ = q̂_x, û_x = iΩq̂_x.
    const cd qx = 1.0 / cd(pm.kx - pm.m * w * w, w * pm.dx);
    const Eigen::Vector<cd, 6> ref(qx, 0.0, qx / pm.r, qx, cd(0.0, w) * qx, 0.0);
    // LU of a 6×6 with rcond ≥ 1e-3 here: forward error ≤ 10·n·u/rcond relative to ‖ẑ‖.
    const double tol = 10.0 * 6 * u / r.rcond[k];
    EXPECT_LE((r.response.col(k) - ref).norm(), tol * ref.norm()) << "omega " << w;
  }
  // Selected outputs, and the raise policy.
  const mbsgen::DescriptorFrf sel = mbsgen::descriptor_frequency_response(model, omega, 0, {3});
  EXPECT_EQ(sel.response.rows(), 1);
  EXPECT_EQ(sel.response(0, 2), r.response(3, 2));  // same computation, bitwise
  EXPECT_THROW(mbsgen::descriptor_frequency_response(model, omega, 0, {},
                                                     mbsgen::PoleHandling::raise),
               mbsgen::SingularSystemError);
  EXPECT_THROW(mbsgen::descriptor_frequency_response(model, omega, 1), mbsgen::DimensionError);
  EXPECT_THROW(mbsgen::descriptor_frequency_response(model, omega, 0, {6}),
               mbsgen::DimensionError);
}

TEST(DescriptorModes, WhippleBicycleAtFiveMetresPerSecond) {
  // x = [φ, δ, φ̇, δ̇], E = blkdiag(I, M), A = [[0, I], [−(g K0 + v² K2), −v C1]].
  const Descriptor d = Bicycle().at(5.0);
  DescriptorEigenSolver s;
  s.compute(d.E, d.A);
  ASSERT_EQ(s.modes().size(), 4u);
  // The 40-digit values of docs/test-references.md. The exact eigenvalues of the 17-digit data
  // differ from them by 2e-15 (mpmath at 50 digits); QZ adds κ·η. 1e-12 is the bar of
  // docs/test-references.md.
  expect_eigenvalues(s, Bicycle::eigenvalues_at_5(), 1e-12);
  // Tighter, to hold the balancing choice: measured 1.4e-14 with permutation and scaling, which
  // the componentwise backward error selects; permutation alone gives 6.7e-13 (its normwise
  // backward errors ≤ 3e-16 cannot tell). 1e-13 is 7× the measured error.
  expect_eigenvalues(s, Bicycle::eigenvalues_at_5(), 1e-13);
  EXPECT_EQ(s.stability(), Stability::stable);  // v_w = 4.29 < 5 < v_c = 6.02: self-stable
  for (const Mode& m : s.modes()) EXPECT_LE(m.backward_error, 100.0 * 4 * u);
}

TEST(DescriptorModes, JordanChainThroughIgnorableCoordinatesIsExact) {
  // The bicycle with yaw ψ and lateral position y of the rear contact, x = [φ, δ, ψ, y, φ̇, δ̇]:
  // ψ̇ = (v δ + c δ̇) cos λ_s / w (paper eq. for the yaw rate), ẏ = v ψ. The column of y in A is
  // zero (first level); removing it and the row ẏ leaves ψ's column zero (second level, exact
  // because the first level removed a row and a column bit for bit). λ = 0 is a 2×2 Jordan
  // block: y is its eigenvector, ψ its generalized eigenvector (A e_ψ = v E e_y).
  const double v = 5.0, w = 1.02, c = 0.08, tilt = 3.141592653589793 / 10;
  const Descriptor d4 = Bicycle().at(v);
  MatrixXd E = MatrixXd::Identity(6, 6), A = MatrixXd::Zero(6, 6);
  const std::vector<Index> keep{0, 1, 4, 5};  // φ, δ, φ̇, δ̇ in the 6-state numbering
  for (Index i = 0; i < 4; ++i)
    for (Index j = 0; j < 4; ++j) {
      E(keep[static_cast<std::size_t>(i)], keep[static_cast<std::size_t>(j)]) = d4.E(i, j);
      A(keep[static_cast<std::size_t>(i)], keep[static_cast<std::size_t>(j)]) = d4.A(i, j);
    }
  A(2, 1) = v * std::cos(tilt) / w;
  A(2, 5) = c * std::cos(tilt) / w;
  A(3, 2) = v;
  DescriptorEigenSolver s, s4;
  s.compute(E, A);
  s4.compute(d4.E, d4.A);
  ASSERT_EQ(s.modes().size(), 6u);
  EXPECT_EQ(s.num_zero(), 2);
  EXPECT_EQ(s.zero_columns(), (std::vector<Index>{2, 3}));
  for (std::size_t j = 0; j < 2; ++j) {
    const Mode& m = s.modes()[j];
    EXPECT_EQ(m.kind, EigenvalueKind::zero);
    EXPECT_EQ(m.lambda, cd(0.0, 0.0));
    EXPECT_TRUE(m.defective);
    // Both report the chain's head e_y: ψ's own column is a generalized eigenvector only.
    EXPECT_EQ(m.shape, Eigen::VectorXcd::Unit(6, 3));
    EXPECT_EQ(m.backward_error, 0.0);  // A e_y = 0 exactly
  }
  // The reduced pencil is the 4×4 lean-steer pencil bit for bit, so QZ returns the same
  // eigenvalues bit for bit (same LAPACK calls on the same data and the same balancing).
  for (std::size_t j = 0; j < 4; ++j) EXPECT_EQ(s.modes()[j + 2].lambda, s4.modes()[j].lambda);
  expect_eigenvalues(s, Bicycle::eigenvalues_at_5(), 1e-13);  // as the 4×4 test
  // The full eigenvectors carry ψ and y by back substitution: the bar of the other tests.
  EXPECT_LE(s.max_backward_error(), 100.0 * 6 * u);
  EXPECT_EQ(s.stability(), Stability::marginal);  // an exact double zero, the rest stable
}

TEST(DescriptorModes, HouseholderDeflationWhenEHasNoUnitColumns) {
  // The planar mass with its equations mixed by an orthogonal U (a product of Givens
  // rotations): U E, U A has the same eigenvalues and the same zero columns of A, but the
  // columns of U E for ψ and s are no longer unit vectors, so the QR of E_Z is a genuine
  // Householder one (dgeqp3) and the reduced pencil carries its rounding.
  const PlanarMass pm;
  const DescriptorModel plain = pm.model();
  MatrixXd U = MatrixXd::Identity(6, 6);
  for (Index i = 0; i + 1 < 6; ++i) {
    const double t = 0.3 + 0.2 * static_cast<double>(i);
    MatrixXd G = MatrixXd::Identity(6, 6);
    G(i, i) = G(i + 1, i + 1) = std::cos(t);
    G(i, i + 1) = -std::sin(t);
    G(i + 1, i) = std::sin(t);
    U = G * U;
  }
  const MatrixXd E = U * plain.E(), A = U * plain.A();
  ASSERT_TRUE((A.col(2).array() == 0.0).all() && (A.col(3).array() == 0.0).all());
  DescriptorEigenSolver s;
  s.compute(E, A);
  EXPECT_EQ(s.num_zero(), 2);
  EXPECT_EQ(s.zero_columns(), (std::vector<Index>{2, 3}));
  for (std::size_t j = 0; j < 2; ++j) {
    EXPECT_EQ(s.modes()[j].lambda, cd(0.0, 0.0));
    EXPECT_EQ(s.modes()[j].shape, Eigen::VectorXcd::Unit(6, static_cast<Index>(j) + 2));
  }
  std::vector<cd> ref = PlanarMass::roots(pm.m, pm.dx, pm.kx);
  const std::vector<cd> ry = PlanarMass::roots(pm.m, pm.dy, pm.ky);
  ref.insert(ref.end(), ry.begin(), ry.end());
  // U's rounding (≈ 6u relative in E and A) and the deflation's add to the plain test's error
  // (8.9e-16): measured 2.2e-15; the plain test's 1e-14 (≈ 20 u·|λ|) still holds with 4× room.
  expect_eigenvalues(s, ref, 1e-14);
  EXPECT_LE(s.max_backward_error(), 100.0 * 6 * u);
  EXPECT_EQ(s.stability(), Stability::marginal);
}
