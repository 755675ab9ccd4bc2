#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "spectral/dense_linear_algebra.hpp"
#include "spectral/spectrum_structure.hpp"

namespace mbsgen {

using cd = std::complex<double>;
namespace {
constexpr double kU = std::numeric_limits<double>::epsilon() / 2;  // unit roundoff 2⁻⁵³
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTwoPi = 6.283185307179586476925286766559;

int kind_order(EigenvalueKind k) {
  return k == EigenvalueKind::zero ? 0 : (k == EigenvalueKind::finite ? 1 : 2);
}

/// ‖x‖₂ = 1 and the largest-modulus entry real positive.
void normalize_shape(Eigen::VectorXcd& x) {
  const double nx = x.norm();
  if (nx == 0.0) return;
  Eigen::Index imax = 0;
  x.cwiseAbs().maxCoeff(&imax);
  const cd phase = std::abs(x[imax]) > 0 ? std::conj(x[imax]) / std::abs(x[imax]) : cd(1.0);
  x *= phase / nx;
  x[imax] = cd(x[imax].real(), 0.0);
}

struct Raw {
  cd alpha;     // unscaled, normalized with beta
  double beta;  // ≥ 0
  Eigen::VectorXcd x, y;
  double eta = 0.0;  // backward error of (α, β, x)
  double size() const { return std::atan2(std::abs(alpha), beta); }  // monotone in |λ|
};

void normalize_pair(cd& alpha, double& beta) {
  const double s = std::hypot(std::abs(alpha), beta);
  if (s > 0) {
    alpha /= s;
    beta /= s;
  }
}

/// M X, Q X, K X for a complex n×m block X by real matrix products (BLAS-3 speed).
struct Products {
  Eigen::MatrixXcd MX, QX, KX;
  Products(const Eigen::MatrixXd& M, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& K,
           const Eigen::MatrixXcd& X) {
    const Eigen::MatrixXd Xr = X.real(), Xi = X.imag();
    auto mul = [&](const Eigen::MatrixXd& A, Eigen::MatrixXcd& out) {
      out.resize(X.rows(), X.cols());
      out.real().noalias() = A * Xr;
      out.imag().noalias() = A * Xi;
    };
    mul(M, MX);
    mul(Q, QX);
    mul(K, KX);
  }
  /// Tisseur's backward error of (α, β, x_k) with x_k = column k of X.
  double backward_error(Eigen::Index k, cd alpha, double beta, double xnorm, double nM, double nQ,
                        double nK) const {
    const double r =
        ((alpha * alpha) * MX.col(k) + (alpha * beta) * QX.col(k) + (beta * beta) * KX.col(k))
            .norm();
    const double a = std::abs(alpha);
    const double den = (a * a * nM + a * beta * nQ + beta * beta * nK) * xnorm;
    if (den == 0.0) return r == 0.0 ? 0.0 : kInf;
    return r / den;
  }
};

}  // namespace

const char* to_string(EigenvalueKind kind) {
  switch (kind) {
    case EigenvalueKind::zero: return "zero";
    case EigenvalueKind::infinite: return "infinite";
    case EigenvalueKind::finite: break;
  }
  return "finite";
}

const char* to_string(Stability verdict) {
  switch (verdict) {
    case Stability::stable: return "stable";
    case Stability::unstable: return "unstable";
    case Stability::marginal: return "marginal";
    case Stability::undecided: break;
  }
  return "undecided";
}

const char* kind_label(const Mode& mode) {
  return mode.zero_within_bound ? "zero_within_bound" : to_string(mode.kind);
}

namespace {


}  // namespace

double quadratic_backward_error(const Eigen::MatrixXd& M, const Eigen::MatrixXd& Q,
                                const Eigen::MatrixXd& K, cd alpha, double beta,
                                const Eigen::VectorXcd& x, double norm_M, double norm_Q,
                                double norm_K) {
  const Eigen::VectorXcd r = (alpha * alpha) * (M.cast<cd>() * x) +
                             (alpha * beta) * (Q.cast<cd>() * x) +
                             (beta * beta) * (K.cast<cd>() * x);
  const double a = std::abs(alpha);
  const double den = (a * a * norm_M + a * beta * norm_Q + beta * beta * norm_K) * x.norm();
  if (den == 0.0) return r.norm() == 0.0 ? 0.0 : kInf;
  return r.norm() / den;
}

QuadraticEigenSolver::QuadraticEigenSolver(Eigen::Index f, QuadraticEigenOptions options)
    : options_(options) {
  A_.resize(2 * f, 2 * f);
  B_.resize(2 * f, 2 * f);
  VL_.resize(2 * f, 2 * f);
  VR_.resize(2 * f, 2 * f);
  alphar_.resize(2 * f);
  alphai_.resize(2 * f);
  beta_.resize(2 * f);
  modes_.reserve(static_cast<std::size_t>(2 * f));
}

QuadraticEigenSolver& QuadraticEigenSolver::compute(const LinearModel& model) {
  return compute(model.M(), model.Q(), model.K());
}

double QuadraticEigenSolver::max_backward_error() const {
  double e = 0.0;
  for (const Mode& m : modes_) e = std::max(e, m.backward_error);
  return e;
}

namespace {
double largest_entry(const Eigen::MatrixXd& X) { return X.size() ? X.cwiseAbs().maxCoeff() : 0.0; }
}  // namespace

QuadraticEigenSolver& QuadraticEigenSolver::compute(const Eigen::MatrixXd& M,
                                                    const Eigen::MatrixXd& Q,
                                                    const Eigen::MatrixXd& K) {
  info_ = Eigen::InvalidInput;
  modes_.clear();
  num_zero_ = num_infinite_ = 0;
  // Validates dimensions and finiteness (throws DimensionError / NonFiniteError).
  const LinearModel check(M, Q.size() == 0 ? Eigen::MatrixXd::Zero(M.rows(), M.rows()) : Q, K,
                          Eigen::MatrixXd(M.rows(), 0), Eigen::MatrixXd(), Eigen::MatrixXd());
  const Eigen::MatrixXd& Qf = check.Q();
  // Data near the ends of the range of double (1e±135 and beyond): solve the exactly scaled
  // problem (powers of two) and scale its eigenvalues back (spectrum_structure.hpp).
  if (const detail::RangeScaling sc = detail::range_scaling({largest_entry(K), largest_entry(Qf), largest_entry(M)});
      sc.active) {
    compute(sc.scaled(M, 2), sc.scaled(Qf, 1), sc.scaled(K, 0));
    detail::unscale_modes(modes_, sc.gamma());
    return *this;
  }
  const Eigen::Index n = M.rows();
  const double rank_tol =
      options_.rank_tolerance > 0 ? options_.rank_tolerance : static_cast<double>(n) * kU;
  // Rank-revealing QR (dgeqp3) of Mᵀ and Kᵀ: numerical ranks and orthonormal null spaces.
  {
    detail::NullSpace nm = detail::null_space(M, rank_tol, true);
    detail::NullSpace nk = detail::null_space(K, rank_tol, true);
    rank_M_ = nm.rank;
    rank_K_ = nk.rank;
    null_M_ = std::move(nm.basis);
    null_K_ = std::move(nk.basis);
  }
  norm_M_ = detail::norm2_estimate(M);
  norm_Q_ = detail::norm2_estimate(Qf);
  norm_K_ = detail::norm2_estimate(K);
  const double fM = M.norm(), fQ = Qf.norm(), fK = K.norm();
  tau_ = (fM > 0 && fK > 0) ? fQ / std::sqrt(fM * fK) : kInf;
  gamma_ = (fM > 0 && fK > 0) ? std::sqrt(fK / fM) : 1.0;

  floor_ = options_.backward_error_floor > 0   ? options_.backward_error_floor
           : options_.backward_error_floor == 0 ? 100.0 * static_cast<double>(n) * kU
                                                : 0.0;
  bool done = false;
  if (options_.symmetric_fast_path && check.is_symmetric_undamped()) compute_symmetric(M, K, done);
  if (!done) compute_general(M, Qf, K);
  finish(M, Qf, K);
  // An undamped (e.g. gyroscopic) system whose zero pattern makes its spectrum symmetric about
  // the imaginary axis: isolated eigenvalues within their bounds of the axis are on it
  // (spectrum_structure.hpp), so a sleeping top is marginal, not undecided.
  if (detail::reversible_sign_pattern({{&M, 1}, {&Qf, -1}, {&K, 1}})) detail::snap_to_axis(modes_);
  stability_ = stability_of(modes_);
  info_ = Eigen::Success;
  return *this;
}

namespace {

/// Real A times complex X by two real products (BLAS-3 speed).
Eigen::MatrixXcd times(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::MatrixXcd& X) {
  Eigen::MatrixXcd out(A.rows(), X.cols());
  const Eigen::MatrixXd Xr = X.real(), Xi = X.imag();
  out.real().noalias() = A * Xr;
  out.imag().noalias() = A * Xi;
  return out;
}

/// Eigenvectors of the zero (or infinite) eigenvalue: right null vectors N of K (or M) and left
/// null vectors W, rotated by the SVD W ᵀQN = U Σ Vᵀ so that y_jᵀ Q x_i = σ_j δ_ij. A null vector
/// x = N v_j starts a Jordan chain at 0 (∞) exactly when σ_j = 0 (Q x ∈ range K), so the
/// smallest σ_j are the chain heads.
struct NullPairs {
  Eigen::MatrixXd x, y;  // columns ordered by decreasing σ
  void compute(const Eigen::MatrixXd& N, const Eigen::MatrixXd& W, const Eigen::MatrixXd& Q) {
    const Eigen::Index d = N.cols();
    if (d == 0) {
      x = y = Eigen::MatrixXd(N.rows(), 0);
      return;
    }
    const Eigen::MatrixXd G = W.transpose() * Q * N;
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(G, Eigen::ComputeFullU | Eigen::ComputeFullV);
    x = N * svd.matrixV();
    y = W * svd.matrixU();
  }
  /// Eigenvector pair of the j-th of `count` deflated eigenvalues (count ≥ d): the first d use
  /// each null vector once; the extra members of Jordan chains reuse the chain heads.
  Eigen::Index column(Eigen::Index j) const {
    const Eigen::Index d = x.cols();
    return j < d ? j : d - 1 - (j - d) % d;
  }
  /// Whether column c is the head of a Jordan chain when `count` eigenvalues were deflated.
  bool defective(Eigen::Index c, Eigen::Index count) const {
    const Eigen::Index d = x.cols();
    return c >= d - std::min(d, count - d);
  }
};

/// Staircase deflation (Van Dooren 1979) of the zero and infinite eigenvalues of the pencil
/// A − μB of order N by orthogonal U, V: after each step
///     Uᵀ(A − μB)V = [[L_A − μL_B, X_A − μX_B], [0, F_A − μF_B]],
/// with the deflated pencil L (order c0) upper triangular — diagonal (0, R_jj) for a zero
/// eigenvalue, (R_jj, 0) for an infinite one — and the active pencil F (order N − c0).
/// A step takes an orthonormal basis of null vectors of F_A (zero) or F_B (infinite), rotates the
/// active columns so that they come first (Householder, k reflectors), sets their residual in F_A
/// (F_B) to zero — the backward error of the deflation — and triangularizes F_B (F_A) on them by a
/// QR of those columns; a rank-deficient R means A and B share a null vector (det P(λ) ≡ 0).
struct Staircase {
  Eigen::MatrixXd A, B, U, V;
  Eigen::Index N = 0, c0 = 0, zeros = 0, infinities = 0;
  double tol_A = 0.0, tol_B = 0.0;  // absolute pivot tolerances for the rank decisions
  std::vector<unsigned char> is_zero;  // per deflated column

