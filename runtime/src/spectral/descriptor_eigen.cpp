// Descriptor models E ẋ = A x + B u: validation, eigenpairs of λE − A, frequency response.
//
// Exact zeros. The generator writes structurally zero entries as exact 0.0, so an ignorable
// coordinate x_k (one the equations never depend on) gives an exactly zero column k of A. Then
// (λE − A)e_k = λE e_k, and for the set Z of such columns and the rest R,
//     det(λE − A) = det([λE_Z, (λE − A)_R]) = λ^|Z| det([E_Z, (λE − A)_R]).
// With the Householder QR E_Z P = [Q1 Q2][R; 0] (LAPACK dgeqp3, column pivoting for the rank
// decision) the second factor is ±det(R)·det(Q2ᵀ(λE − A)_R), so the other eigenvalues are those
// of the (n−|Z|)×(n−|Z|) pencil (Q2ᵀE_R, Q2ᵀA_R), computed without any rounding in the |Z|
// zeros. If E_Z is rank deficient the second factor vanishes identically: the pencil is singular.
// Eigenvectors of the full pencil from those w of the reduced one: right x = [x_Z; w] with
// α R Pᵀx_Z = Q1ᵀ(βA_R − αE_R)w (the first |Z| rows of (βA − αE)x = 0), left y = Q2 l exactly
// (Q2ᵀE_Z = 0 and A_Z = 0 make yᴴ(βA − αE) = 0).
//
// Repeating the test. When every column of E_Z has one nonzero E(p_k, k), in distinct rows, Q is
// a permutation and R = diag(E(p_k, k)): the reduced pencil is (E, A) without the columns Z and
// the rows p_k, bit for bit, so an exactly zero column there is a structural fact too (that
// column of A is zero outside the removed rows), and the deflation is repeated, level by level.
// In a suitable ordering λE − A is then block upper triangular with diagonal blocks
// λ·diag(E(p_k, k)) and the final reduced pencil, which gives the determinant and the back
// substitution for x. A zero of a later level has no eigenvector of its own (A e_k ≠ 0): it
// extends a Jordan chain, E x_{j−1} = A x_j from x = e_k down to a head in the first level's
// columns. After a Householder deflation the test is not repeated: an exact 0.0 in Q2ᵀA_R is
// then a floating-point accident, and a structural zero need not come out as 0.0.
//
// The rest: QZ with left and right eigenvectors (LAPACK dggevx; Moler & Stewart 1973). For the
// pencil A − λE with data errors ‖ΔA‖ ≤ ε‖A‖, ‖ΔE‖ ≤ ε‖E‖ (Higham & Higham 1998, "Structured
// backward error and condition of generalized eigenvalue problems", SIAM J. Matrix Anal. Appl.
// 20(2)):
//     η(α, β, x) = ‖(βA − αE)x‖ / ((|β|‖A‖ + |α|‖E‖)‖x‖),
//     κ_abs(λ)   = (‖A‖ + |λ|‖E‖)‖x‖‖y‖ / |yᴴEx|,
// and |λ − λ_exact| ≲ κ_abs·ε to first order. The homogeneous condition number of (α, β)
// (Dedieu & Tisseur 2003, "Perturbation theory for homogeneous polynomial eigenvalue problems",
// Linear Algebra Appl. 358, for degree 1) is √(|α|²‖E‖² + |β|²‖A‖²)/|yᴴ(βE + ᾱA)x| for unit x, y.
#include "mbsgen/runtime/spectral/descriptor_eigen.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <sstream>

#include "spectral/dense_linear_algebra.hpp"
#include "spectral/spectrum_structure.hpp"

namespace mbsgen {

using cd = std::complex<double>;
using Eigen::Index;

namespace {
constexpr double kU = std::numeric_limits<double>::epsilon() / 2;  // unit roundoff 2⁻⁵³
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kTwoPi = 6.283185307179586476925286766559;
}  // namespace

// ---------------------------------------------------------------------------------------------
// Eigenpairs.

namespace {

/// ‖x‖₂ = 1 and the largest-modulus entry real positive (as QuadraticEigenSolver).
void normalize_shape(Eigen::VectorXcd& x) {
  const double nx = x.norm();
  if (nx == 0.0) return;
  Index imax = 0;
  x.cwiseAbs().maxCoeff(&imax);
  const cd phase = std::abs(x[imax]) > 0 ? std::conj(x[imax]) / std::abs(x[imax]) : cd(1.0);
  x *= phase / nx;
  x[imax] = cd(x[imax].real(), 0.0);
}

/// Real A times complex X by two real products.
Eigen::MatrixXcd times(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::MatrixXcd& X) {
  Eigen::MatrixXcd out(A.rows(), X.cols());
  const Eigen::MatrixXd Xr = X.real(), Xi = X.imag();
  out.real().noalias() = A * Xr;
  out.imag().noalias() = A * Xi;
  return out;
}

/// A computed eigenpair of the full pencil, before classification.
struct Raw {
  cd alpha;     // normalized |α|² + β² = 1
  double beta;  // ≥ 0
  Eigen::VectorXcd x, y;
  double eta = 0.0;       // normwise backward error (reported)
  double eta_comp = 0.0;  // componentwise backward error (chooses the balancing)
  // The eigenvectors and backward error the error bound is computed from: those of the reduced
  // pencil when every deflation was exact (a structured bound, see Conditioning), else x, y, eta.
  Eigen::VectorXcd cx, cy;
  double ceta = 0.0;
};

/// The pencil an eigenvalue's condition is measured on, with its norm estimates.
struct Conditioning {
  const Eigen::MatrixXd& E;
  const Eigen::MatrixXd& A;
  double nE, nA;
};

/// Householder deflation of the exactly zero columns Z of a (sub-)pencil (file comment), once.
struct HouseholderDeflation {
  std::vector<Index> Z, R;  // zero columns of A, and the rest
  Eigen::MatrixXd QR;       // dgeqp3 of E_Z: R in the upper triangle, reflectors below
  Eigen::VectorXd tau;
  std::vector<lapack_int> jpvt;  // E_Z P: column j of E_Z P is column jpvt[j] − 1 of E_Z
  Eigen::MatrixXd E1, A1;        // Q1ᵀE_R, Q1ᵀA_R (|Z|×r)
  Eigen::MatrixXd E2, A2;        // Q2ᵀE_R, Q2ᵀA_R (r×r): the reduced pencil
  Eigen::MatrixXd Qfull;         // [Q1 Q2] (n×n), for the left eigenvectors y = Q2 l

