#include "mbsgen/runtime/quadratic_eigen.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "lapack.hpp"

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
  EigenvalueKind kind = EigenvalueKind::finite;
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

QuadraticEigenSolver& QuadraticEigenSolver::compute(const Eigen::MatrixXd& M,
                                                    const Eigen::MatrixXd& Q,
                                                    const Eigen::MatrixXd& K) {
  info_ = Eigen::InvalidInput;
  modes_.clear();
  // Validates dimensions and finiteness (throws DimensionError / NonFiniteError).
  const LinearModel check(M, Q.size() == 0 ? Eigen::MatrixXd::Zero(M.rows(), M.rows()) : Q, K,
                          Eigen::MatrixXd(M.rows(), 0), Eigen::MatrixXd(), Eigen::MatrixXd());
  const Eigen::MatrixXd& Qf = check.Q();
  const Eigen::Index n = M.rows();
  const double rank_tol =
      options_.rank_tolerance > 0 ? options_.rank_tolerance : static_cast<double>(n) * kU;
  rank_M_ = detail::numerical_rank(M, rank_tol);
  rank_K_ = detail::numerical_rank(K, rank_tol);
  norm_M_ = detail::norm2_estimate(M);
  norm_Q_ = detail::norm2_estimate(Qf);
  norm_K_ = detail::norm2_estimate(K);
  const double fM = M.norm(), fQ = Qf.norm(), fK = K.norm();
  tau_ = (fM > 0 && fK > 0) ? fQ / std::sqrt(fM * fK) : kInf;
  gamma_ = (fM > 0 && fK > 0) ? std::sqrt(fK / fM) : 1.0;

  bool done = false;
  if (options_.symmetric_fast_path && check.is_symmetric_undamped()) compute_symmetric(M, K, done);
  if (!done) compute_general(M, Qf, K);
  finish(M, Qf, K);
  info_ = Eigen::Success;
  return *this;
}

