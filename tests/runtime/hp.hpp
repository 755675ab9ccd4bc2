// High-precision (≈266-bit CLN long float) reference computations for the runtime tests.
// Independent of the library: plain Gaussian elimination and Newton iteration in CLN arithmetic,
// starting from the exact binary values of the double inputs.
#pragma once

#include <Eigen/Dense>
#include <cln/cln.h>
#include <array>
#include <complex>
#include <vector>

namespace hp {

using cln::cl_N;
using cln::cl_R;
using Eigen::Index;

/// Working precision of the references: 80 decimal digits.
const cln::float_format_t& precision();

cl_R real(double x);                     ///< exact value of x as a long float
cl_N cplx(std::complex<double> z);       ///< exact value of z
double to_double(const cl_R& x);         ///< round to nearest double
std::complex<double> to_double(const cl_N& z);

/// Dense column-major matrix of CLN numbers.
struct Matrix {
  Index rows = 0, cols = 0;
  std::vector<cl_N> a;
  Matrix(Index r, Index c);
  cl_N& operator()(Index i, Index j) { return a[static_cast<std::size_t>(i + j * rows)]; }
  const cl_N& operator()(Index i, Index j) const { return a[static_cast<std::size_t>(i + j * rows)]; }
};
using Vector = std::vector<cl_N>;

Matrix from(const Eigen::MatrixXd& A);
Vector from(const Eigen::VectorXd& v);
Vector from(const Eigen::VectorXcd& v);

/// Gaussian elimination with partial pivoting (by |.|); A is n×n, b has n entries.
Vector solve(Matrix A, Vector b);
/// Banded elimination without pivoting for half-bandwidth w (stable enough at 266 bits for the
/// diagonally dominant-at-high-precision chain matrices it is used on; checks pivots ≠ 0).
Vector solve_banded(Matrix A, Vector b, Index w);

/// ẑ = (C_y + iΩ C_v)(K − Ω²M + iΩQ)⁻¹ b at the exact double Ω, for the given output rows.
/// banded_w < 0: dense solve, else banded with that half-bandwidth.
std::vector<std::complex<double>> frf(const Eigen::MatrixXd& M, const Eigen::MatrixXd& Q,
                                      const Eigen::MatrixXd& K, const Eigen::VectorXd& b,
                                      const Eigen::MatrixXd& C_y, const Eigen::MatrixXd& C_v,
                                      double omega, Index banded_w = -1);

/// ‖(α²M + αβQ + β²K)x‖₂ / ((|α|²‖M‖₂ + |α|β‖Q‖₂ + β²‖K‖₂)‖x‖₂) with the residual in high
/// precision and exact 2-norms of the coefficients (from an SVD in double, relative error ~u).
double backward_error(const Eigen::MatrixXd& M, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& K,
                      std::complex<double> alpha, double beta, const Eigen::VectorXcd& x);

/// Newton's method on (P(λ)x = 0, x_k = 1) in high precision from (λ0, x0); returns the
/// converged λ (|Δλ| ≤ 1e-50|λ|) or throws std::runtime_error if it does not converge in 40 steps.
std::complex<double> refine_eigenvalue(const Eigen::MatrixXd& M, const Eigen::MatrixXd& Q,
                                       const Eigen::MatrixXd& K, std::complex<double> lambda0,
                                       const Eigen::VectorXcd& x0);

/// dλ/dt at t = 0 of the eigenvalue near lambda0 of (M + t dM, Q + t dQ, K + t dK), by central
/// differences in high precision: Newton (as refine_eigenvalue) at t = ±1e-30, so that the
/// difference's truncation error, O(1e-60), and its rounding, O(1e-80/1e-30), are far below a
/// double's resolution. Throws std::runtime_error when Newton does not converge.
std::complex<double> eigenvalue_derivative(const Eigen::MatrixXd& M, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& K,
                                           const Eigen::MatrixXd& dM, const Eigen::MatrixXd& dQ,
                                           const Eigen::MatrixXd& dK, std::complex<double> lambda0,
                                           const Eigen::VectorXcd& x0);

/// dẑ/dt at t = 0 of ẑ = (C_y + iΩC_v)(K − Ω²M + iΩQ)⁻¹ b with every matrix X replaced by
/// X + t dX (b by b + t db), for output row `row`, by central differences in high precision at
/// t = ±1e-30 (dense solves).
std::complex<double> frf_derivative(const std::array<Eigen::MatrixXd, 5>& MQKCyCv, const Eigen::VectorXd& b,
                                    const std::array<Eigen::MatrixXd, 5>& derivatives, const Eigen::VectorXd& db,
                                    double omega, Index row);

}  // namespace hp
