// FrfMethod::hessenberg (Laub 1981; SLICOT TB05AD): the one-time Hessenberg(-triangular)
// reduction of the balanced first-order form, then O(f²) per frequency — detail::HessenbergSolver
// and detail::PermutedDiagonal's definitions, and FrequencyResponse::Impl's reductions
// (reduce_hessenberg, reduce_standard, reduce_pencil), a-posteriori checks (backward errors at
// the probe frequencies, forward errors against direct for FrfMethod::automatic),
// prepare_hessenberg, reduced_rhs, select_hessenberg and point_hessenberg.
#include "spectral/frequency_response_impl.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace mbsgen {

namespace detail {

void PermutedDiagonal::from_dense(const Eigen::MatrixXd& X) {
  const Index n = X.cols();
  row.assign(static_cast<std::size_t>(n), 0);
  val.resize(n);
  for (Index j = 0; j < n; ++j) {
    Index i = 0;
    X.col(j).cwiseAbs().maxCoeff(&i);
    row[static_cast<std::size_t>(j)] = i;
    val[j] = X(i, j);
  }
}

void HessenbergSolver::resize(Index n) {
  N = n;
  Wr.resize(n, n);
  Wi.resize(n, n);
  lr.resize(n);
  li.resize(n);
  swapped.assign(static_cast<std::size_t>(n), 0);
  er.resize(n);
  ei.resize(n);
  colH.setZero(n);
  colT.setZero(n);
  rpiv.resize(n);
}

bool HessenbergSolver::solve(const RowMatrixXd& H, const RowMatrixXd* T, double om,
                             Eigen::VectorXd& xr, Eigen::VectorXd& xi, double& rc) {
  er.setZero();
  ei.setZero();
  if (!factorize(H, T, om, xr, xi)) return false;
  // Estimator: the transposed eliminations (r_k −= conj(l_k) r_{k+1}), then y = W⁻ᴴe is done;
  // apply the forward eliminations of W⁻¹ to it.
  for (Index k = N - 2; k >= 0; --k) {
    er[k] -= lr[k] * er[k + 1] + li[k] * ei[k + 1];
    ei[k] -= lr[k] * ei[k + 1] - li[k] * er[k + 1];
    if (swapped[static_cast<std::size_t>(k)]) {
      std::swap(er[k], er[k + 1]);
      std::swap(ei[k], ei[k + 1]);
    }
  }
  double ny = 0;
  for (Index i = 0; i < N; ++i) ny += std::sqrt(er[i] * er[i] + ei[i] * ei[i]);
  for (Index k = 0; k + 1 < N; ++k) {
    if (swapped[static_cast<std::size_t>(k)]) {
      std::swap(er[k], er[k + 1]);
      std::swap(ei[k], ei[k + 1]);
    }
    er[k + 1] -= lr[k] * er[k] - li[k] * ei[k];
    ei[k + 1] -= lr[k] * ei[k] + li[k] * er[k];
  }
  // Back substitution with U for both right-hand sides; the row dot products through Eigen,
  // whose reductions are vectorized (a plain loop cannot be, without reassociation).
  using CMap = Eigen::Map<const Eigen::VectorXd>;
  for (Index i = N - 1; i >= 0; --i) {
    const Index m = N - 1 - i;
    const CMap ur(&Wr(i, 0) + i + 1, m), ui(&Wi(i, 0) + i + 1, m);
    const CMap vxr(xr.data() + i + 1, m), vxi(xi.data() + i + 1, m);
    const CMap ver(er.data() + i + 1, m), vei(ei.data() + i + 1, m);
    const double sr = xr[i] - (ur.dot(vxr) - ui.dot(vxi));
    const double si = xi[i] - (ur.dot(vxi) + ui.dot(vxr));
    const double tr = er[i] - (ur.dot(ver) - ui.dot(vei));
    const double ti = ei[i] - (ur.dot(vei) + ui.dot(ver));
    const cd rd = rpiv[i];
    const cd v = mul(cd(sr, si), rd), w = mul(cd(tr, ti), rd);
    xr[i] = v.real();
    xi[i] = v.imag();
    er[i] = w.real();
    ei[i] = w.imag();
  }
  double nz = 0;
  for (Index i = 0; i < N; ++i) nz += std::sqrt(er[i] * er[i] + ei[i] * ei[i]);
  // ‖W‖₁ ≤ max_j (Σ_i |H_ij| + Ω Σ_i |T_ij|), within √2 of the true value (|a + ib| ≥
  // (|a| + |b|)/√2), in O(N) from column sums computed once; an overestimate makes rcond
  // conservative.
  double anorm = 0.0;
  for (Index j = 0; j < N; ++j) anorm = std::max(anorm, colH[j] + om * colT[j]);
  const double inv = ny > 0 ? nz / ny : std::numeric_limits<double>::infinity();
  rc = (anorm > 0 && inv > 0 && std::isfinite(inv)) ? 1.0 / (anorm * inv) : 0.0;
  return true;
}

bool HessenbergSolver::factorize(const RowMatrixXd& H, const RowMatrixXd* T, double om,
                                 Eigen::VectorXd& xr, Eigen::VectorXd& xi) {
  auto load_row = [&](Index i) {  // row i of W = iΩT − H, columns ≥ i−1
    const Index j0 = i > 0 ? i - 1 : 0;
    const double* hi = &H(i, 0);
    double* wr = &Wr(i, 0);
    double* wi = &Wi(i, 0);
    for (Index j = j0; j < N; ++j) wr[j] = -hi[j];
    if (T == nullptr) {
      for (Index j = j0; j < N; ++j) wi[j] = 0.0;
      wi[i] = om;
    } else {
      const double* ti = &(*T)(i, 0);
      for (Index j = j0; j < N; ++j) wi[j] = om * ti[j];
    }
  };
  load_row(0);
  for (Index k = 0; k < N; ++k) {
    double* ar = &Wr(k, 0);
    double* ai = &Wi(k, 0);
    double* br = nullptr;
    double* bi = nullptr;
    double pr = 0.0, pi = 0.0;
    if (k + 1 < N) {
      load_row(k + 1);
      br = &Wr(k + 1, 0);
      bi = &Wi(k + 1, 0);
      const bool sw = br[k] * br[k] + bi[k] * bi[k] > ar[k] * ar[k] + ai[k] * ai[k];
      swapped[static_cast<std::size_t>(k)] = sw;
      if (sw) {
        for (Index j = k; j < N; ++j) {
          std::swap(ar[j], br[j]);
          std::swap(ai[j], bi[j]);
        }
        std::swap(xr[k], xr[k + 1]);
        std::swap(xi[k], xi[k + 1]);
      }
    }
    if (ar[k] == 0.0 && ai[k] == 0.0) return false;
    rpiv[k] = reciprocal(ar[k], ai[k]);
    if (k + 1 < N) {
      const cd lk = mul(cd(br[k], bi[k]), rpiv[k]);
      pr = lk.real();
      pi = lk.imag();
      lr[k] = pr;
      li[k] = pi;
      br[k] = 0.0;
      bi[k] = 0.0;
      const double x0r = xr[k], x0i = xi[k];
      xr[k + 1] -= pr * x0r - pi * x0i;
      xi[k + 1] -= pr * x0i + pi * x0r;
    }
    // Row k of U is final: step k of Uᴴv = e (column-oriented on the rows of U), fused with
    // the elimination of row k+1 so that row k is read once.
    const double a = std::hypot(er[k], ei[k]);
    if (a > 0) {
      er[k] += er[k] / a;
      ei[k] += ei[k] / a;
    } else {
      er[k] += 1.0;
    }
    const cd v = mul(cd(er[k], ei[k]), std::conj(rpiv[k]));
    const double vr = v.real(), vi = v.imag();
    er[k] = vr;
    ei[k] = vi;
    if (k + 1 < N) {
      // Distinct arrays: __restrict lets the compiler vectorize the loop.
      const double* __restrict ur = ar;
      const double* __restrict ui = ai;
      double* __restrict wr = br;
      double* __restrict wi = bi;
      double* __restrict fr = er.data();
      double* __restrict fi = ei.data();
      for (Index j = k + 1; j < N; ++j) {
        const double tr = ur[j], ti = ui[j];
        wr[j] -= pr * tr - pi * ti;
        wi[j] -= pr * ti + pi * tr;
        fr[j] -= tr * vr + ti * vi;  // e_j −= conj(U_kj)·v
        fi[j] -= tr * vi - ti * vr;
      }
    }
  }
  return true;
}

}  // namespace detail

