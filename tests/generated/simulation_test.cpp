// Time simulation of the nonlinear equations through the generated kernels (issue 18 §2): the
// simple pendulum's period at large amplitude against the closed form with the complete elliptic
// integral, the conservative double pendulum's energy over 100 periods, small sines against the
// frequency response, and the failures the integrator must report.
#include "chain3_sympy_model.hpp"
#include "double_pendulum_model.hpp"
#include "four_bar.hpp"
#include "four_bar_model.hpp"
#include "jeffcott_rotor_model.hpp"
#include "middle_ear_model.hpp"
#include "rotor_disk_model.hpp"
#include "rotor_disk_motion_model.hpp"
#include "simple_pendulum_model.hpp"
#include "spherical_pendulum_conical_model.hpp"
#include "ziegler_column_model.hpp"

#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/time/simulation.hpp"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <complex>
#include <sstream>
#include <string>
#include <vector>

namespace {

using mbsgen::GeneratedModel;
using mbsgen::InputSignal;
using mbsgen::SimulationOptions;
using mbsgen::SimulationResult;

constexpr double kPi = 3.141592653589793238462643383279502884;

SimulationResult run(const GeneratedModel& model, SimulationOptions o) { return simulate(model, model.operating_point(), o); }

// The times where row `i` of y crosses zero, each located on the cubic Hermite interpolant of the
// samples (values y, slopes yd): its error is O(h⁴), 1e-13 s for the pendulum at h = 1 ms.
std::vector<double> zero_crossings(const SimulationResult& r, Eigen::Index i) {
  std::vector<double> times;
  for (Eigen::Index k = 0; k + 1 < r.t.size(); ++k) {
    const double y0 = r.y(i, k), y1 = r.y(i, k + 1);
    if (!(y0 < 0 && y1 >= 0) && !(y0 > 0 && y1 <= 0)) continue;
    const double h = r.t[k + 1] - r.t[k], d0 = h * r.yd(i, k), d1 = h * r.yd(i, k + 1);
    auto p = [&](double s) {
      const double s2 = s * s, s3 = s2 * s;
      return (2 * s3 - 3 * s2 + 1) * y0 + (s3 - 2 * s2 + s) * d0 + (-2 * s3 + 3 * s2) * y1 + (s3 - s2) * d1;
    };
    double a = 0, b = 1;
    for (int it = 0; it < 200 && b - a > 1e-16; ++it) {
      const double m = 0.5 * (a + b);
      ((p(a) < 0) == (p(m) < 0) ? a : b) = m;
    }
    times.push_back(r.t[k] + 0.5 * (a + b) * h);
  }
  return times;
}

const char* method_name(mbsgen::IntegrationMethod m) {
  return m == mbsgen::IntegrationMethod::bdf      ? "bdf"
         : m == mbsgen::IntegrationMethod::radau  ? "radau"
         : m == mbsgen::IntegrationMethod::radau9 ? "radau9"
                                                  : "adams";
}

// The period of the simple pendulum at amplitude θ0: T = 4 √(l/g) K(sin(θ0/2)) (the complete
// elliptic integral of the first kind of modulus k; e.g. Landau & Lifshitz, Mechanics, §11,
// problem 1), against the zero crossings of φ over ten periods (Adams and Radau of orders 5 and
// 9, rtol 1e-12; the crossings between samples of 1 ms from their interpolants): to 1e-9.
TEST(Simulation, SimplePendulumPeriodAtLargeAmplitudeMatchesTheEllipticIntegral) {
  GeneratedModel model(simple_pendulum::kernels());
  const double l = 1.0, g = 9.81;
  for (auto method : {mbsgen::IntegrationMethod::adams, mbsgen::IntegrationMethod::radau, mbsgen::IntegrationMethod::radau9})
  for (double theta0 : {0.1, 1.0, 2.5, 3.0}) {
    const double T = 4 * std::sqrt(l / g) * std::comp_ellint_1(std::sin(theta0 / 2));
    SimulationOptions o;
    o.method = method;
    o.duration = 10.2 * T;
    o.step = 1e-3;
    o.rtol = 1e-12;
    o.atol = 1e-14;
    o.initial = {{"phi", theta0}};
    const SimulationResult r = run(model, o);
    const std::vector<double> c = zero_crossings(r, 0);  // at T/4 + j T/2
    ASSERT_EQ(c.size(), 20u) << "theta0 " << theta0;
    const double measured = 2 * (c.back() - c.front()) / static_cast<double>(c.size() - 1);
    EXPECT_NEAR(measured / T, 1.0, 1e-9) << method_name(method) << ", theta0 " << theta0 << ": T " << T
                                         << " s, measured " << measured;
    EXPECT_NEAR(c.front() / (T / 4), 1.0, 1e-9) << method_name(method) << ", theta0 " << theta0;
  }
}

// The total energy of the double pendulum of point masses (docs/test-references.md §2 model: m1 = m2 =
// 1 kg, l1 = l2 = 1 m), written out here from the coordinates, not from the kernels.
double double_pendulum_energy(double p1, double p2, double w1, double w2) {
  const double m1 = 1, m2 = 1, l1 = 1, l2 = 1, g = 9.81;
  const double kinetic = 0.5 * m1 * l1 * l1 * w1 * w1 +
                         0.5 * m2 * (l1 * l1 * w1 * w1 + l2 * l2 * w2 * w2 + 2 * l1 * l2 * std::cos(p1 - p2) * w1 * w2);
  const double potential = -m1 * g * l1 * std::cos(p1) - m2 * g * (l1 * std::cos(p1) + l2 * std::cos(p2));
  return kinetic + potential;
}

double energy_drift(const GeneratedModel& model, mbsgen::IntegrationMethod method, double p1, double p2, double rtol,
                    long* steps = nullptr) {
  const double slow = 2 * kPi / std::sqrt((2 - std::sqrt(2.0)) * 9.81);  // docs/test-references.md §2
  SimulationOptions o;
  o.method = method;
  o.duration = 100 * slow;
  o.step = slow / 20;
  o.rtol = rtol;
  o.atol = rtol / 100;
  o.initial = {{"phi1", p1}, {"phi2", p2}};
  const SimulationResult r = run(model, o);
  const double e0 = double_pendulum_energy(p1, p2, 0, 0), scale = 9.81;  // m g l
  double worst = 0;
  for (Eigen::Index k = 0; k < r.t.size(); ++k)
    worst = std::max(worst, std::abs(double_pendulum_energy(r.y(0, k), r.y(1, k), r.yd(0, k), r.yd(1, k)) - e0));
  if (steps) *steps = r.steps;
  return worst / scale;
}

// Conservative: over 100 periods of the slower mode at rtol 1e-10, Adams keeps the energy within
// 1e-8 of its initial value (relative to the energy scale m g l).
TEST(Simulation, DoublePendulumConservesEnergyOver100Periods) {
  GeneratedModel model(double_pendulum::kernels());
  long steps = 0;
  const double drift = energy_drift(model, mbsgen::IntegrationMethod::adams, 0.3, -0.2, 1e-10, &steps);
  EXPECT_LT(drift, 1e-8) << steps << " steps";
}

// The drift is the integrator's error, so it falls with the tolerance: by at least 10 from rtol
// 1e-9 to 1e-11 for every method, also in chaotic motion (from 1.5 and 2 rad); BDF on the
// Jacobian kernel and on difference quotients alike.
TEST(Simulation, DoublePendulumEnergyDriftFallsWithTheTolerance) {
  GeneratedModel model(double_pendulum::kernels());
  for (auto method : {mbsgen::IntegrationMethod::adams, mbsgen::IntegrationMethod::bdf, mbsgen::IntegrationMethod::radau,
                      mbsgen::IntegrationMethod::radau9})
    for (const auto& [p1, p2] : std::vector<std::pair<double, double>>{{0.3, -0.2}, {1.5, 2.0}}) {
      const double coarse = energy_drift(model, method, p1, p2, 1e-9), fine = energy_drift(model, method, p1, p2, 1e-11);
      EXPECT_LT(fine, coarse / 10) << method_name(method) << " from " << p1
                                   << ", " << p2 << ": " << coarse << " at 1e-9, " << fine << " at 1e-11";
    }
}


// The Jacobian kernel against central differences of F = M(y) ÿ + k − q through the mass-matrix
// and residual kernels, at a state where every variable differs, of the model's size (radians
// for the pendulums, millimetres for the rotor, 10 µm and 10 mrad for the middle ear). The step h
// balances the truncation error O(h²) against the rounding error O(ε |F| / h): the middle ear's
// F holds forces much larger than their changes, and its quotients agree with the kernel to
// 1e-11 at h = 1e-6 but only to 1e-5 at h = 1e-10. So 1e-7 of the column's largest entry (plus
// 1e-12 of the matrix's, for entries whose quotient is an exact 0 and the kernel's a rounding
// error).
TEST(Simulation, DynamicsJacobianKernelEqualsCentralDifferences) {
  struct Case {
    const mbsgen::ModelKernels* k;
    double size, h;
  };
  for (const Case c : {Case{&double_pendulum::kernels(), 0.5, 1e-5}, Case{&chain3_sympy::kernels(), 0.5, 1e-5},
                       Case{&jeffcott_rotor::kernels(), 1e-3, 1e-6}, Case{&ziegler_column::kernels(), 0.5, 1e-5},
                       Case{&middle_ear::kernels(), 1e-5, 1e-6}}) {
    const mbsgen::ModelKernels* k = c.k;
    ASSERT_NE(k->dynamics_jacobian, nullptr) << k->model;
    GeneratedModel model(*k);
    const std::vector<double>& p = model.parameters();
    const Eigen::Index n = k->n_coordinates;
    const mbsgen::OperatingPoint op = model.operating_point();
    Eigen::VectorXd y = op.y0, yd(n), ydd(n), u(k->n_inputs);
    for (Eigen::Index i = 0; i < n; ++i) {
      y[i] += c.size * std::sin(1.0 + i);
      yd[i] = 3 * c.size * std::cos(2.0 + i);
      ydd[i] = 50 * c.size * std::sin(3.0 * i);
    }
    u.setConstant(0.7);
    auto F = [&](const Eigen::VectorXd& yy, const Eigen::VectorXd& vv) {
      Eigen::MatrixXd M(n, n);
      Eigen::VectorXd r(n);
      EXPECT_EQ(k->mass_matrix(yy.data(), p.data(), M.data()), 0);
      EXPECT_EQ(k->residual(yy.data(), vv.data(), u.data(), p.data(), r.data()), 0);
      return Eigen::VectorXd(M * ydd + r);
    };
    Eigen::MatrixXd Ky(n, n), Kv(n, n), dy(n, n), dv(n, n);
    ASSERT_EQ(k->dynamics_jacobian(y.data(), yd.data(), ydd.data(), u.data(), p.data(), Ky.data(), Kv.data()), 0);
    const double h = c.h;
    for (Eigen::Index j = 0; j < n; ++j) {
      Eigen::VectorXd a = y, b = y, e = yd, f = yd;
      a[j] += h, b[j] -= h, e[j] += 3 * h, f[j] -= 3 * h;
      dy.col(j) = (F(a, yd) - F(b, yd)) / (2 * h);
      dv.col(j) = (F(y, e) - F(y, f)) / (6 * h);
    }
    const double Ky_size = dy.cwiseAbs().maxCoeff(), Kv_size = dv.cwiseAbs().maxCoeff();
    for (Eigen::Index j = 0; j < n; ++j)
      for (Eigen::Index i = 0; i < n; ++i) {
        EXPECT_NEAR(Ky(i, j), dy(i, j), 1e-7 * dy.col(j).cwiseAbs().maxCoeff() + 1e-12 * Ky_size)
            << k->model << " Ky " << i << "," << j;
        EXPECT_NEAR(Kv(i, j), dv(i, j), 1e-7 * dv.col(j).cwiseAbs().maxCoeff() + 1e-12 * Kv_size)
            << k->model << " Kv " << i << "," << j;
      }
  }
}

// The Jeffcott rotor's equations are linear (a point mass on linear springs and dampers, with the
// rotating damping's circulatory term), so the step response has the closed form
// x(t) = U (e^{A(t−ts)} − I) A⁻¹ b after the step at ts, through the eigenvectors of the first-
// order matrix A (Eigen's EigenSolver, not the runtime's). The step restarts the integrator at
// ts. The global error over 160 periods of the whirl is not bounded by the local tolerance, but
// it falls with it: BDF (kernel and difference-quotient Jacobians) and Adams must agree to 1e-7
// of the response's size at rtol 1e-11, and tenfold better than at rtol 1e-9.
// x' = A x + b u of a linear model with x = (y, ẏ), through its eigenvectors (Eigen's
// EigenSolver, not the runtime's): the responses to a unit step, e^{At} − I) A⁻¹ b, and to a unit
// ramp, their integral (A⁻¹(e^{At} − I) − t I) A⁻¹ b, at time t after their start.
struct FirstOrder {
  Eigen::MatrixXcd V;
  Eigen::VectorXcd lambda, w, w2;  // V⁻¹ A⁻¹ b and V⁻¹ A⁻² b
  explicit FirstOrder(const mbsgen::LinearModel& lin) {
    const Eigen::Index n = lin.size();
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2 * n, 2 * n);
    A.topRightCorner(n, n).setIdentity();
    A.bottomLeftCorner(n, n) = -lin.M().lu().solve(lin.K());
    A.bottomRightCorner(n, n) = -lin.M().lu().solve(lin.Q());
    Eigen::VectorXd b = Eigen::VectorXd::Zero(2 * n);
    b.tail(n) = lin.M().lu().solve(lin.B().col(0));
    const Eigen::EigenSolver<Eigen::MatrixXd> es(A);
    V = es.eigenvectors();
    lambda = es.eigenvalues();
    const Eigen::MatrixXcd Ac = A.cast<std::complex<double>>();
    const Eigen::VectorXcd Ainv_b = Ac.lu().solve(b.cast<std::complex<double>>());
    w = V.lu().solve(Ainv_b);
    w2 = V.lu().solve(Eigen::VectorXcd(Ac.lu().solve(Ainv_b)));
  }
  Eigen::VectorXd step(double t) const {
    if (t <= 0) return Eigen::VectorXd::Zero(V.rows());
    Eigen::VectorXcd e(V.rows());
    for (Eigen::Index i = 0; i < e.size(); ++i) e[i] = (std::exp(lambda[i] * t) - 1.0) * w[i];
    return (V * e).real();
  }
  Eigen::VectorXd ramp(double t) const {
    if (t <= 0) return Eigen::VectorXd::Zero(V.rows());
    Eigen::VectorXcd e(V.rows());
    for (Eigen::Index i = 0; i < e.size(); ++i) e[i] = (std::exp(lambda[i] * t) - 1.0) * w2[i] - t * w[i];
    return (V * e).real();
  }
};

