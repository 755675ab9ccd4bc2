// Stage 2: the minimal equations of motion M(y) ÿ + k(y, ẏ) = q(y, ẏ, u) (seed eqs. 3.2–3.6
// projected with J̄ᵀ, docs/design.md, "Linearization"), and the outputs z(y, ẏ).
//
// Newton–Euler per body about the world origin, f_i = I_i a_i + V_i ×* I_i V_i, is projected
// with the joint columns φ of kinematics.hpp through composite sums over subtrees, so that
//   M_jk = φ_jᵀ (I^c φ_k)         (composite-rigid-body form of J̄ᵀ M̄ J̄),
//   (k − q)_j = φ_jᵀ F^c          (F^c the subtree sum of inertial minus applied wrenches).
// Springs, dampers and bushings enter through their potential V(y) and dissipation function
// R(y, ẏ): q_j = −∂V/∂y_j − ∂R/∂ẏ_j, which equals J̄ᵀ q̄ of their forces and keeps the
// stiffness matrix of a conservative element exactly symmetric.
#pragma once

#include "mbsgen/generator/mechanics/nonholonomic.hpp"
#include "mbsgen/generator/mechanics/prescribed_motion.hpp"

#include <vector>

namespace mbsgen {

/// The derived equations; every expression refers to intermediates of `program`.
struct Equations {
  const Model* model = nullptr;
  Program program;
  Kinematics kinematics;
  std::vector<GiNaC::symbol> y, yd, u, p;  ///< coordinates, rates, inputs, parameters
  /// Accelerations ÿ (`NAME_ddot`), variables only when outputs depend on them (reactions.hpp).
  std::vector<GiNaC::symbol> ydd;
  /// The accelerations as variables of the dynamics Jacobian ∂(M ÿ + k − q)/∂y (emit's
  /// `dynamics_jacobian`): `ydd` where outputs need them, else symbols `NAME_ddot` of their own,
  /// registered in `program` but read by no other expression.
  std::vector<GiNaC::symbol> accelerations;
  ExMatrix M;                               ///< f×f mass matrix M(y)
  std::vector<GiNaC::ex> residual;          ///< k(y, ẏ) − q(y, ẏ, u), length f
  /// The same k − q written for evaluation, or empty when `residual` is that form: on the link-
  /// frame route with gravity, the residual and dynamics kernels take gravity as the base's
  /// acceleration (link_frame_residual_with_gravity: 12-link spatial chain 3,213 → 2,346
  /// operations), while `residual`, which the linearization differentiates, keeps it projected in
  /// the world frame, the form whose exact zeros of N the proofs reach (link_frame_dynamics.hpp).
  /// Only for trees without reaction outputs; cleared when loops are closed.
  std::vector<GiNaC::ex> residual_kernel;
  std::vector<GiNaC::ex> outputs;           ///< z(y, ẏ), one per model output
  ExMatrix JT, JR;                          ///< per body 3×f: centre-of-mass and angular Jacobians
  /// Closed loops (loop_closure.hpp). When active, M, residual, outputs, JT and JR above are
  /// those of the independent coordinates (f = n − m columns; the residual and outputs take the
  /// rates of the independent coordinates), and `tree` keeps the tree's (n columns).
  LoopClosure loops;
  /// Nonholonomic constraints (nonholonomic.hpp), built after the loops.
  Nonholonomic nonholonomic;
  /// Motion inputs (prescribed_motion.hpp): M, residual, outputs, JT, JR and the kinematics
  /// above are then those with the support at rest, and `motion` holds what its motion adds.
  PrescribedMotion motion;
  struct Tree {
    ExMatrix M, JT, JR;
    std::vector<GiNaC::ex> residual, outputs;
  } tree;
};

/// How derive() projects the Newton–Euler equations of the bodies onto the coordinates.
enum class Projection {
  /// The default: link_frames, or world_composite for the models prefers_link_frames
  /// (link_frame_dynamics.hpp) declines (planar ones, those with nonholonomic constraints).
  composite,
  /// Composite-rigid-body and recursive Newton–Euler algorithms in link frames
  /// (link_frame_dynamics.hpp; fewest operations on spatial trees); gravity and applied forces
  /// at markers are projected as in world_composite.
  link_frames,
  /// The same algorithms in the world frame: subtree sums I^c and F^c about the world origin,
  /// then M_jk = φ_jᵀ I^c φ_k and (k − q)_j = φ_jᵀ F^c (the default before issue 17 §2).
  world_composite,
  /// The textbook projection body by body, M = Σ_i J̄_iᵀ Ī_i J̄_i and k − q = Σ_i J̄_iᵀ f̄_i, with
  /// J̄_i the 6×f spatial Jacobian of body i (sums of φ along its root path), Ī_i its spatial
  /// inertia and f̄_i its inertial-minus-applied wrench. The same matrices with more operations;
  /// kept for the comparison in bench/ (docs/accuracy-vs-time.md) and its test.
  naive
};

/// Options of derive().
struct DeriveOptions {
  Projection projection = Projection::composite;
};

/// Keeps the equations of the first n coordinates, with `f` applied to every expression (the
/// others fixed by it): y, ẏ, the accelerations, M, k − q (and its kernel form), the outputs,
/// the body Jacobians' columns and the kinematics (restrict_kinematics). For the joint probes of
/// reactions.hpp and the prescribed motion of prescribed_motion.hpp.
void restrict_equations(Equations& eq, std::size_t n, const std::function<GiNaC::ex(const GiNaC::ex&)>& f);
/// Derives the equations of a validated model. When model.inertial_velocity_terms() is false
/// (a scene that drops them), k(y, ẏ) has no velocity-quadratic inertia terms: the residual is
/// then exact at ẏ = 0 only.
Equations derive(const Model& model, const DeriveOptions& options = {});

}  // namespace mbsgen