/// Reduces the first-order form with the balancing `job` ('B', 'P' or 'N'): the standard form
/// A = [[0, E], [−M⁻¹K, −M⁻¹Q]] when rcond₁(M) ≥ mass_rcond, else the pencil.
void FrequencyResponse::Impl::reduce_hessenberg(double mass_rcond, char job) {
  const Eigen::MatrixXd &K = model.K(), &Q = model.Q();
  N = 2 * n;
  hess_job = job;
  Mlu.compute(model.M());
  hess_standard = mass_is_regular(mass_rcond);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(N, N);
  A.topRightCorner(n, n).setIdentity();
  if (hess_standard) {
    A.bottomLeftCorner(n, n) = -Mlu.solve(K);
    A.bottomRightCorner(n, n) = -Mlu.solve(Q);
    hess_standard = A.allFinite();
  }
  if (hess_standard)
    reduce_standard(std::move(A), job);
  else
    reduce_pencil(job);
  hsolver.resize(N);
  for (Index j = 0; j < N; ++j) {
    hsolver.colH[j] = H.col(j).cwiseAbs().sum();
    hsolver.colT[j] = hess_standard ? 1.0 : T.col(j).cwiseAbs().sum();
  }
  xr_ws.resize(N);
  xi_ws.resize(N);
}