TEST(Simulation, LinearRotorStepResponseMatchesTheMatrixExponential) {
  GeneratedModel model(jeffcott_rotor::kernels());
  const FirstOrder exact_model(model.linear_model());
  const Eigen::Index n = 2;
  const double U = 2.0, ts = 0.013;
  auto exact = [&](double t) { return Eigen::VectorXd(U * exact_model.step(t - ts)); };
  struct Case {
    mbsgen::IntegrationMethod method;
    bool quotients;
  };
  for (const Case c : {Case{mbsgen::IntegrationMethod::bdf, false}, Case{mbsgen::IntegrationMethod::bdf, true},
                       Case{mbsgen::IntegrationMethod::adams, false}, Case{mbsgen::IntegrationMethod::radau, false},
                       Case{mbsgen::IntegrationMethod::radau, true}, Case{mbsgen::IntegrationMethod::radau9, false},
                       Case{mbsgen::IntegrationMethod::radau9, true}}) {
    double error[2] = {};
    for (int tight = 0; tight < 2; ++tight) {
      SimulationOptions o;
      o.method = c.method;
      o.difference_quotients = c.quotients;
      o.duration = 5;
      o.step = 1e-3;
      // Radau (of either order) is 100 times as accurate at each tolerance: at 1e-9 it is within 7e-11 of itself at
      // 1e-11, below the error of the eigendecomposition behind `exact` (3e-10 at t = 4 s), so
      // it is compared at 1e-6 and 1e-8.
      const bool radau = c.method == mbsgen::IntegrationMethod::radau || c.method == mbsgen::IntegrationMethod::radau9;
      o.rtol = tight ? (radau ? 1e-8 : 1e-11) : (radau ? 1e-6 : 1e-9);
      o.atol = o.rtol * 1e-7;  // the response is 5e-6 m and 1e-3 m/s
      o.inputs = {InputSignal::step(U, ts)};
      const SimulationResult r = run(model, o);
      EXPECT_EQ(r.restarts, 1);
      EXPECT_EQ(r.analytic_jacobian, c.method != mbsgen::IntegrationMethod::adams && !c.quotients);
      double worst_y = 0, worst_v = 0, size_y = 0, size_v = 0;
      for (Eigen::Index k = 0; k < r.t.size(); ++k) {
        const Eigen::VectorXd x = exact(r.t[k]);
        worst_y = std::max(worst_y, (r.y.col(k) - x.head(n)).cwiseAbs().maxCoeff());
        worst_v = std::max(worst_v, (r.yd.col(k) - x.tail(n)).cwiseAbs().maxCoeff());
        size_y = std::max(size_y, x.head(n).cwiseAbs().maxCoeff());
        size_v = std::max(size_v, x.tail(n).cwiseAbs().maxCoeff());
        EXPECT_EQ(r.u(0, k), r.t[k] > ts ? U : 0.0);
      }
      error[tight] = std::max(worst_y / size_y, worst_v / size_v);
    }
    const std::string which = std::string(method_name(c.method)) +
                              (c.quotients ? " (difference quotients)" : "");
    EXPECT_LT(error[1], 1e-7) << which << ": " << error[1] << " at the tighter rtol";
    EXPECT_LT(error[1], error[0] / 10) << which << ": " << error[0] << " and " << error[1];
  }
}

