// Stage 2c: reaction forces (seed eqs. 3.5–3.6): the loads the joints transmit, as outputs.
//
// The joint of a body to its parent: the body's placement gets six probe coordinates, a
// translation s (in the parent frame) before its rotation and small rotations σ about the parent
// frame's axes (x, then y, then z) at the body frame's origin. The tree's equations of the model
// with probes, evaluated at s = σ = 0 and ṡ = σ̇ = s̈ = σ̈ = 0, have in the probes' rows
//   (M ÿ + k − q)_probe − Φ_probeᵀ λ = the load the parent exerts on the body
// (force along s, torque about σ; Kane's auxiliary speeds, or the virtual cut of SD/FAST's sdreac).
// Every force acting on the subtree — inertia, gravity, springs, dampers, bushings, applied and
// generalized forces, and the loop constraints' multipliers λ — enters without a special case.
// A generalized force on the joint's own coordinate (a joint spring, an actuator) is carried by
// the joint and is part of its load.
//
// A loop constraint's load is its multipliers, λ = Φ_yd⁻ᵀ (M ÿ + h)_d (loop_closure.hpp),
// turned into the force and torque on the body of marker b.
//
// Reaction outputs depend on y, ẏ, ÿ and u: z = g(y, ẏ, ÿ, u), linearized as
//   ẑ = (C_y + iΩ C_v − Ω² C_a) ŷ + D û.
#pragma once

#include "mbsgen/generator/mechanics/kinematics.hpp"

#include <string>
#include <vector>

namespace mbsgen {

struct Equations;

/// The probes of a derived model with probes: the first of the six coordinates (s_x, s_y, s_z,
/// σ_x, σ_y, σ_z) of each probed body, in the model with probes.
struct JointProbes {
  std::vector<std::string> bodies;
  std::vector<std::size_t> first;
  /// The probes' rows (M ÿ + k − q)_probe in the tree's coordinates, rates and accelerations
  /// (6 per body), at s = σ = 0.
  std::vector<GiNaC::ex> rows;
  Kinematics probed;  ///< the kinematics with the probes (for Φ_probe)
  std::vector<GiNaC::symbol> symbols;  ///< the probe coordinates, 6 per body
};

/// The bodies whose joint loads the model's outputs ask for.
std::vector<std::string> probed_bodies(const Model& model);

/// Removes the probes of a derivation of with_joint_probes(model, probes.bodies): their rows go
/// to probes.rows, and every expression of eq is evaluated at s = σ = 0; eq then describes
/// `model` (its coordinates only).
void strip_joint_probes(const Model& model, Equations& eq, JointProbes& probes);

/// The reaction outputs (OutputKind::reaction) of eq.model as expressions in y, ẏ, ÿ (the tree's,
/// eq.ydd) and u, written into eq.outputs (tree form, before reduce_equations).
void reaction_outputs(Equations& eq, JointProbes& probes);

/// The value z(y, ẏ) of an output of type force (model.hpp, Output::elements): the force, or the
/// torque about marker b's point, that the named springs, dampers and bushings exert on the body
/// of their marker b, summed, against the direction in the world frame (or in marker b's frame of
/// the first element). The loads are the gradients of the elements' potential and dissipation
/// with respect to a displacement and a small rotation of marker b, so that their virtual work
/// is the generalized force the element puts on the coordinates (dynamics.hpp):
///   spring   F_b = −k (L − L0) d/L            (d = r_b − r_a, L = |d|; −k d when L0 = 0)
///   damper   F_b = −c (d·ḋ) d/L²
///   bushing  F_b = −S_a (K_t Δr + D_t Δṙ),  τ_b = −S_a (½ (tr R·E − Rᵀ) K_r θ + D_r ω_rel)
///            with R = S_aᵀ S_b, θ = vee(skew R) (model.hpp, Bushing).
GiNaC::ex force_output(const Model& model, Equations& eq, const Output& output);

}  // namespace mbsgen
