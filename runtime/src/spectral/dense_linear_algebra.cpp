#include <algorithm>
#include <cmath>
#include <vector>

#include "spectral/dense_linear_algebra.hpp"

namespace mbsgen::detail {

double norm2_estimate(const Eigen::MatrixXd& A) {
  if (A.size() == 0) return 0.0;
  const double fro = A.norm();
  if (fro == 0.0) return 0.0;
  Eigen::VectorXd v = Eigen::VectorXd::Ones(A.cols());
  // Start from the column sums of |A| direction to avoid a start orthogonal to the top vector,
  // or from the largest column (‖A e_j‖ = its norm) when that start gives less: the sums start
  // can lie in the null space (K of a free-free chain, whose column sums are all equal).
  for (Eigen::Index j = 0; j < A.cols(); ++j) v[j] = 1.0 + A.col(j).cwiseAbs().sum() / fro;
  v.normalize();
  Eigen::Index jmax = 0;
  const double colmax = A.colwise().norm().maxCoeff(&jmax);
  if ((A * v).norm() < colmax) v = Eigen::VectorXd::Unit(A.cols(), jmax);
  double sigma = 0.0;
  Eigen::VectorXd w(A.rows());
  for (int it = 0; it < 60; ++it) {
    w.noalias() = A * v;
    const double s = w.norm();
    v.noalias() = A.transpose() * w;
    const double nv = v.norm();
    if (nv == 0.0) return s;
    v /= nv;
    if (std::abs(s - sigma) <= 1e-6 * s) return s;
    sigma = s;
  }
  return sigma;
}

NullSpace null_space(const Eigen::MatrixXd& A, double tolerance, bool relative,
                     Eigen::Index force_rank) {
  const Eigen::Index n = A.rows();
  NullSpace out;
  if (n == 0) return out;
  Eigen::MatrixXd R = A.transpose();
  std::vector<lapack_int> jpvt(static_cast<std::size_t>(n), 0);
  Eigen::VectorXd tau(n);
  lapack_int info =
      LAPACKE_dgeqp3(LAPACK_COL_MAJOR, li(n), li(n), R.data(), li(n), jpvt.data(), tau.data());
  check_lapack(info, "dgeqp3", "null_space");
  out.r00 = std::abs(R(0, 0));
  const double threshold = relative ? tolerance * out.r00 : tolerance;
  if (force_rank >= 0)
    out.rank = std::min(force_rank, n);
  else
    while (out.rank < n && std::abs(R(out.rank, out.rank)) > threshold) ++out.rank;
  const Eigen::Index d = n - out.rank;
  out.residual = R.bottomRightCorner(d, d).triangularView<Eigen::Upper>().toDenseMatrix().norm();
  out.basis = Eigen::MatrixXd::Zero(n, d);
  out.basis.bottomRows(d).setIdentity();
  if (d > 0) {
    info = LAPACKE_dormqr(LAPACK_COL_MAJOR, 'L', 'N', li(n), li(d), li(n), R.data(), li(n),
                          tau.data(), out.basis.data(), li(n));
    check_lapack(info, "dormqr", "null_space");
  }
  return out;
}

}  // namespace mbsgen::detail
