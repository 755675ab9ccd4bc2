// Outputs on the accelerations and the inputs, z = C_y y + C_v ẏ + C_a ÿ + D u (issue 15 §3 (c):
// joint loads): ẑ(Ω) = (C_y + iΩC_v − Ω²C_a) ŷ + D û for every frequency-response method, against
// closed forms of a spring–mass–damper, the equation of motion as an invariant, and a 266-bit
// reference solve (hp::frf) on a chain; LinearModel::with_output_terms' errors; the kernels'
// optional output_terms through GeneratedModel and the solver's `matrices`; `mbsgen linear --Ca`.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "hp.hpp"
#include "mbsgen/runtime/cli/linear_cli.hpp"
#include "mbsgen/runtime/cli/solver_cli.hpp"
#include "mbsgen/runtime/model/generated_model.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "models.hpp"

using mbsgen::FrequencyResponse;
using mbsgen::FrfFlag;
using mbsgen::FrfMethod;
using mbsgen::LinearModel;
using testmodels::with;
using cd = std::complex<double>;
using Eigen::Index;
using Eigen::MatrixXd;

namespace {

const FrfMethod kMethods[] = {FrfMethod::direct, FrfMethod::banded, FrfMethod::hessenberg,
                              FrfMethod::modal,  FrfMethod::real,   FrfMethod::automatic};

// The spring–mass–damper m ÿ + c ẏ + k y = u: ω_n = 20 rad/s, ζ = c/(2√(km)) = 0.05.
constexpr double kM = 2.0, kC = 4.0, kK = 800.0;

MatrixXd scalar(double v) { return MatrixXd::Constant(1, 1, v); }

/// The single mass with one output row z = cy·y + cv·ẏ (+ C_a, D added by the caller).
LinearModel single_mass(double cy, double cv) {
  return LinearModel(scalar(kM), scalar(kC), scalar(kK), scalar(1.0), scalar(cy), scalar(cv));
}

/// ŷ = 1/(k − Ω²m + iΩc), the closed form.
cd y_hat(double om) { return 1.0 / cd(kK - om * om * kM, om * kC); }

/// Ω = 0, 40 frequencies log-spaced over 0.1 .. 1000 rad/s (five decades around ω_n = 20) and
/// ω_n itself, where |ŷ| peaks at 1/(2ζk).
Eigen::VectorXd sweep() {
  Eigen::VectorXd w(42);
  w[0] = 0.0;
  for (int k = 0; k < 40; ++k) w[k + 1] = 0.1 * std::pow(1e4, k / 39.0);
  w[41] = 20.0;
  return w;
}

// Tolerance for the single mass. direct and banded solve the scalar d·ŷ = 1 (d rounded once, one
// division: a few u); hessenberg, real and modal solve the 2×2 first-order form, well conditioned
// at ζ = 0.05. Measured over this sweep (z = ÿ, relative): direct 2.4e-16, banded 0, hessenberg
// 2.6e-16, real 4.1e-16, modal 1.2e-14 (the modal sum of one conjugate pair cancels below ω_n);
// 1e-12 leaves a factor 80 over modal and still catches a wrong sign or a missing Ω² (errors O(1)).
constexpr double kSingleMassTol = 1e-12;

}  // namespace

// z = ÿ (C_a = 1): ẑ = −Ω² ŷ, for every method.
TEST(FrfOutputTerms, AccelerationOfSpringMassDamperEveryMethod) {
  const LinearModel m = single_mass(0.0, 0.0).with_output_terms(scalar(1.0), MatrixXd());
  ASSERT_TRUE(m.has_output_accelerations());
  ASSERT_FALSE(m.has_feedthrough());
  const Eigen::VectorXd w = sweep();
  for (FrfMethod meth : kMethods) {
    SCOPED_TRACE(to_string(meth));
    FrequencyResponse f(m, with(meth));
    f.compute(w, 0);
    ASSERT_EQ(f.response().rows(), 1);
    double worst = 0;
    for (Index k = 0; k < w.size(); ++k) {
      ASSERT_EQ(f.flags()[static_cast<std::size_t>(k)], FrfFlag::ok) << w[k];
      const cd ref = -w[k] * w[k] * y_hat(w[k]);
      if (w[k] == 0.0) {
        EXPECT_EQ(std::abs(f.response()(0, k)), 0.0);  // no acceleration at rest: exactly −0²·ŷ
        continue;
      }
      const double e = std::abs(f.response()(0, k) - ref) / std::abs(ref);
      worst = std::max(worst, e);
      EXPECT_LE(e, kSingleMassTol) << "Omega " << w[k];
    }
    RecordProperty(std::string("max_rel_error_") + to_string(meth), std::to_string(worst));
  }
}