  void start(Eigen::MatrixXd&& A0, Eigen::MatrixXd&& B0) {
    A = std::move(A0);
    B = std::move(B0);
    N = A.rows();
    U.setIdentity(N, N);
    V.setIdentity(N, N);
    c0 = zeros = infinities = 0;
    is_zero.clear();
  }
  Eigen::Index active() const { return N - c0; }

  /// Deflates the null vectors Nb (m×k, full column rank, active coordinates) of F_A (zero = true) or
  /// F_B (zero = false).
  void deflate(const Eigen::MatrixXd& Nb, bool zero) {
    const Eigen::Index m = active(), k = Nb.cols();
    if (k == 0) return;
    const lapack_int NN = detail::li(N), mm = detail::li(m), kk = detail::li(k);
    const char* who = "QuadraticEigenSolver::compute (deflation)";
    Eigen::MatrixXd H = Nb;
    Eigen::VectorXd tau(k);
    lapack_int info = LAPACKE_dgeqrf(LAPACK_COL_MAJOR, mm, kk, H.data(), mm, tau.data());
    detail::check_lapack(info, "dgeqrf", who);
    for (Eigen::MatrixXd* X : {&A, &B, &V}) {
      info = LAPACKE_dormqr(LAPACK_COL_MAJOR, 'R', 'N', NN, mm, kk, H.data(), mm, tau.data(),
                            X->data() + c0 * N, NN);
      detail::check_lapack(info, "dormqr", who);
    }
    Eigen::MatrixXd& Fz = zero ? A : B;  // the matrix the columns are null vectors of
    Eigen::MatrixXd& Fo = zero ? B : A;  // the other one, triangularized on them
    Fz.block(c0, c0, m, k).setZero();
    Eigen::MatrixXd G = Fo.block(c0, c0, m, k);
    info = LAPACKE_dgeqrf(LAPACK_COL_MAJOR, mm, kk, G.data(), mm, tau.data());
    detail::check_lapack(info, "dgeqrf", who);
    const double tol = zero ? tol_B : tol_A;
    for (Eigen::Index j = 0; j < k; ++j)
      if (!(std::abs(G(j, j)) > tol))
        throw SingularSystemError(
            "QuadraticEigenSolver::compute: the quadratic eigenvalue problem is singular "
            "(det(λ²M + λQ + K) vanishes identically to working precision: M, Q and K have a "
            "common null vector, e.g. a coordinate without mass, damping and stiffness)");
    for (Eigen::MatrixXd* X : {&A, &B}) {
      info = LAPACKE_dormqr(LAPACK_COL_MAJOR, 'L', 'T', mm, NN, kk, G.data(), mm, tau.data(),
                            X->data() + c0, NN);
      detail::check_lapack(info, "dormqr", who);
    }
    info = LAPACKE_dormqr(LAPACK_COL_MAJOR, 'R', 'N', NN, mm, kk, G.data(), mm, tau.data(),
                          U.data() + c0 * N, NN);
    detail::check_lapack(info, "dormqr", who);
    Fo.block(c0 + k, c0, m - k, k).setZero();
    for (Eigen::Index j = 0; j < k; ++j) Fo.block(c0 + j + 1, c0 + j, k - j - 1, 1).setZero();
    c0 += k;
    (zero ? zeros : infinities) += k;
    is_zero.insert(is_zero.end(), static_cast<std::size_t>(k), zero ? 1 : 0);
  }

