// Runtime benchmarks (issue 3 §7): frequency response of an ear-scaled n-mass chain, 1000
// log-spaced frequencies 100 Hz-20 kHz, one input (force on mass 1) and one output (displacement
// of mass 1), by each method; modes of the 1000-mass chain beside a bare LAPACK dggev call on the
// same (unscaled, unbalanced) companion pencil.
//
//   runtime_bench [google-benchmark flags]       run the benchmarks
//   runtime_bench --write-matrices DIR           write DIR/chain_<n>/{M,Q,K}.mtx for Octave
//
// Counters: s_per_freq = seconds per frequency including the one-time setup amortized over the
// call; max_rel_err = largest |g − g_ref|/|g_ref| against direct (complex LU per frequency,
// backward stable; every 50th frequency for n > 200).
#include <benchmark/benchmark.h>

#include <cmath>
#include <complex>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#define lapack_complex_float std::complex<float>
#define lapack_complex_double std::complex<double>
#include <lapacke.h>

#include "mbsgen/runtime/runtime.hpp"

using namespace mbsgen;

namespace {

constexpr double kTwoPi = 6.283185307179586;

/// Ear-scaled chain (as tests/runtime/models.hpp): masses 1e-6..3e-5 kg, springs 1e2..1e4 N/m,
/// dampers 2e-3..2e-4 N·s/m, both ends grounded.
LinearModel chain(int n) {
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n), K = M, Q = M;
  auto add = [n](Eigen::MatrixXd& A, int i, double v) {  // element between i−1 and i
    if (i > 0) A(i - 1, i - 1) += v;
    if (i < n) A(i, i) += v;
    if (i > 0 && i < n) {
      A(i - 1, i) -= v;
      A(i, i - 1) -= v;
    }
  };
  for (int i = 0; i < n; ++i) M(i, i) = 1e-6 * std::pow(30.0, i / double(std::max(1, n - 1)));
  for (int i = 0; i <= n; ++i) {
    add(K, i, 1e2 * std::pow(100.0, i / double(n)));
    add(Q, i, 2e-3 * std::pow(0.1, i / double(n)));
  }
  return LinearModel(M, Q, K);
}

Eigen::VectorXd omegas(int count) {
  Eigen::VectorXd w(count);
  for (int k = 0; k < count; ++k) w[k] = kTwoPi * 100.0 * std::pow(200.0, k / double(count - 1));
  return w;
}

const LinearModel& cached_chain(int n) {
  static std::map<int, LinearModel> cache;
  auto it = cache.find(n);
  if (it == cache.end()) it = cache.emplace(n, chain(n)).first;
  return it->second;
}

/// Reference receptance by direct (complex LU per frequency, backward stable): at all
/// frequencies for n ≤ 200, at every 50th for larger n (NaN elsewhere: not compared).
const Eigen::VectorXcd& reference(int n, int count) {
  static std::map<std::pair<int, int>, Eigen::VectorXcd> cache;
  auto key = std::make_pair(n, count);
  auto it = cache.find(key);
  if (it == cache.end()) {
    const int step = n > 200 ? 50 : 1;
    const Eigen::VectorXd w = omegas(count);
    Eigen::VectorXd ws((count + step - 1) / step);
    for (int k = 0; k < ws.size(); ++k) ws[k] = w[k * step];
    FrfOptions o;
    o.method = FrfMethod::direct;
    FrequencyResponse f(cached_chain(n), o);
    f.compute(ws, 0, {0});
    Eigen::VectorXcd g = Eigen::VectorXcd::Constant(count, std::complex<double>(NAN, NAN));
    for (int k = 0; k < ws.size(); ++k) g[k * step] = f.response()(0, k);
    it = cache.emplace(key, g).first;
  }
  return it->second;
}

void BM_frf(benchmark::State& st, FrfMethod method, bool balance) {
  const int n = static_cast<int>(st.range(0)), count = static_cast<int>(st.range(1));
  const LinearModel& m = cached_chain(n);
  const Eigen::VectorXd w = omegas(count);
  FrfOptions o;
  o.method = method;
  o.balance = balance;
  o.modal_allow_ill_conditioned = true;  // the bench measures cost; accuracy is the counter
  double err = 0;
  for (auto _ : st) {
    FrequencyResponse f(m, o);  // setup included: one call = reduction + all frequencies
    f.compute(w, 0, {0});
    benchmark::DoNotOptimize(f.response().data());
    st.PauseTiming();
    const Eigen::VectorXcd& ref = reference(n, count);
    err = 0;
    for (int k = 0; k < count; ++k)
      if (std::isfinite(ref[k].real()))
        err = std::max(err, std::abs(f.response()(0, k) - ref[k]) / std::abs(ref[k]));
    st.ResumeTiming();
  }
  st.counters["s_per_freq"] =
      benchmark::Counter(count, benchmark::Counter::kIsIterationInvariantRate |
                                    benchmark::Counter::kInvert);
  st.counters["max_rel_err"] = err;
}

void BM_modes(benchmark::State& st) {
  const int n = static_cast<int>(st.range(0));
  const LinearModel& m = cached_chain(n);
  QuadraticEigenOptions o;
  double worst = 0;
  for (auto _ : st) {
    QuadraticEigenSolver s(n, o);
    s.compute(m);
    worst = s.max_backward_error();
    benchmark::DoNotOptimize(s.modes().data());
  }
  st.counters["max_backward_error"] = worst;
}

