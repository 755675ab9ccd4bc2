// Accuracy against time of every frequency-response method (issue 7 §2,
// docs/accuracy-vs-time.md): on the middle-ear model, the ear-scaled n-mass chain and two hard
// cases of the runtime tests, each method's time per frequency (setup and per-frequency cost
// measured apart) and its relative error against a 266-bit CLN reference (tests/runtime/hp.cpp,
// compiled into this program: exact conversion of the double inputs, Gaussian elimination at
// 80 digits).
//
//   frf_accuracy OUT_DIR [--quick] [--sizes 10,30,100] [--reps R]
//
// Problems: the middle ear, the chain for each size, speaker_box, shaft and the gyroscopic rotor of
// the runtime tests (all methods), and a bandwidth sweep (n = 200, half-bandwidth 2 … 50; direct,
// banded, hessenberg and auto only, error at 5 frequencies).
//
// Writes OUT_DIR/frf.csv (one row per problem and method) and, per problem, OUT_DIR/frf_data/
// <problem>/{M,Q,K,b,c,w,wref,gref}.mtx for the Octave peer (bench/peers/octave_frf.m).
//
// Timing of one method on one problem, F = 100 log-spaced frequencies over the problem's band:
//   loop = compute(F') on an object already set up (FrequencyResponse sets up once per method)
//   and first = construct + compute(one frequency), both medians of R repetitions; per frequency
//   = loop/F', setup = first − per frequency, amortized at F = setup/F + per frequency (auto:
//   first with the F' frequencies, since it picks by their number). F' = F unless F frequencies
//   would take more than 2 s (direct and real on large n).
// Error: max and median over 25 of the F frequencies (every 4th) of |ẑ − ẑ_ref|/|ẑ_ref|; for the
// truncated modal variants also the max over the frequencies below a fifth of the smallest
// neglected |λ| (the band where truncation is meant to hold). A flagged point (NaN) counts as error 1.
#include "harness.hpp"
#include "hp.hpp"
#include "middle_ear_model.hpp"
#include "models.hpp"

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/model/matrix_market.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

#include <complex>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <sstream>
#define lapack_complex_float std::complex<float>
#define lapack_complex_double std::complex<double>
#include <lapacke.h>

using namespace mbsgen;
using Eigen::Index;
using cd = std::complex<double>;
using cf = std::complex<float>;
namespace fs = std::filesystem;