// z = y + 2u (D = 2): ẑ = ŷ + 2, for every method; at Ω = 0 the static response 1/k + 2.
TEST(FrfOutputTerms, FeedthroughEveryMethod) {
  const LinearModel m = single_mass(1.0, 0.0).with_output_terms(MatrixXd(), scalar(2.0));
  ASSERT_TRUE(m.has_feedthrough());
  ASSERT_FALSE(m.has_output_accelerations());
  const Eigen::VectorXd w = sweep();
  for (FrfMethod meth : kMethods) {
    SCOPED_TRACE(to_string(meth));
    FrequencyResponse f(m, with(meth));
    f.compute(w, 0);
    for (Index k = 0; k < w.size(); ++k) {
      const cd ref = y_hat(w[k]) + 2.0;
      EXPECT_LE(std::abs(f.response()(0, k) - ref) / std::abs(ref), kSingleMassTol) << w[k];
    }
    // Ω = 0: C_y K⁻¹ b + D = 1/800 + 2 (the relative bound covers the rounding of 1/800).
    EXPECT_NEAR(f.response()(0, 0).real(), 1.0 / kK + 2.0, 4 * testmodels::u * 2.0);
    // Exactly 0 but for modal, whose sum over a conjugate pair leaves rounding (4e-20 seen).
    EXPECT_LE(std::abs(f.response()(0, 0).imag()), kSingleMassTol / kK);
  }
}

// The equation of motion read as an output, z = m ÿ + c ẏ + k y − u (C_a = m, C_v = c, C_y = k,
// D = −1), is zero at every frequency. Its terms are of size |kŷ|, |Ωcŷ|, |Ω²mŷ| and 1; a
// computed ŷ with relative error δ leaves |z| = |d·ŷ·δ| = δ ≤ (that sum)·δ, and the combination
// rounds at u times the same sum: so |z| ≤ 1e-12·(sum of the terms' sizes) — kSingleMassTol
// for δ, plus a few u.
TEST(FrfOutputTerms, SingleMassEquationOfMotionIsZeroForEveryMethod) {
  const LinearModel m = single_mass(kK, kC).with_output_terms(scalar(kM), scalar(-1.0));
  const Eigen::VectorXd w = sweep();
  for (FrfMethod meth : kMethods) {
    SCOPED_TRACE(to_string(meth));
    FrequencyResponse f(m, with(meth));
    f.compute(w, 0);
    for (Index k = 0; k < w.size(); ++k) {
      const double ay = std::abs(y_hat(w[k]));
      const double scale = kK * ay + w[k] * kC * ay + w[k] * w[k] * kM * ay + 1.0;
      EXPECT_LE(std::abs(f.response()(0, k)), kSingleMassTol * scale) << "Omega " << w[k];
    }
  }
}

// The force on the ground of a base-fixed spring–damper, two ways: through the elements
// (z1 = k y + c ẏ, C_y and C_v) and by Newton's law (z2 = u − m ÿ, C_a = −m, D = 1). Both equal the
// closed-form transmissibility (k + iΩc)/(k − Ω²m + iΩc), for every method.
TEST(FrfOutputTerms, TransmittedForceTwoWaysEqualsTransmissibility) {
  MatrixXd Cy(2, 1), Cv(2, 1), Ca(2, 1), D(2, 1);
  Cy << kK, 0.0;
  Cv << kC, 0.0;
  Ca << 0.0, -kM;
  D << 0.0, 1.0;
  const LinearModel m =
      LinearModel(scalar(kM), scalar(kC), scalar(kK), scalar(1.0), Cy, Cv).with_output_terms(Ca, D);
  const Eigen::VectorXd w = sweep();
  for (FrfMethod meth : kMethods) {
    SCOPED_TRACE(to_string(meth));
    FrequencyResponse f(m, with(meth));
    f.compute(w, 0);
    for (Index k = 0; k < w.size(); ++k) {
      const cd ref = cd(kK, w[k] * kC) * y_hat(w[k]);
      // z2 = 1 − Ω²mŷ cancels above resonance (|ref| → 0 like (ω_n/Ω)·2ζ): relative to the
      // size of its terms 1 + Ω²m|ŷ|, as in the invariant above.
      const double scale2 = 1.0 + w[k] * w[k] * kM * std::abs(y_hat(w[k]));
      EXPECT_LE(std::abs(f.response()(0, k) - ref) / std::abs(ref), kSingleMassTol) << w[k];
      EXPECT_LE(std::abs(f.response()(1, k) - ref), kSingleMassTol * scale2) << w[k];
    }
  }
}

