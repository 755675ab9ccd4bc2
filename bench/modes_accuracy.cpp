// Modes: accuracy against time (issue 7 §3, docs/accuracy-vs-time.md) on undamped symmetric
// problems, where all three routes apply:
//   qz        QuadraticEigenSolver with the symmetric fast path off: the full scaled QZ of the
//             2f×2f companion pencil (dggevx, balancing, left and right vectors, residuals);
//   symmetric QuadraticEigenSolver's fast path: dsygvd on K v = ω² M v (all f, with vectors);
//   partial   LAPACK dsygvx for the lowest k eigenpairs only (the runtime has no partial path;
//             this is the bare LAPACK call, with vectors).
// Error: largest relative error of the lowest k natural frequencies ω against a reference in
// 80-digit CLN: for the chains (K tridiagonal, M diagonal) bisection on the inertia of K − σM
// (Sylvester: the number of negative pivots of its LDLᵀ is the number of ω² below σ), for the
// middle ear Newton refinement of each eigenpair (tests/runtime/hp.cpp). k = min(f, 20).
//
//   modes_accuracy OUT_DIR [--quick] [--sizes 10,30,100] [--reps R] [--qz-max N]
//
// The full QZ is skipped above n = 300 (--qz-max): at n = 1000 it takes minutes.
// Writes OUT_DIR/modes.csv and OUT_DIR/modes_data/<problem>/{M,K,wref}.mtx for Octave's polyeig
// (bench/peers/octave_polyeig.m).
#include "harness.hpp"
#include "hp.hpp"
#include "middle_ear_model.hpp"
#include "models.hpp"

#include "mbsgen/runtime/model/matrix_market.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

#include <complex>
#include <filesystem>
#include <iostream>
#include <sstream>
#define lapack_complex_float std::complex<float>
#define lapack_complex_double std::complex<double>
#include <lapacke.h>

using namespace mbsgen;
using Eigen::Index;
namespace fs = std::filesystem;

namespace {

struct Problem {
  std::string name, label;
  Eigen::MatrixXd M, K;
  Index k = 0;                // lowest k compared
  std::vector<double> omega;  // reference ω of the lowest k [rad/s]
};

/// ω² of the lowest k of K v = ω² M v for M diagonal > 0, K tridiagonal symmetric, by bisection
/// on the inertia of K − σM in CLN, each bracketed around the double estimate `guess`.
std::vector<double> chain_reference(const Eigen::MatrixXd& M, const Eigen::MatrixXd& K, const Eigen::VectorXd& guess) {
  const Index n = M.rows();
  std::vector<hp::cl_R> d(static_cast<std::size_t>(n)), e(static_cast<std::size_t>(n)), m(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    d[static_cast<std::size_t>(i)] = hp::real(K(i, i));
    m[static_cast<std::size_t>(i)] = hp::real(M(i, i));
    if (i > 0) e[static_cast<std::size_t>(i)] = hp::real(K(i, i - 1)) * hp::real(K(i, i - 1));
  }
  auto below = [&](const hp::cl_R& s) {  // number of eigenvalues ω² < s
    Index count = 0;
    hp::cl_R p = 0;
    const hp::cl_R tiny = cln::cl_float(1, hp::precision()) / cln::expt(cln::cl_I(10), 70);
    for (Index i = 0; i < n; ++i) {
      const auto u = static_cast<std::size_t>(i);
      p = d[u] - s * m[u] - (i > 0 ? e[u] / p : hp::cl_R(0));
      if (cln::zerop(p)) p = tiny;
      if (cln::minusp(p)) ++count;
    }
    return count;
  };
  std::vector<double> out;
  for (Index j = 0; j < guess.size(); ++j) {
    hp::cl_R lo = hp::real(guess[j] * (1 - 1e-7)), hi = hp::real(guess[j] * (1 + 1e-7));
    for (int widen = 0; below(lo) > j && widen < 60; ++widen) lo = lo / 2;
    for (int widen = 0; below(hi) < j + 1 && widen < 60; ++widen) hi = hi * 2;
    for (int it = 0; it < 200; ++it) {
      const hp::cl_R mid = (lo + hi) / 2;
      if (below(mid) > j)
        hi = mid;
      else
        lo = mid;
      if (hi - lo <= hi * cln::cl_float(1, hp::precision()) / cln::expt(cln::cl_I(10), 30)) break;
    }
    out.push_back(hp::to_double(cln::sqrt((lo + hi) / 2)));
  }
  return out;
}

/// dsygvx: lowest k of K v = ω² M v with vectors; returns ω² (empty on failure).
Eigen::VectorXd partial(const Eigen::MatrixXd& M, const Eigen::MatrixXd& K, Index k, Eigen::MatrixXd& Z) {
  const int n = static_cast<int>(M.rows());
  Eigen::MatrixXd A = K, B = M;
  Eigen::VectorXd w(n);
  Z.resize(n, k);
  std::vector<lapack_int> ifail(static_cast<std::size_t>(n));
  lapack_int found = 0;
  const lapack_int info = LAPACKE_dsygvx(LAPACK_COL_MAJOR, 1, 'V', 'I', 'L', n, A.data(), n, B.data(), n, 0.0, 0.0, 1,
                                         static_cast<lapack_int>(k), 2 * LAPACKE_dlamch('S'), &found, w.data(), Z.data(),
                                         n, ifail.data());
  if (info != 0 || found != k) return {};
  return w.head(k);
}

std::vector<double> lowest_omegas(const QuadraticEigenSolver& s, Index k) {
  std::vector<double> w;
  for (const Mode& m : s.modes())
    if (m.kind == EigenvalueKind::finite && static_cast<Index>(w.size()) < k) w.push_back(std::abs(m.lambda));
  return w;
}

double max_rel(const std::vector<double>& a, const std::vector<double>& ref) {
  if (a.size() < ref.size()) return NAN;
  double e = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) e = std::max(e, std::abs(a[i] - ref[i]) / ref[i]);
  return e;
}