void FrequencyResponse::Impl::reduce_standard(Eigen::MatrixXd&& A, char job) {
  const lapack_int NN = detail::li(N);
  hess_form = "standard";
  Eigen::VectorXd scale(N);
  lapack_int info = LAPACKE_dgebal(LAPACK_COL_MAJOR, job, NN, A.data(), NN, &hilo, &hihi,
                                   scale.data());
  detail::check_lapack(info, "dgebal", "FrequencyResponse (hessenberg)");
  Eigen::MatrixXd I = Eigen::MatrixXd::Identity(N, N);
  info = LAPACKE_dgebak(LAPACK_COL_MAJOR, job, 'R', NN, hilo, hihi, scale.data(), NN, I.data(),
                        NN);
  detail::check_lapack(info, "dgebak", "FrequencyResponse (hessenberg)");
  Xr.from_dense(I);
  I.setIdentity();
  info = LAPACKE_dgebak(LAPACK_COL_MAJOR, job, 'L', NN, hilo, hihi, scale.data(), NN, I.data(),
                        NN);
  detail::check_lapack(info, "dgebak", "FrequencyResponse (hessenberg)");
  Xl.from_dense(I);
  hess_tau.resize(std::max<Index>(N - 1, 1));
  info = LAPACKE_dgehrd(LAPACK_COL_MAJOR, NN, hilo, hihi, A.data(), NN, hess_tau.data());
  detail::check_lapack(info, "dgehrd", "FrequencyResponse (hessenberg)");
  H = A.triangularView<Eigen::Upper>();
  for (Index i = 1; i < N; ++i) H(i, i - 1) = A(i, i - 1);
  reflectors = std::move(A);
}