// A chain of three masses (the data of docs/cli.md) with four outputs mixing the terms, selected
// in a scrambled order and singly, against ŷ from a 266-bit solve (hp::frf with C_y = E) combined
// as (C_y + iΩC_v − Ω²C_a) ŷ + D. Tolerance: the first-order error bound of a backward-stable
// solve, 10·f·u/rcond, relative to the size of the output's terms, floored at 1e-12 (where rcond
// is near 1 the combination's own rounding, a few u, and hessenberg's error constant decide);
// real gets 1e-10 (it squares the condition number, docs/runtime.md), and so does modal: above
// the modes the far mass's ŷ3 ∝ Ω⁻⁶ is a sum of terms ∝ Ω⁻² that cancel (1.8e-12 relative seen
// at 30 Hz on y3, an output without C_a or D), while its rcond measures the cancellation of the
// whole output vector, not of each row.
TEST(FrfOutputTerms, ChainRowsSelectedInAnyOrderAgainst266BitReference) {
  const testmodels::Qep p = testmodels::chain({1, 2, 1}, {1000, 1000, 1000, 0}, {0.5, 0, 0, 0});
  MatrixXd B = MatrixXd::Zero(3, 1);
  B(0, 0) = 1.0;
  MatrixXd Cy = MatrixXd::Zero(4, 3), Cv = MatrixXd::Zero(4, 3), Ca = MatrixXd::Zero(4, 3),
           D = MatrixXd::Zero(4, 1);
  Cy(0, 2) = 1.0;                          // z0 = y3
  Cy(1, 0) = 1000.0;                       // z1 = force on the wall through spring and damper
  Cv(1, 0) = 0.5;
  Ca.row(2) << -1.0, -2.0, -1.0;           // z2 = the same force by Newton: u − Σ mᵢÿᵢ
  D(2, 0) = 1.0;
  Ca(3, 1) = 1.0;                          // z3 = ÿ2 + 0.5 u + 3 y1
  D(3, 0) = 0.5;
  Cy(3, 0) = 3.0;
  const LinearModel m = LinearModel(p.M, p.Q, p.K, B, Cy, Cv).with_output_terms(Ca, D);
  Eigen::VectorXd w = testmodels::log_omegas(0.3, 30, 25);
  w[0] = 0.0;
  const std::vector<std::vector<Index>> selections = {{3, 0, 2, 1}, {2}, {}, {1, 1, 3}};
  for (FrfMethod meth : kMethods)
    for (const auto& sel : selections) {
      SCOPED_TRACE(std::string(to_string(meth)) + " selection of " + std::to_string(sel.size()));
      FrequencyResponse f(m, with(meth));
      f.compute(w, 0, sel);
      std::vector<Index> rows = sel;
      if (rows.empty()) rows = {0, 1, 2, 3};
      ASSERT_EQ(f.response().rows(), static_cast<Index>(rows.size()));
      for (Index k = 0; k < w.size(); ++k) {
        ASSERT_EQ(f.flags()[static_cast<std::size_t>(k)], FrfFlag::ok);
        const auto yv = hp::frf(p.M, p.Q, p.K, B.col(0), MatrixXd::Identity(3, 3),
                                MatrixXd::Zero(3, 3), w[k]);
        const double om = w[k];
        for (std::size_t r = 0; r < rows.size(); ++r) {
          const Index i = rows[r];
          cd ref = D(i, 0);
          double scale = std::abs(D(i, 0));
          for (Index j = 0; j < 3; ++j) {
            const cd c(Cy(i, j) - om * om * Ca(i, j), om * Cv(i, j));
            ref += c * yv[static_cast<std::size_t>(j)];
            scale += std::abs(c) * std::abs(yv[static_cast<std::size_t>(j)]);
          }
          const double bound = meth == FrfMethod::real || meth == FrfMethod::modal
                                   ? 1e-10
                                   : std::max(1e-12, 10.0 * 3.0 * testmodels::u / f.rcond()[k]);
          EXPECT_LE(std::abs(f.response()(static_cast<Index>(r), k) - ref), bound * scale)
              << "row " << i << " Omega " << om;
        }
      }
    }
}

