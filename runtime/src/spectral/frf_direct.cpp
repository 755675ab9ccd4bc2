// FrfMethod::direct: per frequency, a complex LU (zgetrf) of K − Ω²M + iΩQ, its rcond (zgecon)
// and the solve (zgetrs) — FrequencyResponse::Impl's prepare_direct and point_direct.
#include "spectral/frequency_response_impl.hpp"

#include <algorithm>
#include <cmath>

namespace mbsgen {

void FrequencyResponse::Impl::prepare_direct() {
  if (direct_ready) return;
  D.resize(n, n);
  y.resize(n);
  ipiv.resize(static_cast<std::size_t>(n));
  zwork.resize(2 * n);
  rwork.resize(2 * n);
  direct_ready = true;
}

/// Returns false for an exactly singular matrix.
bool FrequencyResponse::Impl::point_direct(double om, double& rc) {
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

}  // namespace mbsgen
