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

}  // namespace mbsgen::detail
