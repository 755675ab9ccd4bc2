// Time simulation of the nonlinear equations through the generated kernels (issue 18 §2): the
// simple pendulum's period at large amplitude against the closed form with the complete elliptic
// integral, the conservative double pendulum's energy over 100 periods, small sines against the
// frequency response, and the failures the integrator must report.
#include "chain3_sympy_model.hpp"
#include "double_pendulum_model.hpp"
#include "jeffcott_rotor_model.hpp"
#include "middle_ear_model.hpp"
#include "simple_pendulum_model.hpp"

#include "mbsgen/runtime/frequency_response.hpp"
#include "mbsgen/runtime/simulation.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
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

// The period of the simple pendulum at amplitude θ0: T = 4 √(l/g) K(sin(θ0/2)) (the complete
// elliptic integral of the first kind of modulus k; e.g. Landau & Lifshitz, Mechanics, §11,
// problem 1), against the zero crossings of φ over ten periods at rtol 1e-12: to 1e-9.
TEST(Simulation, SimplePendulumPeriodAtLargeAmplitudeMatchesTheEllipticIntegral) {
  GeneratedModel model(simple_pendulum::kernels());
  const double l = 1.0, g = 9.81;
  for (double theta0 : {0.1, 1.0, 2.5, 3.0}) {
    const double T = 4 * std::sqrt(l / g) * std::comp_ellint_1(std::sin(theta0 / 2));
    SimulationOptions o;
    o.duration = 10.2 * T;
    o.step = 1e-3;
    o.rtol = 1e-12;
    o.atol = 1e-14;
    o.initial = {{"phi", theta0}};
    const SimulationResult r = run(model, o);
    EXPECT_TRUE(r.analytic_jacobian);
    const std::vector<double> c = zero_crossings(r, 0);  // at T/4 + j T/2
    ASSERT_EQ(c.size(), 20u) << "theta0 " << theta0;
    const double measured = 2 * (c.back() - c.front()) / static_cast<double>(c.size() - 1);
    EXPECT_NEAR(measured / T, 1.0, 1e-9) << "theta0 " << theta0 << ": T " << T << " s, measured " << measured;
    EXPECT_NEAR(c.front() / (T / 4), 1.0, 1e-9) << "theta0 " << theta0;
  }
}

// The total energy of the double pendulum of point masses (closed-forms.md §2 model: m1 = m2 =
// 1 kg, l1 = l2 = 1 m), written out here from the coordinates, not from the kernels.
double double_pendulum_energy(double p1, double p2, double w1, double w2) {
  const double m1 = 1, m2 = 1, l1 = 1, l2 = 1, g = 9.81;
  const double kinetic = 0.5 * m1 * l1 * l1 * w1 * w1 +
                         0.5 * m2 * (l1 * l1 * w1 * w1 + l2 * l2 * w2 * w2 + 2 * l1 * l2 * std::cos(p1 - p2) * w1 * w2);
  const double potential = -m1 * g * l1 * std::cos(p1) - m2 * g * (l1 * std::cos(p1) + l2 * std::cos(p2));
  return kinetic + potential;
}

// Conservative: the energy stays within 1e-8 of its initial value (relative to the energy
// scale m g l) over 100 periods of the slower mode at rtol 1e-10, at moderate and at large
// amplitude (chaotic motion).
TEST(Simulation, DoublePendulumConservesEnergyOver100Periods) {
  GeneratedModel model(double_pendulum::kernels());
  const double slow = 2 * kPi / std::sqrt((2 - std::sqrt(2.0)) * 9.81);  // closed-forms.md §2
  for (const auto& [p1, p2] : std::vector<std::pair<double, double>>{{0.3, -0.2}, {1.5, 2.0}}) {
    SimulationOptions o;
    o.duration = 100 * slow;
    o.step = slow / 20;
    o.rtol = 1e-10;
    o.atol = 1e-12;
    o.initial = {{"phi1", p1}, {"phi2", p2}};
    const SimulationResult r = run(model, o);
    const double e0 = double_pendulum_energy(p1, p2, 0, 0), scale = 9.81;
    double worst = 0;
    for (Eigen::Index k = 0; k < r.t.size(); ++k)
      worst = std::max(worst, std::abs(double_pendulum_energy(r.y(0, k), r.y(1, k), r.yd(0, k), r.yd(1, k)) - e0));
    EXPECT_LT(worst / scale, 1e-8) << "from phi1 " << p1 << ", phi2 " << p2 << " (" << r.steps << " steps)";
  }
}

}  // namespace