void FrequencyResponse::Impl::reduce_pencil(char job) {
  const lapack_int NN = detail::li(N);
  hess_form = "pencil";
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(N, N);
  A.topRightCorner(n, n).setIdentity();
  A.bottomLeftCorner(n, n) = -model.K();
  A.bottomRightCorner(n, n) = -model.Q();
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(N, N);
  E.topLeftCorner(n, n).setIdentity();
  E.bottomRightCorner(n, n) = model.M();
  Eigen::VectorXd lscale(N), rscale(N);
  lapack_int info = LAPACKE_dggbal(LAPACK_COL_MAJOR, job, NN, A.data(), NN, E.data(), NN,
                                   &hilo, &hihi, lscale.data(), rscale.data());
  detail::check_lapack(info, "dggbal", "FrequencyResponse (hessenberg)");
  Eigen::MatrixXd I = Eigen::MatrixXd::Identity(N, N);
  info = LAPACKE_dggbak(LAPACK_COL_MAJOR, job, 'R', NN, hilo, hihi, lscale.data(),
                        rscale.data(), NN, I.data(), NN);
  detail::check_lapack(info, "dggbak", "FrequencyResponse (hessenberg)");
  Xr.from_dense(I);
  I.setIdentity();
  info = LAPACKE_dggbak(LAPACK_COL_MAJOR, job, 'L', NN, hilo, hihi, lscale.data(),
                        rscale.data(), NN, I.data(), NN);
  detail::check_lapack(info, "dggbak", "FrequencyResponse (hessenberg)");
  Xl.from_dense(I);
  // Triangularize E by QR, apply Qᵀ to A, then Hessenberg-triangular reduction (dgghrd).
  qr_tau.resize(N);
  info = LAPACKE_dgeqrf(LAPACK_COL_MAJOR, NN, NN, E.data(), NN, qr_tau.data());
  detail::check_lapack(info, "dgeqrf", "FrequencyResponse (hessenberg)");
  info = LAPACKE_dormqr(LAPACK_COL_MAJOR, 'L', 'T', NN, NN, NN, E.data(), NN, qr_tau.data(),
                        A.data(), NN);
  detail::check_lapack(info, "dormqr", "FrequencyResponse (hessenberg)");
  qr_E = E;
  Eigen::MatrixXd R = E.triangularView<Eigen::Upper>();
  Qleft.setIdentity(N, N);  // LAPACKE checks them for NaN even with compq = compz = 'I'
  Zright.setIdentity(N, N);
  info = LAPACKE_dgghrd(LAPACK_COL_MAJOR, 'I', 'I', NN, hilo, hihi, A.data(), NN, R.data(), NN,
                        Qleft.data(), NN, Zright.data(), NN);
  detail::check_lapack(info, "dgghrd", "FrequencyResponse (hessenberg)");
  H = A;
  for (Index j = 0; j < N; ++j)
    for (Index i = j + 2; i < N; ++i) H(i, j) = 0.0;
  T = R.triangularView<Eigen::Upper>();
}

/// ŷ at Ω by the Hessenberg reduction (the reduction undone); false at an exact zero pivot.
bool FrequencyResponse::Impl::hessenberg_solution(double om, Eigen::VectorXcd& yh) {
  const lapack_int NN = detail::li(N);
  Eigen::MatrixXd X(N, 2);
  Eigen::VectorXd xr = reduced_rhs(), xi = Eigen::VectorXd::Zero(N);
  double rc = 0.0;
  if (!hsolver.solve(H, hess_standard ? nullptr : &T, om, xr, xi, rc)) return false;
  // An overflowed solve (data near the largest double): LAPACKE would refuse its NaNs below.
  if (!xr.allFinite() || !xi.allFinite()) return false;
  X << xr, xi;
  if (hess_standard) {
    const lapack_int info = LAPACKE_dormhr(LAPACK_COL_MAJOR, 'L', 'N', NN, 2, hilo, hihi,
                                           reflectors.data(), NN, hess_tau.data(), X.data(), NN);
    detail::check_lapack(info, "dormhr", "FrequencyResponse (hessenberg)");
  } else {
    X = (Zright * X).eval();
  }
  yh.resize(n);
  for (Index j = 0; j < N; ++j) {
    const Index i = Xr.row[static_cast<std::size_t>(j)];
    if (i < n) yh[i] = Xr.val[j] * cd(X(j, 0), X(j, 1));
  }
  return yh.allFinite();
}