  void compute(const Eigen::MatrixXd& E, const Eigen::MatrixXd& A,
               const std::vector<std::string>& names);
  /// Right eigenvector of the pencil from w of the reduced one (file comment).
  Eigen::VectorXcd right(const Eigen::VectorXcd& w, cd alpha, double beta) const;
  /// Left eigenvector y = Q2 l of the pencil from l of the reduced one.
  Eigen::VectorXcd left(const Eigen::VectorXcd& l) const {
    if (Z.empty()) return l;
    const Index r = static_cast<Index>(R.size());
    return Qfull.rightCols(r).cast<cd>() * l;
  }
};

/// `level` > 0: the column is zero in the equations left after deflating ignorable coordinates.
[[noreturn]] void throw_unused_state(const std::string& name, int level = 0) {
  std::ostringstream s;
  s << "DescriptorEigenSolver::compute: the pencil λE − A is singular (det ≡ 0): state '" << name
    << "' has a zero column in both E and A ";
  if (level == 0)
    s << "(it appears in no equation)";
  else
    s << "in the equations left after deflating the ignorable coordinates (it appears only in "
         "theirs)";
  throw SingularSystemError(s.str());
}

void HouseholderDeflation::compute(const Eigen::MatrixXd& E, const Eigen::MatrixXd& A,
                                   const std::vector<std::string>& names) {
  const Index n = A.rows();
  Z.clear();
  R.clear();
  for (Index j = 0; j < n; ++j) ((A.col(j).array() == 0.0).all() ? Z : R).push_back(j);
  const Index z = static_cast<Index>(Z.size()), r = n - z;
  if (z == 0) {
    E2 = E;
    A2 = A;
    return;
  }
  QR.resize(n, z);
  Eigen::MatrixXd ER(n, r), AR(n, r);
  for (Index j = 0; j < z; ++j) QR.col(j) = E.col(Z[static_cast<std::size_t>(j)]);
  for (Index j = 0; j < r; ++j) {
    ER.col(j) = E.col(R[static_cast<std::size_t>(j)]);
    AR.col(j) = A.col(R[static_cast<std::size_t>(j)]);
  }
  for (Index j = 0; j < z; ++j)
    if ((QR.col(j).array() == 0.0).all())
      throw_unused_state(names[static_cast<std::size_t>(Z[static_cast<std::size_t>(j)])]);
  const lapack_int nn = detail::li(n), zz = detail::li(z);
  const char* who = "DescriptorEigenSolver::compute (zero deflation)";
  jpvt.assign(static_cast<std::size_t>(z), 0);
  tau.resize(z);
  lapack_int info =
      LAPACKE_dgeqp3(LAPACK_COL_MAJOR, nn, zz, QR.data(), nn, jpvt.data(), tau.data());
  detail::check_lapack(info, "dgeqp3", who);
  // Rank decision as QuadraticEigenSolver's default: pivot ≤ n·u·|R_00| counts as zero.
  const double tol = static_cast<double>(n) * kU * std::abs(QR(0, 0));
  for (Index j = 0; j < z; ++j)
    if (!(std::abs(QR(j, j)) > tol)) {
      std::ostringstream s;
      s << "DescriptorEigenSolver::compute: the pencil λE − A is singular (det ≡ 0 to working "
           "precision): the states with zero columns in A (";
      for (Index k = 0; k < z; ++k)
        s << (k ? ", " : "") << names[static_cast<std::size_t>(Z[static_cast<std::size_t>(k)])];
      s << ") have linearly dependent columns in E (rank " << j << " of " << z << ")";
      throw SingularSystemError(s.str());
    }
  Qfull = Eigen::MatrixXd::Identity(n, n);
  for (Eigen::MatrixXd* X : {&ER, &AR, &Qfull}) {
    info = LAPACKE_dormqr(LAPACK_COL_MAJOR, 'L', 'T', nn, detail::li(X->cols()), zz, QR.data(),
                          nn, tau.data(), X->data(), nn);
    detail::check_lapack(info, "dormqr", who);
  }
  Qfull.transposeInPlace();  // (Qᵀ I)ᵀ = Q
  E1 = ER.topRows(z);
  A1 = AR.topRows(z);
  E2 = ER.bottomRows(r);
  A2 = AR.bottomRows(r);
}

Eigen::VectorXcd HouseholderDeflation::right(const Eigen::VectorXcd& w, cd alpha,
                                             double beta) const {
  const Index z = static_cast<Index>(Z.size()), r = static_cast<Index>(R.size());
  Eigen::VectorXcd x(z + r);
  for (Index j = 0; j < r; ++j) x[R[static_cast<std::size_t>(j)]] = w[j];
  if (z == 0) return x;
  // α R Pᵀx_Z = (βA1 − αE1)w. α = 0 exactly (a further zero of the reduced pencil) has no
  // solution unless the right side vanishes: a rounding-level α gives the chain's direction.
  const cd a = alpha != 0.0 ? alpha : cd(kU);
  const Eigen::VectorXcd rhs = (beta * times(A1, w) - alpha * times(E1, w)) / a;
  const Eigen::MatrixXcd Rc = QR.topRows(z).cast<cd>();
  const Eigen::VectorXcd v = Rc.triangularView<Eigen::Upper>().solve(rhs);
  for (Index j = 0; j < z; ++j)
    x[Z[static_cast<std::size_t>(jpvt[static_cast<std::size_t>(j)] - 1)]] = v[j];
  return x;
}

/// All deflations of exact zeros (file comment): exact levels while every zero column of A has
/// one nonzero in E, in distinct rows; then Householder once on what is left.
struct Deflation {
  struct Pivot {
    Index col, row;  // zero column k of A and the one row p where E(:, k) ≠ 0 (full numbering)
    int level;       // 0 for the zero columns of A itself, l for those of the l-th sub-pencil
  };
  std::vector<Pivot> pivots;      // in level order
  std::vector<Index> rows, cols;  // the sub-pencil (E, A)(rows, cols) left by the exact levels
  int levels = 0;
  HouseholderDeflation hh;  // on the sub-pencil, in its numbering

