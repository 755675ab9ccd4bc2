// Newton's linear systems of a BDF step on x' = (v, a(y, v)), x = (y, v), solved in n unknowns
// instead of 2n (internal to simulation.cpp).
//
// The Jacobian of the right-hand side is J = [0, I; −M⁻¹K_y, −M⁻¹K_v] with K_y = ∂(M ÿ + k − q)/∂y
// and K_v = ∂(k − q)/∂ẏ. CVODE's Newton matrix is A = d·I + c·J (d = 1, c = −γ). Eliminating the
// first block row, d·Δy + c·Δv = r₁, from the second and multiplying it by M gives
//
//   (d·M − c·K_v + (c²/d)·K_y) Δv = M r₂ + (c/d)·K_y r₁,   Δy = (r₁ − c·Δv)/d,
//
// an n×n LU instead of a 2n×2n one (8× fewer operations), and no M⁻¹K products. The matrix keeps
// M, K_y, K_v and the scalars c, d (SUNDIALS' custom SUNMatrix: copy, scale-add-identity and zero
// are all CVODE's matrix-based interface calls); the linear solver forms and factors the n×n
// matrix in setup.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>

namespace mbsgen::detail {

/// The mass matrix's equilibration: scale = diag(|M_ii|)^(-1/2) (1 where M_ii is 0 or not
/// finite), so that S M S's pivots do not depend on the units (kg against kg m²).
void mass_scale(const Eigen::MatrixXd& M, Eigen::VectorXd& scale);
/// mass_scale(M, scale), and A := S A S in place. For M's LU per evaluation (simulation.cpp)
/// and for the reduced Newton matrix.
void equilibrate(const Eigen::MatrixXd& M, Eigen::VectorXd& scale, Eigen::MatrixXd& A);
/// The smallest over the largest |pivot| of an LU (1 for an empty matrix): an upper bound of the
/// reciprocal condition number (NaN, never above n·ε, for a zero matrix).
double pivot_ratio(const Eigen::PartialPivLU<Eigen::MatrixXd>& lu);

/// A = d·I + c·[0, I; −M⁻¹K_y, −M⁻¹K_v] (2n×2n), kept as its parts.
struct SecondOrderMatrix {
  Eigen::MatrixXd M, Ky, Kv;
  double c = 0, d = 0;
};

/// A new matrix for n coordinates (zero); null when out of memory.
SUNMatrix new_second_order_matrix(Eigen::Index n, SUNContext context);
/// Its parts (the Jacobian function sets M, K_y, K_v and c = 1, d = 0).
SecondOrderMatrix& parts(SUNMatrix A);
/// The linear solver of such matrices (direct; setup fails recoverably when the n×n matrix is
/// singular to working precision); null when out of memory.
SUNLinearSolver new_second_order_solver(Eigen::Index n, SUNContext context);

}  // namespace mbsgen::detail
