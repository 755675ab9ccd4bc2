// Nonholonomic constraints and steady motions (nonholonomic.hpp): the linearized rolling disk
// against SymPy's published linearization, invariance to the choice of dependent speeds, and the
// errors for rates that violate the constraints and motions that are not steady. Models are read
// from their files and evaluated in process at 50 digits.
#include "mbsgen/generator/linear/linearize.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include "symbolic/point_evaluator.hpp"  // generator/src: the generator's own 50-digit evaluation

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <sstream>
#include <string>

namespace {

using namespace mbsgen;
using GiNaC::ex;

std::string file_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

const std::string kDisk = std::string(MBSGEN_SOURCE_DIR) + "/models/rolling/rolling_disk.yaml";

// A matrix of the linear model at the operating point, with parameter values `set` replacing the
// defaults (the operating point's positions and rates evaluated with them), at 50 digits.
Eigen::MatrixXd value(Equations& eq, const LinearEquations& lin, const ExMatrix& A,
                      const std::map<std::string, double>& set = {}) {
  const long digits = GiNaC::Digits;
  GiNaC::Digits = 50;
  GiNaC::exmap v;
  for (const auto& p : eq.model->parameters()) {
    auto it = set.find(p.name);
    v[p.symbol] = GiNaC::numeric(it == set.end() ? p.value : it->second);
  }
  GiNaC::exmap point = v;
  for (std::size_t k = 0; k < eq.y.size(); ++k) {
    auto closed = eq.loops.closed_at_defaults.find(eq.y[k]);
    point[eq.y[k]] = closed != eq.loops.closed_at_defaults.end() ? closed->second : GiNaC::evalf(lin.y0[k].subs(v));
    point[eq.yd[k]] = GiNaC::evalf(lin.yd0[k].subs(v));
  }
  // Through the program's intermediates one by one (written out, the bicycle's entries are too
  // large to substitute into).
  std::vector<ex> entries;
  for (const auto& row : A) entries.insert(entries.end(), row.begin(), row.end());
  const std::vector<GiNaC::numeric> n = detail::PointEvaluator(eq.program, point).evaluate(entries);
  Eigen::MatrixXd out(static_cast<Eigen::Index>(A.size()), static_cast<Eigen::Index>(A.empty() ? 0 : A[0].size()));
  for (Eigen::Index i = 0; i < out.rows(); ++i)
    for (Eigen::Index j = 0; j < out.cols(); ++j) out(i, j) = n[static_cast<std::size_t>(i * out.cols() + j)].to_double();
  GiNaC::Digits = digits;
  return out;
}

// SymPy's linearized rolling disk (tests/data/reference/rolling_disk.json, "general_A": SymPy's
// KanesMethod and Linearizer as in test_linearize_rolling_disc_kane, its A_sol asserted, and a
// hand Newton–Euler derivation agreeing symbolically), at heading q1 = 0, for a disk of
// diametral and polar moments I, J, in SymPy's state order (q1..q5, u1 = q2', u2 = q3', u3 = q1').
Eigen::MatrixXd sympy_disk(double m, double r, double g, double w, double I, double J) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(8, 8);
  A(0, 7) = 1, A(1, 5) = 1, A(2, 6) = 1;
  A(3, 6) = -r;
  A(4, 0) = -r * w, A(4, 5) = r;
  A(5, 1) = m * g * r / (I + m * r * r), A(5, 7) = w * (J + m * r * r) / (I + m * r * r);
  A(7, 5) = -J * w / I;
  return A;
}

// Our state (q1..q5, q1', q2', q3') in SymPy's order.
Eigen::MatrixXd in_sympy_order(const Eigen::MatrixXd& A) {
  const int to[8] = {0, 1, 2, 3, 4, 7, 5, 6};  // our index → SymPy's
  Eigen::MatrixXd R(8, 8);
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) R(to[i], to[j]) = A(i, j);
  return R;
}