  void compute(const Eigen::MatrixXd& E, const Eigen::MatrixXd& A,
               const std::vector<std::string>& names);
  /// The pencil QZ solves.
  const Eigen::MatrixXd& reduced_E() const { return hh.E2; }
  const Eigen::MatrixXd& reduced_A() const { return hh.A2; }
  /// Whether every deflation was exact (no rounding in the reduced pencil).
  bool exact() const { return hh.Z.empty(); }
  /// Right and left eigenvectors of the full pencil from those of the reduced one.
  Eigen::VectorXcd right(const Eigen::VectorXcd& w, cd alpha, double beta,
                         const Eigen::MatrixXd& E, const Eigen::MatrixXd& A) const;
  Eigen::VectorXcd left(const Eigen::VectorXcd& l, Index n) const;
};

// A level: the zero columns Z of A(rows, cols). When each has exactly one nonzero E(p_k, k) in
// distinct rows p_k, Q = a permutation deflates them exactly (R = diag(E(p_k, k))): the reduced
// pencil is the submatrix without the columns Z and the rows p_k, bit for bit, so a zero column
// there is exactly zero in the data too (column k of A is zero outside the removed rows), and the
// test can be repeated soundly. The first level whose columns lack that structure, if any, goes
// to the Householder deflation, after which nothing is repeated.
void Deflation::compute(const Eigen::MatrixXd& E, const Eigen::MatrixXd& A,
                        const std::vector<std::string>& names) {
  const Index n = A.rows();
  rows.resize(static_cast<std::size_t>(n));
  cols.resize(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    rows[static_cast<std::size_t>(i)] = i;
    cols[static_cast<std::size_t>(i)] = i;
  }
  pivots.clear();
  levels = 0;
  while (!cols.empty()) {
    std::vector<Pivot> level;
    std::vector<char> row_used(static_cast<std::size_t>(n), 0);
    bool structured = true;
    for (Index c : cols) {
      if (!std::all_of(rows.begin(), rows.end(), [&](Index r) { return A(r, c) == 0.0; }))
        continue;
      Index count = 0, p = -1;
      for (Index r : rows)
        if (E(r, c) != 0.0) {
          ++count;
          p = r;
        }
      if (count == 0) throw_unused_state(names[static_cast<std::size_t>(c)], levels);
      if (count > 1 || row_used[static_cast<std::size_t>(p)]) structured = false;
      if (count == 1) row_used[static_cast<std::size_t>(p)] = 1;
      level.push_back({c, p, levels});
    }
    if (level.empty() || !structured) break;
    for (const Pivot& pv : level) {
      rows.erase(std::find(rows.begin(), rows.end(), pv.row));
      cols.erase(std::find(cols.begin(), cols.end(), pv.col));
    }
    pivots.insert(pivots.end(), level.begin(), level.end());
    ++levels;
  }
  const Index m = static_cast<Index>(cols.size());
  Eigen::MatrixXd Es(m, m), As(m, m);
  std::vector<std::string> sub_names;
  for (Index j = 0; j < m; ++j) {
    const Index c = cols[static_cast<std::size_t>(j)];
    sub_names.push_back(names[static_cast<std::size_t>(c)]);
    for (Index i = 0; i < m; ++i) {
      Es(i, j) = E(rows[static_cast<std::size_t>(i)], c);
      As(i, j) = A(rows[static_cast<std::size_t>(i)], c);
    }
  }
  hh.compute(Es, As, sub_names);
}

// Back substitution through the exact levels, deepest first: row p_k of (βA − αE)x = 0 reads
// −αE(p_k, k)x_k + Σ_{j ≠ k} (βA − αE)(p_k, j)x_j = 0, and its other entries in columns of the
// same or earlier levels are zero by construction.
Eigen::VectorXcd Deflation::right(const Eigen::VectorXcd& w, cd alpha, double beta,
                                  const Eigen::MatrixXd& E, const Eigen::MatrixXd& A) const {
  const Eigen::VectorXcd xs = hh.right(w, alpha, beta);
  Eigen::VectorXcd x = Eigen::VectorXcd::Zero(E.rows());
  for (std::size_t j = 0; j < cols.size(); ++j) x[cols[j]] = xs[static_cast<Index>(j)];
  const cd a = alpha != 0.0 ? alpha : cd(kU);  // as HouseholderDeflation::right
  for (auto it = pivots.rbegin(); it != pivots.rend(); ++it) {
    const cd s = (beta * A.row(it->row).transpose().cast<cd>() -
                  alpha * E.row(it->row).transpose().cast<cd>())
                     .cwiseProduct(x)
                     .sum();
    x[it->col] = s / (a * E(it->row, it->col));
  }
  return x;
}

// y vanishes on the removed rows: yᴴ(βA − αE) has zero entries in the removed columns because
// those columns of A and E are nonzero only in removed rows.
Eigen::VectorXcd Deflation::left(const Eigen::VectorXcd& l, Index n) const {
  const Eigen::VectorXcd ys = hh.left(l);
  Eigen::VectorXcd y = Eigen::VectorXcd::Zero(n);
  for (std::size_t i = 0; i < rows.size(); ++i) y[rows[i]] = ys[static_cast<Index>(i)];
  return y;
}

/// Homogeneous normwise backward error η of (α, β, x) for λE − A with norm estimates nE, nA.
double backward_error(const Eigen::MatrixXd& E, const Eigen::MatrixXd& A, cd alpha, double beta,
                      const Eigen::VectorXcd& x, double nE, double nA) {
  const double r = (beta * times(A, x) - alpha * times(E, x)).norm();
  const double den = (beta * nA + std::abs(alpha) * nE) * x.norm();
  if (den == 0.0) return r == 0.0 ? 0.0 : kInf;
  return r / den;
}

/// Componentwise backward error max_i |(βA − αE)x|_i / (|β||A||x| + |α||E||x|)_i (the
/// Oettli-Prager form; Higham & Higham 1998): the smallest ε with |ΔA| ≤ ε|A|, |ΔE| ≤ ε|E|
/// entrywise that makes (α, β, x) exact. It sees what the normwise one cannot in E = blkdiag(I, M), A = [[0, I], [−K, −Q]]:
/// residuals of size u‖K‖ in the kinematic rows, whose own entries are 1.
double componentwise_backward_error(const Eigen::MatrixXd& E, const Eigen::MatrixXd& A, cd alpha,
                                    double beta, const Eigen::VectorXcd& x) {
  const Eigen::VectorXcd r = beta * times(A, x) - alpha * times(E, x);
  const Eigen::VectorXd ax = x.cwiseAbs();
  const Eigen::VectorXd den =
      beta * (A.cwiseAbs() * ax) + std::abs(alpha) * (E.cwiseAbs() * ax);
  double w = 0.0;
  for (Index i = 0; i < r.size(); ++i) {
    const double ri = std::abs(r[i]);
    if (ri == 0.0) continue;
    w = std::max(w, den[i] > 0 ? ri / den[i] : kInf);
  }
  return w;
}

/// QZ (dggevx, balancing `job`) of the reduced pencil (A2, E2), eigenvectors of the full pencil.
std::vector<Raw> qz(const Deflation& d, const Eigen::MatrixXd& E, const Eigen::MatrixXd& A,
                    char job, double nE, double nA) {
  const Index m = d.reduced_A().rows();
  Eigen::MatrixXd As = d.reduced_A(), Es = d.reduced_E(), VL(m, m), VR(m, m);
  Eigen::VectorXd ar(m), ai(m), be(m), lscale(m), rscale(m), rconde(m), rcondv(m);
  lapack_int ilo = 0, ihi = 0;
  double abnrm = 0, bbnrm = 0;
  const lapack_int mm = detail::li(m);
  const lapack_int info = LAPACKE_dggevx(
      LAPACK_COL_MAJOR, job, 'V', 'V', 'N', mm, As.data(), mm, Es.data(), mm, ar.data(),
      ai.data(), be.data(), VL.data(), mm, VR.data(), mm, &ilo, &ihi, lscale.data(),
      rscale.data(), &abnrm, &bbnrm, rconde.data(), rcondv.data());
  detail::check_lapack(info, "dggevx", "DescriptorEigenSolver::compute");
  if (info > 0) throw LapackError("DescriptorEigenSolver::compute: QZ iteration (dggevx) failed");
  std::vector<Raw> out;
  out.reserve(static_cast<std::size_t>(m));
  for (Index j = 0; j < m; ++j) {
    Eigen::VectorXcd w(m), l(m);
    if (ai[j] == 0.0) {
      w = VR.col(j).cast<cd>();
      l = VL.col(j).cast<cd>();
    } else if (ai[j] > 0.0) {
      w.real() = VR.col(j);
      w.imag() = VR.col(j + 1);
      l.real() = VL.col(j);
      l.imag() = VL.col(j + 1);
    } else {  // second of a pair: conjugate of the previous column pair
      w.real() = VR.col(j - 1);
      w.imag() = -VR.col(j);
      l.real() = VL.col(j - 1);
      l.imag() = -VL.col(j);
    }
    if (ar[j] == 0.0 && ai[j] == 0.0 && be[j] == 0.0)  // dggevx's sign of a singular pencil
      throw SingularSystemError(
          "DescriptorEigenSolver::compute: the pencil λE − A is singular (det ≡ 0 to working "
          "precision: QZ found α = β = 0), e.g. equations that are linearly dependent in both E "
          "and A");
    Raw r;
    r.alpha = cd(ar[j], ai[j]);
    r.beta = be[j];
    const double s = std::hypot(std::abs(r.alpha), r.beta);
    if (s > 0) {
      r.alpha /= s;
      r.beta /= s;
    }
    r.x = d.right(w, r.alpha, r.beta, E, A);
    r.y = d.left(l, E.rows());
    r.eta = backward_error(E, A, r.alpha, r.beta, r.x, nE, nA);
    r.eta_comp = componentwise_backward_error(E, A, r.alpha, r.beta, r.x);
    if (d.exact()) {
      r.cx = w, r.cy = l;
      r.ceta = backward_error(d.reduced_E(), d.reduced_A(), r.alpha, r.beta, w,
                              detail::norm2_estimate(d.reduced_E()), detail::norm2_estimate(d.reduced_A()));
    } else {
      r.cx = r.x, r.cy = r.y, r.ceta = r.eta;
    }
    out.push_back(std::move(r));
  }
  return out;
}

double worst(const std::vector<Raw>& v, bool componentwise = false) {
  double e = 0.0;
  for (const Raw& r : v) e = std::max(e, componentwise ? r.eta_comp : r.eta);
  return e;
}


int kind_order(EigenvalueKind k) {
  return k == EigenvalueKind::zero ? 0 : (k == EigenvalueKind::finite ? 1 : 2);
}

/// QuadraticEigenSolver's order: zero, finite by |λ| (Im λ > 0 first in a pair), infinite.
void sort_modes(std::vector<Mode>& modes) {
  std::stable_sort(modes.begin(), modes.end(), [](const Mode& a, const Mode& b) {
    const int ka = kind_order(a.kind), kb = kind_order(b.kind);
    if (ka != kb) return ka < kb;
    if (a.kind != EigenvalueKind::finite) return false;
    const double ra = std::abs(a.lambda), rb = std::abs(b.lambda);
    if (ra != rb) return ra < rb;
    return a.lambda.imag() > b.lambda.imag();
  });
  // Members of a conjugate pair can differ in |λ| by rounding: put Im λ > 0 first.
  for (std::size_t k = 0; k + 1 < modes.size(); ++k) {
    Mode& a = modes[k];
    Mode& b = modes[k + 1];
    if (a.kind != EigenvalueKind::finite || b.kind != EigenvalueKind::finite) continue;
    const double ra = std::abs(a.lambda), rb = std::abs(b.lambda);
    if (std::abs(ra - rb) <= 1e-8 * std::max(ra, rb) && a.lambda.imag() < 0 &&
        b.lambda.imag() > 0 && std::abs(a.lambda - std::conj(b.lambda)) <= 1e-8 * ra) {
      std::swap(a, b);
      ++k;
    }
  }
}

/// Classifies a computed pair (class comment of DescriptorEigenSolver) and fills a Mode. The
/// condition numbers, the infinite test and the error bound use the pencil `c` with r.cx, r.cy,
/// r.ceta: the reduced pencil after exact deflations (a structured bound: the deflated columns
/// are exactly zero in the data, and perturbations that keep them zero move only the reduced
/// pencil's eigenvalues), else the full pencil.
Mode classify(Raw&& r, const Conditioning& c, double floor) {
  Mode md;
  md.alpha = r.alpha;
  md.beta = r.beta;
  md.backward_error = r.eta;
  md.shape = std::move(r.x);
  md.left_shape = std::move(r.y);
  normalize_shape(md.shape);
  normalize_shape(md.left_shape);
  const double cx = r.cx.norm() * r.cy.norm();
  const Eigen::VectorXcd Ex = times(c.E, r.cx), Ax = times(c.A, r.cx);
  const cd yEx = r.cy.dot(Ex) / cx, yAx = r.cy.dot(Ax) / cx;  // yᴴEx, yᴴAx for unit x, y
  const double a = std::abs(md.alpha), b = md.beta;
  const double eta = std::max(r.ceta, floor);
  const double nE = c.nE, nA = c.nA;
  {
    const double num = std::sqrt(a * a * nE * nE + b * b * nA * nA);
    const double den = std::abs(b * yEx + std::conj(md.alpha) * yAx);
    md.condition_homogeneous = den > 0 ? num / den : kInf;
  }
  // Infinite within bound: the reversed pencil's μ = β/α is zero within its error bound
  // (multiplied through by |α| so that α = 0 needs no case); only on the large side of the
  // pencil's own scale |λ| = ‖A‖/‖E‖, so that a zero eigenvalue is never called infinite.
  if (a * nE >= b * nA && b * std::abs(yAx) <= (a * nE + b * nA) * eta) {
    md.kind = EigenvalueKind::infinite;
    md.lambda = kInf;
    md.natural_frequency_hz = kInf;
    md.damped_frequency_hz = 0.0;
    md.damping_ratio = 0.0;
    md.condition = kInf;
    md.error_bound = 0.0;
    return md;
  }
  const cd lam = md.alpha / md.beta;
  const double rl = std::abs(lam);
  md.kind = EigenvalueKind::finite;
  md.lambda = lam;
  md.natural_frequency_hz = rl / kTwoPi;
  md.damped_frequency_hz = lam.imag() / kTwoPi;
  const double kappa_abs = std::abs(yEx) > 0 ? (nA + rl * nE) / std::abs(yEx) : kInf;
  md.condition = rl > 0 ? kappa_abs / rl : kInf;
  md.error_bound = kappa_abs < kInf ? kappa_abs * eta : kInf;
  // A Jordan block at 0 split into ±√δ by rounding has yᴴEx = O(√δ): its bound exceeds |λ|.
  md.zero_within_bound = !(rl > md.error_bound);
  md.damping_ratio = (rl > 0 && !md.zero_within_bound) ? -lam.real() / rl + 0.0 : kNaN;
  return md;
}

/// Jordan chain through a deflated zero column k (file comment): x_l = e_k, then E x_{j−1} =
/// A x_j solved on the exact levels' columns (T = E(pivot rows, pivot columns) is upper
/// triangular in level order) until A x = 0. Returns the chain's head and its length − 1.
std::pair<Eigen::VectorXd, int> chain_head(const Eigen::MatrixXd& E, const Eigen::MatrixXd& A,
                                           const Deflation& d, Index k) {
  const Index n = E.rows(), pe = static_cast<Index>(d.pivots.size());
  Eigen::MatrixXd T(pe, pe);
  for (Index i = 0; i < pe; ++i)
    for (Index j = 0; j < pe; ++j)
      T(i, j) = E(d.pivots[static_cast<std::size_t>(i)].row,
                  d.pivots[static_cast<std::size_t>(j)].col);
  Eigen::VectorXd v = Eigen::VectorXd::Unit(n, k);
  int steps = 0;
  for (int it = 0; it <= d.levels; ++it) {
    const Eigen::VectorXd r = A * v;
    if ((r.array() == 0.0).all()) break;
    // A x_j vanishes outside the pivot rows: the deflated columns of A are zero in the rows
    // that remain after their level (exact zeros times anything).
    Eigen::VectorXd rp(pe);
    for (Index i = 0; i < pe; ++i) rp[i] = r[d.pivots[static_cast<std::size_t>(i)].row];
    assert(std::abs(r.norm() - rp.norm()) <= 1e-12 * r.norm());
    const Eigen::VectorXd s = T.triangularView<Eigen::Upper>().solve(rp);
    v.setZero();
    for (Index j = 0; j < pe; ++j) v[d.pivots[static_cast<std::size_t>(j)].col] = s[j];
    ++steps;
  }
  return {v, steps};
}

/// The deflated zero modes, by increasing column: shape e_k (or the head of its Jordan chain),
/// left_shape from the left null space W of A, made biorthogonal, Y = W (WᵀE X)⁻ᵀ, to the
/// eigenvectors X when there is no chain and WᵀE X is well conditioned (y_jᴴE x_k = 0, j ≠ k).
std::vector<Mode> zero_modes(const Eigen::MatrixXd& E, const Eigen::MatrixXd& A,
                             const Deflation& d, double nA, std::vector<Index>& columns) {
  const Index n = E.rows();
  columns.clear();
  for (const auto& pv : d.pivots) columns.push_back(pv.col);
  for (Index j : d.hh.Z) columns.push_back(d.cols[static_cast<std::size_t>(j)]);
  std::sort(columns.begin(), columns.end());
  const Index z = static_cast<Index>(columns.size());
  if (z == 0) return {};
  std::vector<Eigen::VectorXd> heads;
  std::vector<int> steps;
  for (Index k : columns) {
    auto [v, s] = chain_head(E, A, d, k);
    heads.push_back(std::move(v));
    steps.push_back(s);
  }
  // Defective: a chain member beyond its head, or an e_k that a chain's head involves.
  std::vector<char> defective(static_cast<std::size_t>(z), 0);
  Index g = 0;  // eigenvectors (chains of length 1 or heads)
  for (std::size_t j = 0; j < heads.size(); ++j) {
    if (steps[j] == 0) {
      ++g;
      continue;
    }
    defective[j] = 1;
    for (std::size_t i = 0; i < heads.size(); ++i)
      if (steps[i] == 0 && heads[j][columns[i]] != 0.0) defective[i] = 1;
  }
  const bool chains = g < z;
  const Eigen::MatrixXd W =
      detail::null_space(A.transpose(), static_cast<double>(n) * kU, true, n - g).basis;
  Eigen::MatrixXd X(n, g);
  for (std::size_t j = 0, c = 0; j < heads.size(); ++j)
    if (steps[j] == 0) X.col(static_cast<Index>(c++)) = heads[j];
  const Eigen::MatrixXd G = W.transpose() * E * X;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(G, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::VectorXd sv = svd.singularValues();
  const bool biorthogonal = !chains && sv[g - 1] > static_cast<double>(n) * kU * sv[0];
  const Eigen::MatrixXd Y =
      biorthogonal ? Eigen::MatrixXd(W * svd.solve(Eigen::MatrixXd::Identity(g, g)).transpose())
                   : W;
  std::vector<Mode> out;
  for (std::size_t j = 0, c = 0; j < heads.size(); ++j) {
    Mode md;
    md.kind = EigenvalueKind::zero;
    md.lambda = 0.0;
    md.alpha = 0.0;
    md.beta = 1.0;
    md.damping_ratio = kNaN;
    md.shape = heads[j].cast<cd>();
    normalize_shape(md.shape);
    md.left_shape = Y.col(static_cast<Index>(c % static_cast<std::size_t>(g))).cast<cd>();
    if (steps[j] == 0) ++c;
    normalize_shape(md.left_shape);
    md.defective = defective[j] != 0;
    md.condition = kInf;
    const Eigen::VectorXcd Ex = times(E, md.shape);
    const double den = std::abs(md.left_shape.dot(Ex));  // |yᴴE x|
    md.condition_homogeneous = (biorthogonal && den > 0) ? nA / den : kInf;
    const double nx = (A * heads[j]).norm();  // 0 when the head lies in the zero columns
    md.backward_error = nx == 0.0 ? 0.0 : nx / (nA * heads[j].norm());
    md.error_bound = 0.0;
    out.push_back(std::move(md));
  }
  return out;
}

/// After exact deflations: when the reduced A is structurally rank deficient by k, λ = 0 is an
/// eigenvalue of the reduced pencil at least k times for every value of its nonzero entries (a
/// rolling disk's neighbouring steady turns, a conserved momentum). The k finite eigenvalues of
/// least modulus are then that exact zero, provided each is zero within its error bound (else
/// the computation contradicts the structure, and they are left as computed). Returns how many
/// were made kind zero.
Index structural_zeros(std::vector<Mode>& finite, const Eigen::MatrixXd& reduced_A) {
  const Index k = reduced_A.rows() - detail::structural_rank(reduced_A);
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < finite.size(); ++i)
    if (finite[i].kind == EigenvalueKind::finite) order.push_back(i);
  if (k == 0 || static_cast<Index>(order.size()) < k) return 0;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::abs(finite[a].lambda) < std::abs(finite[b].lambda);
  });
  order.resize(static_cast<std::size_t>(k));
  for (std::size_t i : order)
    if (!finite[i].zero_within_bound) return 0;
  for (std::size_t i : order) {
    Mode& md = finite[i];
    md.kind = EigenvalueKind::zero;
    md.lambda = 0.0;
    md.alpha = 0.0;
    md.beta = 1.0;
    md.natural_frequency_hz = md.damped_frequency_hz = 0.0;
    md.damping_ratio = kNaN;
    md.condition = kInf;
    md.error_bound = 0.0;
    md.zero_within_bound = false;
  }
  return k;
}

}  // namespace

