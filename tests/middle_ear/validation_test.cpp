// Validation of the middle-ear model against reference data: the stapes velocity transfer
// function H(f) = V_stapes/P_ec computed with the runtime library (LinearModel,
// FrequencyResponse, QuadraticEigenSolver) from the generated kernel at the model's default
// parameters, compared with the band of models/middle_ear/reference.csv (lumped-model range
// widened by the Aibara 2001 and Goode 1994 points; see the file's header for provenance) and
// with the tympanometric resonance range of live adults.
#include "middle_ear_kernel.hpp"

#include <mbsgen/runtime/spectral/frequency_response.hpp>
#include <mbsgen/runtime/spectral/quadratic_eigen.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace middle_ear_test {
namespace {

constexpr double kPi = 3.141592653589793;
// ±6 dB around the band (itself 2-10 dB wide: three lumped models and two measurement series):
// the tolerance for a model whose parameters are mostly [U], fixed before the results
// were known and not tuned to them.
const double kSixDb = std::pow(10.0, 6.0 / 20.0);
// Rigid ossicles are a fair assumption up to about 3.5 kHz (FE study cited in the notes); the band
// has points at 2 and 4 kHz, so it is checked from 100 Hz to 4 kHz, the upper end of the issue's
// 3-4 kHz (between 3.5 and 4 kHz the rigid assumption is already marginal).
constexpr double kRigidLimitHz = 4000;
// Multifrequency tympanometry in live adults: typically 800-1200 Hz, means 1049 Hz (SD 261) and
// 965 Hz (SD 234); the range for the main resonance.
constexpr double kResonanceLoHz = 800, kResonanceHiHz = 1300;
constexpr double kToMmPerS = 1e3;  // (m/s)/Pa -> (mm/s)/Pa

struct BandRow {
  double f_hz, lumped_min, lumped_max, phase_min, phase_max, band_lo, band_hi;
};

double cell(const std::string& s) { return s.empty() ? std::nan("") : std::stod(s); }

std::vector<BandRow> read_reference() {
  const std::string path = std::string(MBSGEN_SOURCE_DIR) + "/models/middle_ear/reference.csv";
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::vector<BandRow> rows;
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header) {  // f_hz,lumped_min,lumped_max,phase_min_deg,phase_max_deg,aibara,goode,band_lo,band_hi
      header = false;
      continue;
    }
    std::vector<std::string> c;
    std::stringstream ss(line);
    std::string item;
    while (std::getline(ss, item, ',')) c.push_back(item);
    while (c.size() < 9) c.emplace_back();
    rows.push_back({cell(c[0]), cell(c[1]), cell(c[2]), cell(c[3]), cell(c[4]), cell(c[7]), cell(c[8])});
  }
  return rows;
}

// Band edge at f: log|H| linear in log f between rows; below the first row |H| ∝ f
// (stiffness-dominated, +6 dB/octave, as the CSV header says); NaN above the last row.
double band_edge(const std::vector<BandRow>& rows, double f, bool upper) {
  const auto edge = [&](const BandRow& r) { return upper ? r.band_hi : r.band_lo; };
  if (f <= rows.front().f_hz) return edge(rows.front()) * f / rows.front().f_hz;
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (f <= rows[i].f_hz) {
      const double t = std::log(f / rows[i - 1].f_hz) / std::log(rows[i].f_hz / rows[i - 1].f_hz);
      return std::exp((1 - t) * std::log(edge(rows[i - 1])) + t * std::log(edge(rows[i])));
    }
  return std::nan("");
}

struct Model {
  Linear L = generated_linear(default_parameters());
  // The ear-canal pressure's column (the others move the temporal bone: bone conduction).
  mbsgen::LinearModel lm{L.M, L.Q, L.K, L.B.col(index_of(middle_ear_input_names, kNu, "P")), L.Cy, L.Cv,
                         coordinate_names(), {"P"}, output_names()};
};

// H (in (mm/s)/Pa) for the output `name` at the frequencies f_hz, by the direct (LU) method.
Eigen::VectorXcd response(const Model& m, const std::vector<double>& f_hz, const std::string& name) {
  Eigen::VectorXd w(static_cast<Eigen::Index>(f_hz.size()));
  for (std::size_t k = 0; k < f_hz.size(); ++k) w[static_cast<Eigen::Index>(k)] = 2 * kPi * f_hz[k];
  mbsgen::FrfOptions opt;
  opt.method = mbsgen::FrfMethod::direct;
  mbsgen::FrequencyResponse fr(m.lm, opt);
  fr.compute(w, 0, {output_index(name)});
  EXPECT_EQ(fr.info(), Eigen::Success);
  for (std::size_t k = 0; k < f_hz.size(); ++k)
    EXPECT_EQ(fr.flags()[k], mbsgen::FrfFlag::ok) << f_hz[k] << " Hz, rcond " << fr.rcond()[static_cast<Eigen::Index>(k)];
  return fr.response().row(0).transpose() * kToMmPerS;
}

