#include <cmath>

#include "lapack.hpp"

namespace mbsgen::detail {

double norm2_estimate(const Eigen::MatrixXd& A) {
  if (A.size() == 0) return 0.0;
  const double fro = A.norm();
  if (fro == 0.0) return 0.0;
  Eigen::VectorXd v = Eigen::VectorXd::Ones(A.cols());
  // Start from the column sums of |A| direction to avoid a start orthogonal to the top vector.
  for (Eigen::Index j = 0; j < A.cols(); ++j) v[j] = 1.0 + A.col(j).cwiseAbs().sum() / fro;
  v.normalize();
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

Eigen::Index numerical_rank(const Eigen::MatrixXd& A, double relative_tolerance) {
  if (A.size() == 0 || A.cwiseAbs().maxCoeff() == 0.0) return 0;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  const auto d = qr.matrixQR().diagonal().cwiseAbs();
  const double r00 = d[0];
  Eigen::Index r = 0;
  for (Eigen::Index i = 0; i < d.size(); ++i)
    if (d[i] > relative_tolerance * r00) ++r;
  return r;
}

}  // namespace mbsgen::detail