std::string failure_of(const GeneratedModel& model, SimulationOptions o, double* time = nullptr) {
  try {
    run(model, o);
  } catch (const mbsgen::SimulationError& e) {
    if (time) *time = e.time();
    return e.what();
  }
  return "no failure";
}

// Failures carry the time and the cause; no result is returned.
TEST(Simulation, FailuresAreReportedWithTheTime) {
  {  // the spherical pendulum's M = m L² diag(1, sin²θ) is singular at the pole; the fallback path
    GeneratedModel model(spherical_pendulum_conical::kernels());
    EXPECT_EQ(model.kernels().dynamics_jacobian, nullptr);
    SimulationOptions o;
    o.initial = {{"theta", 0.0}, {"phi_dot", 0.0}};
    double t = -1;
    const std::string what = failure_of(model, o, &t);
    EXPECT_NE(what.find("the mass matrix is singular"), std::string::npos) << what;
    EXPECT_EQ(t, 0.0) << what;
  }
  for (auto method : {mbsgen::IntegrationMethod::adams, mbsgen::IntegrationMethod::radau, mbsgen::IntegrationMethod::radau9}) {
    // more steps between two samples than allowed: a fast pendulum sampled once
    GeneratedModel model(simple_pendulum::kernels());
    model.set("g", 1e7);
    SimulationOptions o;
    o.method = method;
    o.duration = 1000;
    o.step = 1000;
    o.initial = {{"phi", 1.0}};
    double t = -1;
    const std::string what = failure_of(model, o, &t);
    EXPECT_NE(what.find("internal steps between two samples"), std::string::npos) << method_name(method) << ": " << what;
    EXPECT_GT(t, 0.0) << what;
  }
  GeneratedModel pendulum(simple_pendulum::kernels());
  {  // rates so high that the velocity-squared terms overflow: non-finite kernel values at t = 0
    GeneratedModel model(double_pendulum::kernels());
    SimulationOptions o;
    o.initial = {{"phi1_dot", 1e160}};
    double t = -1;
    const std::string what = failure_of(model, o, &t);
    EXPECT_NE(what.find("non-finite"), std::string::npos) << what;
    EXPECT_EQ(t, 0.0) << what;
  }
  {  // gravity of 1e300 m/s²: no step-size control
    GeneratedModel model(simple_pendulum::kernels());
    model.set("g", 1e300);
    SimulationOptions o;
    o.initial = {{"phi", 1.0}};
    double t = -1;
    const std::string what = failure_of(model, o, &t);
    EXPECT_NE(what.find("the integrator lost control of its step size"), std::string::npos) << what;
  }
  SimulationOptions o;
  o.initial = {{"psi", 1.0}};
  EXPECT_THROW(run(pendulum, o), mbsgen::NameError);
  o.initial = {{"phi", std::nan("")}};
  EXPECT_THROW(run(pendulum, o), mbsgen::NonFiniteError);
  o.initial.clear();
  o.duration = -1;
  EXPECT_THROW(run(pendulum, o), mbsgen::Error);
  o.duration = 1;
  o.rtol = 0;
  EXPECT_THROW(run(pendulum, o), mbsgen::Error);
  GeneratedModel dp(double_pendulum::kernels());
  SimulationOptions two;
  two.inputs = {InputSignal(), InputSignal()};  // the double pendulum has one input
  EXPECT_THROW(run(dp, two), mbsgen::DimensionError);
}

