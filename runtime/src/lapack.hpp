// Private: LAPACKE with std::complex<double> as its complex type, and small shared helpers.
#pragma once

#include <complex>
#define lapack_complex_float std::complex<float>
#define lapack_complex_double std::complex<double>
#include <lapacke.h>

#include <Eigen/Dense>
#include <sstream>
#include <string>

#include "mbsgen/runtime/error.hpp"

namespace mbsgen::detail {

inline lapack_int li(Eigen::Index i) { return static_cast<lapack_int>(i); }

/// Throws LapackError for info < 0 (illegal argument: a bug on our side) with the routine name.
inline void check_lapack(lapack_int info, const char* routine, const char* caller) {
  if (info < 0) {
    std::ostringstream s;
    s << caller << ": LAPACK " << routine << " rejected argument " << -info;
    throw LapackError(s.str());
  }
}

/// Lower bound on ‖A‖₂ by power iteration on AᵀA (converges from below; 1e-6 relative or 60 steps).
/// Used where a lower bound is conservative (backward errors become larger, never smaller).
double norm2_estimate(const Eigen::MatrixXd& A);

/// Numerical rank by QR with column pivoting: #{i : |R_ii| > tol·|R_00|}.
Eigen::Index numerical_rank(const Eigen::MatrixXd& A, double relative_tolerance);

/// Higham's (1988) 1-norm estimator of ‖W⁻¹‖₁ (LAPACK xLACON) for complex W of order n, given
/// solve(x) ← W⁻¹x and solve_adjoint(x) ← W⁻ᴴx in place. x, y are caller workspace of size n.
template <class Solve, class SolveAdjoint>
double inverse_norm1_estimate(Eigen::Index n, Solve&& solve, SolveAdjoint&& solve_adjoint,
                              Eigen::VectorXcd& x, Eigen::VectorXcd& xi) {
  using cd = std::complex<double>;
  x.setConstant(cd(1.0 / static_cast<double>(n), 0.0));
  solve(x);
  double est = x.cwiseAbs().sum();
  if (n == 1) return est;
  for (int iter = 0; iter < 4; ++iter) {
    for (Eigen::Index i = 0; i < n; ++i) {
      const double a = std::abs(x[i]);
      xi[i] = a > 0 ? x[i] / a : cd(1.0, 0.0);
    }
    solve_adjoint(xi);
    Eigen::Index j = 0;
    xi.cwiseAbs().maxCoeff(&j);
    x.setZero();
    x[j] = 1.0;
    solve(x);
    const double est_new = x.cwiseAbs().sum();
    if (est_new <= est * (1.0 + 1e-12)) break;
    est = est_new;
  }
  // Alternative vector guarding against the estimator's known blind spots (as in xLACON).
  double alt_sign = 1.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    x[i] = alt_sign * (1.0 + static_cast<double>(i) / static_cast<double>(n - 1));
    alt_sign = -alt_sign;
  }
  solve(x);
  return std::max(est, 2.0 * x.cwiseAbs().sum() / (3.0 * static_cast<double>(n)));
}

}  // namespace mbsgen::detail