DescriptorEigenSolver::DescriptorEigenSolver(DescriptorEigenOptions options)
    : options_(options) {}

DescriptorEigenSolver& DescriptorEigenSolver::compute(const DescriptorModel& model) {
  return compute_named(model.E(), model.A(), model.state_names());
}

DescriptorEigenSolver& DescriptorEigenSolver::compute(const Eigen::MatrixXd& E,
                                                      const Eigen::MatrixXd& A) {
  // Validates dimensions and finiteness (throws DimensionError / NonFiniteError).
  const DescriptorModel check(E, A, Eigen::MatrixXd(E.rows(), 0), Eigen::MatrixXd(0, E.rows()));
  return compute_named(E, A, check.state_names());
}

double DescriptorEigenSolver::max_backward_error() const {
  double e = 0.0;
  for (const Mode& m : modes_) e = std::max(e, m.backward_error);
  return e;
}

DescriptorEigenSolver& DescriptorEigenSolver::compute_named(
    const Eigen::MatrixXd& E, const Eigen::MatrixXd& A, const std::vector<std::string>& names) {
  // Data near the ends of the range of double: the exactly scaled pencil (spectrum_structure.hpp),
  // λE − A with λ = γμ: coefficients −A (λ⁰) and E (λ¹).
  auto largest = [](const Eigen::MatrixXd& X) { return X.size() ? X.cwiseAbs().maxCoeff() : 0.0; };
  if (const detail::RangeScaling sc = detail::range_scaling({largest(A), largest(E)}); sc.active) {
    compute_named(sc.scaled(E, 1), sc.scaled(A, 0), names);
    detail::unscale_modes(modes_, sc.gamma());
    return *this;
  }
  info_ = Eigen::InvalidInput;
  modes_.clear();
  num_zero_ = num_infinite_ = num_structural_zero_ = 0;
  const Index n = E.rows();
  const double nE = detail::norm2_estimate(E), nA = detail::norm2_estimate(A);
  const double floor = options_.backward_error_floor > 0    ? options_.backward_error_floor
                       : options_.backward_error_floor == 0 ? 100.0 * static_cast<double>(n) * kU
                                                            : 0.0;
  // An equation that is 0 = 0 (a zero row of both E and A) makes det(λE − A) ≡ 0.
  for (Index i = 0; i < n; ++i)
    if ((E.row(i).array() == 0.0).all() && (A.row(i).array() == 0.0).all())
      throw SingularSystemError("DescriptorEigenSolver::compute: the pencil λE − A is singular (det ≡ 0): equation " +
                                std::to_string(i + 1) + " (the row of state '" + names[static_cast<std::size_t>(i)] +
                                "') is zero in both E and A");
  Deflation d;
  d.compute(E, A, names);
  modes_ = zero_modes(E, A, d, nA, zero_columns_);
  num_zero_ = static_cast<Index>(zero_columns_.size());

  if (d.reduced_A().rows() > 0) {
    // Balancing: permutation only ('P') first, as QuadraticEigenSolver. Permutation and scaling
    // ('B', Ward's algorithm) when the largest normwise backward error exceeds 10·n·u (kept if
    // smaller: QuadraticEigenSolver's rule), or when the componentwise one does and 'B' lowers it
    // without raising the normwise one above 10·n·u. The second rule is ours: the Whipple
    // bicycle's E = blkdiag(I, M), A = [[0, I], [−K, −vC1]] has normwise backward errors ≤ 3e-16
    // with 'P' but componentwise ones up to 3.3e-11 (the kinematic rows, of norm 1, carry
    // residuals of size u‖K‖), and eigenvalue errors of 6.7e-13 that 'B' reduces to 1.1e-14.
    // Never after a Householder deflation, whose rounding residue where A and E had exact zeros
    // can steer the scaling astray (QuadraticEigenSolver measured this); the exact levels leave
    // a bit-exact submatrix.
    const double bar = 10.0 * static_cast<double>(n) * kU;
    std::vector<Raw> finite = qz(d, E, A, 'P', nE, nA);
    const bool norm_fails = worst(finite) > bar, comp_fails = worst(finite, true) > bar;
    if (d.exact() && (norm_fails || comp_fails)) {
      std::vector<Raw> alt = qz(d, E, A, 'B', nE, nA);
      const bool better = norm_fails ? worst(alt) < worst(finite)
                                     : worst(alt) <= bar && worst(alt, true) < worst(finite, true);
      if (better) finite.swap(alt);
    }
    const Conditioning cond = d.exact() ? Conditioning{d.reduced_E(), d.reduced_A(),
                                                       detail::norm2_estimate(d.reduced_E()),
                                                       detail::norm2_estimate(d.reduced_A())}
                                        : Conditioning{E, A, nE, nA};
    std::vector<Mode> rest;
    for (Raw& r : finite) {
      rest.push_back(classify(std::move(r), cond, floor));
      if (rest.back().kind == EigenvalueKind::infinite) ++num_infinite_;
    }
    num_structural_zero_ = d.exact() ? structural_zeros(rest, d.reduced_A()) : 0;
    num_zero_ += num_structural_zero_;
    if (d.exact() && detail::reversible_sign_pattern({{&d.reduced_E(), 1}, {&d.reduced_A(), -1}})) detail::snap_to_axis(rest);
    for (Mode& md : rest) {
      if (options_.one_per_conjugate_pair && md.kind == EigenvalueKind::finite &&
          md.lambda.imag() < 0.0)
        continue;
      modes_.push_back(std::move(md));
    }
  }
  sort_modes(modes_);
  stability_ = stability_of(modes_);
  info_ = Eigen::Success;
  return *this;
}

