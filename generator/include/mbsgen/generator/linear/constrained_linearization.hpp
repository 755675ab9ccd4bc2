// Stage 3 of a constrained model: the linear model of a constrained steady motion (docs/generator.md,
// "Rolling contact and steady motions"), with the constraints of mechanics/loop_closure.hpp and
// mechanics/nonholonomic.hpp (ẏ = T ẏ_i, ẏ_i = N w + n).
//
// Linearized about a steady motion (y0, ẏ0): constant rates, ÿ0 = 0, and equations, constraints
// and T independent of the coordinates whose rates are not zero (a bicycle's position, heading
// and wheel angles), the state x = (δy_i, δw) obeys the first-order (descriptor) system
//   δẏ_i = P δy_i + N δw,        P = [0; −B_d⁻¹ A_q T],  A_q = ∂(A ẏ + a)/∂y at ẏ0,
//   M_r δẇ + C_r δw + K_r δy_i = B_r δu,
//   M_r = (TN)ᵀ M T N,  C_r = (TN)ᵀ (M T P + H_v T) N,
//   K_r = (TN)ᵀ [(H_y − G) T + (M T P + H_v T) P],  B_r = (TN)ᵀ B,
// with H_y = ∂h/∂y and H_v = ∂h/∂ẏ of the tree's residual h = k − q at the steady motion, and
// G = Σ λ_k ∂²Φ_k/∂y² + Σ μ_k ∂A_kᵀ/∂y the geometric stiffness of the constraint forces there
// (λ, μ from h(y0, ẏ0) = Φ_yᵀ λ + Aᵀ μ; docs/design.md, "Constraints and the geometric
// stiffness"). Without nonholonomic constraints N = E and P = 0: the second-order model of a
// closed loop in steady motion. References (full entries in docs/references.md): Neimark &
// Fufaev, Dynamics of Nonholonomic Systems (1972), ch. III; Peterson, Gede & Hubbard, Multibody
// Syst Dyn 33 (2015) (SymPy's Linearizer, whose state is the same (q_i, u_i)).
#pragma once

#include "mbsgen/generator/mechanics/nonholonomic.hpp"

#include <vector>

namespace mbsgen {

struct Equations;
struct LinearEquations;

/// The reduced second-order form of a descriptor model, where it exists: coordinates q whose rates
/// are independent speeds, closed under the couplings of the linear model at the operating point
/// (their rows of E and A have exact zeros outside q and q̇), so that
///   M q̈ + Q q̇ + K q = B u
/// holds on its own and the rest of the spectrum (ignorable coordinates, decoupled speeds) is
/// block triangular to it: for the bicycle, lean and steer (Meijaard et al. 2007, eq. 5.3).
struct ReducedForm {
  bool exists = false;
  std::vector<std::size_t> coordinates;  ///< model coordinate indices, ascending
  ExMatrix M, Q, K, B;                   ///< from the descriptor matrices (rows of the speeds)
  /// The model's named parts (Model::reduced_coefficients), n×n each, at the operating point:
  /// expressions in the parameters (and the loops' dependent coordinates).
  std::vector<ExMatrix> named;
};

/// The reduced form of lin's descriptor model, decided on its exact zeros (lin.zeros).
ReducedForm reduced_form(const LinearEquations& lin);

/// The model's named parts of the reduced form (the coefficient of each monomial, a Taylor
/// coefficient at zero of the parameters in the matrix's monomials, at the operating point),
/// into lin.reduced.named. Throws ModelError when the model names parts but there is no reduced
/// form, when a monomial is not a product of powers of parameters, when a loop constraint depends
/// on a monomial's parameter, or when a matrix is not the sum of its named parts (checked at two
/// pseudo-random points in 50 digits, to 1e-30 of its size).
void name_reduced_parts(Equations& eq, LinearEquations& lin);

/// The linear model of a constrained steady motion (the formulas above; the constraints from nonholonomic_constraints) into lin: for a model
/// with nonholonomic constraints the descriptor matrices (lin.descriptor), otherwise the
/// second-order M, Q, K, B, C_y, C_v of the independent coordinates. Throws ModelError when the
/// operating point is not a steady motion (residual, or equations that depend on a coordinate
/// whose rate is not zero).
void linearize_constrained(Equations& eq, LinearEquations& lin);

}  // namespace mbsgen