/// Bare LAPACK dggev (right eigenvectors only) on the unscaled companion pencil
/// λ diag(E, M) − [[0, E], [−K, −Q]] of the same chain.
void BM_dggev_bare(benchmark::State& st) {
  const int n = static_cast<int>(st.range(0)), N = 2 * n;
  const LinearModel& m = cached_chain(n);
  Eigen::MatrixXd A0 = Eigen::MatrixXd::Zero(N, N), B0 = A0;
  A0.topRightCorner(n, n).setIdentity();
  A0.bottomLeftCorner(n, n) = -m.K();
  A0.bottomRightCorner(n, n) = -m.Q();
  B0.topLeftCorner(n, n).setIdentity();
  B0.bottomRightCorner(n, n) = m.M();
  Eigen::VectorXd ar(N), ai(N), be(N);
  Eigen::MatrixXd VR(N, N);
  double vl = 0;
  for (auto _ : st) {
    Eigen::MatrixXd A = A0, B = B0;
    LAPACKE_dggev(LAPACK_COL_MAJOR, 'N', 'V', N, A.data(), N, B.data(), N, ar.data(), ai.data(),
                  be.data(), &vl, 1, VR.data(), N);
    benchmark::DoNotOptimize(VR.data());
  }
}

void register_all() {
  const std::vector<int> sizes{10, 15, 20, 30, 50, 200, 1000};
  for (int n : sizes) {
    // direct is O(n³) per frequency: at n = 1000 time 20 frequencies, the per-frequency cost is
    // what is compared.
    const int fdirect = n >= 1000 ? 20 : (n >= 200 ? 200 : 1000);
    benchmark::RegisterBenchmark(("frf/direct/n=" + std::to_string(n)).c_str(), BM_frf,
                                 FrfMethod::direct, true)
        ->Args({n, fdirect})->Unit(benchmark::kMillisecond)->Iterations(n >= 200 ? 1 : 3);
    benchmark::RegisterBenchmark(("frf/hessenberg/n=" + std::to_string(n)).c_str(), BM_frf,
                                 FrfMethod::hessenberg, true)
        ->Args({n, 1000})->Unit(benchmark::kMillisecond)->Iterations(n >= 1000 ? 1 : 3);
    benchmark::RegisterBenchmark(("frf/banded/n=" + std::to_string(n)).c_str(), BM_frf,
                                 FrfMethod::banded, true)
        ->Args({n, 1000})->Unit(benchmark::kMillisecond)->Iterations(3);
  }
  for (int n : {50, 200}) {
    benchmark::RegisterBenchmark(("frf/hessenberg_unbalanced/n=" + std::to_string(n)).c_str(),
                                 BM_frf, FrfMethod::hessenberg, false)
        ->Args({n, 1000})->Unit(benchmark::kMillisecond)->Iterations(1);
    benchmark::RegisterBenchmark(("frf/real/n=" + std::to_string(n)).c_str(), BM_frf,
                                 FrfMethod::real, true)
        ->Args({n, 200})->Unit(benchmark::kMillisecond)->Iterations(1);
    benchmark::RegisterBenchmark(("frf/modal/n=" + std::to_string(n)).c_str(), BM_frf,
                                 FrfMethod::modal, true)
        ->Args({n, 1000})->Unit(benchmark::kMillisecond)->Iterations(1);
  }
  for (int n : {200, 1000}) {
    benchmark::RegisterBenchmark(("modes/mbsgen/n=" + std::to_string(n)).c_str(), BM_modes)
        ->Arg(n)->Unit(benchmark::kSecond)->Iterations(1);
    benchmark::RegisterBenchmark(("modes/dggev_bare/n=" + std::to_string(n)).c_str(),
                                 BM_dggev_bare)
        ->Arg(n)->Unit(benchmark::kSecond)->Iterations(1);
  }
}

int write_matrices(const std::string& dir) {
  for (int n : {10, 50, 200, 1000}) {
    const std::filesystem::path d = std::filesystem::path(dir) / ("chain_" + std::to_string(n));
    std::filesystem::create_directories(d);
    const LinearModel& m = cached_chain(n);
    const std::string c = "ear-scaled chain, n = " + std::to_string(n) + " (bench/runtime_bench.cpp)";
    write_matrix_market((d / "M.mtx").string(), m.M(), MatrixMarketFormat::coordinate, c);
    write_matrix_market((d / "Q.mtx").string(), m.Q(), MatrixMarketFormat::coordinate, c);
    write_matrix_market((d / "K.mtx").string(), m.K(), MatrixMarketFormat::coordinate, c);
    // our response at the 1000 frequencies (banded LU, checked against direct by the bench),
    // for Octave's error
    FrfOptions ob;
    ob.method = FrfMethod::banded;
    FrequencyResponse fb(m, ob);
    fb.compute(omegas(1000), 0, {0});
    const Eigen::VectorXcd g = fb.response().row(0).transpose();
    Eigen::MatrixXd G(g.size(), 2);
    G.col(0) = g.real();
    G.col(1) = g.imag();
    write_matrix_market((d / "g_ref.mtx").string(), G, MatrixMarketFormat::array,
                        "receptance y1/u1 at 1000 log-spaced frequencies 100 Hz..20 kHz");
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::strcmp(argv[1], "--write-matrices") == 0) return write_matrices(argv[2]);
  register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