// Input signals against their definitions.
TEST(Simulation, InputSignals) {
  EXPECT_EQ(InputSignal()(3.0), 0.0);
  EXPECT_EQ(InputSignal::constant(2.5)(7.0), 2.5);
  EXPECT_DOUBLE_EQ(InputSignal::sine(2, 5, kPi / 2, 1)(0.1), 1 + 2 * std::sin(kPi + kPi / 2));
  const InputSignal step = InputSignal::step(3, 0.5, 1);
  EXPECT_EQ(step(0.5), 1.0);
  EXPECT_EQ(step(0.5000001), 4.0);
  EXPECT_EQ(step.breakpoints(), std::vector<double>{0.5});
  // chirp: phase 2π (f0 t + (f1 − f0) t²/(2T)), instantaneous frequency f0 + (f1 − f0) t/T
  const InputSignal chirp = InputSignal::chirp(1, 10, 30, 2);
  EXPECT_NEAR(chirp(0.75), std::sin(2 * kPi * (10 * 0.75 + 20 * 0.75 * 0.75 / 4)), 1e-12);
  EXPECT_NEAR(chirp(2.5), std::sin(2 * kPi * (10 * 2 + 20 * 2.0 * 2.0 / 4 + 30 * 0.5)), 1e-12);
  const InputSignal table = InputSignal::table({0, 1, 3}, {0, 2, -2});
  EXPECT_EQ(table(-1), 0.0);
  EXPECT_EQ(table(0.5), 1.0);
  EXPECT_EQ(table(2), 0.0);
  EXPECT_EQ(table(9), -2.0);
  EXPECT_THROW(InputSignal::table({0, 0}, {1, 2}), mbsgen::Error);
  EXPECT_THROW(InputSignal::table({0}, {1, 2}), mbsgen::DimensionError);
  EXPECT_DOUBLE_EQ(InputSignal::parse("sine:2,5,90,1", 1)(0.1), 1 + 2 * std::sin(kPi + kPi / 2));
  EXPECT_EQ(InputSignal::parse("step:3,0.5,1", 1)(0.6), 4.0);
  EXPECT_EQ(InputSignal::parse("-1.5", 1)(0.6), -1.5);
  EXPECT_NEAR(InputSignal::parse("chirp:1,10,30", 2)(0.75), chirp(0.75), 1e-15);
  for (const char* bad : {"sine:1", "sine:1,2,3,4,5", "step:", "nope:1", "sine:1,x", "1e400", "table:/nonexistent.csv", ""})
    EXPECT_THROW(InputSignal::parse(bad, 1), mbsgen::NameError) << bad;
}


// The fundamental of output `output` under A sin Ωt on `input` (sine_response: from the linear
// steady state, fitted over the last `fit` of `periods` periods), divided by the frequency
// response's A·G (FrequencyResponse, the runtime's method), minus 1.
std::complex<double> sine_against_frf(const GeneratedModel& model, Eigen::Index input, Eigen::Index output, double hz,
                                      double A, int periods, int fit, double rtol,
                                      mbsgen::IntegrationMethod method = mbsgen::IntegrationMethod::bdf) {
  const mbsgen::OperatingPoint op = model.operating_point();
  mbsgen::SineResponseOptions o;
  o.method = method;
  o.periods = periods;
  o.fit_periods = fit;
  o.rtol = rtol;
  const mbsgen::SineResponse s = mbsgen::sine_response(model, op, input, hz, A, o);
  const mbsgen::LinearModel lin = model.linear_model(op);
  mbsgen::FrequencyResponse frf(lin);
  frf.compute(Eigen::VectorXd::Constant(1, 2 * kPi * hz), input, {output});
  return s.fundamental[output] / (A * frf.response()(0, 0)) - 1.0;
}

struct SineCase {
  const mbsgen::ModelKernels* k;
  const char* input;
  const char* output;
  double hz, amplitude;
  int periods, fit;
  double rtol;
  double small_bound;  // the largest relative difference allowed at amplitude / 10
  bool linear;         // the equations are linear: the difference is the integration's
};