std::vector<double> log_grid(double f0, double f1, int count) {
  std::vector<double> f;
  for (int k = 0; k < count; ++k) f.push_back(f0 * std::pow(f1 / f0, k / double(count - 1)));
  return f;
}

double db(double ratio) { return 20 * std::log10(ratio); }

TEST(MiddleEarValidation, StapesVelocityWithinReferenceBandUpTo4kHz) {
  const std::vector<BandRow> rows = read_reference();
  ASSERT_EQ(rows.size(), 6u);
  const Model m;
  const std::vector<double> f = log_grid(100, 10000, 401);
  const Eigen::VectorXcd H = response(m, f, "v_stapes");
  double worst_below = 0, worst_above = 0;  // dB outside the unwidened band (≥ 0)
  for (std::size_t k = 0; k < f.size(); ++k) {
    if (f[k] > kRigidLimitHz * (1 + 1e-12)) break;
    const double a = std::abs(H[static_cast<Eigen::Index>(k)]);
    const double lo = band_edge(rows, f[k], false), hi = band_edge(rows, f[k], true);
    EXPECT_GE(a, lo / kSixDb) << f[k] << " Hz";
    EXPECT_LE(a, hi * kSixDb) << f[k] << " Hz";
    worst_below = std::max(worst_below, db(lo / a));
    worst_above = std::max(worst_above, db(a / hi));
  }
  std::printf("largest excursion outside the unwidened band, 100 Hz-4 kHz: %.2f dB below, %.2f dB above\n",
              worst_below, worst_above);

  // The table of docs/middle-ear.md: |H| and phase at the band frequencies.
  std::vector<double> table_f = {100};
  for (const auto& r : rows) table_f.push_back(r.f_hz);
  table_f.push_back(10000);
  const Eigen::VectorXcd Ht = response(m, table_f, "v_stapes");
  std::printf("%8s %10s %9s %17s %9s %17s\n", "f [Hz]", "|H| model", "phase", "band", "vs band",
              "lumped phase");
  for (std::size_t k = 0; k < table_f.size(); ++k) {
    const double a = std::abs(Ht[static_cast<Eigen::Index>(k)]);
    const double ph = std::arg(Ht[static_cast<Eigen::Index>(k)]) * 180 / kPi;
    const double lo = band_edge(rows, table_f[k], false), hi = band_edge(rows, table_f[k], true);
    const double off = a < lo ? db(a / lo) : a > hi ? db(a / hi) : 0.0;
    const BandRow* r = nullptr;
    for (const auto& row : rows)
      if (row.f_hz == table_f[k]) r = &row;
    if (std::isnan(lo))
      std::printf("%8.0f %10.4f %8.1f° %17s %10s", table_f[k], a, ph, "-", "-");
    else
      std::printf("%8.0f %10.4f %8.1f° %8.4f-%-8.4f %+8.2fdB", table_f[k], a, ph, lo, hi, off);
    if (r && !std::isnan(r->phase_min)) std::printf("  %+5.0f…%+4.0f°", r->phase_min, r->phase_max);
    std::printf("\n");
  }
}

