// Parameter sensitivities (issue 20 §1) through the generated `sensitivity` kernels: closed forms
// of a spring–mass–damper and of a pendulum whose equilibrium moves with its parameters,
// high-precision central differences (80 digits, tests/runtime/hp.cpp) of the middle ear's
// eigenvalues and response, and the flags of repeated and defective eigenvalues.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <complex>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "base_excited_oscillator_model.hpp"
#include "chain3_sympy_model.hpp"
#include "double_pendulum_model.hpp"
#include "jeffcott_rotor_model.hpp"
#include "rotor_disk_model.hpp"
#include "spring_chain_fixed_fixed_model.hpp"
#include "spring_chain_free_free_model.hpp"
#include "ziegler_column_model.hpp"
#include "hp.hpp"
#include "mbsgen/runtime/cli/solver_cli.hpp"
#include "mbsgen/runtime/model/generated_model.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"
#include "mbsgen/runtime/spectral/sensitivity.hpp"
#include "middle_ear_sensitivity_model.hpp"
#include "torqued_pendulum_model.hpp"

namespace {

using cd = std::complex<double>;
using mbsgen::EigenvalueKind;
using mbsgen::GeneratedModel;
using mbsgen::MatrixSensitivity;
using mbsgen::Mode;

const MatrixSensitivity& by_name(const std::vector<MatrixSensitivity>& d, const std::string& name) {
  for (const auto& x : d)
    if (x.parameter == name) return x;
  throw std::runtime_error("no sensitivity to " + name);
}

std::vector<Mode> modes_of(const mbsgen::LinearModel& lin) {
  mbsgen::QuadraticEigenSolver solver(lin.size());
  solver.compute(lin);
  return solver.modes();
}

// The oscillator's eigenvalue with Im λ > 0.
std::size_t upper(const std::vector<Mode>& modes) {
  for (std::size_t k = 0; k < modes.size(); ++k)
    if (modes[k].lambda.imag() > 0) return k;
  throw std::runtime_error("no eigenvalue with Im > 0");
}

// m λ² + c λ + k = 0: dλ/dm = −λ²/(2mλ + c), dλ/dc = −λ/(2mλ + c), dλ/dk = −1/(2mλ + c). The
// 1×1 problem's eigenvalue and vectors carry a few roundings: 1e-13 relative.
TEST(Sensitivity, OscillatorEigenvalueMatchesTheClosedForm) {
  GeneratedModel model(base_excited_oscillator::kernels());
  const double m = 2, c = 8;
  const auto op = model.operating_point();
  const auto lin = model.linear_model(op);
  const auto d = model.linear_sensitivities(op);
  ASSERT_EQ(d.size(), 3u);
  const auto modes = modes_of(lin);
  const auto s = mbsgen::eigenvalue_sensitivities(lin, modes, d);
  for (std::size_t i = 0; i < modes.size(); ++i) {
    const cd l = modes[i].lambda, den = 2.0 * m * l + c;
    const cd expect[3] = {-l * l / den, -1.0 / den, -l / den};  // m, k, c (the model's order)
    for (std::size_t j = 0; j < 3; ++j) {
      ASSERT_TRUE(s[i][j].defined) << s[i][j].note;
      EXPECT_LE(std::abs(s[i][j].dlambda - expect[j]), 1e-13 * std::abs(expect[j])) << d[j].parameter;
    }
  }
  // The matrices' own derivatives, exactly: B = [k, 1], B1 = [c, 0], M = m.
  EXPECT_EQ(by_name(d, "k").B(0, 0), 1.0);
  EXPECT_EQ(by_name(d, "k").B(0, 1), 0.0);
  EXPECT_EQ(by_name(d, "c").B1(0, 0), 1.0);
  EXPECT_EQ(by_name(d, "m").M(0, 0), 1.0);
  EXPECT_EQ(by_name(d, "m").K(0, 0), 0.0);
}

// The closed form: an undamped spring–mass, dω/dk = 1/(2mω); relative sensitivities of
// the natural frequency to k and m are exactly ±1/2.
TEST(Sensitivity, UndampedSpringMassFrequency) {
  GeneratedModel model(base_excited_oscillator::kernels());
  model.set("c", 0.0);
  const double m = 2, k = 800, w = std::sqrt(k / m);
  const auto op = model.operating_point();
  const auto lin = model.linear_model(op);
  const auto d = model.linear_sensitivities(op, {"k", "m"});
  const auto modes = modes_of(lin);
  const auto s = mbsgen::eigenvalue_sensitivities(lin, modes, d);
  const std::size_t i = upper(modes);
  EXPECT_NEAR(2 * M_PI * s[i][0].dfrequency_hz, 1 / (2 * m * w), 1e-14 / (2 * m * w));
  EXPECT_NEAR(s[i][0].relative_frequency, 0.5, 1e-14);
  EXPECT_NEAR(s[i][1].relative_frequency, -0.5, 1e-14);
  EXPECT_NEAR(s[i][0].ddamping_ratio, 0.0, 1e-15);
}

// H = X/F = 1/(k − Ω²m + iΩc): dH/dk = −H², dH/dm = Ω²H², dH/dc = −iΩH²; the table's
// transmissibility T = (k + iΩc)/D: dT/dk = (1 − T)/D, dT/dc = iΩ(1 − T)/D, dT/dm = Ω²T/D.
// 1e-12 relative: a 1×1 solve and the closed form's own roundings, through the resonance.
TEST(Sensitivity, OscillatorResponseMatchesTheClosedForm) {
  GeneratedModel model(base_excited_oscillator::kernels());
  const double m = 2, k = 800, c = 8;
  const auto op = model.operating_point();
  const auto lin = model.linear_model(op);
  const auto d = model.linear_sensitivities(op);
  std::vector<double> hz;
  for (int i = 0; i <= 40; ++i) hz.push_back(0.2 * std::pow(10.0, 2.0 * i / 40.0));
  const auto r = mbsgen::frequency_response_sensitivity(lin, d, hz);
  const Eigen::Index x_abs = 0, xb = 0, F = 1;
  for (std::size_t n = 0; n < hz.size(); ++n) {
    const double w = 2 * M_PI * hz[n];
    const cd D = k - w * w * m + cd(0, w * c), H = 1.0 / D, T = (k + cd(0, w * c)) / D;
    const cd dH[3] = {w * w * H * H, -H * H, cd(0, -w) * H * H};
    const cd dT[3] = {w * w * T / D, (1.0 - T) / D, cd(0, w) * (1.0 - T) / D};
    EXPECT_LE(std::abs(r.response[n](x_abs, F) - H), 1e-13 * std::abs(H));
    for (std::size_t j = 0; j < 3; ++j) {
      EXPECT_LE(std::abs(r.derivative[j][n](x_abs, F) - dH[j]), 1e-12 * std::abs(dH[j])) << d[j].parameter << " " << hz[n];
      EXPECT_LE(std::abs(r.derivative[j][n](x_abs, xb) - dT[j]), 1e-12 * std::abs(dT[j])) << d[j].parameter << " " << hz[n];
    }
  }
}

// m g l sin φ0 = T moves with the parameters: dφ0/dT = 1/(m g l cos φ0), and the total
// derivatives of K = m g l cos φ0 are dK/dT = −tan φ0, dK/dm = g l/cos φ0 = dK/dl · l/m; of
// M = m l², dM/dl = 2 m l. 1e-13 relative: Newton's φ0 and a handful of roundings.
TEST(Sensitivity, EquilibriumThatMovesWithTheParameters) {
  GeneratedModel model(torqued_pendulum::kernels());
  const double m = 1.5, l = 0.8, g = 9.81, T = 5;
  const double phi0 = std::asin(T / (m * g * l));
  const auto op = model.operating_point();
  ASSERT_NEAR(op.y0[0], phi0, 1e-14);
  const auto d = model.linear_sensitivities(op, {"T", "m", "l"});
  auto near = [](double a, double b) { EXPECT_NEAR(a, b, 1e-13 * std::abs(b)); };
  near(d[0].dy0[0], 1 / (m * g * l * std::cos(phi0)));
  near(d[0].K(0, 0), -std::tan(phi0));
  near(d[1].K(0, 0), g * l / std::cos(phi0));
  near(d[2].K(0, 0), m * g / std::cos(phi0));
  near(d[2].M(0, 0), 2 * m * l);
  EXPECT_EQ(d[0].M(0, 0), 0.0);
  // The same through the whole pipeline by central differences (equilibrium and K again at
  // T ± h, h = 1e-5 T): truncation O(h²) ≈ 1e-10 and rounding ε/h ≈ 1e-11 relative, so 1e-8.
  const double h = 1e-5 * T;
  auto K_at = [&](double t) {
    GeneratedModel p(torqued_pendulum::kernels());
    p.set("T", t);
    return p.linear_model().K()(0, 0);
  };
  EXPECT_NEAR((K_at(T + h) - K_at(T - h)) / (2 * h), d[0].K(0, 0), 1e-8 * std::abs(d[0].K(0, 0)));
}

// Every kernel derivative of the middle ear against central differences of the linear kernel
// (h = 1e-5 |p|): the truncation, O(h²)·A''', and rounding, O(ε/h)·‖A‖, stay below 1e-7 ‖A‖/|p|
// for these smooth entries; 87 parameters × M, Q, K, B, C_y, C_v (middle_ear_sensitivity: the
// full model generated with --sensitivity). The derivatives are exact (symbolic); this checks that
// the emitted code computes the model's.
TEST(Sensitivity, MiddleEarKernelsAgainstCentralDifferences) {
  GeneratedModel model(middle_ear_sensitivity::kernels());
  const auto op = model.operating_point();
  const auto d = model.linear_sensitivities(op);
  ASSERT_EQ(static_cast<int>(d.size()), middle_ear_sensitivity::kernels().n_parameters);
  const auto names = model.parameter_names();
  for (std::size_t j = 0; j < d.size(); ++j) {
    const double p = d[j].value, h = 1e-5 * std::abs(p);
    if (p == 0) continue;  // a zero inertia cannot go negative; the high-precision tests cover such parameters
    auto lin_at = [&](double v) {
      GeneratedModel q(middle_ear_sensitivity::kernels());
      q.set(d[j].parameter, v);
      return q.linear_model(q.operating_point());
    };
    const auto plus = lin_at(p + h), minus = lin_at(p - h), here = model.linear_model(op);
    auto check = [&](const Eigen::MatrixXd& dA, const Eigen::MatrixXd& Ap, const Eigen::MatrixXd& Am,
                     const Eigen::MatrixXd& A, const char* what) {
      const Eigen::MatrixXd fd = (Ap - Am) / (2 * h);
      const double scale = A.cwiseAbs().maxCoeff() / std::max(std::abs(p), 1e-6);
      EXPECT_LE((dA - fd).cwiseAbs().maxCoeff(), 1e-7 * scale + 1e-300) << what << " by " << d[j].parameter;
    };
    check(d[j].M, plus.M(), minus.M(), here.M(), "M");
    check(d[j].Q, plus.Q(), minus.Q(), here.Q(), "Q");
    check(d[j].K, plus.K(), minus.K(), here.K(), "K");
    check(d[j].B, plus.B(), minus.B(), here.B(), "B");
    check(d[j].C_y, plus.C_y(), minus.C_y(), here.C_y(), "C_y");
    check(d[j].C_v, plus.C_v(), minus.C_v(), here.C_v(), "C_v");
  }
}

// dλ/dp of the middle ear's modes against 80-digit central differences of the eigenvalues of
// (M + t dM, Q + t dQ, K + t dK), for parameters of every kind (mass, inertia, geometry, stiffness,
// damping), every finite mode (normwise condition numbers 3e5 to 7e7: the coefficients' norms
// differ by 15 orders; the eigenvalues are accurate to about 1e-10 nevertheless): 1e-9 relative,
// plus a floor of 1e-13 |λ|/|p|, a relative sensitivity (p/λ) dλ/dp of 1e-13, for a mode that a
// parameter barely moves (relative sensitivities down to 5e-10, whose derivatives carry the
// rounding of the larger ones: up to 8e-7 relative, 1e-16 in relative units).
TEST(Sensitivity, MiddleEarEigenvaluesAgainstHighPrecision) {
  GeneratedModel model(middle_ear_sensitivity::kernels());
  const auto op = model.operating_point();
  const auto lin = model.linear_model(op);
  const std::vector<std::string> chosen = {"m_malleus", "com_malleus_x", "k_al_z", "d_cochlea_z", "k_eardrum_x"};
  const auto d = model.linear_sensitivities(op, chosen);
  const auto modes = modes_of(lin);
  const auto s = mbsgen::eigenvalue_sensitivities(lin, modes, d);
  int checked = 0;
  double worst = 0, worst_large = 0;
  for (std::size_t k = 0; k < modes.size(); ++k) {
    if (modes[k].kind != EigenvalueKind::finite || modes[k].lambda.imag() < 0) continue;
    for (std::size_t j = 0; j < d.size(); ++j) {
      ASSERT_TRUE(s[k][j].defined) << k << " " << s[k][j].note;
      const cd ref = hp::eigenvalue_derivative(lin.M(), lin.Q(), lin.K(), d[j].M, d[j].Q, d[j].K, modes[k].lambda,
                                               modes[k].shape);
      const double floor = 1e-13 * std::abs(modes[k].lambda) / std::abs(d[j].value);
      EXPECT_LE(std::abs(s[k][j].dlambda - ref), 1e-9 * std::abs(ref) + floor) << "mode " << k << " by " << d[j].parameter;
      const double error = std::abs(s[k][j].dlambda - ref) / std::abs(ref);
      if (std::abs(ref) >= 1e7 * floor) worst = std::max(worst, error);
      if (std::abs(ref) >= 1e10 * floor) worst_large = std::max(worst_large, error);
      ++checked;
    }
  }
  EXPECT_GE(checked, 5 * 5);
  std::printf("dλ/dp: %d checked, largest relative error %.3g where |(p/λ) dλ/dp| ≥ 1e-6, %.3g where ≥ 1e-3\n",
              checked, worst, worst_large);
}

// dẑ/dp of the stapes velocity per ear-canal pressure at 0.5, 1 and 4 kHz against 80-digit
// central differences of the whole response: 1e-9 relative.
TEST(Sensitivity, MiddleEarResponseAgainstHighPrecision) {
  GeneratedModel model(middle_ear_sensitivity::kernels());
  const auto op = model.operating_point();
  const auto lin = model.linear_model(op);
  const auto d = model.linear_sensitivities(op, {"k_al_z", "m_stapes", "d_cochlea_z", "A_tm"});
  const Eigen::Index P = model.input_index("P"), v = model.output_index("v_stapes");
  const std::vector<double> hz = {500, 1000, 4000};
  const auto r = mbsgen::frequency_response_sensitivity(lin, d, hz);
  for (std::size_t j = 0; j < d.size(); ++j)
    for (std::size_t n = 0; n < hz.size(); ++n) {
      const cd ref = hp::frf_derivative({lin.M(), lin.Q(), lin.K(), lin.C_y(), lin.C_v()}, lin.B().col(P),
                                        {d[j].M, d[j].Q, d[j].K, d[j].C_y, d[j].C_v}, d[j].B.col(P),
                                        2 * M_PI * hz[n], v);
      EXPECT_LE(std::abs(r.derivative[j][n](v, P) - ref), 1e-9 * std::abs(ref)) << d[j].parameter << " at " << hz[n];
    }
}

// The textbook models, every parameter: (a) the kernel's total derivatives against central
// differences of the whole pipeline — operating point found again (the spring chain's
// equilibrium, by Newton; the rotor's steady spin rate Omega), linear model — at p ± h,
// h = 1e-6 |p|: 1e-6 of the matrix's scale per unit of p, the differences' own truncation and
// rounding; (b) dλ/dp of every finite, simple mode against 80-digit central differences of the
// eigenvalues along the kernel's derivatives: 1e-9 relative plus 1e-13 |λ|/|p|, as for the middle
// ear. Models: a double pendulum, SymPy's three-link chain, a spring chain at its equilibrium
// under gravity, a Jeffcott rotor with rotating damping (circulatory K), a spinning rotor disk
// (gyroscopic Q about a steady motion) and Ziegler's follower-force column.
TEST(Sensitivity, TextbookModelsAgainstCentralDifferences) {
  std::vector<std::string> one_sided;
  for (const mbsgen::ModelKernels* k : {&double_pendulum::kernels(), &chain3_sympy::kernels(),
                                        &spring_chain_fixed_fixed::kernels(), &jeffcott_rotor::kernels(),
                                        &rotor_disk::kernels(), &ziegler_column::kernels()}) {
    SCOPED_TRACE(k->model);
    GeneratedModel model(*k);
    ASSERT_TRUE(model.has_sensitivities());
    const auto op = model.operating_point();
    const auto lin = model.linear_model(op);
    const auto d = model.linear_sensitivities(op);
    for (const auto& dj : d) {
      if (dj.value == 0) continue;
      const double h = 1e-6 * std::abs(dj.value);
      auto at = [&](double v) {
        GeneratedModel q(*k);
        q.set(dj.parameter, v);
        return q.linear_model(q.operating_point());
      };
      // Central differences, or at the edge of the physical values (the rotor disk is flat,
      // I_p = 2 I_d: a smaller I_d or a larger I_p is refused, ParameterError) the one-sided
      // differences ±(−3 A(p) + 4 A(p ± h) − A(p ± 2h)) / 2h, also O(h²).
      auto try_at = [&](double v) -> std::optional<mbsgen::LinearModel> {
        try {
          return at(v);
        } catch (const mbsgen::ParameterError&) {
          return std::nullopt;
        }
      };
      const std::optional<mbsgen::LinearModel> plus = try_at(dj.value + h), minus = try_at(dj.value - h);
      ASSERT_TRUE(plus || minus) << dj.parameter;
      const double side = plus ? 1 : -1;  // of a one-sided difference
      std::optional<mbsgen::LinearModel> twice;
      if (!plus || !minus) {
        one_sided.push_back(std::string(k->model) + ":" + dj.parameter);
        twice = at(dj.value + 2 * side * h);
      }
      auto check = [&](const Eigen::MatrixXd& dA, auto matrix, const Eigen::MatrixXd& A, const char* what) {
        const double scale = std::max(A.cwiseAbs().maxCoeff(), 1e-300) / std::abs(dj.value);
        const Eigen::MatrixXd fd =
            twice ? Eigen::MatrixXd(side * (-3 * A + 4 * matrix(plus ? *plus : *minus) - matrix(*twice)) / (2 * h))
                  : Eigen::MatrixXd((matrix(*plus) - matrix(*minus)) / (2 * h));
        EXPECT_LE((dA - fd).cwiseAbs().maxCoeff(), 1e-6 * scale) << what << " by " << dj.parameter;
      };
      check(dj.M, [](const mbsgen::LinearModel& l) { return l.M(); }, lin.M(), "M");
      check(dj.Q, [](const mbsgen::LinearModel& l) { return l.Q(); }, lin.Q(), "Q");
      check(dj.K, [](const mbsgen::LinearModel& l) { return l.K(); }, lin.K(), "K");
    }
    const auto modes = modes_of(lin);
    const auto s = mbsgen::eigenvalue_sensitivities(lin, modes, d);
    int checked = 0;
    for (std::size_t m = 0; m < modes.size(); ++m)
      for (std::size_t j = 0; j < d.size(); ++j) {
        if (!s[m][j].defined || d[j].value == 0) continue;
        const cd ref = hp::eigenvalue_derivative(lin.M(), lin.Q(), lin.K(), d[j].M, d[j].Q, d[j].K, modes[m].lambda,
                                                 modes[m].shape);
        const double floor = 1e-13 * std::abs(modes[m].lambda) / std::abs(d[j].value);
        EXPECT_LE(std::abs(s[m][j].dlambda - ref), 1e-9 * std::abs(ref) + floor) << "mode " << m << " by " << d[j].parameter;
        ++checked;
      }
    EXPECT_GT(checked, 0);
  }
  EXPECT_EQ(one_sided, (std::vector<std::string>{"rotor_disk:I_d", "rotor_disk:I_p"}));
}

// A repeated eigenvalue (two equal, uncoupled oscillators) and a defective one (a critically
// damped oscillator, λ = −1 twice with one eigenvector) have no derivative: flagged, NaN.
TEST(Sensitivity, RepeatedAndDefectiveEigenvaluesAreFlagged) {
  {
    const mbsgen::LinearModel lin(Eigen::Matrix2d::Identity(), Eigen::Matrix2d::Zero(), Eigen::Matrix2d::Identity());
    MatrixSensitivity d;
    d.parameter = "k1", d.value = 1;
    d.K = Eigen::Matrix2d::Zero();
    d.K(0, 0) = 1;
    const auto modes = modes_of(lin);
    const auto s = mbsgen::eigenvalue_sensitivities(lin, modes, {d});
    for (std::size_t k = 0; k < modes.size(); ++k) {
      EXPECT_FALSE(s[k][0].defined);
      EXPECT_EQ(s[k][0].note, "repeated");
      EXPECT_TRUE(std::isnan(s[k][0].dlambda.real()));
    }
  }
  {
    const mbsgen::LinearModel lin(Eigen::MatrixXd::Constant(1, 1, 1.0), Eigen::MatrixXd::Constant(1, 1, 2.0),
                                  Eigen::MatrixXd::Constant(1, 1, 1.0));
    MatrixSensitivity d;
    d.parameter = "k", d.value = 1;
    d.K = Eigen::MatrixXd::Constant(1, 1, 1.0);
    const auto modes = modes_of(lin);
    const auto s = mbsgen::eigenvalue_sensitivities(lin, modes, {d});
    for (std::size_t k = 0; k < modes.size(); ++k) {
      EXPECT_FALSE(s[k][0].defined) << modes[k].lambda;
      EXPECT_TRUE(s[k][0].note == "repeated" || s[k][0].note == "defective") << s[k][0].note;
    }
  }
}

int run(const mbsgen::ModelKernels& k, std::vector<std::string> args, std::string& out, std::string& err) {
  args.insert(args.begin(), "solve");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream o, e;
  const int rc = mbsgen::cli::solver_main(k, static_cast<int>(argv.size()), argv.data(), o, e);
  out = o.str(), err = e.str();
  return rc;
}

// The solver's `modes --sensitivity` and `frf --sensitivity`: the closed form in the CSV, and
// clear errors for an unknown parameter and for a plot of sensitivities.
TEST(Sensitivity, SolverCommandLine) {
  std::string out, err;
  ASSERT_EQ(run(base_excited_oscillator::kernels(), {"modes", "--sensitivity", "k", "--format", "csv", "--set", "c=0"},
                out, err), 0) << err;
  std::istringstream lines(out);
  std::string header, row;
  std::getline(lines, header);
  std::getline(lines, row);
  EXPECT_NE(header.find("relative_frequency"), std::string::npos);
  EXPECT_NE(row.find(",\"k\",800,"), std::string::npos) << row;
  // (k/f) df/dk = 1/2: the tenth field, to 1e-14 (the eigenvalue's roundings).
  std::string field;
  std::istringstream fields(row);
  for (int i = 0; i < 10; ++i) std::getline(fields, field, ',');
  EXPECT_NEAR(std::stod(field), 0.5, 1e-14) << row;
  ASSERT_EQ(run(base_excited_oscillator::kernels(), {"modes", "--sensitivity", "kk"}, out, err), 2);
  EXPECT_NE(err.find("no sensitivity to 'kk'"), std::string::npos) << err;
  EXPECT_NE(err.find("m, k, c"), std::string::npos) << err;
  ASSERT_EQ(run(base_excited_oscillator::kernels(),
                {"frf", "--input", "F", "--output", "x_abs", "--from", "1", "--to", "10", "--points", "3",
                 "--sensitivity", "--format", "json"},
                out, err), 0) << err;
  EXPECT_NE(out.find("\"dlnmag_dlnp\""), std::string::npos);
  EXPECT_EQ(run(base_excited_oscillator::kernels(),
                {"frf", "--input", "F", "--output", "x_abs", "--from", "1", "--to", "10", "--sensitivity", "--plot",
                 "/tmp/never.svg"},
                out, err), 1);
  EXPECT_NE(err.find("--plot"), std::string::npos) << err;
  // The modes are numbered as `modes` numbers them: the spring chain with free ends has a
  // rigid-body double zero, listed once.
  ASSERT_EQ(run(spring_chain_free_free::kernels(), {"modes", "--format", "csv"}, out, err), 0) << err;
  const auto rows = std::count(out.begin(), out.end(), '\n') - 1;
  ASSERT_EQ(run(spring_chain_free_free::kernels(), {"modes", "--sensitivity", "k", "--format", "csv"}, out, err), 0)
      << err;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n') - 1, rows) << out;
  EXPECT_NE(out.find("\n" + std::to_string(rows) + ","), std::string::npos) << out;
}

}  // namespace
