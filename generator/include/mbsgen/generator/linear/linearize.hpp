// Stage 3: linearization about an operating point (seed eqs. 3.7–3.8, docs/design.md, "Linearization"):
//   M y_s'' + Q y_s' + K y_s = B u,   z_s = C_y y_s + C_v y_s',
//   M = M(y0), Q = ∂(k − q)/∂ẏ, K = ∂(k − q)/∂y, B = −∂(k − q)/∂u at (y0, ẏ0, u = 0),
// symbolic in the parameters and in (y0, ẏ0), which stay run-time arguments. Q splits into
// damping D = sym Q and gyroscopic G = skew Q, K into stiffness sym K and circulatory N = skew K.
#pragma once

#include "mbsgen/generator/linear/constrained_linearization.hpp"
#include "mbsgen/generator/linear/structural_zeros.hpp"
#include "mbsgen/generator/mechanics/dynamics.hpp"
#include "mbsgen/generator/mechanics/nonholonomic.hpp"

namespace mbsgen {

struct LinearEquations {
  /// True when every steady velocity of the operating point is zero: ẏ0 = 0 is then
  /// substituted before differentiation and the kernels take no ẏ0.
  bool at_rest = true;
  /// Coordinates whose rate ẏ0 is fixed at zero before differentiation: all of them at rest,
  /// and in a scene every rate its operating point sets to zero; the kernels ignore these
  /// components of ẏ0.
  std::vector<std::size_t> zero_rates;
  /// The model's coordinates (indices) that the linear model and the kernels use: all of them,
  /// or the independent ones of a model with closed loops (loop_closure.hpp).
  std::vector<std::size_t> coordinates;
  /// Nonholonomic constraints (nonholonomic.hpp): the coordinates whose rates are the
  /// independent speeds w (all of `coordinates` without such constraints).
  std::vector<std::size_t> speeds;
  /// True for a model with nonholonomic constraints: its linear model is the descriptor system
  ///   E ẋ = A x + Bx u,  z = Cx x,  x = (δy_i, δw)  (f + s states),
  /// and M, Q, K, B, C_y, C_v above are empty.
  bool descriptor = false;
  ExMatrix E, A, Bx, Cx;
  /// The reduced second-order form of the descriptor model, where it exists (nonholonomic.hpp).
  ReducedForm reduced;
  ExMatrix M, Q, K, B, Cy, Cv;  ///< f×f, f×f, f×f, f×m, r×f, r×f (expressions in y, ẏ, p)
  ExMatrix D, G, Ks, N;         ///< sym Q, skew Q, sym K, skew K
  /// Outputs that depend on accelerations and inputs (reaction forces, reactions.hpp):
  /// z_s = C_y y_s + C_v y_s' + C_a y_s'' + D_u u. Empty when no output does.
  ExMatrix Ca, Du;              ///< r×f, r×m
  /// Prescribed motion (prescribed_motion.hpp): h = B u + B1 u̇ + B2 ü and z += D1 u̇ (f×m,
  /// f×m, r×m; zero columns for force inputs). Empty without motion inputs.
  ExMatrix B1, B2, D1;
  std::vector<GiNaC::ex> y0, yd0;  ///< default operating point (expressions in p)
  bool equilibrium = false;     ///< y0 is an initial guess for a static equilibrium
  /// D, G, N vanish at the operating point for all parameter values (the manifest's
  /// "structure"). Where they vanish for all arguments (y0, ẏ0, p) of the kernels they are
  /// exact zeros, and Q and K exactly symmetric or skew (each pair of entries computed once).
  bool D_zero = false, G_zero = false, N_zero = false;
  /// Exact structural zeros (structural_zeros.hpp): those zero everywhere are already 0 in the
  /// matrices above; those zero at the operating point only are emitted as conditional zeros.
  StructuralZeros zeros;
};

/// Linearizes about the model's operating point. Whether D, G, N vanish is decided by
/// evaluating them at two pseudo-random points with 50 digits (linearize.cpp).
LinearEquations linearize(Equations& eq);

}  // namespace mbsgen