namespace {

constexpr double kTwoPi = 6.283185307179586;
constexpr int kF = 100;        // frequencies per sweep
constexpr int kRefStep = 4;    // error at every 4th: 25 points
constexpr double kLoopBudget = 2.0;  // s per timed sweep, at most

struct Problem {
  std::string name, label;
  LinearModel model;
  Index input = 0, output = 0;
  Eigen::VectorXd omega;               // F timing frequencies [rad/s]
  Eigen::VectorXd omega_ref;           // reference frequencies (subset of omega)
  std::vector<cd> ref;                 // 266-bit reference at omega_ref
};

Eigen::VectorXd log_omegas(double f0_hz, double f1_hz, int count) {
  Eigen::VectorXd w(count);
  for (int k = 0; k < count; ++k) w[k] = kTwoPi * f0_hz * std::pow(f1_hz / f0_hz, k / double(count - 1));
  return w;
}

Problem make(std::string name, std::string label, LinearModel m, Index input, Index output, double f0, double f1,
             int ref_step = kRefStep) {
  Problem p{std::move(name), std::move(label), std::move(m), input, output, log_omegas(f0, f1, kF), {}, {}};
  std::vector<double> wr;
  for (int k = 0; k < kF; k += ref_step) wr.push_back(p.omega[k]);
  p.omega_ref = Eigen::Map<Eigen::VectorXd>(wr.data(), static_cast<Index>(wr.size()));
  const Index n = p.model.size();
  const Index band = n > 30 ? p.model.bandwidth() : -1;  // banded elimination for the chains
  const Eigen::MatrixXd cy = p.model.C_y().row(output), cv = p.model.C_v().row(output);
  for (Index k = 0; k < p.omega_ref.size(); ++k)
    p.ref.push_back(hp::frf(p.model.M(), p.model.Q(), p.model.K(), p.model.B().col(input), cy, cv,
                            p.omega_ref[k], band)[0]);
  return p;
}

LinearModel model_of(const testmodels::Qep& q) { return LinearModel(q.M, q.Q, q.K); }

/// The ear-scaled chain with every mass also coupled to its b − 1 next-but-one neighbours
/// (springs k/j², dampers c/j² to mass i + j, j = 1 … b): half-bandwidth b, for the sweep that
/// places the banded/Hessenberg/direct crossover.
LinearModel wide_chain(int n, int b) {
  const testmodels::Qep q = testmodels::ear_chain(n, true);
  Eigen::MatrixXd K = q.K, Q = q.Q;
  for (int i = 0; i < n; ++i)
    for (int j = 2; j <= b && i + j < n; ++j) {
      const double k = -q.K(i, i + 1) / (j * j), c = -q.Q(i, i + 1) / (j * j);
      K(i, i) += k, K(i + j, i + j) += k, K(i, i + j) -= k, K(i + j, i) -= k;
      Q(i, i) += c, Q(i + j, i + j) += c, Q(i, i + j) -= c, Q(i + j, i) -= c;
    }
  return LinearModel(q.M, Q, K);
}

// ---- single-precision solvers (not in the runtime: "float where it applies") ----------------

/// Complex LU in single precision per frequency (LAPACK cgetrf/cgetrs), dense or banded.
class FloatSolver {
 public:
  FloatSolver(const LinearModel& m, Index input, Index output, bool banded)
      : n_(m.size()), kl_(banded ? m.bandwidth() : 0), banded_(banded) {
    M_ = m.M().cast<float>();
    Q_ = m.Q().cast<float>();
    K_ = m.K().cast<float>();
    b_ = m.B().col(input).cast<float>();
    cy_ = m.C_y().row(output).transpose().cast<float>();
    cv_ = m.C_v().row(output).transpose().cast<float>();
    ipiv_.resize(static_cast<std::size_t>(n_));
    const Index ldab = 3 * kl_ + 1;
    A_.resize(banded_ ? ldab : n_, n_);
    x_.resize(n_);
  }
  std::vector<cd> compute(const Eigen::VectorXd& omega) {
    std::vector<cd> out;
    for (Index k = 0; k < omega.size(); ++k) out.push_back(point(omega[k]));
    return out;
  }
  cd point(double om) {
    const float w = static_cast<float>(om);
    const int n = static_cast<int>(n_);
    if (!banded_) {
      for (Index j = 0; j < n_; ++j)
        for (Index i = 0; i < n_; ++i) A_(i, j) = cf(K_(i, j) - w * w * M_(i, j), w * Q_(i, j));
      x_ = b_.cast<cf>();
      if (LAPACKE_cgesv(LAPACK_COL_MAJOR, n, 1, A_.data(), n, ipiv_.data(), x_.data(), n) != 0)
        return {NAN, NAN};
    } else {
      const int kl = static_cast<int>(kl_), ldab = 3 * kl + 1;
      A_.setZero();
      for (Index j = 0; j < n_; ++j)
        for (Index i = std::max<Index>(0, j - kl_); i <= std::min(n_ - 1, j + kl_); ++i)
          A_(2 * kl_ + i - j, j) = cf(K_(i, j) - w * w * M_(i, j), w * Q_(i, j));
      x_ = b_.cast<cf>();
      if (LAPACKE_cgbsv(LAPACK_COL_MAJOR, n, kl, kl, 1, A_.data(), ldab, ipiv_.data(), x_.data(), n) != 0)
        return {NAN, NAN};
    }
    cf z = 0;
    for (Index i = 0; i < n_; ++i) z += cf(cy_[i], w * cv_[i]) * x_[i];
    return {z.real(), z.imag()};
  }