// Small sines on the damped textbook models and the middle ear: the steady-state amplitude and
// phase of the nonlinear simulation agree with the frequency response, and the difference is the
// nonlinearity's, so it falls with the amplitude, at least in proportion (by 6 or more from A to
// A/10: the middle ear's quadratic terms give slope 1 at 140–160 dB SPL, the pendulum chain's
// symmetric ones slope 2). The linear rotor stays at the integration's floor (1e-8 at rtol
// 1e-11) at every amplitude. Measured figures: docs/simulation.md.
TEST(Simulation, SmallSinesAgreeWithTheFrequencyResponse) {
  const std::vector<SineCase> cases = {
      {&jeffcott_rotor::kernels(), "F", "deflection_x", 30, 100, 40, 10, 1e-11, 1e-8, true},
      {&chain3_sympy::kernels(), "F", "end_x", 0.5, 1, 20, 10, 1e-11, 1e-4, false},
      {&middle_ear::kernels(), "P", "v_stapes", 1000, 2000, 10, 5, 1e-9, 1e-5, false},
      {&middle_ear::kernels(), "P", "v_stapes", 4000, 2000, 20, 10, 1e-9, 1e-5, false},
  };
  for (const SineCase& c : cases) {
    GeneratedModel model(*c.k);
    const Eigen::Index input = model.input_index(c.input), output = model.output_index(c.output);
    const double large = std::abs(sine_against_frf(model, input, output, c.hz, c.amplitude, c.periods, c.fit, c.rtol));
    const double small =
        std::abs(sine_against_frf(model, input, output, c.hz, c.amplitude / 10, c.periods, c.fit, c.rtol));
    std::ostringstream text;
    text << c.k->model << " at " << c.hz << " Hz: " << large << " at amplitude " << c.amplitude << ", " << small
         << " at a tenth";
    const std::string what = text.str();
    EXPECT_LT(small, c.small_bound) << what;
    if (c.linear)
      EXPECT_LT(large, c.small_bound) << what;
    else
      EXPECT_LT(small, large / 6) << what;
  }
}


// A table input from rest: nothing happens until a triangular pulse of 0.2 ms at t = 1 s. An
// integrator left alone grows its steps over the quiet second to far more than 0.2 ms and sees
// u = 0 on both sides of the pulse; the table's points are stops. Exact response:
// U/w (ramp(t − t1) − 2 ramp(t − t1 − w) + ramp(t − t1 − 2w)).
TEST(Simulation, TableInputIsFollowedFromRest) {
  GeneratedModel model(jeffcott_rotor::kernels());
  const FirstOrder exact_model(model.linear_model());
  const double U = 2.0, t1 = 1.0, w = 1e-4;
  auto exact = [&](double t) {
    return Eigen::VectorXd(U / w *
                           (exact_model.ramp(t - t1) - 2 * exact_model.ramp(t - t1 - w) + exact_model.ramp(t - t1 - 2 * w)));
  };
  const std::string path = ::testing::TempDir() + "mbsgen_pulse.csv";
  {
    std::ofstream csv(path);
    csv << "\xEF\xBB\xBFtime,F\r\n# a comment\r\n0,0\r\n" << t1 << ",0\r\n" << t1 + w << "," << U << "\r\n"
        << t1 + 2 * w << ",0\r\n3,0\r\n";
  }
  for (auto method : {mbsgen::IntegrationMethod::bdf, mbsgen::IntegrationMethod::adams, mbsgen::IntegrationMethod::radau}) {
    SimulationOptions o;
    o.method = method;
    o.duration = 1.5;
    o.step = 0.5;
    o.rtol = 1e-8;
    o.atol = 1e-15;
    o.inputs = {InputSignal::parse("table:" + path, o.duration)};
    const SimulationResult r = run(model, o);
    EXPECT_EQ(r.restarts, 0);
    double worst = 0, size = 0;
    for (Eigen::Index k = 0; k < r.t.size(); ++k) {
      const Eigen::VectorXd x = exact(r.t[k]);
      worst = std::max(worst, (r.y.col(k) - x.head(2)).cwiseAbs().maxCoeff());
      size = std::max(size, x.head(2).cwiseAbs().maxCoeff());
    }
    EXPECT_GT(size, 1e-9);
    EXPECT_LT(worst, 1e-5 * size) << method_name(method);
  }
  std::remove(path.c_str());
}


// The four-bar's energy, written out by hand from its geometry (models/linkages/four_bar.yaml):
// crank O–B (l1, angle th1), coupler B–C (l2), rocker D–C (l3) with D = (a, 0); C is where the
// circles about B (l2) and D (l3) meet, on the branch nearest `C` (updated: the caller follows the
// motion). The coupler's and rocker's angular rates from C's velocity, B' + l2 φ2' e⊥(φ2) =
// l3 φ3' e⊥(φ3); gravity −y on the bars' centres and the spring from the anchor (a/2, 0.5) to the
// coupler's middle.
struct FourBarBranch {
  double cx = 0, cy = 0;
};
double four_bar_energy(const GeneratedModel& model, double th1, double th1_dot, FourBarBranch& branch) {
  const std::vector<double>& p = model.parameters();  // g, a, l1, l2, l3, m, k, L0
  const double g = p[0], a = p[1], l1 = p[2], l2 = p[3], l3 = p[4], m = p[5], k = p[6], L0 = p[7];
  const double bx = l1 * std::cos(th1), by = l1 * std::sin(th1);
  const double dx = a - bx, dy = -by, d = std::hypot(dx, dy);
  const double along = (d * d + l2 * l2 - l3 * l3) / (2 * d), across = std::sqrt(l2 * l2 - along * along);
  const double mx = bx + along * dx / d, my = by + along * dy / d;
  const double c1x = mx - across * dy / d, c1y = my + across * dx / d;
  const double c2x = mx + across * dy / d, c2y = my - across * dx / d;
  const bool first = std::hypot(c1x - branch.cx, c1y - branch.cy) < std::hypot(c2x - branch.cx, c2y - branch.cy);
  branch = first ? FourBarBranch{c1x, c1y} : FourBarBranch{c2x, c2y};
  const double phi2 = std::atan2(branch.cy - by, branch.cx - bx), phi3 = std::atan2(branch.cy, branch.cx - a);
  // l2 φ2' e⊥(φ2) − l3 φ3' e⊥(φ3) = −B', e⊥(φ) = (−sin φ, cos φ): Cramer's rule.
  const double vbx = -l1 * std::sin(th1) * th1_dot, vby = l1 * std::cos(th1) * th1_dot;
  const double a11 = -l2 * std::sin(phi2), a21 = l2 * std::cos(phi2), a12 = l3 * std::sin(phi3), a22 = -l3 * std::cos(phi3);
  const double det = a11 * a22 - a12 * a21;
  const double w2 = (-vbx * a22 + vby * a12) / det, w3 = (-vby * a11 + vbx * a21) / det;
  const double vgx = vbx - 0.5 * l2 * std::sin(phi2) * w2, vgy = vby + 0.5 * l2 * std::cos(phi2) * w2;
  const double kinetic = 0.5 * (m * l1 * l1 / 3) * th1_dot * th1_dot + 0.5 * m * (vgx * vgx + vgy * vgy) +
                         0.5 * (m * l2 * l2 / 12) * w2 * w2 + 0.5 * (m * l3 * l3 / 3) * w3 * w3;
  const double gx = bx + 0.5 * l2 * std::cos(phi2), gy = by + 0.5 * l2 * std::sin(phi2);
  const double heights = 0.5 * l1 * std::sin(th1) + gy + 0.5 * l3 * std::sin(phi3);
  const double stretch = std::hypot(gx - a / 2, gy - 0.5) - L0;
  return kinetic + m * g * heights + 0.5 * k * stretch * stretch;
}