TEST(MiddleEarValidation, MainResonanceBetween800And1300Hz) {
  const Model m;
  // Peak of |H| on a fine grid (0.25 % steps).
  const std::vector<double> f = log_grid(100, 10000, 1845);
  const Eigen::VectorXcd H = response(m, f, "v_stapes");
  Eigen::Index peak = 0;
  H.cwiseAbs().maxCoeff(&peak);
  const double f_peak = f[static_cast<std::size_t>(peak)];
  std::printf("peak |H| = %.4f (mm/s)/Pa at %.0f Hz\n", std::abs(H[peak]), f_peak);
  EXPECT_GE(f_peak, kResonanceLoHz);
  EXPECT_LE(f_peak, kResonanceHiHz);

  // Where the umbo velocity is in phase with the pressure (zero reactance of the admittance at
  // the umbo, what tympanometry calls the resonance).
  const Eigen::VectorXcd U = response(m, f, "v_umbo");
  for (Eigen::Index k = 1; k < U.size(); ++k)
    if (std::arg(U[k - 1]) > 0 && std::arg(U[k]) <= 0)
      std::printf("umbo velocity in phase with the pressure at %.0f Hz\n", f[static_cast<std::size_t>(k)]);

  // Modes: the lowest oscillatory (underdamped) mode is the main resonance.
  mbsgen::QuadraticEigenOptions opt;
  opt.one_per_conjugate_pair = true;
  mbsgen::QuadraticEigenSolver qe(kN, opt);
  qe.compute(m.lm);
  ASSERT_EQ(qe.info(), Eigen::Success);
  // The runtime's own bar for a trustworthy eigenpair (docs/runtime.md): η ≤ 100·f·u.
  EXPECT_LE(qe.max_backward_error(), 100 * kN * 1.1102230246251565e-16);
  std::printf("modes (%s scaling): f_n [Hz], zeta, damped f [Hz]\n", qe.method().c_str());
  const mbsgen::Mode* main_mode = nullptr;
  for (const auto& mode : qe.modes()) {
    ASSERT_EQ(mode.kind, mbsgen::EigenvalueKind::finite);
    EXPECT_LT(mode.lambda.real(), 0);  // every mode decays: the chain is held and damped
    std::printf("  %10.1f %7.3f %10.1f%s\n", mode.natural_frequency_hz, mode.damping_ratio,
                mode.damped_frequency_hz, mode.lambda.imag() == 0 ? "  (overdamped, real)" : "");
    if (!main_mode && mode.lambda.imag() > 0) main_mode = &mode;
  }
  ASSERT_NE(main_mode, nullptr);
  EXPECT_GE(main_mode->natural_frequency_hz, kResonanceLoHz);
  EXPECT_LE(main_mode->natural_frequency_hz, kResonanceHiHz);
}

// Stiffness-dominated below the resonance (Chien et al. 2009, live ears: phase about +72° at
// 0.3 kHz; the lumped models +73…+77° at 250 Hz): the phase of V/P lies closer to the +90° of a
// pure stiffness than to the 0° of a resistance or the −90° of a mass, i.e. within 45° of +90°,
// from 100 to 400 Hz. (V_stapes/P is a transfer, not a driving-point, function, so a phase
// slightly above +90° is not unphysical: the model has 90.04° at 100 Hz, near the real poles
// of the incudostapedial dashpot.)
TEST(MiddleEarValidation, StiffnessDominatedBelowResonance) {
  const Model m;
  const std::vector<double> f = log_grid(100, 400, 61);
  const Eigen::VectorXcd H = response(m, f, "v_stapes");
  for (std::size_t k = 0; k < f.size(); ++k) {
    const double ph = std::arg(H[static_cast<Eigen::Index>(k)]) * 180 / kPi;
    EXPECT_LT(std::abs(ph - 90), 45) << f[k] << " Hz";
  }
}

// The force of the stapes on the cochlea per ear-canal pressure (output F_cochlea, scene
// stapes_force): through the world-fixed annular ligament it is (k_z + iΩ d_z) times the medial
// footplate displacement, d_z including the cochlear load (Aibara et al. 2001's 21.1 GΩ on a
// 3.2 mm² footplate). Checked against that relation from the parameters at 0.5, 1 and 4 kHz; the
// magnitude at 1 kHz is quoted in docs/middle-ear.md.
TEST(MiddleEarValidation, CochlearForceIsTheAnnularLigamentLoad) {
  const Model m;
  const Parameters p = default_parameters();
  const std::vector<double> f = {500, 1000, 4000};
  const Eigen::VectorXcd F = response(m, f, "F_cochlea") / kToMmPerS, x = response(m, f, "x_stapes") / kToMmPerS;
  const double k = p.at("k_al_z"), d = p.at("d_al_z") + p.at("d_cochlea_z");
  for (std::size_t i = 0; i < f.size(); ++i) {
    const auto j = static_cast<Eigen::Index>(i);
    const std::complex<double> expected = std::complex<double>(k, 2 * kPi * f[i] * d) * x[j];
    // Both rows come from the same solve: 1e-12 relative is rounding in the output rows.
    EXPECT_LE(std::abs(F[j] - expected), 1e-12 * std::abs(expected)) << f[i] << " Hz";
  }
  std::printf("|F_cochlea / P| at 1 kHz: %.4g N/Pa (phase %.1f deg)\n", std::abs(F[1]), std::arg(F[1]) * 180 / kPi);
}

}  // namespace
}  // namespace middle_ear_test
