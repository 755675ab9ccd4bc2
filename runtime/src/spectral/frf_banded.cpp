// FrfMethod::banded: per frequency, a complex band LU of K − Ω²M + iΩQ with a fused LINPACK
// condition estimate — detail::BandSolver's definitions and FrequencyResponse::Impl's
// prepare_banded, point_banded, select_banded (and SparseRows, the outputs in compressed rows).
#include "spectral/frequency_response_impl.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace mbsgen {

namespace detail {

void BandSolver::resize(Index n_, Index b_) {
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

bool BandSolver::solve(double anorm, Eigen::VectorXd& xr, Eigen::VectorXd& xi, double& rc) {
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

}  // namespace detail

void FrequencyResponse::Impl::prepare_banded() {
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

bool FrequencyResponse::Impl::point_banded(double om, double& rc) {
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

void FrequencyResponse::Impl::SparseRows::assign(const Eigen::MatrixXd& C) {
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

void FrequencyResponse::Impl::select_banded() {
  out_y.assign(Cy_re);
  out_v.assign(Cv_re);
}

}  // namespace mbsgen