 private:
  Index n_, kl_;
  bool banded_;
  Eigen::MatrixXf M_, Q_, K_;
  Eigen::VectorXf b_, cy_, cv_;
  Eigen::MatrixXcf A_;
  Eigen::VectorXcf x_;
  std::vector<lapack_int> ipiv_;
};

// ---- variants --------------------------------------------------------------------------------

struct Variant {
  std::string name;
  FrfMethod method = FrfMethod::direct;
  bool balance = true;
  int modal_fraction = 0;   // keep n/modal_fraction mode pairs; 0 all
  bool static_correction = true;
  int single = 0;           // 1 dense float LU, 2 banded float LU
};

std::vector<Variant> variants() {
  std::vector<Variant> v;
  v.push_back({"direct", FrfMethod::direct});
  v.push_back({"banded", FrfMethod::banded});
  v.push_back({"hessenberg", FrfMethod::hessenberg});
  v.push_back({"hessenberg_unbalanced", FrfMethod::hessenberg, false});
  v.push_back({"modal_all", FrfMethod::modal});
  v.push_back({"modal_half", FrfMethod::modal, true, 2, true});
  v.push_back({"modal_half_nosc", FrfMethod::modal, true, 2, false});
  v.push_back({"modal_quarter", FrfMethod::modal, true, 4, true});
  v.push_back({"modal_quarter_nosc", FrfMethod::modal, true, 4, false});
  v.push_back({"real", FrfMethod::real});
  v.push_back({"direct_float", FrfMethod::direct, true, 0, true, 1});
  v.push_back({"banded_float", FrfMethod::banded, true, 0, true, 2});
  v.push_back({"auto", FrfMethod::automatic});
  return v;
}

FrfOptions options_of(const Variant& v, Index n) {
  FrfOptions o;
  o.method = v.method;
  o.balance = v.balance;
  o.modal_modes = v.modal_fraction ? std::max<Index>(1, n / v.modal_fraction) : 0;
  o.static_correction = v.static_correction;
  o.modal_allow_ill_conditioned = true;  // measured, with the warning recorded
  return o;
}

struct Measured {
  std::string used, status = "ok", note;
  double setup = NAN, per_freq = NAN, amortized = NAN, per_min = NAN, per_max = NAN;
  double err_max = NAN, err_median = NAN;
  double band_limit = INFINITY, err_in_band = NAN;  // truncated modal: Ω ≤ |λ_k+1|/5
  int flagged = 0, F_timed = 0, reps = 0, in_band = 0;
  /// From the timed loop (F_timed frequencies on a set-up object) and a fresh object's first
  /// call with `first_frequencies` frequencies.
  void set(const bench::Timing& loop, const bench::Timing& first_call, int first_frequencies) {
    per_freq = loop.median / F_timed;
    per_min = loop.min / F_timed;
    per_max = loop.max / F_timed;
    setup = std::max(0.0, first_call.median - first_frequencies * per_freq);
    amortized = setup / kF + per_freq;
    reps = loop.repetitions;
  }
};

/// Errors of responses g (at omega_ref) against the reference; flagged points (NaN) count as
/// error 1 and are counted. The in-band error is over Ω ≤ r.band_limit.
void errors(const Problem& p, const std::vector<cd>& g, Measured& r) {
  std::vector<double> e;
  r.err_in_band = 0;
  for (std::size_t k = 0; k < p.ref.size(); ++k) {
    double ek = 1.0;
    if (!std::isfinite(g[k].real()) || !std::isfinite(g[k].imag()))
      ++r.flagged;
    else
      ek = std::abs(g[k] - p.ref[k]) / std::abs(p.ref[k]);
    e.push_back(ek);
    if (p.omega_ref[static_cast<Index>(k)] <= r.band_limit) {
      r.err_in_band = std::max(r.err_in_band, ek);
      ++r.in_band;
    }
  }
  r.err_max = *std::max_element(e.begin(), e.end());
  r.err_median = bench::median_of(e);
  if (r.in_band == 0) r.err_in_band = NAN;
}

/// A fifth of the smallest neglected |λ| (pair k + 1): below it the neglected modes respond
/// quasi-statically, to within about (1/5)² = 4 %, which the static correction removes.
double band_limit(const LinearModel& m, Index k) {
  QuadraticEigenOptions o;
  o.one_per_conjugate_pair = true;
  QuadraticEigenSolver s(m.size(), o);
  s.compute(m);
  std::vector<double> l;
  for (const Mode& md : s.modes())
    if (md.kind == EigenvalueKind::finite) l.push_back(std::abs(md.lambda));
  std::sort(l.begin(), l.end());
  return k < static_cast<Index>(l.size()) ? 0.2 * l[static_cast<std::size_t>(k)] : INFINITY;
}

Eigen::VectorXd first(const Eigen::VectorXd& w, int count) {
  // `count` frequencies spread over the band (every k-th), so that cost is representative.
  Eigen::VectorXd out(count);
  for (int k = 0; k < count; ++k)
    out[k] = w[static_cast<Index>(std::llround(k * (w.size() - 1) / std::max(1.0, count - 1.0)))];
  return out;
}

Measured measure(const Problem& p, const Variant& v, int reps) {
  Measured r;
  const Index n = p.model.size();
  const bool band_ok = p.model.bandwidth() <= std::max<Index>(1, n / 4);
  if ((v.method == FrfMethod::banded || v.single == 2) && !band_ok) {
    r.status = "n/a";
    r.note = "dense (bandwidth " + std::to_string(p.model.bandwidth()) + ")";
    return r;
  }
  if (v.single) {
    FloatSolver probe(p.model, p.input, p.output, v.single == 2);
    errors(p, probe.compute(p.omega_ref), r);
    r.used = v.single == 2 ? "banded (float)" : "direct (float)";
    const auto t0 = bench::Clock::now();
    probe.compute(first(p.omega, 8));
    const double per = bench::seconds_since(t0) / 8;
    r.F_timed = per * kF <= kLoopBudget ? kF : std::max(4, static_cast<int>(kLoopBudget / per));
    const Eigen::VectorXd w = first(p.omega, r.F_timed);
    FloatSolver s(p.model, p.input, p.output, v.single == 2);
    const bench::Timing loop = bench::time_calls([&] { s.compute(w); }, reps);
    const Eigen::VectorXd w1 = first(p.omega, 1);
    const bench::Timing one = bench::time_calls([&] {
      FloatSolver fresh(p.model, p.input, p.output, v.single == 2);
      fresh.compute(w1);
    }, reps);
    r.set(loop, one, 1);
    return r;
  }
  if (v.method == FrfMethod::modal && n >= 1000) {
    r.status = "skipped";
    r.note = "eigen-solution of n = 1000 takes about 100 s (modes table)";
    return r;
  }
  const FrfOptions o = options_of(v, n);
  FrfOptions o_acc = o;  // auto: the accuracy of what it picks for the F-frequency sweep
  if (v.method == FrfMethod::automatic) o_acc.method = automatic_frf_method(p.model, kF);
  try {
    if (v.method == FrfMethod::modal && o.modal_modes > 0) r.band_limit = band_limit(p.model, o.modal_modes);
    // Accuracy at the reference frequencies; the same object (set up) then times the loop.
    FrequencyResponse f(p.model, o_acc);
    f.compute(p.omega_ref, p.input, {p.output});
    std::vector<cd> g;
    for (Index k = 0; k < p.omega_ref.size(); ++k) g.push_back(f.response()(0, k));
    errors(p, g, r);
    r.used = to_string(f.method());
    for (const auto& w : f.warnings()) {
      if (!r.note.empty()) r.note += "; ";
      r.note += w.substr(0, std::min<std::size_t>(w.size(), 90));
    }
    const Eigen::VectorXd w8 = first(p.omega, 8);
    const auto t0 = bench::Clock::now();
    f.compute(w8, p.input, {p.output});
    const double per = bench::seconds_since(t0) / 8;
    r.F_timed = per * kF <= kLoopBudget ? kF : std::max(4, static_cast<int>(kLoopBudget / per));
    const Eigen::VectorXd w = first(p.omega, r.F_timed);
    std::unique_ptr<FrequencyResponse> fa;  // auto: what it picks for F' frequencies
    if (v.method == FrfMethod::automatic) {
      fa = std::make_unique<FrequencyResponse>(p.model, o);
      fa->compute(w, p.input, {p.output});
    }
    FrequencyResponse& timed = fa ? *fa : f;
    const bench::Timing loop = bench::time_calls([&] { timed.compute(w, p.input, {p.output}); }, reps);
    r.used = to_string(timed.method());
    // Setup: a fresh object's first call minus that call's frequencies — one frequency, where
    // the per-frequency noise is smallest; auto needs the F' frequencies to pick the same method.
    const Eigen::VectorXd w1 = fa ? w : first(p.omega, 1);
    const bench::Timing one = bench::time_calls([&] {
      FrequencyResponse fresh(p.model, o);
      fresh.compute(w1, p.input, {p.output});
    }, reps);
    r.set(loop, one, static_cast<int>(w1.size()));
  } catch (const mbsgen::Error& e) {
    r.status = "refused";
    std::string what = e.what();
    const auto colon = what.find(": ");
    r.note = (colon == std::string::npos ? what : what.substr(colon + 2)).substr(0, 90);
  }
  return r;
}

void write_octave_data(const Problem& p, const fs::path& dir) {
  fs::create_directories(dir);
  const LinearModel& m = p.model;
  const std::string c = p.label + " (bench/frf_accuracy.cpp)";
  write_matrix_market((dir / "M.mtx").string(), m.M(), MatrixMarketFormat::array, c);
  write_matrix_market((dir / "Q.mtx").string(), m.Q(), MatrixMarketFormat::array, c);
  write_matrix_market((dir / "K.mtx").string(), m.K(), MatrixMarketFormat::array, c);
  write_matrix_market((dir / "b.mtx").string(), Eigen::MatrixXd(m.B().col(p.input)), MatrixMarketFormat::array, c);
  Eigen::MatrixXd C(2, m.size());
  C.row(0) = m.C_y().row(p.output);
  C.row(1) = m.C_v().row(p.output);
  write_matrix_market((dir / "c.mtx").string(), C, MatrixMarketFormat::array, "rows: C_y, C_v of the output");
  write_matrix_market((dir / "w.mtx").string(), Eigen::MatrixXd(p.omega), MatrixMarketFormat::array, "rad/s");
  write_matrix_market((dir / "wref.mtx").string(), Eigen::MatrixXd(p.omega_ref), MatrixMarketFormat::array, "rad/s");
  Eigen::MatrixXd G(static_cast<Index>(p.ref.size()), 2);
  for (std::size_t k = 0; k < p.ref.size(); ++k) G.row(static_cast<Index>(k)) << p.ref[k].real(), p.ref[k].imag();
  write_matrix_market((dir / "gref.mtx").string(), G, MatrixMarketFormat::array, "266-bit reference: re, im");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: frf_accuracy OUT_DIR [--quick] [--sizes 10,30,100] [--reps R] [--only NAME]\n";
    return 2;
  }
  const fs::path out = argv[1];
  bool quick = false;
  std::vector<int> sizes{10, 30, 100, 300, 1000};
  int reps = 5;
  std::string only;
  std::vector<int> sweep_bands{2, 5, 10, 20, 50};
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") {
      quick = true;
      sizes = {10, 30, 100};
      sweep_bands = {2, 10, 50};
      reps = 3;
    } else if (a == "--sizes" && i + 1 < argc) {
      sizes = bench::parse_int_list(argv[++i]);
    } else if (a == "--reps" && i + 1 < argc) {
      reps = std::stoi(argv[++i]);
    } else if (a == "--only" && i + 1 < argc) {
      only = argv[++i];
    }
  }
  (void)quick;
  fs::create_directories(out);
  bench::Csv csv((out / "frf.csv").string(),
                 "problem,label,n,bandwidth,F,method,used,status,setup_s,per_freq_s,amortized_s,"
                 "per_freq_min_s,per_freq_max_s,F_timed,reps,err_max,err_median,flagged,band_limit_hz,err_in_band,"
                 "in_band_points,note");
  if (!csv.ok()) {
    std::cerr << "frf_accuracy: cannot write " << (out / "frf.csv") << "\n";
    return 1;
  }
  std::vector<std::pair<std::string, std::function<Problem()>>> problems;
  problems.emplace_back("middle_ear", [] {
    return make("middle_ear", "middle ear (18 coordinates; P -> v_stapes)", middle_ear::linear_model(), 0,
                static_cast<Index>(middle_ear::Output::v_stapes), 100, 10000);
  });
  for (int n : sizes)
    problems.emplace_back("chain_" + std::to_string(n), [n] {
      return make("chain_" + std::to_string(n), "ear-scaled chain, n = " + std::to_string(n),
                  model_of(testmodels::ear_chain(n, true)), 0, 0, 100, 20000);
    });
  problems.emplace_back("speaker_box", [] {
    return make("speaker_box", "speaker_box-like (n = 12; norms 1, 1e-3, 1e7)",
                model_of(testmodels::speaker_box_like(12)), 0, 0, 0.01, 1000);
  });
  problems.emplace_back("shaft", [] {
    return make("shaft", "shaft-like (n = 12; M singular, one damper)", model_of(testmodels::shaft_like(12)), 0, 0,
                1, 1000);
  });
  problems.emplace_back("rotor", [] {
    return make("rotor", "gyroscopic rotor at 3e4 rad/s (n = 4; undamped, tau = 32)",
                model_of(testmodels::rotor(3e4)), 0, 0, 1, 10000);
  });
  const std::size_t sweep_from = problems.size();
  for (int b : sweep_bands)
    problems.emplace_back("band_" + std::to_string(b), [b] {
      return make("band_" + std::to_string(b), "chain n = 200 with half-bandwidth " + std::to_string(b),
                  wide_chain(200, b), 0, 0, 100, 20000, 20);
    });
  bench::Csv autos((out / "frf_auto.csv").string(), "problem,n,bandwidth,frequencies,auto");
  std::size_t index = 0;
  for (auto& [name, build] : problems) {
    const bool sweep = index++ >= sweep_from;
    if (!only.empty() && name != only) continue;
    const auto t0 = bench::Clock::now();
    const Problem p = build();
    std::cerr << "frf_accuracy: " << p.label << " (reference " << bench::num(bench::seconds_since(t0)) << " s)\n";
    write_octave_data(p, out / "frf_data" / p.name);
    for (Index F : {1, 3, 10, 30, 100, 1000, 10000})
      autos.row({p.name, std::to_string(p.model.size()), std::to_string(p.model.bandwidth()), std::to_string(F),
                 to_string(automatic_frf_method(p.model, F))});
    for (const Variant& v : variants()) {
      if (sweep && v.name != "direct" && v.name != "banded" && v.name != "hessenberg" && v.name != "auto") continue;
      const auto t1 = bench::Clock::now();
      const Measured r = measure(p, v, reps);
      csv.row({p.name, p.label, std::to_string(p.model.size()), std::to_string(p.model.bandwidth()),
               std::to_string(kF), v.name, r.used, r.status, bench::num(r.setup), bench::num(r.per_freq),
               bench::num(r.amortized), bench::num(r.per_min), bench::num(r.per_max), std::to_string(r.F_timed),
               std::to_string(r.reps), bench::num(r.err_max), bench::num(r.err_median), std::to_string(r.flagged),
               std::isfinite(r.band_limit) ? bench::num(r.band_limit / kTwoPi) : "", bench::num(r.err_in_band),
               std::to_string(r.in_band), r.note});
      std::cerr << "  " << v.name << ": " << r.status << " " << bench::num(r.amortized) << " s/freq, err "
                << bench::num(r.err_max) << " in band " << bench::num(r.err_in_band) << " (" << bench::num(bench::seconds_since(t1)) << " s)\n";
    }
  }
  return 0;
}
