// Stage 3c: parameter sensitivities of the linear model (issue 20 §1).
//
// The linear matrices M, Q, K, B, C_y, C_v (and C_a, D of outputs on ÿ and u; B1, B2, D1 of a
// moving support) are expressions in the operating point (y0, ẏ0) and the parameters p. Their
// total derivative along a parameter p_j is
//
//     dA/dp_j = ∂A/∂p_j + Σ_k ∂A/∂y_k · dy0_k/dp_j + Σ_k ∂A/∂ẏ_k · dẏ0_k/dp_j,
//
// formed symbolically through the program (forward differentiation, Program::diff). The second
// and third sums are there only when the operating point moves with the parameters: a `given`
// point whose expressions hold p, or a static equilibrium, where r(y0(p), ẏ0(p), p) = 0 gives
//
//     K dy0/dp_j = −(∂r/∂p_j + Q dẏ0/dp_j)       (r = k − q at u = 0; K, Q the linear ones).
//
// The kernel `sensitivity(y0, yd0, p, dy0, dyd0, dM, …)` takes the directions dy0/dp, dẏ0/dp
// (f×s each, column-major; read only when the point moves) and `operating_point_sensitivity
// (y0, yd0, p, dy0, dyd0)` gives them: for a given point dy0/dp and dẏ0/dp themselves, for an
// equilibrium ∂r/∂p_j + Q dẏ0/dp_j in its first output (the runtime solves with K) and dẏ0/dp.
//
// Exact zeros: a derivative whose entry is not a syntactic zero is screened numerically at the
// structural-zero points (50 digits) and a candidate is proved zero symbolically
// (structural_zeros.hpp) before it becomes 0; entries of A that are zero at the operating point
// for every p have derivative 0 there, emitted as conditional zeros like A's own.
//
// Not for models with closed loops or rolling constraints (their linear model depends on p also
// through the dependent coordinates Newton's method finds): refused when a scene asks for it.
#pragma once

#include "mbsgen/generator/linear/linearize.hpp"

#include <string>
#include <vector>

namespace mbsgen {

/// The derivatives of one linear matrix, rows×cols, for each selected parameter, column-major
/// and one after the other (entry (i, k) of parameter j at j·rows·cols + k·rows + i).
struct MatrixDerivative {
  std::string name;  ///< M, Q, K, B, Cy, Cv, Ca, D, B1, B2, D1
  std::size_t rows = 0, cols = 0;
  std::vector<GiNaC::ex> values;
  const ZeroPattern* zeros = nullptr;  ///< the matrix's structural zeros (lin.zeros)
};

struct LinearSensitivity {
  bool active = false;
  std::vector<std::size_t> parameters;  ///< indices into Equations::p (s of them)
  std::vector<MatrixDerivative> matrices;
  /// The operating point moves with a selected parameter (a static equilibrium, or a given point
  /// whose expressions hold it): the kernel reads dy0, dyd0.
  bool moving_point = false;
  std::vector<GiNaC::symbol> dy0, dyd0;   ///< the direction arguments, f×s each (moving_point)
  std::vector<GiNaC::ex> op_first, op_rates;  ///< operating_point_sensitivity's outputs
  std::size_t proved_zero = 0;            ///< derivatives proved zero (numerically zero candidates)
  std::size_t unproved = 0;               ///< candidates not proved within the budget (kept)
};

/// The sensitivities of lin's matrices to the parameters `parameters` (indices into eq.p; all of
/// them when empty). Throws std::invalid_argument for a model with closed loops or rolling
/// constraints.
LinearSensitivity linear_sensitivity(Equations& eq, const LinearEquations& lin,
                                     std::vector<std::size_t> parameters);

}  // namespace mbsgen
