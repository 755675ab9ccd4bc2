// Stage 2b: closed kinematic loops (docs/generator.md, "Closed loops").
//
// The tree's coordinates y ∈ ℝⁿ are bound by holonomic constraints Φ(y) = 0 (model.hpp,
// Constraint), m independent equations with Jacobian Φ_y of rank m. The coordinates split into
// independent y_i (n − m of them: the model's listed ones, or chosen by column-pivoted QR of Φ_y
// at the operating point) and dependent y_d, with Φ_yd regular. Admissible motions are
//   ẏ = T ẏ_i,   T = [E; X],   X = −Φ_yd⁻¹ Φ_yi,
//   ÿ = T ÿ_i + [0; g_d],   g_d = −Φ_yd⁻¹ γ,   γ = (∂(Φ_y ẏ)/∂y) ẏ,
// and the tree equations M ÿ + h(y, ẏ, u) = Φ_yᵀ λ, premultiplied by Tᵀ (which removes λ),
// give the equations in the independent coordinates (the reaction forces do no virtual work):
//   Tᵀ M T ÿ_i + Tᵀ (M [0; g_d] + h) = 0.
// λ follows from the dependent rows, Φ_ydᵀ λ = (M ÿ + h)_d. Linearized at rest, the reduced
// stiffness is Tᵀ (K − Σ_k λ_k ∂²Φ_k/∂y²) T: the Jacobian of Tᵀ h restricted to the constraint
// manifold, whose λ term (the geometric stiffness of the reaction forces) is easy to lose
// (docs/design.md, "Constraints and the geometric stiffness"; Peterson, Gede & Hubbard, Multibody
// Syst Dyn 33, 2015, and González et al., J Comput Nonlinear Dyn 12, 2017: docs/references.md).
//
// X, g_d and λ are program intermediates: Gaussian elimination of Φ_yd with the row order that
// partial pivoting chooses at the operating point with the default parameter values, so that the
// reduced matrices stay expressions (exact zeros proved as for a tree). The dependent coordinates
// themselves have no closed form: the emitted kernels find them by Newton's method (emit.cpp).
#pragma once

#include "mbsgen/generator/mechanics/kinematics.hpp"

#include <string>
#include <vector>

namespace mbsgen {

struct Equations;

/// One scalar constraint equation.
struct ConstraintEquation {
  std::string constraint;  ///< the model's constraint name
  std::string component;   ///< "x", "y", "z", "rx", "ry", "rz", "length" or "" (expression)
  GiNaC::ex phi;           ///< Φ_k(y), program expression
  /// Scale of Φ_k at the operating point (a length [m] or 1) for the residual check.
  double scale = 1;
};

/// A square matrix of program expressions factored as P A = L U (Gaussian elimination with the
/// row order `rows` that partial pivoting chooses at the operating point, exact zeros skipped),
/// for solving with it symbolically: the loops' Φ_yd, the nonholonomic constraints' speed block.
struct SymbolicLU {
  std::vector<std::size_t> rows;
  ExMatrix L, U;
  /// Factors A (k×k) with the given row order.
  static SymbolicLU factor(Program& program, const ExMatrix& A, std::vector<std::size_t> rows);
  /// A⁻¹ b and A⁻ᵀ b (program expressions).
  std::vector<GiNaC::ex> solve(Program& program, const std::vector<GiNaC::ex>& b) const;
  std::vector<GiNaC::ex> solve_transposed(Program& program, const std::vector<GiNaC::ex>& b) const;
};

struct LoopClosure {
  bool active = false;  ///< the model has constraints
  std::vector<ConstraintEquation> equations;  ///< the m equations kept
  /// Equations dropped: identically zero (a 3-D joint in a planar model) or redundant for
  /// every configuration; with `reason`.
  std::vector<std::pair<ConstraintEquation, std::string>> dropped;
  bool redundant = false;  ///< some equations were redundant: reaction forces are not unique
  std::vector<std::size_t> independent, dependent;  ///< coordinate indices, ascending
  bool chosen = false;     ///< independent coordinates chosen by mbsgen (not listed in the model)
  ExMatrix Phi_y;          ///< m×n
  /// The dependent coordinates at the operating point (or the equilibrium's guess) with the
  /// default parameter values, closed to 50 digits (for `mbsgen check`).
  GiNaC::exmap closed_at_defaults;
  ExMatrix X;              ///< (n−m)… dependent × independent: ẏ_d = X ẏ_i
  std::vector<GiNaC::ex> g;  ///< g_d (length of dependent): ÿ_d = X ÿ_i + g_d
  std::vector<GiNaC::ex> gamma;  ///< γ(y, ẏ) (length m): Φ_y ÿ + γ = 0
  /// Eliminates with Φ_yd: solve(b) = Φ_yd⁻¹ b, solve_transposed(b) = Φ_yd⁻ᵀ b (program
  /// expressions; b indexed like `dependent` / like `equations`).
  std::vector<GiNaC::ex> solve(Program& program, const std::vector<GiNaC::ex>& b) const;
  std::vector<GiNaC::ex> solve_transposed(Program& program, const std::vector<GiNaC::ex>& b) const;

  SymbolicLU lu;  ///< P Φ_yd = L U
};

/// Every equation of the model's constraints (none dropped), written with the kinematics `kin`.
std::vector<ConstraintEquation> constraint_equations(const Model& model, Program& program, const Kinematics& kin);

/// Builds the constraint equations of a derived model, drops those that vanish identically,
/// checks the operating point (a `given` one must close the loops), chooses or checks the
/// independent coordinates and factors Φ_yd. Throws ModelError for a singular Jacobian at the
/// operating point (naming constraints and coordinates), badly chosen independent coordinates,
/// or a given operating point that does not close a loop. Inactive for a model without
/// constraints.
LoopClosure close_loops(const Model& model, Equations& eq);

/// The reduced equations: eq.M, eq.residual, eq.outputs, eq.JT, eq.JR become those of the
/// independent coordinates (residual and outputs with the dependent rates ẏ_d = X ẏ_i
/// substituted; they still depend on every coordinate y, which the kernels close by Newton).
void reduce_equations(Equations& eq);

/// The linear matrices of the tree at rest (f = n) in lin become those of the independent
/// coordinates, with the geometric stiffness of the multipliers at the operating point.
/// `residual_at_rest` is (k − q)(y, 0, 0) of the tree.
void reduce_linear(Equations& eq, const std::vector<GiNaC::ex>& residual_at_rest, ExMatrix& M, ExMatrix& Q,
                   ExMatrix& K, ExMatrix& B, ExMatrix& Cy, ExMatrix& Cv);

/// A T: the columns of the tree's coordinates become those of the independent ones.
ExMatrix reduce_columns(Equations& eq, const ExMatrix& A);

}  // namespace mbsgen