TEST(RollingDisk, MatchesSymPysLinearization) {
  const Model model = read_model_file(kDisk);
  Equations eq = derive(model);
  LinearEquations lin = linearize(eq);
  ASSERT_TRUE(lin.descriptor);
  ASSERT_EQ(lin.E.size(), 8u);
  EXPECT_FALSE(eq.loops.active) << "the coordinates keep the disk on the ground: its contact condition is identically 0";
  for (const auto& [m, r, g] : {std::array<double, 3>{1, 1, 1}, std::array<double, 3>{2, 0.3, 9.81}})
    for (double w : {0.5, 1 / std::sqrt(3.0), 1.0, 2.0}) {
      const std::map<std::string, double> set = {{"m", m}, {"r", r}, {"g", g}, {"w", w}};
      const Eigen::MatrixXd E = value(eq, lin, lin.E, set), A = value(eq, lin, lin.A, set);
      const Eigen::MatrixXd ours = in_sympy_order(E.partialPivLu().solve(A));
      const Eigen::MatrixXd ref = sympy_disk(m, r, g, w, m * r * r / 4, m * r * r / 2);
      // 50-digit evaluation, one 8×8 solve in double: rounding of order 1e-15 of the entries.
      EXPECT_LE((ours - ref).cwiseAbs().maxCoeff(), 1e-13 * (1 + ref.cwiseAbs().maxCoeff()))
          << "m " << m << " r " << r << " g " << g << " w " << w << "\nours\n" << ours << "\nSymPy\n" << ref;
    }
}

// The eigenvalues do not depend on which speeds are independent (issue 16 §3): the centre's x
// rate instead of the spin rate gives the same nonzero eigenvalues (the zeros are defective, split
// by rounding to about u^(1/3), and compared apart).
TEST(RollingDisk, EigenvaluesInvariantToTheDependentSpeeds) {
  auto nonzero = [](const std::string& text) {
    const Model model = read_model_string(text, "disk.yaml");
    Equations eq = derive(model);
    LinearEquations lin = linearize(eq);
    const Eigen::MatrixXd E = value(eq, lin, lin.E, {{"w", 2}}), A = value(eq, lin, lin.A, {{"w", 2}});
    const Eigen::VectorXcd l = Eigen::EigenSolver<Eigen::MatrixXd>(E.partialPivLu().solve(A)).eigenvalues();
    std::vector<std::complex<double>> out;
    for (const auto& x : l)
      if (std::abs(x) > 1e-3) out.push_back(x);
    std::sort(out.begin(), out.end(), [](auto a, auto b) { return a.imag() < b.imag(); });
    return out;
  };
  const std::string text = file_text(kDisk);
  const std::string other = std::regex_replace(text, std::regex("independent_speeds: \\[q1, q2, q3\\]"),
                                               "independent_speeds: [q1, q2, q4]");
  ASSERT_NE(text, other);
  const auto a = nonzero(text), b = nonzero(other);
  ASSERT_EQ(a.size(), 2u);
  ASSERT_EQ(b.size(), 2u);
  // λ² = 4/5 − 12 w²/5 at w = 2 (closed form of rolling_disk.json): ±i √8.8.
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_NEAR(std::abs(a[k] - b[k]), 0, 1e-12);
    EXPECT_NEAR(std::abs(a[k].imag()), std::sqrt(8.8), 1e-12);
    EXPECT_NEAR(a[k].real(), 0, 1e-12);
  }
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ModelError& e) {
    return e.message();
  }
  return "(no error)";
}

TEST(RollingDisk, RatesThatViolateTheConstraintsAreAnError) {
  const std::string text = std::regex_replace(file_text(kDisk), std::regex("velocity: \\{q3: w, q4: -r\\*w\\}"),
                                              "velocity: {q3: w}");
  const std::string message = error_of([&] {
    const Model model = read_model_string(text, "disk.yaml");
    derive(model);
  });
  EXPECT_NE(message.find("the rate of 'q4' is 0 but the constraints make it -1"), std::string::npos) << message;
}