// The largest change of the four-bar's energy over a run, relative to m g a, with the branch
// followed from the operating point's configuration (th1 stepped there by 1 mrad).
double four_bar_energy_drift(const GeneratedModel& model, const SimulationResult& r) {
  FourBarBranch branch;
  const std::vector<double>& p = model.parameters();
  // The operating point's C (tests/reference: th1 = 1.2563..., C above the ground).
  const double th0 = 1.256311620944826482631333;
  branch = {p[1], p[4]};  // a start above D: the upper branch
  for (double th = th0, to = r.y(0, 0), h = (to > th0 ? 1e-3 : -1e-3); (to - th) * h > 0; th += h)
    four_bar_energy(model, th, 0.0, branch);
  const double e0 = four_bar_energy(model, r.y(0, 0), r.yd(0, 0), branch);
  double worst = 0;
  for (Eigen::Index j = 0; j < r.t.size(); ++j)
    worst = std::max(worst, std::abs(four_bar_energy(model, r.y(0, j), r.yd(0, j), branch) - e0));
  return worst / (p[5] * p[0] * p[1]);  // m g a
}

// The four-bar (closed loop; the state holds the crank angle, the kernels close the loop by
// Newton's method at every evaluation). Small swings about the equilibrium have the period 2π/ω
// with ω² = 115.2470787951297394601 1/s² (tests/reference/four_bar_linkage_reference.py, mpmath
// at 50 digits, the loop's geometric stiffness included): at 0.1 mrad, so that the amplitude's
// own shift of the period (4.3e-6 at 1 mrad, falling with A²) stays below the bound of 1e-6. Large swings (0.5 rad) over 100
// periods: the constraints stay closed to the closure's own tolerance (1e-13 of each equation's
// scale, lengths below 0.4 m: 1e-12 m), and the energy stays within 1e-8 of m g a (conservative;
// Adams at rtol 1e-10).
TEST(Simulation, FourBarSwingsWithItsLoopClosed) {
  GeneratedModel model(four_bar::kernels());
  ASSERT_EQ(model.kernels().n_constraints, 2);
  const mbsgen::OperatingPoint op = model.operating_point();
  const double omega = std::sqrt(115.2470787951297394601), T = 2 * kPi / omega;
  // Radau too, on difference-quotient Jacobians (the loops' kernels have no dynamics_jacobian).
  for (auto method : {mbsgen::IntegrationMethod::adams, mbsgen::IntegrationMethod::radau, mbsgen::IntegrationMethod::radau9}) {
    SimulationOptions o;
    o.method = method;
    o.duration = 10.2 * T;
    o.step = T / 200;
    o.rtol = 1e-12;
    o.atol = 1e-16;
    o.initial = {{"th1", op.y0[0] + 1e-4}};
    SimulationResult r = run(model, o);
    EXPECT_FALSE(r.analytic_jacobian);
    EXPECT_GT(r.constraint_drift, 0.0);
    EXPECT_LT(r.constraint_drift, 1e-12) << method_name(method);
    r.y.array() -= op.y0[0];
    const std::vector<double> c = zero_crossings(r, 0);
    ASSERT_EQ(c.size(), 20u);
    const double measured = 2 * (c.back() - c.front()) / static_cast<double>(c.size() - 1);
    EXPECT_NEAR(measured / T, 1.0, 1e-6) << method_name(method) << ": period " << measured << " s against " << T << " s";
  }
  SimulationOptions o;
  o.method = mbsgen::IntegrationMethod::adams;
  o.duration = 100 * T;
  o.step = T / 20;
  // rtol 1e-11: the energy drifts 4.0e-10 of m g a (at 1e-10 it was 9.0e-9, under 10% below the
  // bound, and one change in the order of rounding took it to 1.1e-8).
  o.rtol = 1e-11;
  o.atol = 1e-12;
  o.initial = {{"th1", op.y0[0] + 0.5}};
  const SimulationResult r = run(model, o);
  EXPECT_GT(r.constraint_drift, 0.0);  // computed
  EXPECT_LT(r.constraint_drift, 1e-12);
  EXPECT_LT(four_bar_energy_drift(model, r), 1e-8) << r.steps << " steps";
  EXPECT_GT(r.z.rows(), 0);  // the joint loads through outputs_general
}

// Outputs on ÿ and u (the four-bar's joint loads) at every sample are those of the inputs the
// sample stores, also at an input step that falls on a sample (stored: the value before the
// jump, whichever side of the restart the sample is taken on): recomputed here from the kernels,
// ÿ = −M⁻¹(k − q) at the stored state and input, to 1e-9 of the largest load (the same state;
// only the solve's rounding differs). Before the fix, a sample taken after the restart had ÿ of
// the new input with u of the old one, off by the step's whole effect.
TEST(Simulation, OutputsAtAStepUseTheStoredInputs) {
  GeneratedModel model(four_bar::kernels());
  const mbsgen::ModelKernels& k = model.kernels();
  const std::vector<double>& p = model.parameters();
  // Loose tolerances and dense samples: an integrator step that ends at the step input then
  // also passes the sample before it, which is interpolated before the restart.
  for (double step : {0.1, 0.02, 0.01, 0.005}) {
    SimulationOptions o;
    o.duration = 1;
    o.step = step;
    o.rtol = 1e-5;
    o.atol = 1e-7;
    o.inputs = {InputSignal::step(0.05, 0.5)};
    const SimulationResult r = run(model, o);
    ASSERT_EQ(r.restarts, 1);
    ASSERT_GT(r.z.rows(), 0);
    double worst = 0, largest = 0;
    for (Eigen::Index j = 0; j < r.t.size(); ++j) {
      double y = r.y(0, j), yd = r.yd(0, j), u = r.u(0, j), M = 0, res = 0;
      ASSERT_EQ(k.dynamics(&y, &yd, &u, p.data(), &M, &res), 0);
      double ydd = -res / M;
      Eigen::VectorXd z(k.n_outputs);
      ASSERT_EQ(k.outputs_general(&y, &yd, &ydd, &u, p.data(), z.data()), 0);
      worst = std::max(worst, (z - r.z.col(j)).cwiseAbs().maxCoeff());
      largest = std::max(largest, z.cwiseAbs().maxCoeff());
      if (std::abs(r.t[j] - 0.5) < 1e-12) {
        EXPECT_EQ(u, 0.0) << "the sample at the step stores the value before it";
      }
    }
    EXPECT_LE(worst, 1e-9 * largest) << "output step " << step;
  }
}

