#include "mbsgen/runtime/frequency_response.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>

#include "lapack.hpp"
#include "mbsgen/runtime/quadratic_eigen.hpp"

namespace mbsgen {

using cd = std::complex<double>;
using Eigen::Index;
using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMatrixXcd = Eigen::Matrix<cd, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

namespace {
constexpr double kU = std::numeric_limits<double>::epsilon() / 2;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTwoPi = 6.283185307179586476925286766559;

/// Column j of a permuted-diagonal matrix X has its single nonzero val[j] in row row[j];
/// X is obtained by applying LAPACK's xGEBAK/xGGBAK to the identity.
struct PermutedDiagonal {
  std::vector<Index> row;
  Eigen::VectorXd val;
  void from_dense(const Eigen::MatrixXd& X) {
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
  /// (Xᵀ v)_j = val_j · v_{row_j}
  template <class V>
  Eigen::VectorXd transpose_times(const V& v) const {
    Eigen::VectorXd out(val.size());
    for (Index j = 0; j < val.size(); ++j) out[j] = val[j] * v[row[static_cast<std::size_t>(j)]];
    return out;
  }
};

/// 1/(c + id) by Smith's (1962) algorithm, inline: std::complex division calls libgcc's
/// __divdc3 (C99 Annex G), which dominated the O(n) band solve.
inline cd reciprocal(double c, double d) {
  if (std::abs(c) >= std::abs(d)) {
    const double r = d / c, den = c + d * r;
    return {1.0 / den, -r / den};
  }
  const double r = c / d, den = c * r + d;
  return {r / den, -1.0 / den};
}
inline cd mul(cd a, cd b) {
  return {a.real() * b.real() - a.imag() * b.imag(), a.real() * b.imag() + a.imag() * b.real()};
}

/// Solver for (iΩT − H) x = b with H upper Hessenberg and T upper triangular (or T = E), real,
/// of order N, in O(N²) per frequency (Laub 1981): Gaussian elimination with adjacent-row
/// partial pivoting, fused so that the matrix is streamed twice per frequency — once to form and
/// factorize W = iΩT − H (also accumulating ‖W‖₁, eliminating the right-hand side and running the
/// first half of the condition estimate), once for the back substitution of two right-hand
/// sides. W is kept as separate row-major real and imaginary planes so the inner loops are plain
/// real arithmetic the compiler vectorizes (std::complex products would call __muldc3 for C99
/// Annex G Inf/NaN semantics; a non-finite result is caught by the caller's check). The
/// condition estimate follows Cline, Moler, Stewart & Wilkinson (1979, LINPACK): solve Wᴴy = e
/// choosing |e_j| = 1 during the substitution with Uᴴ so that y grows, then z = W⁻¹y, and
/// ‖z‖₁/‖y‖₁ ≤ ‖W⁻¹‖₁ (in practice within a small factor). Workspaces are allocated once.
struct HessenbergSolver {
  RowMatrixXd Wr, Wi;              // U after factorization
  Eigen::VectorXd lr, li;          // multipliers l_k (row k+1 −= l_k·row k)
  std::vector<unsigned char> swapped;
  Eigen::VectorXd er, ei;          // estimator vector
  Eigen::VectorXd colH, colT;      // column sums of |H| and |T| (set by the owner)
  Eigen::VectorXcd rpiv;           // 1/U_kk
  Index N = 0;
  void resize(Index n) {
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

  /// Solves (iΩT − H)x = b for real b given in xr (xi must be zero on entry); T == nullptr
  /// means T = E. Returns false at an exact zero pivot; rc receives the reciprocal condition
  /// estimate 1/(‖W‖₁·est‖W⁻¹‖₁).
  bool solve(const RowMatrixXd& H, const RowMatrixXd* T, double om, Eigen::VectorXd& xr,
             Eigen::VectorXd& xi, double& rc) {
    er.setZero();
    ei.setZero();
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
};

/// Solver for a complex band matrix W (kl = ku = b) given column by column, in the layout of
/// LAPACK xGBTRF (row kv + i − j of column j holds W(i, j), kv = 2b, room for the fill-in of
/// partial pivoting) but with separate real and imaginary planes: Gaussian elimination with
/// partial pivoting as in xGBTF2, the right-hand side eliminated on the fly, and the two-solve
/// LINPACK condition estimate (Cline, Moler, Stewart & Wilkinson 1979) fused into the back
/// substitution. O(f·b²) per frequency; replaces zgbtrf + zgbcon, whose estimator (zlacn2 with
/// zlatbs) cost several times the factorization on chains.
struct BandSolver {
  Index n = 0, b = 0, kv = 0, ld = 0;
  Eigen::MatrixXd Ar, Ai;  // ld × n, ld = 3b + 1
  std::vector<Index> piv;
  Eigen::VectorXd er, ei;
  Eigen::VectorXcd rpiv;  // 1/U_jj
  void resize(Index n_, Index b_) {
    n = n_;
    b = b_;
    kv = 2 * b;
    ld = 3 * b + 1;
    Ar.resize(ld, n);
    Ai.resize(ld, n);
    piv.assign(static_cast<std::size_t>(n), 0);
    er.resize(n);
    ei.resize(n);
    rpiv.resize(n);
  }
  double& re(Index i, Index j) { return Ar(kv + i - j, j); }
  double& im(Index i, Index j) { return Ai(kv + i - j, j); }

  /// Factorizes (the matrix must already be stored, fill-in rows zero) and solves for the real
  /// right-hand side in xr (xi zero on entry). anorm = ‖W‖₁. Returns false at a zero pivot.
  bool solve(double anorm, Eigen::VectorXd& xr, Eigen::VectorXd& xi, double& rc) {
    Index ju = 0;  // last column touched by the fill-in so far
    for (Index j = 0; j < n; ++j) {
      const Index km = std::min(b, n - 1 - j);
      // pivot search in column j, rows j..j+km
      Index p = 0;
      double best = -1.0;
      for (Index i = 0; i <= km; ++i) {
        const double a = re(j + i, j) * re(j + i, j) + im(j + i, j) * im(j + i, j);
        if (a > best) {
          best = a;
          p = i;
        }
      }
      piv[static_cast<std::size_t>(j)] = j + p;
      if (best == 0.0) return false;
      ju = std::max(ju, std::min(j + b + p, n - 1));
      if (p != 0) {
        for (Index c = j; c <= ju; ++c) {
          std::swap(re(j, c), re(j + p, c));
          std::swap(im(j, c), im(j + p, c));
        }
        std::swap(xr[j], xr[j + p]);
        std::swap(xi[j], xi[j + p]);
      }
      const cd inv = reciprocal(re(j, j), im(j, j));
      rpiv[j] = inv;
      if (km > 0) {
        for (Index i = 1; i <= km; ++i) {  // multipliers l_i = W(j+i, j)/W(j, j), kept in place
          const cd l = mul(cd(re(j + i, j), im(j + i, j)), inv);
          re(j + i, j) = l.real();
          im(j + i, j) = l.imag();
        }
        for (Index c = j + 1; c <= ju; ++c) {
          const double ur = re(j, c), ui = im(j, c);
          if (ur == 0.0 && ui == 0.0) continue;
          for (Index i = 1; i <= km; ++i) {
            const double lr = re(j + i, j), li = im(j + i, j);
            re(j + i, c) -= lr * ur - li * ui;
            im(j + i, c) -= lr * ui + li * ur;
          }
        }
        const double x0r = xr[j], x0i = xi[j];
        for (Index i = 1; i <= km; ++i) {
          const double lr = re(j + i, j), li = im(j + i, j);
          xr[j + i] -= lr * x0r - li * x0i;
          xi[j + i] -= lr * x0i + li * x0r;
        }
      }
    }
    // Estimator, first half: Uᴴ v = e with |e_j| = 1 chosen to make v grow (dot-product form on
    // the columns of U, bandwidth kv), then the transposed eliminations and interchanges.
    for (Index j = 0; j < n; ++j) {
      double sr = 0, si = 0;  // s = Σ_{i<j} conj(U_ij) v_i
      for (Index i = std::max<Index>(0, j - kv); i < j; ++i) {
        const double ur = re(i, j), ui = im(i, j);
        sr += ur * er[i] + ui * ei[i];
        si += ur * ei[i] - ui * er[i];
      }
      const double a = std::sqrt(sr * sr + si * si);
      const cd e = a > 0 ? cd(-sr / a, -si / a) : cd(1.0, 0.0);
      const cd v = mul(e - cd(sr, si), std::conj(rpiv[j]));
      er[j] = v.real();
      ei[j] = v.imag();
    }
    for (Index j = n - 2; j >= 0; --j) {
      const Index km = std::min(b, n - 1 - j);
      double sr = 0, si = 0;  // Σ conj(l_i) v_{j+i}
      for (Index i = 1; i <= km; ++i) {
        const double lr = re(j + i, j), li = im(j + i, j);
        sr += lr * er[j + i] + li * ei[j + i];
        si += lr * ei[j + i] - li * er[j + i];
      }
      er[j] -= sr;
      ei[j] -= si;
      const Index pj = piv[static_cast<std::size_t>(j)];
      if (pj != j) {
        std::swap(er[j], er[pj]);
        std::swap(ei[j], ei[pj]);
      }
    }
    double ny = 0;  // ‖·‖₁ with |re| + |im| for the modulus: ratios change by at most √2
    for (Index i = 0; i < n; ++i) ny += std::abs(er[i]) + std::abs(ei[i]);
    for (Index j = 0; j < n; ++j) {  // forward eliminations of W⁻¹ on the estimator vector
      const Index pj = piv[static_cast<std::size_t>(j)];
      if (pj != j) {
        std::swap(er[j], er[pj]);
        std::swap(ei[j], ei[pj]);
      }
      const Index km = std::min(b, n - 1 - j);
      const double x0r = er[j], x0i = ei[j];
      for (Index i = 1; i <= km; ++i) {
        const double lr = re(j + i, j), li = im(j + i, j);
        er[j + i] -= lr * x0r - li * x0i;
        ei[j + i] -= lr * x0i + li * x0r;
      }
    }
    // Back substitution with U (bandwidth kv), column-oriented, both right-hand sides.
    for (Index j = n - 1; j >= 0; --j) {
      const cd rd = rpiv[j];
      const cd v = mul(cd(xr[j], xi[j]), rd), w = mul(cd(er[j], ei[j]), rd);
      xr[j] = v.real();
      xi[j] = v.imag();
      er[j] = w.real();
      ei[j] = w.imag();
      for (Index i = std::max<Index>(0, j - kv); i < j; ++i) {
        const double ur = re(i, j), ui = im(i, j);
        xr[i] -= ur * v.real() - ui * v.imag();
        xi[i] -= ur * v.imag() + ui * v.real();
        er[i] -= ur * w.real() - ui * w.imag();
        ei[i] -= ur * w.imag() + ui * w.real();
      }
    }
    double nz = 0;
    for (Index i = 0; i < n; ++i) nz += std::abs(er[i]) + std::abs(ei[i]);
    const double inv = ny > 0 ? nz / ny : std::numeric_limits<double>::infinity();
    rc = (anorm > 0 && inv > 0 && std::isfinite(inv)) ? 1.0 / (anorm * inv) : 0.0;
    return true;
  }
};

std::string hz(double omega) {
  std::ostringstream s;
  s << omega << " rad/s (" << omega / kTwoPi << " Hz)";
  return s.str();
}

}  // namespace

const char* to_string(FrfMethod method) {
  switch (method) {
    case FrfMethod::automatic: return "automatic";
    case FrfMethod::direct: return "direct";
    case FrfMethod::banded: return "banded";
    case FrfMethod::hessenberg: return "hessenberg";
    case FrfMethod::modal: return "modal";
    case FrfMethod::real: return "real";
  }
  return "?";
}

FrfMethod parse_frf_method(const std::string& name) {
  if (name == "auto" || name == "automatic") return FrfMethod::automatic;
  if (name == "direct") return FrfMethod::direct;
  if (name == "banded") return FrfMethod::banded;
  if (name == "hessenberg") return FrfMethod::hessenberg;
  if (name == "modal") return FrfMethod::modal;
  if (name == "real") return FrfMethod::real;
  throw Error("parse_frf_method: unknown method '" + name +
              "' (expected auto, direct, banded, hessenberg, modal, real)");
}

// The rule follows docs/accuracy-vs-time.md §5 (the recommendation table; measured by
// bench/frf_accuracy.cpp, checked by tests/runtime/test_auto_method.cpp): banded wherever the
// band is narrow (faster than the dense methods on every chain and in the sweep up to b = n/4,
// where it ties with hessenberg; as accurate as direct); dense and below 12 coordinates direct,
// the backward-stable reference, since every method costs microseconds there (the rotor:
// hessenberg 3× faster, 1000× less accurate); among the dense methods hessenberg once its
// one-time reduction is paid back (break-even from about 8 frequencies at f = 12 to about 25–35
// from f = 100 on), unless the first-order form is badly conditioned: its error grows like
// u·κ(M̃)κ(K̃) (speaker_box: 4e-8 against direct's 3e-10), so above 1e8 — or with M or K
// singular — direct.
FrfMethod automatic_frf_method(const LinearModel& model, Index frequencies) {
  const Index n = model.size(), b = model.bandwidth();
  if (4 * b <= n && b * b <= 16 * n) return FrfMethod::banded;
  if (n < 12) return FrfMethod::direct;
  if (frequencies < std::min<Index>(30, std::max<Index>(8, n / 2))) return FrfMethod::direct;
  // κ₁ of M and K scaled to unit diagonal of M (the coordinates' units divided out).
  const Eigen::VectorXd d = model.M().diagonal();
  if (!(d.minCoeff() > 0)) return FrfMethod::direct;
  const Eigen::VectorXd s = d.cwiseSqrt().cwiseInverse();
  const double rc_M = Eigen::PartialPivLU<Eigen::MatrixXd>(s.asDiagonal() * model.M() * s.asDiagonal()).rcond();
  const double rc_K = Eigen::PartialPivLU<Eigen::MatrixXd>(s.asDiagonal() * model.K() * s.asDiagonal()).rcond();
  return rc_M * rc_K >= 1e-8 ? FrfMethod::hessenberg : FrfMethod::direct;
}

const char* to_string(FrfFlag flag) {
  switch (flag) {
    case FrfFlag::ok: return "ok";
    case FrfFlag::ill_conditioned: return "ill_conditioned";
    case FrfFlag::pole: return "pole";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------------
struct FrequencyResponse::Impl {
  const LinearModel& model;
  Index n;
  // selected input/outputs for the current compute()
  Eigen::VectorXd b;
  // The rows every method computes, ẑ_r = (C_y + iΩC_v)_r ŷ: the p selected outputs, then one
  // pseudo-row per selected output with a nonzero row of C_a (C_y := that row, C_v := 0), so
  // that the methods need not know C_a; combine_outputs() adds −Ω²·(C_a ŷ) and D(:, input).
  Eigen::MatrixXcd Cy, Cv;  // (p + q)×n, complex copies so that products do not allocate
  Eigen::MatrixXd Cy_re, Cv_re;  // (p + q)×n real
  Eigen::VectorXcd z;       // p + q
  std::vector<Index> acc_row;  // per output r < p: its pseudo-row in z, or −1
  Eigen::VectorXd feed;        // per output r < p: D(row, input), 0 without D
  bool combine = false;        // some pseudo-row or nonzero feedthrough: combine_outputs needed

  explicit Impl(const LinearModel& m) : model(m), n(m.size()) {}

  /// Selects input column `input` and the output `rows` (validated by the caller): b, the rows
  /// above, acc_row, feed and combine. Without C_a and D (or with zero rows) exactly the old
  /// rows and no combination step.
  void select_outputs(const std::vector<Index>& rows, Index input) {
    const Index p = static_cast<Index>(rows.size());
    b = model.B().col(input);
    acc_row.assign(rows.size(), -1);
    feed.setZero(p);
    Index q = 0;
    for (std::size_t r = 0; r < rows.size(); ++r) {
      if (model.has_output_accelerations() && (model.C_a().row(rows[r]).array() != 0.0).any())
        acc_row[r] = p + q++;
      if (model.has_feedthrough()) feed[static_cast<Index>(r)] = model.D()(rows[r], input);
    }
    combine = q > 0 || (feed.array() != 0.0).any();
    Cy.resize(p + q, n);
    Cv.resize(p + q, n);
    for (Index r = 0; r < p; ++r) {
      const Index row = rows[static_cast<std::size_t>(r)];
      Cy.row(r) = model.C_y().row(row).cast<cd>();
      Cv.row(r) = model.C_v().row(row).cast<cd>();
      const Index a = acc_row[static_cast<std::size_t>(r)];
      if (a >= 0) {
        Cy.row(a) = model.C_a().row(row).cast<cd>();
        Cv.row(a).setZero();
      }
    }
    z.resize(p + q);
    Cy_re = Cy.real();
    Cv_re = Cv.real();
  }

  /// The right-hand side b and the feedthrough d(rows) of one part of a moving support's
  /// excitation (FrequencyResponse::compute): B1's or B2's column and D1's or none.
  void select_part(const Eigen::MatrixXd& part_B, const Eigen::MatrixXd* part_D, const std::vector<Index>& rows,
                   Index input) {
    if (part_B.size() != 0) b = part_B.col(input);
    else b.setZero(n);
    feed.setZero(static_cast<Index>(rows.size()));
    if (part_D && part_D->size() != 0)
      for (std::size_t r = 0; r < rows.size(); ++r) feed[static_cast<Index>(r)] = (*part_D)(rows[r], input);
    bool acc = false;
    for (Index a : acc_row) acc = acc || a >= 0;
    combine = acc || (feed.array() != 0.0).any();
  }

  /// ẑ_r = (C_y + iΩC_v)_r ŷ − Ω²(C_a ŷ)_r + D(r, input) for the p outputs, in place in z's
  /// first p entries (the pseudo-rows are read before being overwritten: their index is ≥ p).
  void combine_outputs(double om) {
    const double om2 = om * om;
    for (std::size_t r = 0; r < acc_row.size(); ++r) {
      const Index i = static_cast<Index>(r);
      if (acc_row[r] >= 0) z[i] -= om2 * z[acc_row[r]];
      if (feed[i] != 0.0) z[i] += feed[i];
    }
  }

  // ---- direct ----
  bool direct_ready = false;
  Eigen::MatrixXcd D;
  Eigen::VectorXcd y;
  std::vector<lapack_int> ipiv;
  Eigen::VectorXcd zwork;
  Eigen::VectorXd rwork;
  void prepare_direct() {
    if (direct_ready) return;
    D.resize(n, n);
    y.resize(n);
    ipiv.resize(static_cast<std::size_t>(n));
    zwork.resize(2 * n);
    rwork.resize(2 * n);
    direct_ready = true;
  }
  /// Returns false for an exactly singular matrix.
  bool point_direct(double om, double& rc) {
    const Eigen::MatrixXd &M = model.M(), &Q = model.Q(), &K = model.K();
    const double om2 = om * om;
    double anorm = 0.0;
    for (Index j = 0; j < n; ++j) {
      double s = 0.0;
      for (Index i = 0; i < n; ++i) {
        const cd v(K(i, j) - om2 * M(i, j), om * Q(i, j));
        D(i, j) = v;
        s += std::abs(v);
      }
      anorm = std::max(anorm, s);
    }
    const lapack_int nn = detail::li(n);
    lapack_int info = LAPACKE_zgetrf_work(LAPACK_COL_MAJOR, nn, nn, D.data(), nn, ipiv.data());
    detail::check_lapack(info, "zgetrf", "FrequencyResponse::compute");
    if (info > 0) {
      rc = 0.0;
      return false;
    }
    info = LAPACKE_zgecon_work(LAPACK_COL_MAJOR, '1', nn, D.data(), nn, anorm, &rc, zwork.data(),
                               rwork.data());
    detail::check_lapack(info, "zgecon", "FrequencyResponse::compute");
    for (Index i = 0; i < n; ++i) y[i] = b[i];
    info = LAPACKE_zgetrs_work(LAPACK_COL_MAJOR, 'N', nn, 1, D.data(), nn, ipiv.data(), y.data(),
                               nn);
    detail::check_lapack(info, "zgetrs", "FrequencyResponse::compute");
    z.noalias() = Cy * y;
    z.noalias() += cd(0.0, om) * (Cv * y);
    return true;
  }

  // ---- banded ----
  bool banded_ready = false;
  BandSolver band;
  Eigen::VectorXd bxr, bxi;
  Eigen::MatrixXd Bm, Bq, Bk;  // the bands of M, Q, K: row b + i − j of column j holds (i, j)
  void prepare_banded() {
    if (banded_ready) return;
    const Index bw = std::max<Index>(model.bandwidth(), 0);
    band.resize(n, bw);
    Bm.setZero(2 * bw + 1, n);
    Bq.setZero(2 * bw + 1, n);
    Bk.setZero(2 * bw + 1, n);
    for (Index j = 0; j < n; ++j)
      for (Index i = std::max<Index>(0, j - bw); i <= std::min(n - 1, j + bw); ++i) {
        Bm(bw + i - j, j) = model.M()(i, j);
        Bq(bw + i - j, j) = model.Q()(i, j);
        Bk(bw + i - j, j) = model.K()(i, j);
      }
    bxr.resize(n);
    bxi.resize(n);
    banded_ready = true;
  }
  bool point_banded(double om, double& rc) {
    const Index bw = band.b;
    const double om2 = om * om;
    band.Ar.setZero();
    band.Ai.setZero();
    double anorm = 0.0;
    for (Index j = 0; j < n; ++j) {
      double s = 0.0;
      for (Index r = 0; r < 2 * bw + 1; ++r) {
        const Index i = j + r - bw;
        if (i < 0 || i >= n) continue;
        const double vr = Bk(r, j) - om2 * Bm(r, j), vi = om * Bq(r, j);
        band.Ar(band.kv + i - j, j) = vr;
        band.Ai(band.kv + i - j, j) = vi;
        s += std::sqrt(vr * vr + vi * vi);
      }
      anorm = std::max(anorm, s);
    }
    bxr = b;
    bxi.setZero();
    if (!band.solve(anorm, bxr, bxi, rc)) {
      rc = 0.0;
      return false;
    }
    // ẑ = (C_y + iΩC_v) ŷ over the nonzeros of the requested rows only: O(nnz) instead of the
    // O(p·f) of a dense product, which dominated the O(f·b²) solve when many outputs are asked.
    for (std::size_t r = 0; r + 1 < out_y.start.size(); ++r) {
      double yr = 0, yi = 0, vr = 0, vi = 0;
      for (std::size_t e = out_y.start[r]; e < out_y.start[r + 1]; ++e) {
        yr += out_y.val[e] * bxr[out_y.col[e]];
        yi += out_y.val[e] * bxi[out_y.col[e]];
      }
      for (std::size_t e = out_v.start[r]; e < out_v.start[r + 1]; ++e) {
        vr += out_v.val[e] * bxr[out_v.col[e]];
        vi += out_v.val[e] * bxi[out_v.col[e]];
      }
      z[static_cast<Index>(r)] = cd(yr - om * vi, yi + om * vr);
    }
    return true;
  }
  /// The requested output rows of C_y and C_v in compressed-row form.
  struct SparseRows {
    std::vector<std::size_t> start;
    std::vector<Index> col;
    std::vector<double> val;
    void assign(const Eigen::MatrixXd& C) {
      start.assign(1, 0);
      col.clear();
      val.clear();
      for (Index r = 0; r < C.rows(); ++r) {
        for (Index j = 0; j < C.cols(); ++j)
          if (C(r, j) != 0.0) {
            col.push_back(j);
            val.push_back(C(r, j));
          }
        start.push_back(col.size());
      }
    }
  };
  SparseRows out_y, out_v;
  void select_banded() {
    out_y.assign(Cy_re);
    out_v.assign(Cv_re);
  }

  // ---- hessenberg (Laub 1981; SLICOT TB05AD) ----
  bool hess_ready = false;
  bool hess_standard = false;
  Index N = 0;
  RowMatrixXd H, T;                  // reduced pencil (T unused in the standard form)
  Eigen::MatrixXd reflectors;        // dgehrd output (standard form)
  Eigen::VectorXd hess_tau;          // dgehrd tau
  lapack_int hilo = 1, hihi = 1;
  Eigen::PartialPivLU<Eigen::MatrixXd> Mlu;  // standard form: LU of M
  Eigen::MatrixXd Qleft, Zright;     // pencil form: Qᵀ(balanced) Z, both N×N
  Eigen::MatrixXd qr_E;              // pencil form: QR factors of the balanced E
  Eigen::VectorXd qr_tau;
  PermutedDiagonal Xl, Xr;           // balancing: Ã = Xlᵀ A Xr, x = Xr x̃
  HessenbergSolver hsolver;
  Eigen::MatrixXd Chat_re;           // p×N reduced outputs (real)
  std::string hess_form;

  /// LU of M exists (no zero pivot) and its 1-norm rcond estimate is at least `threshold`.
  bool mass_is_regular(double threshold) const {
    if (!(Mlu.matrixLU().diagonal().cwiseAbs().minCoeff() > 0.0)) return false;
    const double rc = Mlu.rcond();
    return std::isfinite(rc) && rc >= threshold;
  }

  /// Balancing job of the current reduction: 'B' (permute and scale), 'P' (permute) or 'N'.
  char hess_job = 'N';
  /// Largest backward error of the probe solves of the kept reduction (hessenberg_check), and
  /// whether it met the bar.
  double hess_backward_error = 0.0, hess_bar = 0.0, hess_forward_ratio = 0.0;

  /// Reduces the first-order form with the balancing `job` ('B', 'P' or 'N'): the standard form
  /// A = [[0, E], [−M⁻¹K, −M⁻¹Q]] when rcond₁(M) ≥ mass_rcond, else the pencil.
  void reduce_hessenberg(double mass_rcond, char job) {
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

  void reduce_standard(Eigen::MatrixXd&& A, char job) {
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

  void reduce_pencil(char job) {
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

  /// Backward error, in the second-order system scaled to unit coordinates, of the Hessenberg
  /// solution at Ω for the current input b (FrfOptions::hessenberg_backward_error_bar), with ŷ
  /// the first n entries of x = Xr·(Q or Z)·x̃ (the reduction undone). +∞ at an exact zero pivot
  /// or a non-finite solution. O(N²), about two frequencies' worth.
  /// ŷ at Ω by the Hessenberg reduction (the reduction undone); false at an exact zero pivot.
  bool hessenberg_solution(double om, Eigen::VectorXcd& yh) {
    const lapack_int NN = detail::li(N);
    Eigen::MatrixXd X(N, 2);
    Eigen::VectorXd xr = reduced_rhs(), xi = Eigen::VectorXd::Zero(N);
    double rc = 0.0;
    if (!hsolver.solve(H, hess_standard ? nullptr : &T, om, xr, xi, rc)) return false;
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
  Eigen::VectorXd unit_scaling(double om) const {
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
  std::array<double, 4> forward_errors(double om) {
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
  bool hessenberg_as_accurate_as_direct(const Eigen::VectorXd& omega, double& worst_ratio) {
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

  double hessenberg_backward_error(double om) {
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
  double hessenberg_check(const Eigen::VectorXd& omega) {
    double eta = 0.0;
    for (double om : probe_frequencies(omega)) eta = std::max(eta, hessenberg_backward_error(om));
    return eta;
  }

  std::vector<double> probe_frequencies(const Eigen::VectorXd& omega) const {
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
  void prepare_hessenberg(const FrfOptions& opt, const Eigen::VectorXd& omega) {
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
  Eigen::VectorXd reduced_rhs() const {
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
  void select_hessenberg() {
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
  Eigen::VectorXd rhs_reduced;

  bool point_hessenberg(double om, double& rc) {
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
  Eigen::VectorXd xr_ws, xi_ws, zr_ws, zi_ws;

  // ---- modal ----
  bool modal_ready = false;
  std::vector<Mode> modes;
  double eigvec_condition = 0.0;
  Eigen::VectorXcd lam, coef;  // kept eigenvalues; y_kᴴ b / (y_kᴴ P'(λ_k) x_k)
  Eigen::MatrixXcd CX, CVX;    // p×k: C_y x_k, C_v x_k
  Eigen::VectorXcd zstatic_y, zstatic_v;  // C_y r0, C_v r0 (static correction)
  Eigen::VectorXcd dk;
  void prepare_modal(const FrfOptions& opt, std::vector<std::string>& warnings) {
    if (!modal_ready) {
      QuadraticEigenOptions eo;
      QuadraticEigenSolver es(n, eo);
      es.compute(model);
      for (const Mode& m : es.modes())
        if (m.kind != EigenvalueKind::finite)
          throw SingularSystemError(
              std::string("FrequencyResponse (modal): the model has ") + to_string(m.kind) +
              " eigenvalues (singular " + (m.kind == EigenvalueKind::zero ? "K" : "M") +
              "); modal superposition needs all 2f eigenvalues finite and nonzero: use direct");
      modes = es.modes();
      const Index nm = static_cast<Index>(modes.size());
      Eigen::MatrixXcd V(2 * n, nm);
      dk.resize(nm);
      const Eigen::MatrixXcd Mc = model.M().cast<cd>(), Qc = model.Q().cast<cd>();
      // Eigenvector matrix of the linearization in the scaled variable μ = λ/γ, so that the
      // estimate measures near-defectiveness rather than the spread of |λ|.
      const double gamma = es.gamma();
      for (Index k = 0; k < nm; ++k) {
        const Mode& m = modes[static_cast<std::size_t>(k)];
        V.col(k) << m.shape, (m.lambda / gamma) * m.shape;
        V.col(k).normalize();
        dk[k] = m.left_shape.dot(2.0 * m.lambda * (Mc * m.shape) + Qc * m.shape);
      }
      const double rc = Eigen::PartialPivLU<Eigen::MatrixXcd>(V).rcond();
      eigvec_condition = rc > 0 ? 1.0 / rc : std::numeric_limits<double>::infinity();
      modal_ready = true;
    }
    if (!(eigvec_condition <= opt.modal_max_condition)) {
      std::ostringstream s;
      s << "FrequencyResponse (modal): eigenvector matrix condition estimate " << eigvec_condition
        << " exceeds " << opt.modal_max_condition
        << " (ill-conditioned eigenvectors, e.g. near-defective eigenvalues); the modal sum is unreliable: use direct";
      if (!opt.modal_allow_ill_conditioned) throw IllConditionedError(s.str());
      warnings.push_back(s.str());
    }
  }
  void select_modal(const FrfOptions& opt, std::vector<std::string>& warnings) {
    const Index nm = static_cast<Index>(modes.size());
    Index keep = nm;
    if (opt.modal_modes > 0 && 2 * opt.modal_modes < nm) {
      keep = 2 * opt.modal_modes;
      const auto& a = modes[static_cast<std::size_t>(keep - 1)].lambda;
      const auto& c = modes[static_cast<std::size_t>(keep)].lambda;
      if (a.imag() != 0 && c == std::conj(a)) ++keep;  // do not split a conjugate pair
    }
    const Index p = Cy.rows();
    lam.resize(keep);
    coef.resize(keep);
    CX.resize(p, keep);
    CVX.resize(p, keep);
    Eigen::VectorXcd y0 = Eigen::VectorXcd::Zero(n);
    for (Index k = 0; k < keep; ++k) {
      const Mode& m = modes[static_cast<std::size_t>(k)];
      lam[k] = m.lambda;
      coef[k] = m.left_shape.dot(b.cast<cd>()) / dk[k];
      CX.col(k) = Cy * m.shape;
      CVX.col(k) = Cv * m.shape;
      y0 += m.shape * (coef[k] / (-m.lambda));
    }
    zstatic_y = Eigen::VectorXcd::Zero(p);
    zstatic_v = Eigen::VectorXcd::Zero(p);
    if (keep < nm) {
      if (!opt.static_correction) {
        warnings.push_back("FrequencyResponse (modal): truncated without static correction");
      } else {
        Eigen::FullPivLU<Eigen::MatrixXd> Klu(model.K());
        if (!Klu.isInvertible()) {
          warnings.push_back("FrequencyResponse (modal): K singular, no static correction");
        } else {
          const Eigen::VectorXcd r0 = Klu.solve(b).cast<cd>() - y0;
          zstatic_y = Cy * r0;
          zstatic_v = Cv * r0;
        }
      }
    }
  }
  bool point_modal(double om, double& rc) {
    const cd s(0.0, om);
    z = zstatic_y + s * zstatic_v;
    double dmin = std::numeric_limits<double>::infinity();
    double terms = z.norm();
    for (Index k = 0; k < lam.size(); ++k) {
      const cd d = s - lam[k];
      dmin = std::min(dmin, std::abs(d) / std::max(std::abs(lam[k]), om));
      if (d == cd(0.0)) {
        rc = 0.0;
        return false;
      }
      const cd w = coef[k] / d;
      z += w * (CX.col(k) + s * CVX.col(k));
      terms += std::abs(w) * (CX.col(k) + s * CVX.col(k)).norm();
    }
    // Relative distance to the nearest pole (eigenvalues carry errors ~u|λ|) and cancellation in
    // the sum (rounding errors of the terms relative to the result), whichever is worse, divided
    // by the eigenvector condition (errors of the computed eigenvectors).
    const double cancellation = terms > 0 ? z.norm() / terms : 1.0;
    rc = std::min(dmin, cancellation) / std::max(1.0, eigvec_condition);
    return true;
  }

  // ---- real formulation (DESIGN.md §2) ----
  bool real_ready = false;
  Eigen::MatrixXd A1, A2, S, G;
  Eigen::VectorXd req, ceq;  // equilibration of Ω²E + A² (dgeequb)
  Eigen::VectorXd Ab;
  std::vector<lapack_int> ipiv_r;
  Eigen::VectorXd dwork;
  std::vector<lapack_int> iwork;
  Eigen::MatrixXcd Cxc;
  Eigen::VectorXcd gc;
  void prepare_real() {
    if (real_ready) return;
    N = 2 * n;
    Mlu.compute(model.M());
    if (!mass_is_regular(1e3 * kU))
      throw SingularSystemError(
          "FrequencyResponse (real): M is singular or nearly so (rcond " +
          std::to_string(Mlu.rcond()) + "); the real formulation needs A = [[0,E],[-M^-1 K, "
          "-M^-1 Q]]: use direct or hessenberg");
    A1 = Eigen::MatrixXd::Zero(N, N);
    A1.topRightCorner(n, n).setIdentity();
    A1.bottomLeftCorner(n, n) = -Mlu.solve(model.K());
    A1.bottomRightCorner(n, n) = -Mlu.solve(model.Q());
    A2.noalias() = A1 * A1;
    S.resize(N, N);
    G.resize(N, 2);
    req.resize(N);
    ceq.resize(N);
    ipiv_r.resize(static_cast<std::size_t>(N));
    dwork.resize(4 * N);
    iwork.resize(static_cast<std::size_t>(N));
    gc.resize(N);
    real_ready = true;
  }
  void select_real() {
    Eigen::VectorXd bx = Eigen::VectorXd::Zero(N);
    bx.tail(n) = Mlu.solve(b);
    Ab = -(A1 * bx);
    rhs_reduced = bx;
    Cxc.resize(Cy.rows(), N);
    Cxc << Cy, Cv;
  }
  bool point_real(double om, double& rc) {
    S = A2;
    S.diagonal().array() += om * om;
    // Equilibrate (dgeequ: row and column scalings by powers of the radix, exact): A² carries
    // the squared spread of the model's scales (1e20 on ear-scaled models), and the rcond of the
    // unscaled matrix measured that, not the conditioning of the solve.
    double rowcnd = 0.0, colcnd = 0.0, amax = 0.0;
    const lapack_int NE = detail::li(N);
    const lapack_int einfo = LAPACKE_dgeequb_work(LAPACK_COL_MAJOR, NE, NE, S.data(), NE,
                                                  req.data(), ceq.data(), &rowcnd, &colcnd, &amax);
    if (einfo != 0) {  // an exactly zero row or column: singular
      rc = 0.0;
      return false;
    }
    S.array().colwise() *= req.array();
    S.array().rowwise() *= ceq.array().transpose();
    double anorm = 0.0;
    for (Index j = 0; j < N; ++j) anorm = std::max(anorm, S.col(j).cwiseAbs().sum());
    const lapack_int NN = detail::li(N);
    lapack_int info = LAPACKE_dgetrf_work(LAPACK_COL_MAJOR, NN, NN, S.data(), NN, ipiv_r.data());
    detail::check_lapack(info, "dgetrf", "FrequencyResponse (real)");
    if (info > 0) {
      rc = 0.0;
      return false;
    }
    info = LAPACKE_dgecon_work(LAPACK_COL_MAJOR, '1', NN, S.data(), NN, anorm, &rc, dwork.data(),
                               iwork.data());
    detail::check_lapack(info, "dgecon", "FrequencyResponse (real)");
    G.col(0) = req.cwiseProduct(Ab);
    G.col(1) = -om * req.cwiseProduct(rhs_reduced);
    info = LAPACKE_dgetrs_work(LAPACK_COL_MAJOR, 'N', NN, 2, S.data(), NN, ipiv_r.data(),
                               G.data(), NN);
    detail::check_lapack(info, "dgetrs", "FrequencyResponse (real)");
    G.array().colwise() *= ceq.array();
    gc.real() = G.col(0);
    gc.imag() = G.col(1);
    z.noalias() = Cxc * gc;
    return true;
  }
};

FrequencyResponse::FrequencyResponse(const LinearModel& model, FrfOptions options)
    : model_(model), options_(options), impl_(std::make_unique<Impl>(model)) {}

FrequencyResponse::~FrequencyResponse() = default;

char FrequencyResponse::hessenberg_balancing() const {
  return impl_->hess_ready ? impl_->hess_job : '\0';
}

double FrequencyResponse::hessenberg_backward_error() const {
  return impl_->hess_ready ? impl_->hess_backward_error : 0.0;
}

FrequencyResponse& FrequencyResponse::compute(const Eigen::VectorXd& omega, Index input,
                                              const std::vector<Index>& outputs) {
  info_ = Eigen::InvalidInput;
  warnings_.clear();
  notes_.clear();
  Impl& im = *impl_;
  const Index n = model_.size();
  if (input < 0 || input >= model_.num_inputs()) {
    std::ostringstream s;
    s << "FrequencyResponse::compute: input index " << input << " out of range (B is " << n
      << "x" << model_.num_inputs() << ")";
    throw DimensionError(s.str());
  }
  std::vector<Index> rows = outputs;
  if (rows.empty())
    for (Index i = 0; i < model_.num_outputs(); ++i) rows.push_back(i);
  for (Index r : rows)
    if (r < 0 || r >= model_.num_outputs()) {
      std::ostringstream s;
      s << "FrequencyResponse::compute: output index " << r << " out of range (C_y is "
        << model_.num_outputs() << "x" << n << ")";
      throw DimensionError(s.str());
    }
  for (Index k = 0; k < omega.size(); ++k)
    if (!std::isfinite(omega[k]) || omega[k] < 0) {
      std::ostringstream s;
      s << "FrequencyResponse::compute: frequency " << k << " is " << omega[k]
        << " rad/s; frequencies must be finite and non-negative";
      throw NonFiniteError(s.str());
    }
  const Index p = static_cast<Index>(rows.size());
  im.select_outputs(rows, input);

  FrfMethod m = options_.method;
  if (m == FrfMethod::automatic) m = automatic_frf_method(model_, omega.size());
  used_ = m;
  switch (m) {
    case FrfMethod::direct: im.prepare_direct(); break;
    case FrfMethod::banded:
      im.prepare_banded();
      im.select_banded();
      break;
    case FrfMethod::hessenberg:
      im.prepare_hessenberg(options_, omega);
      if (options_.method == FrfMethod::automatic && im.hess_backward_error <= im.hess_bar &&
          !im.hessenberg_as_accurate_as_direct(omega, im.hess_forward_ratio)) {
        std::ostringstream s;
        s << "FrequencyResponse (hessenberg): forward error " << im.hess_forward_ratio
          << "x direct's at a probe frequency (bar 10x); automatic uses direct";
        notes_.push_back(s.str());
        used_ = m = FrfMethod::direct;
        im.prepare_direct();
      } else if (!(im.hess_backward_error <= im.hess_bar)) {
        std::ostringstream s;
        s << "FrequencyResponse (hessenberg): backward error " << im.hess_backward_error
          << " at the probe frequencies exceeds " << im.hess_bar << " (balancing '" << im.hess_job
          << "' kept)";
        if (options_.method == FrfMethod::automatic) {
          s << "; automatic uses direct";
          used_ = m = FrfMethod::direct;
          im.prepare_direct();
          notes_.push_back(s.str());
        } else {
          s << "; expect that many fewer correct digits than direct";
          im.select_hessenberg();
          warnings_.push_back(s.str());
        }
      } else {
        im.select_hessenberg();
      }
      break;
    case FrfMethod::modal:
      im.prepare_modal(options_, warnings_);
      im.select_modal(options_, warnings_);
      break;
    case FrfMethod::real:
      im.prepare_real();
      im.select_real();
      break;
    case FrfMethod::automatic: break;
  }

  sweep(omega, m, p, response_);
  // A moving support (LinearModel::B1): the response to B(Ω) = B + iΩB1 − Ω²B2 is, by
  // linearity, that to B plus iΩ times that to B1 (with D1) minus Ω² times that to B2: two more
  // sweeps, every method unchanged (those that factor per frequency factor again: three times the
  // cost for a motion input). A point's flag and rcond are the worst of the three sweeps (the
  // modal method's rcond depends on the right-hand side), and a pole in any makes it NaN.
  if (model_.input_has_rates(input)) {
    const std::vector<FrfFlag> flags = flags_;
    const Eigen::VectorXd rcond = rcond_;
    auto worst = [](FrfFlag a, FrfFlag b) {
      if (a == FrfFlag::pole || b == FrfFlag::pole) return FrfFlag::pole;
      return a == FrfFlag::ill_conditioned || b == FrfFlag::ill_conditioned ? FrfFlag::ill_conditioned : FrfFlag::ok;
    };
    std::vector<FrfFlag> merged = flags;
    Eigen::VectorXd merged_rcond = rcond;
    for (int part = 1; part <= 2; ++part) {
      im.select_part(part == 1 ? model_.B1() : model_.B2(), part == 1 ? &model_.D1() : nullptr, rows, input);
      switch (m) {
        case FrfMethod::banded: im.select_banded(); break;
        case FrfMethod::hessenberg: im.select_hessenberg(); break;
        case FrfMethod::modal: im.select_modal(options_, warnings_); break;
        case FrfMethod::real: im.select_real(); break;
        default: break;
      }
      Eigen::MatrixXcd z;
      sweep(omega, m, p, z);
      for (Index k = 0; k < omega.size(); ++k) {
        const auto K = static_cast<std::size_t>(k);
        merged[K] = worst(merged[K], flags_[K]);
        merged_rcond[k] = std::min(merged_rcond[k], rcond_[k]);
        const cd factor = part == 1 ? cd(0.0, omega[k]) : cd(-omega[k] * omega[k], 0.0);
        if (merged[K] == FrfFlag::pole)
          response_.col(k).setConstant(cd(kNaN, kNaN));
        else
          response_.col(k) += factor * z.col(k);
      }
    }
    flags_ = merged;
    rcond_ = merged_rcond;
    // Each part's selection may say the same thing again (a modal truncation): once is enough.
    std::vector<std::string> once;
    for (const std::string& w : warnings_)
      if (std::find(once.begin(), once.end(), w) == once.end()) once.push_back(w);
    warnings_ = once;
  }
  info_ = Eigen::Success;
  return *this;
}

void FrequencyResponse::sweep(const Eigen::VectorXd& omega, FrfMethod m, Index p, Eigen::MatrixXcd& out) {
  Impl& im = *impl_;
  const Index n = model_.size();
  const Index F = omega.size();
  out.resize(p, F);
  rcond_.resize(F);
  flags_.assign(static_cast<std::size_t>(F), FrfFlag::ok);
  const double pole_rc =
      options_.pole_rcond > 0 ? options_.pole_rcond : static_cast<double>(n) * kU;
  for (Index k = 0; k < F; ++k) {
    const double om = omega[k];
    double rc = 0.0;
    bool ok = false;
    switch (m) {
      case FrfMethod::direct: ok = im.point_direct(om, rc); break;
      case FrfMethod::banded: ok = im.point_banded(om, rc); break;
      case FrfMethod::hessenberg: ok = im.point_hessenberg(om, rc); break;
      case FrfMethod::modal: ok = im.point_modal(om, rc); break;
      case FrfMethod::real: ok = im.point_real(om, rc); break;
      case FrfMethod::automatic: break;
    }
    if (ok && im.combine) im.combine_outputs(om);
    rcond_[k] = rc;
    FrfFlag flag = FrfFlag::ok;
    // `real` solves the squared system Ω²E + A², whose rcond is about the square of the complex
    // one's: a small rcond there says the real 2f×2f solve is ill-conditioned, not that Ω is a
    // pole; a pole is an exact zero pivot or a non-finite value.
    if (!ok || !im.z.allFinite() || (!(rc > pole_rc) && m != FrfMethod::real))
      flag = FrfFlag::pole;
    else if (rc < options_.ill_conditioned_rcond)
      flag = FrfFlag::ill_conditioned;
    flags_[static_cast<std::size_t>(k)] = flag;
    if (flag == FrfFlag::pole) {
      if (options_.on_pole == PoleHandling::raise) {
        std::ostringstream s;
        s << "FrequencyResponse::compute (" << to_string(m) << "): the system is singular at "
          << hz(om) << ", rcond = " << rc << " (an undamped resonance?)";
        throw SingularSystemError(s.str());
      }
      out.col(k).setConstant(cd(kNaN, kNaN));
    } else {
      out.col(k) = im.z.head(p);
    }
  }
}

}  // namespace mbsgen