TEST(RollingDisk, ANonAxisymmetricWheelIsNotASteadyMotion) {
  // I_xx ≠ I_zz: the spinning wheel's inertia depends on its angle q3, whose rate is not zero.
  const std::string text = std::regex_replace(file_text(kDisk), std::regex("zz: m\\*r\\^2/4"), "zz: m*r^2/3");
  const std::string message = error_of([&] {
    const Model model = read_model_string(text, "disk.yaml");
    Equations eq = derive(model);
    linearize(eq);
  });
  EXPECT_NE(message.find("not a steady motion"), std::string::npos) << message;
  EXPECT_NE(message.find("'q3'"), std::string::npos) << message;
}

}  // namespace

namespace {

const std::string kBicycle = std::string(MBSGEN_SOURCE_DIR) + "/models/bicycle/whipple_benchmark.yaml";

// The lean–steer block of the bicycle's descriptor model: states (x, y, psi, phi, thetaR, delta,
// thetaF; phi', thetaR', delta'), so phi and delta are coordinates 3 and 5 and speeds 7 and 9;
// the dynamic rows are M_r w' + C_r w + K_r y = B u with A = [[P, N], [−K_r, −C_r]].
struct LeanSteer {
  Eigen::Matrix2d M, C, K;
};

LeanSteer lean_steer(Equations& eq, const LinearEquations& lin, double v, double g) {
  const std::map<std::string, double> set = {{"v", v}, {"g", g}};
  const Eigen::MatrixXd E = value(eq, lin, lin.E, set), A = value(eq, lin, lin.A, set);
  const int q[2] = {3, 5}, w[2] = {7, 9};
  LeanSteer out;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      out.M(i, j) = E(w[i], w[j]);
      out.C(i, j) = -A(w[i], w[j]);
      out.K(i, j) = -A(w[i], q[j]);
    }
  return out;
}

// Meijaard, Papadopoulos, Ruina & Schwab (2007), eq. 5.3 and its published values
// (docs/test-references.md, "The Whipple bicycle": 14 decimals, recomputed at 40 digits from
// Table 1; the 17-digit values used here).
TEST(WhippleBicycle, LeanSteerMatricesMatchTheBenchmark) {
  const Model model = read_model_file(kBicycle);
  Equations eq = derive(model);
  LinearEquations lin = linearize(eq);
  ASSERT_TRUE(lin.descriptor);
  ASSERT_EQ(lin.E.size(), 10u);
  Eigen::Matrix2d M, C1, K0, K2;
  M << 80.81722, 2.3194133220870913, 2.3194133220870913, 0.29784188199685553;
  C1 << 0, 33.866413914924944, -0.85035641456978437, 1.6854039739755967;
  K0 << -80.95, -2.5995168524987164, -2.5995168524987164, -0.80329488458617688;
  K2 << 0, 76.597345895732222, 0, 2.6543152379460403;
  // K = g K0 + v² K2 and C = v C1: g = 1, v = 0 gives K0; g = 0, v = 1 gives C1 and K2.
  const LeanSteer a = lean_steer(eq, lin, 0, 1), b = lean_steer(eq, lin, 1, 0);
  // 1e-12 absolute (issue 16 §3): entries up to 81, evaluated at 50 digits; the references
  // carry 17 significant digits (about 1e-15 of 81).
  EXPECT_LE((a.M - M).cwiseAbs().maxCoeff(), 1e-12) << a.M;
  EXPECT_LE((a.K - K0).cwiseAbs().maxCoeff(), 1e-12) << a.K;
  EXPECT_LE((b.C - C1).cwiseAbs().maxCoeff(), 1e-12) << b.C;
  EXPECT_LE((b.K - K2).cwiseAbs().maxCoeff(), 1e-12) << b.K;
  EXPECT_EQ(a.C.cwiseAbs().maxCoeff(), 0) << "no damping at v = 0";
}

}  // namespace
