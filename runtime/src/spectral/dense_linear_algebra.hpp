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

/// Numerical rank and null space of a square A from the column-pivoted QR (LAPACK dgeqp3) of its
/// transpose, Aᵀ P = Q R (a rank-revealing QR).
struct NullSpace {
  Eigen::Index rank = 0;  ///< #{leading pivots with |R_ii| > threshold}
  Eigen::MatrixXd basis;  ///< n×(n − rank) orthonormal: Q(:, rank:n), and A·basis = P·[0; R22ᵀ]
  double r00 = 0.0;       ///< |R_00|: the largest row norm of A
  double residual = 0.0;  ///< ‖A·basis‖_F = ‖R22‖_F, the part of A the rank decision discards
};
/// The pivot threshold is `tolerance`·|R_00| if `relative`, else `tolerance` (absolute);
/// `force_rank` ≥ 0 imposes the rank instead (for a left null space of known dimension).
NullSpace null_space(const Eigen::MatrixXd& A, double tolerance, bool relative,
                     Eigen::Index force_rank = -1);

}  // namespace mbsgen::detail