// ---------------------------------------------------------------------------------------------
// Frequency response.

namespace {

void check_frf_arguments(const DescriptorModel& model, const Eigen::VectorXd& omega,
                         Index input, const std::vector<Index>& rows) {
  const char* who = "descriptor_frequency_response";
  if (input < 0 || input >= model.num_inputs()) {
    std::ostringstream s;
    s << who << ": input index " << input << " out of range (B is " << model.size() << "x"
      << model.num_inputs() << ")";
    throw DimensionError(s.str());
  }
  for (Index r : rows)
    if (r < 0 || r >= model.num_outputs()) {
      std::ostringstream s;
      s << who << ": output index " << r << " out of range (C is " << model.num_outputs() << "x"
        << model.size() << ")";
      throw DimensionError(s.str());
    }
  for (Index k = 0; k < omega.size(); ++k)
    if (!std::isfinite(omega[k]) || omega[k] < 0) {
      std::ostringstream s;
      s << who << ": frequency " << k << " is " << omega[k]
        << " rad/s; frequencies must be finite and non-negative";
      throw NonFiniteError(s.str());
    }
}

}  // namespace

DescriptorFrf descriptor_frequency_response(const DescriptorModel& model,
                                            const Eigen::VectorXd& omega, Index input,
                                            const std::vector<Index>& outputs,
                                            PoleHandling on_pole) {
  std::vector<Index> rows = outputs;
  if (rows.empty())
    for (Index i = 0; i < model.num_outputs(); ++i) rows.push_back(i);
  check_frf_arguments(model, omega, input, rows);
  const char* who = "descriptor_frequency_response";
  const Index n = model.size(), p = static_cast<Index>(rows.size()), F = omega.size();
  const Eigen::MatrixXd &E = model.E(), &A = model.A();
  Eigen::MatrixXcd Cr(p, n);
  Eigen::VectorXcd d(p);
  for (Index r = 0; r < p; ++r) {
    Cr.row(r) = model.C().row(rows[static_cast<std::size_t>(r)]).cast<cd>();
    d[r] = model.D()(rows[static_cast<std::size_t>(r)], input);
  }
  DescriptorFrf out;
  out.omega = omega;
  out.response.resize(p, F);
  out.rcond.resize(F);
  out.flags.assign(static_cast<std::size_t>(F), FrfFlag::ok);
  const double pole_rc = static_cast<double>(n) * kU;  // FrfOptions::pole_rcond's default
  const Eigen::MatrixXd minus_a = -A;  // for frf_scaled_rcond at a failing point
  const double ill_rc = 1e-8;                          // FrfOptions::ill_conditioned_rcond's
  const lapack_int nn = detail::li(n);
  Eigen::MatrixXcd G(n, n);
  Eigen::VectorXcd x(n), zwork(2 * n);
  Eigen::VectorXd rwork(2 * n);
  std::vector<lapack_int> ipiv(static_cast<std::size_t>(n));
  for (Index k = 0; k < F; ++k) {
    const double om = omega[k];
    double anorm = 0.0;  // ‖iΩE − A‖₁ for zgecon
    for (Index j = 0; j < n; ++j) {
      double s = 0.0;
      for (Index i = 0; i < n; ++i) {
        G(i, j) = cd(-A(i, j), om * E(i, j));
        s += std::abs(G(i, j));
      }
      anorm = std::max(anorm, s);
    }
    lapack_int info = LAPACKE_zgetrf_work(LAPACK_COL_MAJOR, nn, nn, G.data(), nn, ipiv.data());
    detail::check_lapack(info, "zgetrf", who);
    double rc = 0.0;
    bool ok = info == 0;
    if (ok) {
      info = LAPACKE_zgecon_work(LAPACK_COL_MAJOR, '1', nn, G.data(), nn, anorm, &rc,
                                 zwork.data(), rwork.data());
      detail::check_lapack(info, "zgecon", who);
      x = model.B().col(input).cast<cd>();
      info = LAPACKE_zgetrs_work(LAPACK_COL_MAJOR, 'N', nn, 1, G.data(), nn, ipiv.data(),
                                 x.data(), nn);
      detail::check_lapack(info, "zgetrs", who);
      out.response.col(k).noalias() = Cr * x;
      out.response.col(k) += d;
    }
    out.rcond[k] = rc;
    FrfFlag flag = FrfFlag::ok;
    const bool finite = ok && out.response.col(k).allFinite();
    if (finite && !out.response.col(k).cwiseAbs().allFinite())  // |re + i im| beyond the range
      flag = FrfFlag::overflow;
    else if (!finite || !(rc > pole_rc))  // a pole unless the system scaled to unit size is not
      flag = frf_scaled_rcond(Eigen::MatrixXd(), E, minus_a, om) > pole_rc ? FrfFlag::overflow : FrfFlag::pole;
    else if (rc < ill_rc)
      flag = FrfFlag::ill_conditioned;
    out.flags[static_cast<std::size_t>(k)] = flag;
    if (flag == FrfFlag::overflow) {
      if (on_pole == PoleHandling::raise) {
        std::ostringstream s;
        s << who << ": the range of double is exceeded at Ω = " << om
          << " rad/s (iΩE − A, the solution or an output overflows): rescale the model's units";
        throw NonFiniteError(s.str());
      }
      out.response.col(k).setConstant(cd(kNaN, kNaN));
    } else if (flag == FrfFlag::pole) {
      if (on_pole == PoleHandling::raise) {
        std::ostringstream s;
        s << who << ": iΩE − A is singular at Ω = " << om << " rad/s, rcond = " << rc
          << " (an eigenvalue on the imaginary axis at iΩ?)";
        throw SingularSystemError(s.str());
      }
      out.response.col(k).setConstant(cd(kNaN, kNaN));
    }
  }
  return out;
}

}  // namespace mbsgen