// An undamped mass exactly at resonance (k − Ω²m = 0 in floating point) stays a flagged pole
// with a NaN response when the output has C_a and D: the combination never turns it into a number.
TEST(FrfOutputTerms, PoleStaysFlaggedWithAccelerationAndFeedthrough) {
  const LinearModel m =
      LinearModel(scalar(1.0), MatrixXd(), scalar(4.0), scalar(1.0), scalar(1.0), MatrixXd())
          .with_output_terms(scalar(1.0), scalar(1.0));
  Eigen::VectorXd w(2);
  w << 1.0, 2.0;
  FrequencyResponse f(m, with(FrfMethod::direct));
  f.compute(w, 0);
  EXPECT_EQ(f.flags()[0], FrfFlag::ok);
  EXPECT_NEAR(f.response()(0, 0).real(), (1.0 - 1.0) / 3.0 + 1.0, 1e-15);  // (1 − Ω²)/(4 − Ω²) + 1
  EXPECT_EQ(f.flags()[1], FrfFlag::pole);
  EXPECT_TRUE(std::isnan(f.response()(0, 1).real()));
}

// Zero C_a and D are stored empty: the model is the one without them (same path, same numbers).
TEST(FrfOutputTerms, ZeroTermsAreTheModelWithoutThem) {
  const LinearModel plain = single_mass(1.0, 0.5);
  const LinearModel zero = plain.with_output_terms(MatrixXd::Zero(1, 1), MatrixXd::Zero(1, 1));
  EXPECT_FALSE(zero.has_output_accelerations());
  EXPECT_FALSE(zero.has_feedthrough());
  EXPECT_EQ(zero.C_a().size(), 0);
  EXPECT_EQ(zero.D().size(), 0);
  const Eigen::VectorXd w = sweep();
  for (FrfMethod meth : kMethods) {
    FrequencyResponse a(plain, with(meth)), b(zero, with(meth));
    a.compute(w, 0);
    b.compute(w, 0);
    EXPECT_EQ(a.response(), b.response()) << to_string(meth);
    EXPECT_EQ(a.rcond(), b.rcond()) << to_string(meth);
  }
}