/// Scaling of the coordinates to unit size at Ω: s_i = d_i^(−1/2), d_i = |K_ii| + Ω²|M_ii|
/// + Ω|Q_ii| (1 where all three vanish), so that units (m, rad) do not decide a norm.
Eigen::VectorXd FrequencyResponse::Impl::unit_scaling(double om) const {
  const Eigen::MatrixXd &M = model.M(), &Q = model.Q(), &K = model.K();
  Eigen::VectorXd sc(n);
  for (Index i = 0; i < n; ++i) {
    const double d = std::abs(K(i, i)) + om * om * std::abs(M(i, i)) + om * std::abs(Q(i, i));
    sc[i] = d > 0 ? 1.0 / std::sqrt(d) : 1.0;
  }
  return sc;
}

/// Forward errors at Ω of direct (an LU with partial pivoting of K − Ω²M + iΩQ, estimated by
/// one step of iterative refinement, whose correction is that error to first order) and of
/// the Hessenberg solution against the refined direct one: {direct, hessenberg} in the
/// unit-scaled max norm of ŷ, then {direct, hessenberg} of the selected outputs ẑ, each
/// relative to its own size (an output that cancels can lose digits the state keeps).
/// O(f³): used at the probe frequencies only, by FrfMethod::automatic.
std::array<double, 4> FrequencyResponse::Impl::forward_errors(double om) {
  Eigen::VectorXcd yh;
  if (!hessenberg_solution(om, yh)) return {0.0, kInf, 0.0, kInf};
  const Eigen::MatrixXd &M = model.M(), &Q = model.Q(), &K = model.K();
  Eigen::MatrixXcd Dw(n, n);
  for (Index j = 0; j < n; ++j)
    for (Index i = 0; i < n; ++i) Dw(i, j) = cd(K(i, j) - om * om * M(i, j), om * Q(i, j));
  const Eigen::PartialPivLU<Eigen::MatrixXcd> lu(Dw);
  const Eigen::VectorXcd bc = b.cast<cd>();
  const Eigen::VectorXcd yd = lu.solve(bc);
  const Eigen::VectorXcd dy = lu.solve(bc - Dw * yd);
  const Eigen::VectorXcd ref = yd + dy;
  const Eigen::VectorXd sc = unit_scaling(om);
  double nref = 0.0, ed = 0.0, eh = 0.0;
  for (Index i = 0; i < n; ++i) {
    nref = std::max(nref, std::abs(ref[i]) / sc[i]);
    ed = std::max(ed, std::abs(dy[i]) / sc[i]);
    eh = std::max(eh, std::abs(yh[i] - ref[i]) / sc[i]);
  }
  // A solution that is not finite (a probe at a pole) must not pass: std::max drops NaN.
  if (!ref.allFinite() || !dy.allFinite() || !yh.allFinite()) return {0.0, kInf, 0.0, kInf};
  double zd = 0.0, zh = 0.0;
  if (Cy.rows() > 0) {
    const Eigen::MatrixXcd C = Cy + cd(0.0, om) * Cv;
    const Eigen::VectorXcd zr = C * ref, ez_d = C * dy, ez_h = C * (yh - ref);
    for (Index r = 0; r < zr.size(); ++r) {
      const double size = std::abs(zr[r]);
      if (!(size > 0) || !std::isfinite(size)) continue;
      zd = std::max(zd, std::abs(ez_d[r]) / size);
      zh = std::max(zh, std::abs(ez_h[r]) / size);
    }
  }
  if (!(nref > 0) || !std::isfinite(nref)) return {0.0, eh == 0.0 ? 0.0 : kInf, zd, zh};
  return {ed / nref, eh / nref, zd, zh};
}

/// FrfMethod::automatic's accuracy check of hessenberg: true when at every probe frequency
/// its forward error is within 10× of direct's (or both below 10·f·u, rounding level), in the
/// state and in every selected output.
bool FrequencyResponse::Impl::hessenberg_as_accurate_as_direct(const Eigen::VectorXd& omega,
                                                               double& worst_ratio) {
  worst_ratio = 0.0;
  const double floor = 10.0 * static_cast<double>(n) * kU;
  bool ok = true;
  for (double om : probe_frequencies(omega)) {
    const std::array<double, 4> e = forward_errors(om);
    for (int k = 0; k < 4; k += 2) {
      const double ed = e[static_cast<std::size_t>(k)], eh = e[static_cast<std::size_t>(k) + 1];
      worst_ratio = std::max(worst_ratio, eh / std::max(ed, floor));
      if (!(eh <= 10.0 * std::max(ed, floor))) ok = false;
    }
  }
  return ok;
}