// Absolute tolerances per state (CVODE's vector tolerances): the same value for every state by
// name is the scalar run, bit for bit; another value for one state reaches the integrator (the
// run changes); names and values are checked.
TEST(Simulation, AbsoluteToleranceOfEachState) {
  GeneratedModel model(jeffcott_rotor::kernels());
  SimulationOptions o;
  o.duration = 0.5;
  o.step = 1e-3;
  o.rtol = 1e-9;
  o.atol = 1e-16;
  o.inputs = {InputSignal::step(2.0, 0.013)};
  const SimulationResult scalar = run(model, o);
  const std::vector<std::string> names = mbsgen::name_list(model.kernels().coordinate_names, 2);
  for (const auto& c : names) o.atol_of.insert(o.atol_of.end(), {{c, 1e-16}, {c + "_dot", 1e-16}});
  const SimulationResult same = run(model, o);
  EXPECT_EQ((same.y - scalar.y).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(same.steps, scalar.steps);
  o.atol_of = {{"psi", 1e-16}};
  EXPECT_THROW(run(model, o), mbsgen::NameError);
  o.atol_of = {{names[0], 0.0}};
  EXPECT_THROW(run(model, o), mbsgen::Error);
  o.atol_of = {{names[0], std::nan("")}};
  EXPECT_THROW(run(model, o), mbsgen::Error);
  o.atol_of = {{names[0], 5e-9}};  // 1e-3 of its 5e-6 m response, against 1e-16
  const SimulationResult loose = run(model, o);
  EXPECT_GT((loose.y - scalar.y).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_NE(loose.steps, scalar.steps);
}

// The crank of this crank-rocker (Grashof: l1 + a <= l2 + l3) turns fully. The loops are closed
// from the last step's configuration (assemble_from), so the motion keeps its branch over many
// turns; started half a turn from the operating point, the closure reaches the start by
// continuation on the operating point's branch. The energy, written out by hand on that branch,
// is kept (a branch switch would change the motion and break it), and Φ
// stays at the closure's tolerance; the drift falls with the tolerance (to 1e-8 of m g a at rtol
// 1e-12, Adams, 6 turns in 1 s).
TEST(Simulation, FourBarCrankTurnsFully) {
  GeneratedModel model(four_bar::kernels());
  const mbsgen::OperatingPoint op = model.operating_point();
  SimulationOptions o;
  o.method = mbsgen::IntegrationMethod::adams;
  o.duration = 1;
  o.step = 1e-3;  // the hand-written branch follows C from sample to sample (0.04 rad apart)
  for (double start : {0.0, kPi}) {
    o.initial = {{"th1", op.y0[0] + start}, {"th1_dot", 40.0}};
    double drift[3] = {};
    for (int tight = 0; tight < 3; ++tight) {
      o.rtol = std::pow(10.0, -10 - tight);
      o.atol = o.rtol * 1e-2;
      const SimulationResult r = run(model, o);
      const Eigen::Index last = r.t.size() - 1;
      EXPECT_GT(r.y(0, last) - r.y(0, 0), 4 * 2 * kPi) << "start " << start;  // four turns at least
      for (Eigen::Index j = 1; j <= last; ++j) ASSERT_GT(r.y(0, j), r.y(0, j - 1)) << "the crank turns on";
      EXPECT_LT(r.constraint_drift, 1e-12) << "start " << start;
      drift[tight] = four_bar_energy_drift(model, r);
    }
    // Measured: 3.5e-8, 9.2e-9, 3.8e-10 from the operating point; 1.9e-8, 6.0e-9, 9.5e-10 from
    // half a turn. A wrong branch, or loops closed off the motion, would not fall with rtol.
    EXPECT_LT(drift[2], 1e-8) << "start " << start;
    EXPECT_LT(drift[2], drift[0] / 10) << "start " << start << ": " << drift[0] << " at rtol 1e-10";
  }
}

// The middle ear's steady state under a small tone against its frequency response (as
// SmallSinesAgreeWithTheFrequencyResponse for BDF): within 1e-5 at 200 Pa, 1 kHz, and the
// difference falls with the amplitude (it is the model's nonlinearity, not the integrator's).
TEST(Simulation, RadauMiddleEarSineAgreesWithTheFrequencyResponse) {
  GeneratedModel model(middle_ear::kernels());
  const Eigen::Index input = model.input_index("P"), output = model.output_index("v_stapes");
  for (auto radau : {mbsgen::IntegrationMethod::radau, mbsgen::IntegrationMethod::radau9}) {
    const double large = std::abs(sine_against_frf(model, input, output, 1000, 2000, 10, 5, 1e-9, radau));
    const double small = std::abs(sine_against_frf(model, input, output, 1000, 200, 10, 5, 1e-9, radau));
    EXPECT_LT(small, 1e-5) << method_name(radau) << ": " << large << " at 2000 Pa, " << small << " at 200 Pa";
    EXPECT_LT(small, large / 6) << method_name(radau) << ": " << large << " at 2000 Pa, " << small << " at 200 Pa";
  }
}

// Radau without a first step: gravity of 1e300 m/s² (CVODE's case is in
// FailuresAreReportedWithTheTime); and an rtol it cannot work to.
TEST(Simulation, RadauWithoutAFirstStepSaysSo) {
  GeneratedModel model(simple_pendulum::kernels());
  model.set("g", 1e300);
  SimulationOptions o;
  o.method = mbsgen::IntegrationMethod::radau;
  o.initial = {{"phi", 1.0}};
  double t = -1;
  const std::string what = failure_of(model, o, &t);
  EXPECT_NE(what.find("cannot start at t = 0 s: no first step fits"), std::string::npos) << what;
  EXPECT_EQ(t, 0.0) << what;
  // Below 100 ε the Newton tolerance, 10 ε / rtol, would exceed the tolerance itself: refused
  // before the run (with g back to a value that would run).
  model.set("g", 9.81);
  o.rtol = 1e-15;
  for (auto method : {mbsgen::IntegrationMethod::radau, mbsgen::IntegrationMethod::radau9}) {
    o.method = method;
    try {
      run(model, o);
      ADD_FAILURE() << method_name(method) << " ran at rtol 1e-15";
    } catch (const mbsgen::Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(std::string("--method ") + method_name(method) + " needs rtol of at least"), std::string::npos)
          << message;
    }
  }
}

// Radau9 is the five-stage method: on the middle ear under a tone (1 Pa, 1 kHz, 20 ms, rtol 1e-4)
// it takes fewer than half the order-5 method's steps (121 against 426) with about 11 evaluations
// a step (five per Newton iteration, against 6.5 for three stages), for an error no larger (both
// about 1e-5, against a run of the order-5 method at 1e-8).
TEST(Simulation, Radau9TakesFewerLongerStepsOnTheMiddleEar) {
  GeneratedModel model(middle_ear::kernels());
  SimulationOptions o;
  o.duration = 0.02;
  o.step = 1e-4;
  o.inputs.assign(static_cast<std::size_t>(model.kernels().n_inputs), InputSignal());
  o.inputs[static_cast<std::size_t>(model.input_index("P"))] = InputSignal::sine(1.0, 1000);
  o.outputs = false;
  o.method = mbsgen::IntegrationMethod::radau;
  o.rtol = 1e-8;  // 1.4e-9 off a run at 1e-11 (docs/accuracy-vs-time.md, section 6)
  o.atol = 1e-17;
  const SimulationResult reference = run(model, o);
  o.rtol = 1e-4;
  o.atol = 1e-13;
  const SimulationResult five = run(model, o);
  o.method = mbsgen::IntegrationMethod::radau9;
  const SimulationResult nine = run(model, o);
  auto error = [&reference](const SimulationResult& r) {
    return (r.y - reference.y).cwiseAbs().maxCoeff() / reference.y.cwiseAbs().maxCoeff();
  };
  EXPECT_LT(2 * nine.steps, five.steps) << nine.steps << " and " << five.steps << " steps";
  EXPECT_GT(nine.rhs_evaluations, 8 * nine.steps) << nine.rhs_evaluations << " evaluations";
  EXPECT_LT(five.rhs_evaluations, 8 * five.steps) << five.rhs_evaluations << " evaluations";
  EXPECT_LE(error(nine), error(five)) << error(nine) << " against " << error(five);
}

// A scene that asks for simulate (models/textbook/rotor_disk.yaml, `motion`): linearized at
// standstill, it still keeps the velocity-quadratic inertia terms (a simulation leaves rest) and
// has the kernels of a time step without --dynamics, but not `linear`. Released at α = A with
// γ' = Ω, the tilt whirls as z = α + iβ = A (−ω2 e^{iω1 t} + ω1 e^{iω2 t})/(ω1 − ω2), the roots
// of I_d ω² − I_p Ω ω − k_t = 0 (161.80 and −61.80 rad/s); without the gyroscopic terms α would
// be A cos(100 t). Bound: 1e-7 A, the integration error at rtol 1e-11 over 5 slow periods (the
// nonlinearity's part is O(A²) = 1e-12 of A). The full model (difference-quotient Jacobians)
// gives the same motion to the same bound.
TEST(Simulation, SceneKeepsWhatMotionNeeds) {
  GeneratedModel scene(rotor_disk_motion::kernels());
  EXPECT_STREQ(scene.kernels().scene, "motion");
  EXPECT_NE(scene.kernels().dynamics_jacobian, nullptr);
  EXPECT_EQ(scene.kernels().linear, nullptr);
  GeneratedModel full(rotor_disk::kernels());
  const std::vector<double>& p = scene.parameters();  // m, I_d, I_p, k_t, Omega
  const double Id = p[1], Ip = p[2], kt = p[3], Omega = p[4], A = 1e-6;
  const double root = std::sqrt(Ip * Ip * Omega * Omega + 4 * Id * kt);
  const double w1 = (Ip * Omega + root) / (2 * Id), w2 = (Ip * Omega - root) / (2 * Id);
  SimulationOptions o;
  o.duration = 0.5;
  o.step = 1e-3;
  o.rtol = 1e-11;
  o.atol = 1e-19;
  o.initial = {{"alpha", A}, {"gamma_dot", Omega}};
  const SimulationResult r = run(scene, o), rf = run(full, o);
  ASSERT_TRUE(r.analytic_jacobian);
  double worst = 0, worst_full = 0;
  for (Eigen::Index j = 0; j < r.t.size(); ++j) {
    const std::complex<double> i(0, 1), t = r.t[j];
    const std::complex<double> z = A * (-w2 * std::exp(i * w1 * t) + w1 * std::exp(i * w2 * t)) / (w1 - w2);
    worst = std::max({worst, std::abs(r.y(0, j) - z.real()), std::abs(r.y(1, j) - z.imag())});
    worst_full = std::max(worst_full, (r.y.col(j).head(2) - rf.y.col(j).head(2)).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-7 * A);
  EXPECT_LT(worst_full, 1e-7 * A);
}

// Outputs at any state (issue 39 §4; before, only a one-step simulation gave them). The simple
// pendulum's bob at x = l sin φ for any φ and rates; a four-bar's joint loads at its operating
// point with no acceleration and no input equal those `static` prints (the same loads by another
// kernel).
TEST(OutputsAt, AnyStateMatchesClosedFormsAndTheStaticLoads) {
  GeneratedModel pendulum(simple_pendulum::kernels());
  pendulum.set("l", 0.7);
  for (double phi : {-2.0, 0.0, 0.5, 3.0}) {
    const Eigen::VectorXd y = Eigen::VectorXd::Constant(1, phi), yd = Eigen::VectorXd::Constant(1, 4.0);
    const Eigen::VectorXd z = pendulum.outputs_at(y, yd, Eigen::VectorXd::Constant(1, -1.0), Eigen::VectorXd());
    ASSERT_EQ(z.size(), 2);
    EXPECT_EQ(z[0], phi);                                     // angle: the coordinate itself
    EXPECT_NEAR(z[1], 0.7 * std::sin(phi), 2e-16 * 0.7);      // bob_x, one rounding of sin and a product
  }
  EXPECT_THROW(pendulum.outputs_at(Eigen::VectorXd::Zero(2), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1),
                                   Eigen::VectorXd()),
               mbsgen::DimensionError);
  EXPECT_THROW(pendulum.outputs_at(Eigen::VectorXd::Constant(1, NAN), Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1),
                                   Eigen::VectorXd()),
               mbsgen::NonFiniteError);

  GeneratedModel bar(four_bar::kernels());
  const mbsgen::OperatingPoint op = bar.operating_point();
  const Eigen::Index f = bar.size();
  const Eigen::VectorXd at_rest = bar.outputs_at(op.y0, op.yd0, Eigen::VectorXd::Zero(f), Eigen::VectorXd::Zero(bar.kernels().n_inputs));
  const Eigen::VectorXd loads = bar.outputs(op);
  ASSERT_EQ(at_rest.size(), loads.size());
  for (Eigen::Index i = 0; i < loads.size(); ++i)
    EXPECT_NEAR(at_rest[i], loads[i], 1e-13 * (1 + std::abs(loads[i]))) << i;  // two kernels' rounding
}

}  // namespace
