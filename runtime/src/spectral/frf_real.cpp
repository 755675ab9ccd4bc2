// FrfMethod::real: docs/design.md, "Linearization"'s corrected real formulation, (Ω²E + A²)g = −A b, −Ω b, solved
// by an equilibrated real LU per frequency — FrequencyResponse::Impl's prepare_real, select_real
// and point_real.
#include "spectral/frequency_response_impl.hpp"

#include <algorithm>
#include <string>

namespace mbsgen {

void FrequencyResponse::Impl::prepare_real() {
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

void FrequencyResponse::Impl::select_real() {
  Eigen::VectorXd bx = Eigen::VectorXd::Zero(N);
  bx.tail(n) = Mlu.solve(b);
  Ab = -(A1 * bx);
  rhs_reduced = bx;
  Cxc.resize(Cy.rows(), N);
  Cxc << Cy, Cv;
}

bool FrequencyResponse::Impl::point_real(double om, double& rc) {
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

}  // namespace mbsgen