Problem chain_problem(int n) {
  const testmodels::Qep q = testmodels::ear_chain(n, false);
  Problem p{"chain_" + std::to_string(n), "ear-scaled chain, undamped, n = " + std::to_string(n), q.M, q.K,
            std::min<Index>(n, 20), {}};
  Eigen::MatrixXd Z;
  const Eigen::VectorXd guess = partial(p.M, p.K, p.k, Z);
  p.omega = chain_reference(p.M, p.K, guess);
  return p;
}

Problem middle_ear_problem() {
  const LinearModel lm = middle_ear::linear_model();
  Problem p{"middle_ear", "middle ear, undamped (Q = 0), n = 18", lm.M(), lm.K(), 18, {}};
  // The symmetric fast path needs exact symmetry; the generated M and K are (docs/generator.md).
  QuadraticEigenOptions o;
  o.one_per_conjugate_pair = true;
  QuadraticEigenSolver s(p.M.rows(), o);
  s.compute(p.M, Eigen::MatrixXd::Zero(p.M.rows(), p.M.cols()), p.K);
  const Eigen::MatrixXd Q0 = Eigen::MatrixXd::Zero(p.M.rows(), p.M.cols());
  for (const Mode& m : s.modes())
    if (m.kind == EigenvalueKind::finite && static_cast<Index>(p.omega.size()) < p.k)
      p.omega.push_back(std::abs(hp::refine_eigenvalue(p.M, Q0, p.K, m.lambda, m.shape)));
  std::sort(p.omega.begin(), p.omega.end());
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: modes_accuracy OUT_DIR [--quick] [--sizes 10,30,100] [--reps R] [--qz-max N]\n";
    return 2;
  }
  const fs::path out = argv[1];
  std::vector<int> sizes{10, 30, 100, 300, 1000};
  int reps = 5;
  Index qz_max = 300;  // the full QZ of n = 1000 takes minutes (docs/runtime.md: 100-118 s damped)
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") {
      sizes = {10, 30, 100, 300};
      reps = 3;
    } else if (a == "--sizes" && i + 1 < argc) {
      sizes = bench::parse_int_list(argv[++i]);
    } else if (a == "--reps" && i + 1 < argc) {
      reps = std::stoi(argv[++i]);
    } else if (a == "--qz-max" && i + 1 < argc) {
      qz_max = std::stoi(argv[++i]);
    }
  }
  fs::create_directories(out);
  bench::Csv csv((out / "modes.csv").string(),
                 "problem,label,n,k,method,path,time_s,time_min_s,time_max_s,reps,err_lowest_k,max_backward_error");
  std::vector<Problem> problems;
  problems.push_back(middle_ear_problem());
  for (int n : sizes) problems.push_back(chain_problem(n));
  for (const Problem& p : problems) {
    std::cerr << "modes_accuracy: " << p.label << "\n";
    const Index n = p.M.rows();
    const fs::path d = out / "modes_data" / p.name;
    fs::create_directories(d);
    write_matrix_market((d / "M.mtx").string(), p.M, MatrixMarketFormat::array, p.label);
    write_matrix_market((d / "K.mtx").string(), p.K, MatrixMarketFormat::array, p.label);
    write_matrix_market((d / "wref.mtx").string(),
                        Eigen::MatrixXd(Eigen::Map<const Eigen::VectorXd>(p.omega.data(), static_cast<Index>(p.omega.size()))),
                        MatrixMarketFormat::array, "reference omega of the lowest k [rad/s], 80-digit CLN");
    const Eigen::MatrixXd Q0 = Eigen::MatrixXd::Zero(n, n);
    for (const bool fast : {false, true}) {
      if (!fast && n > qz_max) {
        csv.row({p.name, p.label, std::to_string(n), std::to_string(p.k), "qz", "skipped", "nan", "nan", "nan", "0",
                 "nan", "nan"});
        continue;
      }
      QuadraticEigenOptions o;
      o.symmetric_fast_path = fast;
      o.one_per_conjugate_pair = true;
      QuadraticEigenSolver s(n, o);
      const bench::Timing t = bench::time_calls([&] { s.compute(p.M, Q0, p.K); }, reps);
      csv.row({p.name, p.label, std::to_string(n), std::to_string(p.k), fast ? "symmetric" : "qz", s.method(),
               bench::num(t.median), bench::num(t.min), bench::num(t.max), std::to_string(t.repetitions),
               bench::num(max_rel(lowest_omegas(s, p.k), p.omega)), bench::num(s.max_backward_error())});
      std::cerr << "  " << (fast ? "symmetric" : "qz") << " (" << s.method() << "): " << bench::num(t.median) << " s\n";
    }
    Eigen::MatrixXd Z;
    Eigen::VectorXd w2;
    const bench::Timing t = bench::time_calls([&] { w2 = partial(p.M, p.K, p.k, Z); }, reps);
    std::vector<double> w;
    for (Index i = 0; i < w2.size(); ++i) w.push_back(std::sqrt(w2[i]));
    csv.row({p.name, p.label, std::to_string(n), std::to_string(p.k), "partial", "dsygvx", bench::num(t.median),
             bench::num(t.min), bench::num(t.max), std::to_string(t.repetitions), bench::num(max_rel(w, p.omega)), "nan"});
    std::cerr << "  partial: " << bench::num(t.median) << " s\n";
  }
  return 0;
}