// ---------------------------------------------------------------------------------------------
// Symmetric undamped fast path: K v = ω² M v by dsygvd (itype 1), λ = ±iω.
void QuadraticEigenSolver::compute_symmetric(const Eigen::MatrixXd& M, const Eigen::MatrixXd& K,
                                             bool& ok) {
  const Eigen::Index n = M.rows();
  Eigen::MatrixXd V = K, Mw = M;
  Eigen::VectorXd w(n);
  const lapack_int info = LAPACKE_dsygvd(LAPACK_COL_MAJOR, 1, 'V', 'U', detail::li(n), V.data(),
                                         detail::li(n), Mw.data(), detail::li(n), w.data());
  detail::check_lapack(info, "dsygvd", "QuadraticEigenSolver::compute");
  if (info > 0) return;  // M not positive definite (or no convergence): general path
  ok = true;
  method_ = "symmetric";
  modes_.clear();
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::VectorXd v = V.col(i);
    // A perturbation of K of size (10·f·u)‖K‖₂ moves ω² = vᵀKv/vᵀMv by at most this much.
    const double tol =
        10.0 * static_cast<double>(n) * kU * norm_K_ * v.squaredNorm() / v.dot(M * v);
    Mode m;
    m.shape = v.cast<cd>();
    if (std::abs(w[i]) <= tol && rank_K_ < n) {
      m.kind = EigenvalueKind::zero;
      m.alpha = 0.0;
      m.beta = 1.0;
      modes_.push_back(m);
      if (!options_.one_per_conjugate_pair) modes_.push_back(m);
      continue;
    }
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
// General path: scaled first companion linearization, dggevx with balancing.
void QuadraticEigenSolver::compute_general(const Eigen::MatrixXd& M, const Eigen::MatrixXd& Q,
                                           const Eigen::MatrixXd& K) {
  const Eigen::Index n = M.rows(), N = 2 * n;
  const double fM = M.norm(), fQ = Q.norm(), fK = K.norm();
  A_.resize(N, N);
  B_.resize(N, N);
  VL_.resize(N, N);
  VR_.resize(N, N);
  alphar_.resize(N);
  alphai_.resize(N);
  beta_.resize(N);
  Eigen::VectorXd lscale(N), rscale(N), rconde(N), rcondv(N);

  auto run = [&](double g, double d, std::vector<Raw>& out) {
    A_.setZero();
    B_.setZero();
    A_.topRightCorner(n, n).setIdentity();
    A_.bottomLeftCorner(n, n) = -d * K;
    A_.bottomRightCorner(n, n) = -(g * d) * Q;
    B_.topLeftCorner(n, n).setIdentity();
    B_.bottomRightCorner(n, n) = (g * g * d) * M;
    lapack_int ilo = 0, ihi = 0;
    double abnrm = 0, bbnrm = 0;
    const lapack_int info = LAPACKE_dggevx(
        LAPACK_COL_MAJOR, options_.balance ? 'B' : 'N', 'V', 'V', 'N', detail::li(N), A_.data(),
        detail::li(N), B_.data(), detail::li(N), alphar_.data(), alphai_.data(), beta_.data(),
        VL_.data(), detail::li(N), VR_.data(), detail::li(N), &ilo, &ihi, lscale.data(),
        rscale.data(), &abnrm, &bbnrm, rconde.data(), rcondv.data());
    detail::check_lapack(info, "dggevx", "QuadraticEigenSolver::compute");
    if (info > 0) throw LapackError("QuadraticEigenSolver::compute: QZ iteration (dggevx) failed");
    out.clear();
    out.reserve(static_cast<std::size_t>(N));
    // Complex eigenvectors z = [top; bottom] and the bottom blocks of the left ones.
    Eigen::MatrixXcd Z(N, N), W(n, N);
    for (Eigen::Index j = 0; j < N; ++j) {
      if (alphai_[j] == 0.0) {
        Z.col(j) = VR_.col(j).cast<cd>();
        W.col(j) = VL_.col(j).tail(n).cast<cd>();
      } else if (alphai_[j] > 0.0) {
        Z.col(j).real() = VR_.col(j);
        Z.col(j).imag() = VR_.col(j + 1);
        W.col(j).real() = VL_.col(j).tail(n);
        W.col(j).imag() = VL_.col(j + 1).tail(n);
      } else {  // second of a pair: conjugates of the previous column pair
        Z.col(j).real() = VR_.col(j - 1);
        Z.col(j).imag() = -VR_.col(j);
        W.col(j).real() = VL_.col(j - 1).tail(n);
        W.col(j).imag() = -VL_.col(j).tail(n);
      }
    }
    const Eigen::MatrixXcd top = Z.topRows(n), bottom = Z.bottomRows(n);
    const Products pt(M, Q, K, top), pb(M, Q, K, bottom);
    for (Eigen::Index j = 0; j < N; ++j) {
      Raw r;
      r.alpha = g * cd(alphar_[j], alphai_[j]);
      r.beta = beta_[j];
      normalize_pair(r.alpha, r.beta);
      const double nt = top.col(j).norm(), nb = bottom.col(j).norm();
      const double e_top =
          nt > 0 ? pt.backward_error(j, r.alpha, r.beta, nt, norm_M_, norm_Q_, norm_K_) : kInf;
      const double e_bot =
          nb > 0 ? pb.backward_error(j, r.alpha, r.beta, nb, norm_M_, norm_Q_, norm_K_) : kInf;
      r.x = e_top <= e_bot ? top.col(j) : bottom.col(j);
      r.y = W.col(j);
      out.push_back(std::move(r));
    }
  };

  std::vector<Raw> raw;
  const bool degenerate = !(fM > 0 && fK > 0);
  auto scaling = options_.scaling;
  if (scaling == QuadraticEigenOptions::Scaling::automatic)
    scaling = (!degenerate && fQ > 0 && tau_ >= 10.0)
                  ? QuadraticEigenOptions::Scaling::tropical
                  : QuadraticEigenOptions::Scaling::fan_lin_van_dooren;
  if (scaling == QuadraticEigenOptions::Scaling::tropical && (degenerate || fQ == 0))
    scaling = QuadraticEigenOptions::Scaling::fan_lin_van_dooren;

  if (scaling == QuadraticEigenOptions::Scaling::none) {
    method_ = "none";
    run(1.0, 1.0, raw);
  } else if (scaling == QuadraticEigenOptions::Scaling::fan_lin_van_dooren) {
    method_ = "fan_lin_van_dooren";
    const double g = degenerate ? 1.0 : std::sqrt(fK / fM);
    const double den = degenerate ? std::max({fM, fQ, fK}) : 0.5 * (fK + g * fQ);
    run(g, den > 0 ? 1.0 / den : 1.0, raw);
  } else {
    // Tropical scaling (Gaubert & Sharify 2009, as used by quadeig): the f largest eigenvalues
    // from the run scaled by γ+ = ‖Q‖/‖M‖, the f smallest from the run scaled by γ− = ‖K‖/‖Q‖.
    method_ = "tropical";
    std::vector<Raw> big, small;
    const double gp = fQ / fM, gm = fK / fQ;
    run(gp, 1.0 / std::max({fK, gp * fQ, gp * gp * fM}), big);
    run(gm, 1.0 / std::max({fK, gm * fQ, gm * gm * fM}), small);
    auto by_size = [](const Raw& a, const Raw& b) { return a.size() < b.size(); };
    std::stable_sort(big.begin(), big.end(), by_size);
    std::stable_sort(small.begin(), small.end(), by_size);
    // Keep conjugate pairs together: the split point must not cut a pair.
    Eigen::Index cut = n;
    auto pair_split = [](const std::vector<Raw>& v, Eigen::Index c) {
      const auto i = static_cast<std::size_t>(c);
      return i > 0 && i < v.size() && v[i].alpha == std::conj(v[i - 1].alpha) &&
             v[i].alpha.imag() != 0.0;
    };
    if (pair_split(small, cut)) cut += 1;
    raw.assign(small.begin(), small.begin() + cut);
    raw.insert(raw.end(), big.begin() + cut, big.end());
  }

  // Classification of zero and infinite eigenvalues: rank counts from the column-pivoted QR of
  // K and M bound how many there can be (≤ 2 per null vector for the problems we target).
  const double tol = options_.classification_tolerance;
  std::vector<std::size_t> idx(raw.size());
  std::iota(idx.begin(), idx.end(), 0);
  const double gc = gamma_;
  auto rel = [&](const Raw& r) {
    return r.beta == 0.0 ? kInf : std::abs(r.alpha) / (r.beta * gc);
  };
  if (rank_M_ < n) {
    std::stable_sort(idx.begin(), idx.end(),
                     [&](std::size_t a, std::size_t b) { return rel(raw[a]) > rel(raw[b]); });
    Eigen::Index count = 0;
    for (std::size_t i : idx) {
      if (count >= 2 * (n - rank_M_) || rel(raw[i]) < 1.0 / tol) break;
      raw[i].kind = EigenvalueKind::infinite;
      ++count;
    }
  }
  if (rank_K_ < n) {
    std::stable_sort(idx.begin(), idx.end(),
                     [&](std::size_t a, std::size_t b) { return rel(raw[a]) < rel(raw[b]); });
    Eigen::Index count = 0;
    for (std::size_t i : idx) {
      if (count >= 2 * (n - rank_K_) || rel(raw[i]) > tol) break;
      if (raw[i].kind != EigenvalueKind::finite) continue;
      raw[i].kind = EigenvalueKind::zero;
      ++count;
    }
  }
  modes_.clear();
  Eigen::Index zeros_kept = 0;
  for (Raw& r : raw) {
    if (options_.one_per_conjugate_pair) {
      if (r.kind == EigenvalueKind::finite && r.alpha.imag() < 0.0) continue;
      if (r.kind == EigenvalueKind::zero && zeros_kept++ >= n - rank_K_) continue;
    }
    Mode m;
    m.alpha = r.alpha;
    m.beta = r.beta;
    m.kind = r.kind;
    m.shape = std::move(r.x);
    m.left_shape = std::move(r.y);
    modes_.push_back(std::move(m));
  }
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
      md.condition_homogeneous = std::abs(den) > 0 ? num / std::abs(den) : kInf;
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

}  // namespace mbsgen