/// Backward error, in the second-order system scaled to unit coordinates, of the Hessenberg
/// solution at Ω for the current input b (FrfOptions::hessenberg_backward_error_bar), with ŷ
/// the first n entries of x = Xr·(Q or Z)·x̃ (the reduction undone). +∞ at an exact zero pivot
/// or a non-finite solution. O(N²), about two frequencies' worth.
double FrequencyResponse::Impl::hessenberg_backward_error(double om) {
  Eigen::VectorXcd yh;
  if (!hessenberg_solution(om, yh)) return kInf;
  const Eigen::MatrixXd &M = model.M(), &Q = model.Q(), &K = model.K();
  const Eigen::VectorXd yr = yh.real(), yi = yh.imag();
  const Eigen::VectorXd Kr = K * yr - om * om * (M * yr) - om * (Q * yi);
  const Eigen::VectorXd Ki = K * yi - om * om * (M * yi) + om * (Q * yr);
  // Normwise after the symmetric diagonal scaling S = diag(unit_scaling): D̃ = SDS, ỹ = S⁻¹ŷ,
  // b̃ = Sb, so that the units of the coordinates (m, rad) do not decide it, as they would
  // ‖·‖ of the unscaled system.
  const Eigen::VectorXd sc = unit_scaling(om);
  double res = 0.0, dnorm = 0.0, ynorm = 0.0, bnorm = 0.0;
  for (Index i = 0; i < n; ++i) {
    res = std::max(res, sc[i] * std::abs(cd(b[i] - Kr[i], -Ki[i])));
    double row = 0.0;
    for (Index j = 0; j < n; ++j)
      row += std::abs(cd(K(i, j) - om * om * M(i, j), om * Q(i, j))) * sc[j];
    dnorm = std::max(dnorm, sc[i] * row);
    ynorm = std::max(ynorm, std::abs(yh[i]) / sc[i]);
    bnorm = std::max(bnorm, sc[i] * std::abs(b[i]));
  }
  const double den = dnorm * ynorm + bnorm;
  const double eta = den > 0 ? res / den : (res == 0.0 ? 0.0 : kInf);
  return std::isfinite(eta) ? eta : kInf;
}

/// Largest hessenberg_backward_error over up to five probe frequencies: the smallest, the
/// quartiles and the largest of `omega` (or Ω = √(‖K‖_F/‖M‖_F) when omega is empty).
double FrequencyResponse::Impl::hessenberg_check(const Eigen::VectorXd& omega) {
  double eta = 0.0;
  for (double om : probe_frequencies(omega)) eta = std::max(eta, hessenberg_backward_error(om));
  return eta;
}

std::vector<double> FrequencyResponse::Impl::probe_frequencies(const Eigen::VectorXd& omega) const {
  std::vector<double> w(omega.data(), omega.data() + omega.size());
  std::sort(w.begin(), w.end());
  std::vector<double> probes;
  const std::size_t F = w.size();
  if (F == 0) {
    const double g = std::sqrt(model.K().norm() / model.M().norm());
    probes.push_back(std::isfinite(g) ? g : 1.0);
  }
  for (std::size_t q = 0; F > 0 && q <= 4; ++q) {
    const double v = w[(F - 1) * q / 4];
    if (probes.empty() || probes.back() != v) probes.push_back(v);
  }
  return probes;
}

