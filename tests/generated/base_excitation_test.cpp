// Prescribed motion and base excitation (issue 19) through the generated kernels: closed forms
// of the base-excited oscillator and the shaken pendulum, the equivalence of a shaken pivot and
// its inertial force, and invariants of a support's rigid parts.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <sstream>
#include <string>
#include <vector>

#include "base_excited_oscillator_model.hpp"
#include "mbsgen/runtime/cli/solver_cli.hpp"
#include "mbsgen/runtime/model/generated_model.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/time/simulation.hpp"
#include "middle_ear.hpp"
#include "middle_ear_model.hpp"
#include "shaken_pendulum_model.hpp"

namespace {

using cd = std::complex<double>;
using mbsgen::FrfMethod;

const std::vector<FrfMethod> kMethods = {FrfMethod::direct, FrfMethod::banded, FrfMethod::hessenberg,
                                         FrfMethod::modal, FrfMethod::real};

Eigen::Index index_of(const std::vector<std::string>& names, const std::string& name) {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<Eigen::Index>(i);
  ADD_FAILURE() << "no " << name;
  return 0;
}

// 0.05 to 20 times the natural frequency, through the resonance.
Eigen::VectorXd frequencies(double wn) {
  Eigen::VectorXd w(61);
  for (Eigen::Index k = 0; k < w.size(); ++k) w[k] = wn * std::pow(10.0, -1.3 + 2.6 * static_cast<double>(k) / 60.0);
  return w;
}

// The response of one output to one input at the frequencies w, by one method.
Eigen::VectorXcd frf(const mbsgen::LinearModel& lin, const Eigen::VectorXd& w, const std::string& input,
                     const std::string& output, FrfMethod method) {
  mbsgen::FrfOptions o;
  o.method = method;
  mbsgen::FrequencyResponse r(lin, o);
  r.compute(w, index_of(lin.input_names(), input), {index_of(lin.output_names(), output)});
  return r.response().row(0).transpose();
}

// The relative error of a against the closed form b, the largest over the frequencies.
double relative_error(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  double e = 0;
  for (Eigen::Index k = 0; k < a.size(); ++k) e = std::max(e, std::abs(a[k] - b[k]) / std::abs(b[k]));
  return e;
}

struct Oscillator {
  double m = 2, k = 800, c = 8;  // the model file's defaults
  cd dyn(double w) const { return cd(k - w * w * m, w * c); }
};

TEST(BaseExcitation, MatricesOfTheOscillatorAreTheClosedForms) {
  const mbsgen::LinearModel lin = base_excited_oscillator::linear_model();
  const Oscillator o;
  // B = [k, 1], B1 = [c, 0], B2 = 0 (x absolute): the model file's header.
  EXPECT_EQ(lin.B()(0, 0), o.k);
  EXPECT_EQ(lin.B()(0, 1), 1.0);
  ASSERT_EQ(lin.B1().rows(), 1);
  EXPECT_EQ(lin.B1()(0, 0), o.c);
  EXPECT_EQ(lin.B1()(0, 1), 0.0);
  EXPECT_EQ(lin.B2().size(), 0) << "B2 is exactly zero: stored empty";
  EXPECT_TRUE(lin.input_has_rates(0));
  EXPECT_FALSE(lin.input_has_rates(1)) << "the force input F has no rate terms";
}

// Displacement and force transmissibility of a base-excited spring-mass-damper (Rao §3.6.2):
// X/Xb = (k + iΩc)/(k − Ω²m + iΩc), and the mount's force on the mass m ẍ = −Ω²m X. Every
// method, to 1e-12 relative: a 1-DOF system with ζ = 0.1 has a condition number near 10, so
// each method's rounding is a few ulps; 1e-12 leaves a factor 100 for the methods that
// reduce to first order (hessenberg, real).
TEST(BaseExcitation, OscillatorTransmissibilityIsTheClosedForm) {
  const mbsgen::LinearModel lin = base_excited_oscillator::linear_model();
  const Oscillator o;
  const Eigen::VectorXd w = frequencies(std::sqrt(o.k / o.m));
  Eigen::VectorXcd T(w.size()), rel(w.size()), vrel(w.size()), force(w.size()), byF(w.size());
  for (Eigen::Index j = 0; j < w.size(); ++j) {
    T[j] = cd(o.k, w[j] * o.c) / o.dyn(w[j]);
    rel[j] = w[j] * w[j] * o.m / o.dyn(w[j]);
    vrel[j] = cd(0, w[j]) * rel[j];
    force[j] = -w[j] * w[j] * o.m * T[j];
    byF[j] = 1.0 / o.dyn(w[j]);
  }
  for (FrfMethod m : kMethods) {
    SCOPED_TRACE(mbsgen::to_string(m));
    EXPECT_LE(relative_error(frf(lin, w, "xb", "x_abs", m), T), 1e-12);
    EXPECT_LE(relative_error(frf(lin, w, "xb", "v_abs", m), (cd(0, 1) * w.cast<cd>()).cwiseProduct(T)), 1e-12);
    EXPECT_LE(relative_error(frf(lin, w, "xb", "x_rel", m), rel), 1e-12);
    EXPECT_LE(relative_error(frf(lin, w, "xb", "v_rel", m), vrel), 1e-12);
    EXPECT_LE(relative_error(frf(lin, w, "xb", "mount_force", m), force), 1e-12);
    EXPECT_LE(relative_error(frf(lin, w, "F", "x_abs", m), byF), 1e-12) << "the force input in the same model";
  }
}

struct Pendulum {
  double m = 0.5, l = 0.8, g = 9.81, c = 0.05;  // the model file's defaults
  // φ per pivot acceleration a: −m l / (m g l − Ω² m l² + iΩc).
  cd per_acceleration(double w) const { return -m * l / cd(m * g * l - w * w * m * l * l, w * c); }
  // φ (relative to the cart) per tilt of the cart: −(m g l − Ω² m l²) / (m g l − Ω² m l² + iΩc).
  cd per_tilt(double w) const { return -(m * g * l - w * w * m * l * l) / cd(m * g * l - w * w * m * l * l, w * c); }
};

// A pendulum whose pivot is shaken horizontally: the angle per pivot displacement is −Ω² times
// the closed form per acceleration; the same model driven by the equivalent inertial force −m a
// at the bob (d'Alembert) gives the same angle per acceleration.
TEST(BaseExcitation, ShakenPendulumIsTheClosedFormAndItsInertialForce) {
  const mbsgen::LinearModel lin = shaken_pendulum::linear_model();
  const Pendulum p;
  const Eigen::VectorXd w = frequencies(std::sqrt(p.g / p.l));
  Eigen::VectorXcd per_a(w.size()), per_x(w.size()), bob(w.size());
  for (Eigen::Index j = 0; j < w.size(); ++j) {
    per_a[j] = p.per_acceleration(w[j]);
    per_x[j] = -w[j] * w[j] * per_a[j];
    bob[j] = 1.0 + p.l * per_x[j];  // x_bob = xp + l sin φ
  }
  for (FrfMethod m : kMethods) {
    SCOPED_TRACE(mbsgen::to_string(m));
    const Eigen::VectorXcd shaken = frf(lin, w, "xp", "angle", m), forced = frf(lin, w, "a", "angle", m);
    EXPECT_LE(relative_error(shaken, per_x), 1e-12);
    EXPECT_LE(relative_error(forced, per_a), 1e-12);
    EXPECT_LE(relative_error(shaken, -w.cwiseAbs2().cast<cd>().cwiseProduct(forced)), 1e-12);
    EXPECT_LE(relative_error(frf(lin, w, "xp", "bob_x", m), bob), 1e-12);
    EXPECT_LE(relative_error(frf(lin, w, "xp", "bob_x_rel", m), p.l * per_x), 1e-12);
  }
}

// The cart tilted (a small rotation of the support): gravity and the inertia of the bob both
// act through it (B = −m g l, B2 = −m l²), and φ, the angle relative to the cart, is the closed
// form. Away from Ω² = g/l, where φ/tilt has a zero (the error is relative to |φ|).
TEST(BaseExcitation, TiltedPendulumIsTheClosedForm) {
  const mbsgen::LinearModel lin = shaken_pendulum::linear_model();
  const Pendulum p;
  const Eigen::VectorXd w = frequencies(std::sqrt(p.g / p.l));
  std::vector<double> kept;
  for (Eigen::Index j = 0; j < w.size(); ++j)
    if (std::abs(w[j] * w[j] * p.l / p.g - 1) > 0.05) kept.push_back(w[j]);
  const Eigen::VectorXd wk = Eigen::Map<const Eigen::VectorXd>(kept.data(), static_cast<Eigen::Index>(kept.size()));
  Eigen::VectorXcd expected(wk.size());
  for (Eigen::Index j = 0; j < wk.size(); ++j) expected[j] = p.per_tilt(wk[j]);
  for (FrfMethod m : kMethods) {
    SCOPED_TRACE(mbsgen::to_string(m));
    EXPECT_LE(relative_error(frf(lin, wk, "tilt", "angle", m), expected), 1e-12);
  }
}

// Invariant: the parts of a model that move rigidly with the support have no motion relative
// to it at any frequency (exactly: their rows of C_y, C_v, D and D1 are exact zeros), while they
// move with it absolutely. The corner of the cart sits off the pivot, so its relative position
// S_pivotᵀ (r_corner − r_pivot) is a sum of products of sines and cosines of the tilt whose
// derivatives cancel only exactly (the generator proves them zero); the rod's pivot point moves
// with the cart through the joint, while the rod swings.
TEST(BaseExcitation, RigidPartsMoveWithTheirSupport) {
  const mbsgen::LinearModel lin = shaken_pendulum::linear_model();
  const Eigen::VectorXd w = frequencies(std::sqrt(9.81 / 0.8));
  for (FrfMethod m : kMethods) {
    SCOPED_TRACE(mbsgen::to_string(m));
    for (const char* input : {"xp", "tilt"}) {
      SCOPED_TRACE(input);
      const Eigen::VectorXcd angle = frf(lin, w, input, "angle", m);
      const Eigen::VectorXcd pivot = frf(lin, w, input, "pivot_x_rel", m), pivot_v = frf(lin, w, input, "pivot_v_rel", m);
      const Eigen::VectorXcd corner = frf(lin, w, input, "corner_x_rel", m), corner_v = frf(lin, w, input, "corner_v_rel", m);
      const Eigen::VectorXcd corner_abs = frf(lin, w, input, "corner_x", m);
      EXPECT_GT(angle.cwiseAbs().minCoeff() + angle.cwiseAbs().maxCoeff(), 0.1) << "the rod swings";
      for (Eigen::Index j = 0; j < w.size(); ++j) {
        EXPECT_EQ(pivot[j], cd(0, 0));
        EXPECT_EQ(pivot_v[j], cd(0, 0));
        EXPECT_EQ(corner[j], cd(0, 0));
        EXPECT_EQ(corner_v[j], cd(0, 0));
        // Absolutely the corner moves with the cart: x = xp + 0.3 cos(tilt) − 0.1 sin(tilt).
        EXPECT_EQ(corner_abs[j], cd(std::string(input) == "xp" ? 1.0 : -0.1, 0));
      }
    }
  }
}

// The kernels say which input is which; simulate refuses a signal on a motion input (its
// kernels hold the support still) instead of losing it, and takes the force input.
TEST(BaseExcitation, SimulateRefusesAMovingSupport) {
  mbsgen::GeneratedModel model(base_excited_oscillator::kernels());
  ASSERT_NE(model.kernels().input_kinds, nullptr);
  EXPECT_STREQ(model.kernels().input_kinds[0], "motion");
  EXPECT_STREQ(model.kernels().input_kinds[1], "force");
  mbsgen::SimulationOptions o;
  o.duration = 0.1;
  o.step = 0.01;
  o.inputs = {mbsgen::InputSignal::sine(1e-3, 5), mbsgen::InputSignal()};
  try {
    mbsgen::simulate(model, model.operating_point(), o);
    ADD_FAILURE() << "no error";
  } catch (const mbsgen::Error& e) {
    EXPECT_NE(std::string(e.what()).find("input 'xb' prescribes motion"), std::string::npos) << e.what();
  }
  o.inputs = {mbsgen::InputSignal(), mbsgen::InputSignal::step(1.0)};
  const mbsgen::SimulationResult r = mbsgen::simulate(model, model.operating_point(), o);
  EXPECT_GT(r.y(0, r.t.size() - 1), 0.0) << "the force input moves the mass";
}

// The solver's `info` says which inputs prescribe motion (the manifest's `kind`).
TEST(BaseExcitation, InfoSaysWhichInputsMove) {
  std::vector<std::string> args = {"base_excited_oscillator-solve", "info"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream out, err;
  ASSERT_EQ(mbsgen::cli::solver_main(base_excited_oscillator::kernels(), static_cast<int>(argv.size()), argv.data(),
                                     out, err),
            0)
      << err.str();
  EXPECT_NE(out.str().find("inputs (2): xb [m, motion] F [N]\n"), std::string::npos) << out.str();
}

// Bone conduction of the middle ear (models/middle_ear): the temporal bone moves the chain
// through its inertia only. d'Alembert: a support accelerating by a (translation) or α (rotation
// about the origin) loads each body i with −m_i a, or −m_i α × c_i and −I_i α, so
// B2 = −Σ_i (JT_iᵀ m_i a_i + JR_iᵀ I_i α) with the unit accelerations of each input, from the
// `bodies` kernel (centres c_i, Jacobians, masses, inertias): a different path than the
// composite-body mass matrix that gives B2. Every bushing measures relative motion, so B and B1
// of the bone's inputs are exactly zero, and the outputs relative to the oval window do not see
// the bone's motion at all (exact zeros of D, D1): a chain frozen to the bone would have no
// relative motion at any frequency. The absolute stapes velocity moves with the bone (D1 = −1
// along the output's −z).
TEST(BaseExcitation, MiddleEarBoneConductionIsInertial) {
  const mbsgen::GeneratedModel model(middle_ear::kernels());
  const mbsgen::LinearModel lin = model.linear_model();
  const Eigen::Index n = lin.size(), nb = middle_ear_n_bodies;
  const std::vector<double> p = model.parameters();
  const Eigen::VectorXd y0 = model.operating_point().y0;
  Eigen::VectorXd rc(3 * nb), S(9 * nb), JT(3 * nb * n), JR(3 * nb * n), m(nb), Ic(9 * nb);
  ASSERT_EQ(middle_ear_bodies(y0.data(), p.data(), rc.data(), S.data(), JT.data(), JR.data(), m.data(), Ic.data()), 0);
  const std::vector<std::string> motions = {"bone_x", "bone_y", "bone_z", "bone_rx", "bone_ry", "bone_rz"};
  ASSERT_EQ(lin.B2().rows(), n);
  double scale = 0;
  Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(n, 6);
  for (int k = 0; k < 6; ++k) {
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(k % 3);
    for (Eigen::Index i = 0; i < nb; ++i) {
      const Eigen::Vector3d c = rc.segment<3>(3 * i);
      const Eigen::Matrix3d I = Eigen::Map<const Eigen::Matrix3d>(Ic.data() + 9 * i);
      const Eigen::Vector3d a = k < 3 ? e : Eigen::Vector3d(e.cross(c)), alpha = k < 3 ? Eigen::Vector3d::Zero() : e;
      const Eigen::Map<const Eigen::MatrixXd> Jt(JT.data() + 3 * n * i, 3, n), Jr(JR.data() + 3 * n * i, 3, n);
      expected.col(k) -= Jt.transpose() * (m[i] * a) + Jr.transpose() * (I * alpha);
    }
  }
  for (int k = 0; k < 6; ++k) {
    const Eigen::Index j = index_of(lin.input_names(), motions[static_cast<std::size_t>(k)]);
    // Rounding of sums of terms of the size of the largest mass-weighted Jacobian: 1e-13 of it.
    scale = std::max(scale, expected.col(k).cwiseAbs().maxCoeff());
    EXPECT_LE((lin.B2().col(j) - expected.col(k)).cwiseAbs().maxCoeff(), 1e-13 * scale) << motions[static_cast<std::size_t>(k)];
    EXPECT_EQ(lin.B().col(j).cwiseAbs().maxCoeff(), 0.0) << motions[static_cast<std::size_t>(k)];
    if (lin.B1().size()) {
      EXPECT_EQ(lin.B1().col(j).cwiseAbs().maxCoeff(), 0.0) << motions[static_cast<std::size_t>(k)];
    }
    for (const char* rel : {"x_stapes_rel", "v_stapes_rel"}) {
      const Eigen::Index r = index_of(lin.output_names(), rel);
      if (lin.D().size()) {
        EXPECT_EQ(lin.D()(r, j), 0.0) << rel;
      }
      if (lin.D1().size()) {
        EXPECT_EQ(lin.D1()(r, j), 0.0) << rel;
      }
    }
  }
  EXPECT_GT(scale, 0.0);
  ASSERT_EQ(lin.D1().rows(), lin.num_outputs());
  EXPECT_EQ(lin.D1()(index_of(lin.output_names(), "v_stapes"), index_of(lin.input_names(), "bone_z")), -1.0);
  // Far below the chain's slowest relaxation (571 1/s) the relative motion is the inertial load
  // on the stiffness, x_rel ≈ Ω² C K⁻¹ B2 u (relative corrections of (Ω/571)², 2e-4 at 2 Hz):
  // doubling the frequency multiplies it by 4 (40 dB/decade per displacement).
  const Eigen::VectorXd w = (Eigen::VectorXd(2) << 2 * 3.141592653589793, 4 * 3.141592653589793).finished();
  const Eigen::VectorXcd z = frf(lin, w, "bone_z", "x_stapes_rel", FrfMethod::direct);
  EXPECT_NEAR(std::abs(z[1] / z[0]), 4.0, 4e-3) << "Omega^2 at 1 and 2 Hz";
}

// Outputs at any state (issue 39 §4): the force of the mount on the mass, −k x − c ẋ, with the
// table at rest (x absolute); a force input does not move the mount; a nonzero motion input is
// refused, not ignored (the outputs hold the support at its reference position).
TEST(OutputsAt, MountForceIsTheSpringAndDamperForce) {
  mbsgen::GeneratedModel model(base_excited_oscillator::kernels());
  const double k = 800, c = 8, x = 0.01, v = 0.2;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(2);
  u[1] = 3.0;  // F
  const Eigen::VectorXd z = model.outputs_at(Eigen::VectorXd::Constant(1, x), Eigen::VectorXd::Constant(1, v),
                                             Eigen::VectorXd::Constant(1, 0.5), u);
  ASSERT_EQ(z.size(), 6);
  EXPECT_EQ(z[0], x);
  EXPECT_EQ(z[1], v);
  EXPECT_NEAR(z[5], -k * x - c * v, 4e-16 * (k * x + c * v));
  u[0] = 0.004;  // xb
  EXPECT_THROW(model.outputs_at(Eigen::VectorXd::Constant(1, x), Eigen::VectorXd::Constant(1, v),
                                Eigen::VectorXd::Zero(1), u),
               mbsgen::Error);
}

}  // namespace