TEST(LinearModelOutputTerms, DimensionAndFiniteErrorsNameTheMatrix) {
  MatrixXd Cy = MatrixXd::Zero(2, 3);
  const LinearModel m(MatrixXd::Identity(3, 3), MatrixXd(), MatrixXd::Identity(3, 3),
                      MatrixXd::Zero(3, 1), Cy, MatrixXd());
  auto message = [&m](const MatrixXd& Ca, const MatrixXd& D) -> std::string {
    try {
      (void)m.with_output_terms(Ca, D);
    } catch (const mbsgen::Error& e) {
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_EQ(message(MatrixXd::Ones(3, 3), MatrixXd()),
            "LinearModel::with_output_terms: C_a is 3x3 but must be 2x3 (p x f, the size of C_y)");
  EXPECT_EQ(message(MatrixXd(), MatrixXd::Ones(2, 2)),
            "LinearModel::with_output_terms: D is 2x2 but must be 2x1 (p x m, one row per output, "
            "one column per input)");
  EXPECT_EQ(message(MatrixXd(0, 3), MatrixXd()),  // empty is 0×0 only: 0×3 is a wrong size
            "LinearModel::with_output_terms: C_a is 0x3 but must be 2x3 (p x f, the size of C_y)");
  MatrixXd bad = MatrixXd::Zero(2, 3);
  bad(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(message(bad, MatrixXd()),
            "LinearModel::with_output_terms: C_a (2x3) has a non-finite entry nan at (2,3)");
  EXPECT_THROW((void)m.with_output_terms(bad, MatrixXd()), mbsgen::NonFiniteError);
  EXPECT_THROW((void)m.with_output_terms(MatrixXd::Ones(3, 3), MatrixXd()), mbsgen::DimensionError);
  MatrixXd badD = MatrixXd::Zero(2, 1);
  badD(0, 0) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(message(MatrixXd(), badD),
            "LinearModel::with_output_terms: D (2x1) has a non-finite entry inf at (1,1)");
}

// ---- the kernels' optional output_terms, through GeneratedModel and the solver ----
namespace {

// A hand-written "generated" single mass m ÿ + c ẏ + k y = F, parameters (m, c, k), with the
// outputs y (C_y = 1) and the force on the ground through the elements k y + c ẏ, and by Newton
// F − m ÿ (C_a = −m, D = 1) from output_terms.
int sm_op(const double*, double* y0, double* yd0) {
  y0[0] = 0.0;
  yd0[0] = 0.0;
  return 0;
}
int sm_linear(const double*, const double*, const double* p, double* M, double* Q, double* K,
              double* B, double* Cy, double* Cv) {
  M[0] = p[0];
  Q[0] = p[1];
  K[0] = p[2];
  B[0] = 1.0;
  Cy[0] = 1.0;   // (0,0): y
  Cy[1] = p[2];  // (1,0): k y
  Cy[2] = 0.0;   // (2,0)
  Cv[0] = 0.0;
  Cv[1] = p[1];
  Cv[2] = 0.0;
  return 0;
}
int sm_output_terms(const double*, const double*, const double* p, double* Ca, double* D) {
  Ca[0] = 0.0;
  Ca[1] = 0.0;
  Ca[2] = -p[0];
  D[0] = 0.0;
  D[1] = 0.0;
  D[2] = 1.0;
  return std::isfinite(p[0]) && p[0] < 1e300 ? 0 : 1;
}
const char* const sm_coordinates[] = {"x"};
const char* const sm_coordinate_units[] = {"m"};
const char* const sm_parameters[] = {"m", "c", "k"};
const char* const sm_parameter_units[] = {"kg", "N*s/m", "N/m"};
const double sm_defaults[] = {kM, kC, kK};
const char* const sm_inputs[] = {"F"};
const char* const sm_input_units[] = {"N"};
const char* const sm_outputs[] = {"x", "ground_force_elements", "ground_force_newton"};
const char* const sm_output_units[] = {"m", "N", "N"};

mbsgen::ModelKernels single_mass_kernels() {
  mbsgen::ModelKernels k{"single_mass", "single_mass", "full", mbsgen::kKernelAbiVersion, 1, 1, 3, 3,
                         true, false, 0.0, 0.0, sm_coordinates, sm_coordinate_units, sm_parameters,
                         sm_parameter_units, sm_defaults, sm_inputs, sm_input_units, sm_outputs,
                         sm_output_units, sm_op, sm_linear, nullptr, nullptr};
  return k;  // output_terms left at its default: null, as in a typed API generated before it
}

}  // namespace

TEST(GeneratedModelOutputTerms, KernelFillsCaAndDAndTheFrfFollows) {
  mbsgen::ModelKernels k = single_mass_kernels();
  EXPECT_EQ(k.output_terms, nullptr);
  EXPECT_FALSE(mbsgen::GeneratedModel(k).linear_model().has_output_accelerations());
  k.output_terms = sm_output_terms;
  const LinearModel lin = mbsgen::GeneratedModel(k).linear_model();
  ASSERT_TRUE(lin.has_output_accelerations());
  ASSERT_TRUE(lin.has_feedthrough());
  EXPECT_EQ(lin.C_a(), (MatrixXd(3, 1) << 0.0, 0.0, -kM).finished());
  EXPECT_EQ(lin.D(), (MatrixXd(3, 1) << 0.0, 0.0, 1.0).finished());
  // Both ground forces equal the transmissibility (k + iΩc)ŷ (see the test above).
  const Eigen::VectorXd w = sweep();
  FrequencyResponse f(lin);
  f.compute(w, 0, {1, 2});
  for (Index i = 0; i < w.size(); ++i) {
    const cd ref = cd(kK, w[i] * kC) * y_hat(w[i]);
    const double scale2 = 1.0 + w[i] * w[i] * kM * std::abs(y_hat(w[i]));
    EXPECT_LE(std::abs(f.response()(0, i) - ref), kSingleMassTol * std::abs(ref)) << w[i];
    EXPECT_LE(std::abs(f.response()(1, i) - ref), kSingleMassTol * scale2) << w[i];
  }
  // A failing output_terms kernel is named.
  mbsgen::GeneratedModel bad(k);
  bad.set("m", 1e301);
  try {
    (void)bad.linear_model();
    ADD_FAILURE() << "no error";
  } catch (const mbsgen::NonFiniteError& e) {
    EXPECT_EQ(std::string(e.what()),
              "kernel output_terms of model 'single_mass' returned a non-finite value (check the parameters)");
  }
}

TEST(GeneratedModelOutputTerms, SolverMatricesListCaAndDOnlyWhenPresent) {
  mbsgen::ModelKernels k = single_mass_kernels();
  auto matrices = [&k]() {
    std::vector<std::string> args = {"solve", "matrices"};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    std::ostringstream out, err;
    EXPECT_EQ(mbsgen::cli::solver_main(k, static_cast<int>(argv.size()), argv.data(), out, err), 0)
        << err.str();
    return out.str();
  };
  const std::string without = matrices();
  EXPECT_EQ(without.find("\"C_a\""), std::string::npos);
  EXPECT_EQ(without.find("\"D\""), std::string::npos);
  k.output_terms = sm_output_terms;
  const std::string with_terms = matrices();
  EXPECT_NE(with_terms.find(",\n\"C_a\":[[0],[0],[-2]]"), std::string::npos) << with_terms;
  EXPECT_NE(with_terms.find(",\n\"D\":[[0],[0],[1]]}"), std::string::npos) << with_terms;
}

namespace {

// `mbsgen linear ARGS` in process: its status, standard output and standard error.
int linear_cli(std::vector<std::string> args, std::string& out_text, std::string& err_text) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream out, err;
  const int rc = mbsgen::cli::linear_main(static_cast<int>(argv.size()), argv.data(), out, err);
  out_text = out.str();
  err_text = err.str();
  return rc;
}

// The rows (frequency, re + i im) of `frf --format csv`.
std::vector<std::pair<double, cd>> frf_csv(const std::string& csv) {
  std::vector<std::pair<double, cd>> v;
  std::istringstream s(csv);
  std::string line;
  std::getline(s, line);  // header
  while (std::getline(s, line)) {
    double f = 0, re = 0, im = 0;
    char c1 = 0, c2 = 0;
    std::istringstream l(line);
    l >> f >> c1 >> re >> c2 >> im;
    v.emplace_back(f, cd(re, im));
  }
  return v;
}

}  // namespace

// `mbsgen linear frf --Ca --D`: the sizes are checked against C and B with the library's message
// (status 1, bad data); the two routes to the wall force agree (the docs/cli.md example shows the
// table; here to rounding).
TEST(MbsgenLinearCli, AccelerationAndFeedthroughOptions) {
  const std::string data = std::string(MBSGEN_SOURCE_DIR) + "/tests/runtime/data/";
  auto run = [&data](std::vector<std::string> more, std::string& out_text, std::string& err_text) {
    std::vector<std::string> args = {"linear", "frf", "--M", data + "M.mtx", "--K", data + "K.mtx",
                                     "--Q", data + "Q.mtx", "--B", data + "B.mtx", "--C",
                                     data + "Cwall.mtx", "--Cv", data + "Cvwall.mtx", "--format", "csv",
                                     "--points", "7"};
    args.insert(args.end(), more.begin(), more.end());
    return linear_cli(args, out_text, err_text);
  };
  std::string out, err;
  EXPECT_EQ(run({"--Ca", data + "M.mtx"}, out, err), 1);
  EXPECT_EQ(err, "mbsgen linear: error: LinearModel::with_output_terms: C_a is 3x3 but must be 2x3 (p x f, "
                 "the size of C_y)\n");
  EXPECT_EQ(run({"--D", data + "Cwall.mtx"}, out, err), 1);
  EXPECT_EQ(err, "mbsgen linear: error: LinearModel::with_output_terms: D is 2x3 but must be 2x1 (p x m, "
                 "one row per output, one column per input)\n");
  std::string out1, out2;
  ASSERT_EQ(run({"--Ca", data + "Cawall.mtx", "--D", data + "Dwall.mtx", "--output", "1"}, out1, err), 0) << err;
  ASSERT_EQ(run({"--Ca", data + "Cawall.mtx", "--D", data + "Dwall.mtx", "--output", "2"}, out2, err), 0) << err;
  auto re_im = [](const std::string& csv) {
    std::vector<cd> v;
    for (const auto& row : frf_csv(csv)) v.push_back(row.second);
    return v;
  };
  const auto z1 = re_im(out1), z2 = re_im(out2);
  ASSERT_EQ(z1.size(), 7u);
  ASSERT_EQ(z2.size(), 7u);
  // 1 to 1000 Hz: the Newton route u − Σmᵢÿᵢ has terms of a few N per N at most (about 1 above
  // the modes, where they cancel to 3e-5): its rounding is a few u, and the solve's error
  // n·u/rcond ≤ 2e-14 (rcond ≥ 0.03 here). Seen: 1.6e-16. 1e-12 absolute.
  for (std::size_t i = 0; i < z1.size(); ++i) EXPECT_LE(std::abs(z1[i] - z2[i]), 1e-12) << i;
}

// `mbsgen linear frf --B1 --B2 --D1`: a moving support given as matrices (what a solver's
// `matrices` writes). The base-excited oscillator (models/textbook/base_excited_oscillator.yaml):
// M = m, Q = c, K = k, B = k, B1 = c; x/xb = (k + iΩc)/(k − Ω²m + iΩc), and the relative
// displacement x − xb (C = 1, D = −1) = Ω²m/(k − Ω²m + iΩc), to 1e-12 relative (a 1-DOF solve;
// the CSV's 17 digits). A wrong size is refused with the library's message.
TEST(MbsgenLinearCli, MovingSupportOptions) {
  const std::string dir = ::testing::TempDir();
  auto scalar = [&dir](const std::string& name, double v) {
    const std::string path = dir + "mbsgen_" + name + ".mtx";
    std::ofstream f(path);
    f.precision(17);
    f << "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 " << v << "\n";
    return path;
  };
  const double m = 2, k = 800, c = 8;
  auto run = [&](std::vector<std::string> more, std::string& out_text, std::string& err_text) {
    std::vector<std::string> args = {"linear", "frf", "--M", scalar("M", m), "--K", scalar("K", k), "--Q",
                                     scalar("Q", c), "--B", scalar("B", k), "--B1", scalar("B1", c),
                                     "--format", "csv", "--from", "0.5", "--to", "50", "--points", "9"};
    args.insert(args.end(), more.begin(), more.end());
    return linear_cli(args, out_text, err_text);
  };
  std::string out, err;
  ASSERT_EQ(run({}, out, err), 0) << err;
  const auto absolute = frf_csv(out);
  ASSERT_EQ(absolute.size(), 9u);
  for (const auto& [f, z] : absolute) {
    const double w = 2 * 3.141592653589793 * f;
    const cd T = cd(k, w * c) / cd(k - w * w * m, w * c);
    EXPECT_LE(std::abs(z - T), 1e-12 * std::abs(T)) << f << " Hz";
  }
  ASSERT_EQ(run({"--D", scalar("D", -1)}, out, err), 0) << err;
  const auto relative = frf_csv(out);
  ASSERT_EQ(relative.size(), 9u);
  for (const auto& [f, z] : relative) {
    const double w = 2 * 3.141592653589793 * f;
    const cd rel = w * w * m / cd(k - w * w * m, w * c);
    EXPECT_LE(std::abs(z - rel), 1e-12 * std::abs(rel)) << f << " Hz";
  }
  EXPECT_EQ(run({"--B2", std::string(MBSGEN_SOURCE_DIR) + "/tests/runtime/data/M.mtx"}, out, err), 1);
  EXPECT_NE(err.find("LinearModel::with_input_rates: B2 is 3x3 but must be 1x1"), std::string::npos) << err;
}