  /// Deflates null vectors of F_A (zero) or F_B (infinite) found by a rank-revealing QR of the
  /// active block with the absolute tolerance, until there are none; returns how many.
  Eigen::Index deflate_chains(bool zero) {
    Eigen::Index total = 0;
    while (active() > 0) {
      const Eigen::Index m = active();
      const Eigen::MatrixXd F = (zero ? A : B).bottomRightCorner(m, m);
      const detail::NullSpace ns = detail::null_space(F, zero ? tol_A : tol_B, false);
      if (ns.rank == m) break;
      deflate(ns.basis, zero);
      total += m - ns.rank;
    }
    return total;
  }
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Symmetric undamped fast path: K v = ω² M v by dsygvd (itype 1), λ = ±iω. A null space N of K
// (rigid-body modes) is deflated exactly: the nonzero ω² belong to eigenvectors M-orthogonal to
// N (Nᵀ K = 0 gives ω² NᵀM v = 0), so dsygvd runs on Zᵀ K Z, Zᵀ M Z with Z an orthonormal basis
// of (M N)^⊥; each null vector is a double eigenvalue λ = 0 (a 2×2 Jordan block, Q = 0).
void QuadraticEigenSolver::compute_symmetric(const Eigen::MatrixXd& M, const Eigen::MatrixXd& K,
                                             bool& ok) {
  const Eigen::Index n = M.rows(), d = n - rank_K_, r = n - d;
  Eigen::MatrixXd V, Mw;
  Eigen::MatrixXd Z;  // n×r, only when d > 0
  if (d == 0) {
    V = K;
    Mw = M;
  } else {
    if (rank_M_ < n || Eigen::LLT<Eigen::MatrixXd>(M).info() != Eigen::Success) return;
    Eigen::MatrixXd MN = M * null_K_;
    Eigen::VectorXd tau(d);
    lapack_int info = LAPACKE_dgeqrf(LAPACK_COL_MAJOR, detail::li(n), detail::li(d), MN.data(),
                                     detail::li(n), tau.data());
    detail::check_lapack(info, "dgeqrf", "QuadraticEigenSolver::compute");
    Z = Eigen::MatrixXd::Zero(n, r);
    Z.bottomRows(r).setIdentity();
    info = LAPACKE_dormqr(LAPACK_COL_MAJOR, 'L', 'N', detail::li(n), detail::li(r),
                          detail::li(d), MN.data(), detail::li(n), tau.data(), Z.data(),
                          detail::li(n));
    detail::check_lapack(info, "dormqr", "QuadraticEigenSolver::compute");
    V = Z.transpose() * K * Z;
    Mw = Z.transpose() * M * Z;
    V = (0.5 * (V + V.transpose())).eval();
    Mw = (0.5 * (Mw + Mw.transpose())).eval();
  }
  Eigen::VectorXd w(r);
  if (r > 0) {
    const lapack_int info = LAPACKE_dsygvd(LAPACK_COL_MAJOR, 1, 'V', 'U', detail::li(r), V.data(),
                                           detail::li(r), Mw.data(), detail::li(r), w.data());
    detail::check_lapack(info, "dsygvd", "QuadraticEigenSolver::compute");
    if (info > 0) return;  // M not positive definite (or no convergence): general path
  }
  if (d > 0) V = (Z * V).eval();
  ok = true;
  method_ = "symmetric";
  modes_.clear();
  num_zero_ = 2 * d;
  for (Eigen::Index j = 0; j < d; ++j) {
    Mode m;
    m.kind = EigenvalueKind::zero;
    m.alpha = 0.0;
    m.beta = 1.0;
    m.defective = true;
    m.shape = null_K_.col(j).cast<cd>();
    modes_.push_back(m);
    if (!options_.one_per_conjugate_pair) modes_.push_back(m);
  }
  for (Eigen::Index i = 0; i < r; ++i) {
    Mode m;
    m.shape = V.col(i).cast<cd>();
    if (w[i] > 0) {
      const double om = std::sqrt(w[i]);
      m.alpha = cd(0.0, om);
      m.beta = 1.0;
      normalize_pair(m.alpha, m.beta);
      modes_.push_back(m);
      if (!options_.one_per_conjugate_pair) {
        m.alpha = std::conj(m.alpha);
        modes_.push_back(m);
      }
    } else {
      const double s = std::sqrt(-w[i]);
      for (double sign : {1.0, -1.0}) {
        m.alpha = cd(sign * s, 0.0);
        m.beta = 1.0;
        normalize_pair(m.alpha, m.beta);
        modes_.push_back(m);
      }
    }
  }
  for (Mode& m : modes_) m.left_shape = m.shape;
}

// ---------------------------------------------------------------------------------------------
// General path: scaled first companion linearization; zero and infinite eigenvalues deflated by
// the staircase above; dggevx with balancing on the remaining (finite) pencil.
namespace {

/// The finite eigenpairs of one QZ run and how many zero and infinite eigenvalues it deflated.
struct Run {
  std::vector<Raw> finite;
  Eigen::Index zeros = 0, infinities = 0;
};

/// What the runs of the general path share: the data, their norms and rank decisions, the
/// solver's workspaces of the linearization and the staircase.
struct GeneralPath {
  const Eigen::MatrixXd &M, &Q, &K;
  const Eigen::MatrixXd &null_K, &null_M;  // right null spaces of K and M
  Eigen::Index n, N, dK, dM;               // N = 2n; dK, dM: dimensions of the null spaces
  double fM, fQ, fK;                       // Frobenius norms
  double rank_tol;
  double norm_M, norm_Q, norm_K;  // ‖·‖₂ lower estimates
  bool balance;                   // QuadraticEigenOptions::balance
  Eigen::MatrixXd &A, &B, &VL, &VR;
  Eigen::VectorXd &alphar, &alphai, &beta;
  Staircase st;
  bool deflating() const { return dK > 0 || dM > 0; }
  bool degenerate() const { return !(fM > 0 && fK > 0); }
};

/// Sets A − μB to the first companion linearization of the problem scaled by λ = gμ and d.
void linearize(GeneralPath& p, double g, double d) {
  const Eigen::Index n = p.n, N = p.N;
  p.A.setZero(N, N);
  p.B.setZero(N, N);
  p.A.topRightCorner(n, n).setIdentity();
  p.A.bottomLeftCorner(n, n) = -d * p.K;
  p.A.bottomRightCorner(n, n) = -(g * d) * p.Q;
  p.B.topLeftCorner(n, n).setIdentity();
  p.B.bottomRightCorner(n, n) = (g * g * d) * p.M;
}

/// Deflates the zero and infinite eigenvalues of A − μB by the staircase p.st and leaves the
/// remaining pencil, of order m = N − k after k deflated eigenvalues, in A and B.
void deflate_linearization(GeneralPath& p, Eigen::Index& k, Eigen::Index& m) {
  const Eigen::Index n = p.n, N = p.N;
  Staircase& st = p.st;
  st.tol_A = 2.0 * p.rank_tol * p.A.norm();
  st.tol_B = 2.0 * p.rank_tol * p.B.norm();
  st.start(std::move(p.A), std::move(p.B));
  if (p.dK > 0) {  // null(A) = [N_K; 0]
    Eigen::MatrixXd Nb = Eigen::MatrixXd::Zero(N, p.dK);
    Nb.topRows(n) = p.null_K;
    st.deflate(Nb, true);
  }
  if (p.dM > 0) {  // null(B) = [0; N_M], inside the span of the active columns
    const Eigen::MatrixXd Nb = st.V.block(n, st.c0, n, st.active()).transpose() * p.null_M;
    st.deflate(Nb, false);
  }
  if (p.dK > 0) st.deflate_chains(true);
  if (p.dM > 0) st.deflate_chains(false);
  k = st.c0;
  m = N - k;
  p.A = st.A.bottomRightCorner(m, m);
  p.B = st.B.bottomRightCorner(m, m);
}

/// Eigenvalues (alphar, alphai, beta) and real right and left eigenvectors (VR, VL) of the m×m
/// pencil (A, B) by dggevx with balancing `job`.
void qz_pencil(GeneralPath& p, char job, Eigen::Index m) {
  p.VL.resize(m, m);
  p.VR.resize(m, m);
  p.alphar.resize(m);
  p.alphai.resize(m);
  p.beta.resize(m);
  Eigen::VectorXd lscale(m), rscale(m), rconde(m), rcondv(m);
  lapack_int ilo = 0, ihi = 0;
  double abnrm = 0, bbnrm = 0;
  const lapack_int mm = detail::li(m);
  const lapack_int info = LAPACKE_dggevx(
      LAPACK_COL_MAJOR, job, 'V', 'V', 'N', mm, p.A.data(), mm, p.B.data(), mm, p.alphar.data(),
      p.alphai.data(), p.beta.data(), p.VL.data(), mm, p.VR.data(), mm, &ilo, &ihi, lscale.data(),
      rscale.data(), &abnrm, &bbnrm, rconde.data(), rcondv.data());
  detail::check_lapack(info, "dggevx", "QuadraticEigenSolver::compute");
  if (info > 0)
    throw LapackError("QuadraticEigenSolver::compute: QZ iteration (dggevx) failed");
}

/// Complex right (Zc) and left (Lc) eigenvectors of the m×m pencil from dggevx's real storage.
void complex_eigenvectors(const GeneralPath& p, Eigen::Index m, Eigen::MatrixXcd& Zc,
                          Eigen::MatrixXcd& Lc) {
  for (Eigen::Index j = 0; j < m; ++j) {
    if (p.alphai[j] == 0.0) {
      Zc.col(j) = p.VR.col(j).cast<cd>();
      Lc.col(j) = p.VL.col(j).cast<cd>();
    } else if (p.alphai[j] > 0.0) {
      Zc.col(j).real() = p.VR.col(j);
      Zc.col(j).imag() = p.VR.col(j + 1);
      Lc.col(j).real() = p.VL.col(j);
      Lc.col(j).imag() = p.VL.col(j + 1);
    } else {  // second of a pair: conjugates of the previous column pair
      Zc.col(j).real() = p.VR.col(j - 1);
      Zc.col(j).imag() = -p.VR.col(j);
      Lc.col(j).real() = p.VL.col(j - 1);
      Lc.col(j).imag() = -p.VL.col(j);
    }
  }
}

/// The components w_L on the k deflated columns of the right eigenvectors of the full pencil,
/// one per column w of Zc.
Eigen::MatrixXcd deflated_components(const GeneralPath& p, Eigen::Index k, Eigen::Index m,
                                     const Eigen::MatrixXcd& Zc) {
  const Staircase& st = p.st;
  Eigen::MatrixXcd WL(k, m);
  if (k > 0) {
    const Eigen::MatrixXcd XA = times(st.A.block(0, k, k, m), Zc);
    const Eigen::MatrixXcd XB = times(st.B.block(0, k, k, m), Zc);
    const Eigen::MatrixXd LA = st.A.topLeftCorner(k, k), LB = st.B.topLeftCorner(k, k);
    Eigen::MatrixXcd T(k, k);
    for (Eigen::Index j = 0; j < m; ++j) {
      const cd a(p.alphar[j], p.alphai[j]);
      const double b = p.beta[j];
      T = b * LA.cast<cd>() - a * LB.cast<cd>();
      double tmax = 0.0;
      for (Eigen::Index i = 0; i < k; ++i) tmax = std::max(tmax, std::abs(T(i, i)));
      for (Eigen::Index i = 0; i < k; ++i)  // an undeflated 0 or ∞ of F: rounding pivot
        if (T(i, i) == 0.0) T(i, i) = kU * (tmax > 0 ? tmax : 1.0);
      const Eigen::VectorXcd rhs = -(b * XA.col(j) - a * XB.col(j));
      WL.col(j) = T.triangularView<Eigen::Upper>().solve(rhs);
    }
  }
  return WL;
}

/// Right (Z) and left (W, its bottom n rows) eigenvectors of the full linearization from those
/// of the m×m active pencil after k deflated eigenvalues.
void full_eigenvectors(const GeneralPath& p, Eigen::Index k, Eigen::Index m, Eigen::MatrixXcd& Zc,
                       const Eigen::MatrixXcd& Lc, Eigen::MatrixXcd& Z, Eigen::MatrixXcd& W) {
  // Eigenvectors z = [x; μx] of the full pencil. The left ones are U [0; l]. The right ones
  // are V [w_L; w] with (βL_A − αL_B) w_L = −(βX_A − αX_B) w, a triangular solve of order k.
  const Eigen::Index n = p.n;
  if (!p.deflating()) {
    Z = std::move(Zc);
    W = Lc.bottomRows(n);
  } else {
    const Staircase& st = p.st;
    W = times(st.U.block(n, k, n, m), Lc);
    const Eigen::MatrixXcd WL = deflated_components(p, k, m, Zc);
    Z = times(st.V.rightCols(m), Zc);
    if (k > 0) Z += times(st.V.leftCols(k), WL);
  }
}

/// The m finite eigenpairs (α, β, x, y) of a run with eigenvalue scaling g, x from the block of z
/// with the smaller backward error.
void select_eigenpairs(const GeneralPath& p, double g, Eigen::Index m, const Eigen::MatrixXcd& Z,
                       const Eigen::MatrixXcd& W, std::vector<Raw>& finite) {
  const Eigen::Index n = p.n;
  const Eigen::MatrixXcd top = Z.topRows(n), bottom = Z.bottomRows(n);
  const Products pt(p.M, p.Q, p.K, top), pb(p.M, p.Q, p.K, bottom);
  finite.clear();
  finite.reserve(static_cast<std::size_t>(m));
  for (Eigen::Index j = 0; j < m; ++j) {
    Raw r;
    r.alpha = g * cd(p.alphar[j], p.alphai[j]);
    r.beta = p.beta[j];
    normalize_pair(r.alpha, r.beta);
    const double nt = top.col(j).norm(), nb = bottom.col(j).norm();
    const double e_top =
        nt > 0 ? pt.backward_error(j, r.alpha, r.beta, nt, p.norm_M, p.norm_Q, p.norm_K) : kInf;
    const double e_bot =
        nb > 0 ? pb.backward_error(j, r.alpha, r.beta, nb, p.norm_M, p.norm_Q, p.norm_K) : kInf;
    r.x = e_top <= e_bot ? top.col(j) : bottom.col(j);
    r.eta = std::min(e_top, e_bot);
    r.y = W.col(j);
    finite.push_back(std::move(r));
  }
}

/// QZ of the m×m pencil (A, B) by dggevx with balancing `job`, eigenvectors of the full
/// linearization, x from the block of z with the smaller backward error.
void qz(GeneralPath& p, char job, double g, Eigen::Index k, Eigen::Index m,
        std::vector<Raw>& finite) {
  qz_pencil(p, job, m);
  // Complex right and left eigenvectors of the active pencil.
  Eigen::MatrixXcd Zc(m, m), Lc(m, m);
  complex_eigenvectors(p, m, Zc, Lc);
  Eigen::MatrixXcd Z, W;
  full_eigenvectors(p, k, m, Zc, Lc, Z, W);
  select_eigenpairs(p, g, m, Z, W, finite);
}

/// The largest backward error of a run's finite eigenpairs.
double largest_backward_error(const std::vector<Raw>& v) {
  double e = 0.0;
  for (const Raw& r : v) e = std::max(e, r.eta);
  return e;
}

/// QZ of the m×m pencil (A, B) with the balancing of the options: permutation, or permutation and
/// scaling when that gives the smaller largest backward error.
void qz_balanced(GeneralPath& p, double g, Eigen::Index k, Eigen::Index m,
                 std::vector<Raw>& finite) {
  // Balancing of the linearization: permutation ('P') first. LAPACK's scaling (Ward's
  // algorithm in dggbal, 'B') is not normwise safe: on damped ear-scaled chains of 30-100
  // masses it cost two to three digits of backward error (5.4e-13 against the bar
  // 100·f·u = 3.3e-13 at f = 30, 4.1e-12 at f = 100; 1.2e-15 and 3.7e-15 with permutation
  // only), and it was nowhere needed for the bar in the tests. It remains the fallback: when
  // the largest backward error exceeds 10·f·u, the pencil is solved again with 'B' and the run
  // with the smaller largest backward error is kept. After a deflation, permutation only: the
  // orthogonal transformations leave rounding-level residue where the linearization had exact
  // zeros, which steers the scaling into factors of 1e5 (measured: residuals 2.8e-12 instead
  // of 1.4e-16 on a heavily damped free-free chain).
  if (!p.balance) {
    qz(p, 'N', g, k, m, finite);
    return;
  }
  const bool deflating = p.deflating();
  const Eigen::MatrixXd A_keep = deflating ? Eigen::MatrixXd() : p.A;
  const Eigen::MatrixXd B_keep = deflating ? Eigen::MatrixXd() : p.B;
  qz(p, 'P', g, k, m, finite);
  if (!deflating && largest_backward_error(finite) > 10.0 * static_cast<double>(p.n) * kU) {
    p.A = A_keep;
    p.B = B_keep;
    std::vector<Raw> alt;
    qz(p, 'B', g, k, m, alt);
    if (largest_backward_error(alt) < largest_backward_error(finite)) finite.swap(alt);
  }
}

/// One run on the problem scaled by λ = gμ and d: linearization, deflation of the zero and
/// infinite eigenvalues, balanced QZ of the remaining pencil.
void run_scaled(GeneralPath& p, double g, double d, Run& out) {
  linearize(p, g, d);
  const bool deflating = p.deflating();
  Eigen::Index k = 0, m = p.N;
  if (deflating) deflate_linearization(p, k, m);
  out.zeros = deflating ? p.st.zeros : 0;
  out.infinities = deflating ? p.st.infinities : 0;
  out.finite.clear();
  if (m == 0) return;
  qz_balanced(p, g, k, m, out.finite);
}

/// The scaling to use: `scaling` with automatic resolved by τ, and tropical only when it applies.
QuadraticEigenOptions::Scaling choose_scaling(QuadraticEigenOptions::Scaling scaling,
                                              const GeneralPath& p, double tau) {
  const bool degenerate = p.degenerate();
  if (scaling == QuadraticEigenOptions::Scaling::automatic)
    scaling = (!degenerate && p.fQ > 0 && tau >= 10.0)
                  ? QuadraticEigenOptions::Scaling::tropical
                  : QuadraticEigenOptions::Scaling::fan_lin_van_dooren;
  if (scaling == QuadraticEigenOptions::Scaling::tropical && (degenerate || p.fQ == 0))
    scaling = QuadraticEigenOptions::Scaling::fan_lin_van_dooren;
  return scaling;
}

/// The run with the Fan-Lin-Van Dooren scaling (γ = √(‖K‖/‖M‖), δ = 2/(‖K‖ + γ‖Q‖)).
void run_fan_lin_van_dooren(GeneralPath& p, std::string& method, Run& r) {
  method = "fan_lin_van_dooren";
  const bool degenerate = p.degenerate();
  const double g = degenerate ? 1.0 : std::sqrt(p.fK / p.fM);
  const double den = degenerate ? std::max({p.fM, p.fQ, p.fK}) : 0.5 * (p.fK + g * p.fQ);
  run_scaled(p, g, den > 0 ? 1.0 / den : 1.0, r);
}

/// Order of finite eigenpairs by |λ|.
bool by_size(const Raw& a, const Raw& b) { return a.size() < b.size(); }

/// Whether splitting v (sorted by size) before index c cuts a conjugate pair.
bool pair_split(const std::vector<Raw>& v, Eigen::Index c) {
  const auto i = static_cast<std::size_t>(c);
  return i > 0 && i < v.size() && v[i].alpha == std::conj(v[i - 1].alpha) &&
         v[i].alpha.imag() != 0.0;
}

/// The tropical result when there are deflated eigenvalues: a third, Fan-Lin-Van Dooren run, and
/// three consecutive blocks of finite eigenvalues with the split points of least backward error.
void combine_three_runs(GeneralPath& p, Run& big, Run& small, Run& result) {
  Run mid;
  const double g = std::sqrt(p.fK / p.fM);
  run_scaled(p, g, 1.0 / (0.5 * (p.fK + g * p.fQ)), mid);
  std::stable_sort(big.finite.begin(), big.finite.end(), by_size);
  std::stable_sort(small.finite.begin(), small.finite.end(), by_size);
  std::stable_sort(mid.finite.begin(), mid.finite.end(), by_size);
  const bool use_mid = mid.zeros == small.zeros && mid.infinities == small.infinities;
  const auto mf = small.finite.size();
  std::vector<double> head(mf + 1, 0.0), tail(mf + 1, 0.0);
  for (std::size_t i = 0; i < mf; ++i) head[i + 1] = std::max(head[i], small.finite[i].eta);
  for (std::size_t i = mf; i-- > 0;) tail[i] = std::max(tail[i + 1], big.finite[i].eta);
  auto splits = [&](std::size_t c) {
    const auto ci = static_cast<Eigen::Index>(c);
    return pair_split(small.finite, ci) || pair_split(big.finite, ci) ||
           (use_mid && pair_split(mid.finite, ci));
  };
  std::size_t c1 = 0, c2 = 0;
  double best = kInf;
  for (std::size_t a = 0; a <= mf; ++a) {
    if (splits(a)) continue;
    double mid_max = 0.0;
    for (std::size_t b = a; b <= mf; ++b) {
      if (b > a) {
        if (!use_mid) break;
        mid_max = std::max(mid_max, mid.finite[b - 1].eta);
      }
      if (splits(b)) continue;
      const double worst = std::max({head[a], mid_max, tail[b]});
      if (worst < best) {  // strict: ties keep the smaller FLV block found first
        best = worst;
        c1 = a;
        c2 = b;
      }
    }
  }
  result.zeros = small.zeros;
  result.infinities = small.infinities;
  const auto d1 = static_cast<std::ptrdiff_t>(c1), d2 = static_cast<std::ptrdiff_t>(c2);
  result.finite.assign(small.finite.begin(), small.finite.begin() + d1);
  if (c2 > c1)
    result.finite.insert(result.finite.end(), mid.finite.begin() + d1, mid.finite.begin() + d2);
  result.finite.insert(result.finite.end(), big.finite.begin() + d2, big.finite.end());
}

/// The runs with tropical scaling and their combined finite eigenpairs.
void run_tropical(GeneralPath& p, std::string& method, Run& result) {
  // Tropical scaling (Gaubert & Sharify 2009, as used by quadeig): the n largest eigenvalues
  // from the run scaled by γ+ = ‖Q‖/‖M‖, the n smallest from the run scaled by γ− = ‖K‖/‖Q‖.
  // Deflated zero and infinite eigenvalues upset these counts and can leave finite ones
  // between the two groups; then a third run with the Fan-Lin-Van Dooren scaling is added and
  // the finite eigenvalues, sorted by |λ| in all three runs, are taken as three consecutive
  // blocks (from the γ−, the FLV and the γ+ run) with the split points that minimize the
  // largest backward error.
  method = "tropical";
  Run big, small;
  const double gp = p.fQ / p.fM, gm = p.fK / p.fQ;
  run_scaled(p, gp, 1.0 / std::max({p.fK, gp * p.fQ, gp * gp * p.fM}), big);
  run_scaled(p, gm, 1.0 / std::max({p.fK, gm * p.fQ, gm * gm * p.fM}), small);
  if (big.zeros != small.zeros || big.infinities != small.infinities) {
    // Rank decisions differ between the scalings: one run.
    run_fan_lin_van_dooren(p, method, result);
  } else if (small.zeros == 0 && small.infinities == 0) {
    std::stable_sort(big.finite.begin(), big.finite.end(), by_size);
    std::stable_sort(small.finite.begin(), small.finite.end(), by_size);
    Eigen::Index cut = p.n;  // keep conjugate pairs together: the split must not cut a pair
    if (pair_split(small.finite, cut)) cut += 1;
    result.finite.assign(small.finite.begin(), small.finite.begin() + cut);
    result.finite.insert(result.finite.end(), big.finite.begin() + cut, big.finite.end());
  } else {
    combine_three_runs(p, big, small, result);
  }
}

/// Appends the modes of `count` deflated zero or infinite eigenvalues (eigenvectors from pairs).
void push_null_modes(const NullPairs& pairs, Eigen::Index count, EigenvalueKind kind,
                     bool one_per_conjugate_pair, std::vector<Mode>& modes) {
  for (Eigen::Index j = 0; j < count; ++j) {
    if (one_per_conjugate_pair && kind == EigenvalueKind::zero && j >= pairs.x.cols())
      continue;  // a Jordan chain's extra zeros: listed once
    const Eigen::Index c = pairs.column(j);
    Mode md;
    md.kind = kind;
    md.alpha = kind == EigenvalueKind::zero ? cd(0.0) : cd(1.0);
    md.beta = kind == EigenvalueKind::zero ? 1.0 : 0.0;
    md.defective = pairs.defective(c, count);
    md.shape = pairs.x.col(c).cast<cd>();
    md.left_shape = pairs.y.col(c).cast<cd>();
    modes.push_back(std::move(md));
  }
}

/// Appends the modes of the finite eigenpairs, moving their eigenvectors.
void push_finite_modes(std::vector<Raw>& finite, bool one_per_conjugate_pair,
                       std::vector<Mode>& modes) {
  for (Raw& r : finite) {
    if (one_per_conjugate_pair && r.alpha.imag() < 0.0) continue;
    Mode m;
    m.alpha = r.alpha;
    m.beta = r.beta;
    m.kind = EigenvalueKind::finite;
    m.shape = std::move(r.x);
    m.left_shape = std::move(r.y);
    modes.push_back(std::move(m));
  }
}

}  // namespace

// The general path: null-vector pairs of the deflated eigenvalues, the runs of the chosen scaling
// and the modes.
void QuadraticEigenSolver::compute_general(const Eigen::MatrixXd& M, const Eigen::MatrixXd& Q,
                                           const Eigen::MatrixXd& K) {
  const Eigen::Index n = M.rows(), N = 2 * n;
  const Eigen::Index dK = n - rank_K_, dM = n - rank_M_;
  const double fM = M.norm(), fQ = Q.norm(), fK = K.norm();
  const double rank_tol =
      options_.rank_tolerance > 0 ? options_.rank_tolerance : static_cast<double>(n) * kU;
  // Left null spaces, of the dimension the right ones have.
  const Eigen::MatrixXd WK =
      dK > 0 ? detail::null_space(K.transpose(), rank_tol, true, rank_K_).basis
             : Eigen::MatrixXd(n, 0);
  const Eigen::MatrixXd WM =
      dM > 0 ? detail::null_space(M.transpose(), rank_tol, true, rank_M_).basis
             : Eigen::MatrixXd(n, 0);
  NullPairs zero_pairs, inf_pairs;
  zero_pairs.compute(null_K_, WK, Q);
  inf_pairs.compute(null_M_, WM, Q);

  GeneralPath p{M, Q, K, null_K_, null_M_,  // data
                n, N, dK, dM, fM, fQ, fK, rank_tol, norm_M_, norm_Q_, norm_K_, options_.balance,
                A_, B_, VL_, VR_, alphar_, alphai_, beta_,  // workspaces
                {}};
  const auto scaling = choose_scaling(options_.scaling, p, tau_);
  Run result;
  if (scaling == QuadraticEigenOptions::Scaling::none) {
    method_ = "none";
    run_scaled(p, 1.0, 1.0, result);
  } else if (scaling == QuadraticEigenOptions::Scaling::fan_lin_van_dooren) {
    run_fan_lin_van_dooren(p, method_, result);
  } else {
    run_tropical(p, method_, result);
  }

  num_zero_ = result.zeros;
  num_infinite_ = result.infinities;
  modes_.clear();
  push_null_modes(zero_pairs, num_zero_, EigenvalueKind::zero, options_.one_per_conjugate_pair,
                  modes_);
  push_null_modes(inf_pairs, num_infinite_, EigenvalueKind::infinite,
                  options_.one_per_conjugate_pair, modes_);
  push_finite_modes(result.finite, options_.one_per_conjugate_pair, modes_);
}

void QuadraticEigenSolver::finish(const Eigen::MatrixXd& M, const Eigen::MatrixXd& Q,
                                  const Eigen::MatrixXd& K) {
  const Eigen::Index n = M.rows(), m = static_cast<Eigen::Index>(modes_.size());
  Eigen::MatrixXcd X(n, m), Y(n, m);
  for (Eigen::Index k = 0; k < m; ++k) {
    Mode& md = modes_[static_cast<std::size_t>(k)];
    normalize_shape(md.shape);
    normalize_shape(md.left_shape);
    X.col(k) = md.shape;
    Y.col(k) = md.left_shape;
  }
  const Products px(M, Q, K, X);
  for (Eigen::Index k = 0; k < m; ++k) {
    Mode& md = modes_[static_cast<std::size_t>(k)];
    const auto y = Y.col(k);
    // Homogeneous condition number (Dedieu & Tisseur 2003) of the computed pair.
    {
      const cd a = md.alpha;
      const double b = md.beta;
      const Eigen::VectorXcd Da = 2.0 * a * px.MX.col(k) + b * px.QX.col(k);
      const Eigen::VectorXcd Db = a * px.QX.col(k) + 2.0 * b * px.KX.col(k);
      const cd den = y.dot(b * Da - std::conj(a) * Db);  // y.dot(v) = yᴴv
      const double aa = std::norm(a);
      const double num = std::sqrt(aa * aa * norm_M_ * norm_M_ + aa * b * b * norm_Q_ * norm_Q_ +
                                   b * b * b * b * norm_K_ * norm_K_);
      md.condition_homogeneous =
          (std::abs(den) > 0 && !md.defective) ? num / std::abs(den) : kInf;
    }
    const double xn = X.col(k).norm();
    switch (md.kind) {
      case EigenvalueKind::zero:
        md.lambda = 0.0;
        md.natural_frequency_hz = 0.0;
        md.damped_frequency_hz = 0.0;
        md.damping_ratio = std::numeric_limits<double>::quiet_NaN();
        md.backward_error = px.backward_error(k, 0.0, 1.0, xn, norm_M_, norm_Q_, norm_K_);
        md.condition = kInf;
        break;
      case EigenvalueKind::infinite:
        md.lambda = kInf;
        md.natural_frequency_hz = kInf;
        md.damped_frequency_hz = 0.0;
        md.damping_ratio = 0.0;
        md.backward_error = px.backward_error(k, 1.0, 0.0, xn, norm_M_, norm_Q_, norm_K_);
        md.condition = kInf;
        break;
      case EigenvalueKind::finite: {
        const cd lam = md.alpha / md.beta;
        md.lambda = lam;
        const double r = std::abs(lam);
        md.natural_frequency_hz = r / kTwoPi;
        md.damped_frequency_hz = lam.imag() / kTwoPi;
        md.damping_ratio = r > 0 ? -lam.real() / r + 0.0 : std::numeric_limits<double>::quiet_NaN();
        md.backward_error =
            px.backward_error(k, md.alpha, md.beta, xn, norm_M_, norm_Q_, norm_K_);
        const cd d = y.dot(2.0 * lam * px.MX.col(k) + px.QX.col(k));
        const double num = (r * r * norm_M_ + r * norm_Q_ + norm_K_);
        md.condition = (r > 0 && std::abs(d) > 0) ? num / (r * std::abs(d)) : kInf;
        // Absolute condition number times the backward error (not below the floor): a
        // Jordan block at 0 split into ±√δ by rounding has yᴴ(2λM + Q)x = O(√δ), so its bound
        // exceeds |λ| and it is reported zero within bound, without a damping ratio.
        const double kappa_abs =
            std::abs(d) > 0 ? num * xn * y.norm() / std::abs(d) : kInf;
        const double eta = std::max(md.backward_error, floor_);
        md.error_bound = kappa_abs < kInf ? kappa_abs * eta : kInf;
        md.zero_within_bound = !(r > md.error_bound);
        if (md.zero_within_bound) md.damping_ratio = std::numeric_limits<double>::quiet_NaN();
        break;
      }
    }
  }
  std::stable_sort(modes_.begin(), modes_.end(), [](const Mode& a, const Mode& b) {
    const int ka = kind_order(a.kind), kb = kind_order(b.kind);
    if (ka != kb) return ka < kb;
    if (a.kind != EigenvalueKind::finite) return false;
    const double ra = std::abs(a.lambda), rb = std::abs(b.lambda);
    if (ra != rb) return ra < rb;
    return a.lambda.imag() > b.lambda.imag();
  });
  // Members of a conjugate pair computed as two separate eigenvalues (undamped problems) can
  // differ in |λ| by rounding: put the one with Im λ > 0 first.
  for (std::size_t k = 0; k + 1 < modes_.size(); ++k) {
    Mode& a = modes_[k];
    Mode& b = modes_[k + 1];
    if (a.kind != EigenvalueKind::finite || b.kind != EigenvalueKind::finite) continue;
    const double ra = std::abs(a.lambda), rb = std::abs(b.lambda);
    if (std::abs(ra - rb) <= 1e-8 * std::max(ra, rb) && a.lambda.imag() < 0 &&
        b.lambda.imag() > 0 && std::abs(a.lambda - std::conj(b.lambda)) <= 1e-8 * ra) {
      std::swap(a, b);
      ++k;
    }
  }
}

Stability stability_of(const std::vector<Mode>& modes) {
  bool undecided = false, on_axis = false;
  for (const Mode& m : modes) {
    if (m.kind == EigenvalueKind::infinite) continue;
    if (m.kind == EigenvalueKind::zero) {
      on_axis = true;
      continue;
    }
    const double re = m.lambda.real();
    if (m.zero_within_bound || !(m.error_bound < kInf)) {
      undecided = true;
    } else if (re > m.error_bound) {
      return Stability::unstable;
    } else if (re == 0.0) {
      on_axis = true;
    } else if (re >= -m.error_bound) {
      undecided = true;
    }
  }
  if (undecided) return Stability::undecided;
  return on_axis ? Stability::marginal : Stability::stable;
}

}  // namespace mbsgen