/// The reduction with balancing chosen a posteriori (as QuadraticEigenSolver does): permute
/// and scale ('B'); when the largest backward error of the probe solves exceeds
/// FrfOptions::hessenberg_backward_error_bar, permute only ('P') and keep whichever is smaller.
/// balance == false: neither ('N').
void FrequencyResponse::Impl::prepare_hessenberg(const FrfOptions& opt,
                                                 const Eigen::VectorXd& omega) {
  if (hess_ready) return;
  const double bar = opt.hessenberg_backward_error_bar > 0
                         ? opt.hessenberg_backward_error_bar
                         : 10.0 * static_cast<double>(n) * kU;
  hess_bar = bar;
  if (!opt.balance) {
    reduce_hessenberg(opt.hessenberg_mass_rcond, 'N');
    hess_backward_error = hessenberg_check(omega);
  } else {
    reduce_hessenberg(opt.hessenberg_mass_rcond, 'B');
    hess_backward_error = hessenberg_check(omega);
    if (!(hess_backward_error <= bar)) {
      const double eta_b = hess_backward_error;
      reduce_hessenberg(opt.hessenberg_mass_rcond, 'P');
      hess_backward_error = hessenberg_check(omega);
      if (!(hess_backward_error < eta_b)) {
        reduce_hessenberg(opt.hessenberg_mass_rcond, 'B');
        hess_backward_error = eta_b;
      }
    }
  }
  hess_ready = true;
}

/// The right-hand side [0; b] (pencil) or [0; M⁻¹b] (standard form), balanced and reduced.
Eigen::VectorXd FrequencyResponse::Impl::reduced_rhs() const {
  const lapack_int NN = detail::li(N);
  Eigen::VectorXd bx = Eigen::VectorXd::Zero(N);
  if (hess_standard)
    bx.tail(n) = Mlu.solve(b);
  else
    bx.tail(n) = b;
  Eigen::VectorXd r = Xl.transpose_times(bx);
  if (hess_standard) {
    const lapack_int info =
        LAPACKE_dormhr(LAPACK_COL_MAJOR, 'L', 'T', NN, 1, hilo, hihi, reflectors.data(), NN,
                       hess_tau.data(), r.data(), NN);
    detail::check_lapack(info, "dormhr", "FrequencyResponse (hessenberg)");
  } else {
    const lapack_int info = LAPACKE_dormqr(LAPACK_COL_MAJOR, 'L', 'T', NN, 1, NN, qr_E.data(),
                                           NN, qr_tau.data(), r.data(), NN);
    detail::check_lapack(info, "dormqr", "FrequencyResponse (hessenberg)");
    r = Qleft.transpose() * r;
  }
  return r;
}

/// Reduced right-hand side and outputs for the current input/outputs.
void FrequencyResponse::Impl::select_hessenberg() {
  const lapack_int NN = detail::li(N);
  const Index p = Cy.rows();
  Eigen::MatrixXd Cx(p, N);  // first-order outputs z = [C_y, C_v] x
  Cx << Cy.real(), Cv.real();
  Eigen::MatrixXd Ct(N, p);  // (C_x Xr)ᵀ
  for (Index k = 0; k < p; ++k) Ct.col(k) = Xr.transpose_times(Cx.row(k).transpose());
  if (hess_standard) {
    if (p > 0) {
      const lapack_int info =
          LAPACKE_dormhr(LAPACK_COL_MAJOR, 'L', 'T', NN, detail::li(p), hilo, hihi,
                         reflectors.data(), NN, hess_tau.data(), Ct.data(), NN);
      detail::check_lapack(info, "dormhr", "FrequencyResponse (hessenberg)");
    }
  } else {
    Ct = Zright.transpose() * Ct;
  }
  Chat_re = Ct.transpose();
  rhs_reduced = reduced_rhs();
  zr_ws.resize(p);
  zi_ws.resize(p);
}

bool FrequencyResponse::Impl::point_hessenberg(double om, double& rc) {
  xr_ws = rhs_reduced;
  xi_ws.setZero();
  if (!hsolver.solve(H, hess_standard ? nullptr : &T, om, xr_ws, xi_ws, rc)) {
    rc = 0.0;
    return false;
  }
  zr_ws.noalias() = Chat_re * xr_ws;
  zi_ws.noalias() = Chat_re * xi_ws;
  z.real() = zr_ws;
  z.imag() = zi_ws;
  return true;
}

}  // namespace mbsgen
