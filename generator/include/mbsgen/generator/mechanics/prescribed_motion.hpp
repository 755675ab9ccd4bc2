// Stage 2b: prescribed motion (rheonomic supports, issue 19).
//
// A motion input u prescribes the motion of a support: a body driven as a whole, a marker on the
// world, or a coordinate whose value is given (docs/model-format.md, "Prescribed motion"). The
// derivation treats u as one more coordinate with rate u̇, so that the kinematics, the
// Newton–Euler projection and the force elements need nothing new: for the extended coordinates
// (y, u) the equations are M_ext (ÿ, ü) + k_ext − q_ext = 0. The motion is prescribed, so the
// virtual displacements are δy only (Jourdain's principle) and the equations of motion are the
// rows of y:
//
//     M_yy ÿ + M_yu ü + (k − q)_y(y, ẏ, u, u̇) = 0.
//
// Linearized about u = u̇ = ü = 0 they are M ÿ + Q ẏ + K y = B0 u + B1 u̇ + B2 ü with
//     B0 = −∂(k − q)/∂u,   B1 = −∂(k − q)/∂u̇,   B2 = −M_yu,
// and an output z(y, ẏ, u, u̇) adds D0 u + D1 u̇ (a point's absolute velocity moves with the
// support). For a harmonic u = Re(û e^{iΩt}) the right-hand side is (B0 + iΩB1 − Ω²B2) û.
//
// The nonlinear kernels (mass matrix, residual, dynamics, bodies, outputs) are those of the
// support at rest in its reference place (u = u̇ = 0; a motion input's entry of their u is not
// read): the motion reaches the linear analyses through B, B1 and B2 only. (Keeping u in the
// residual would cost the middle ear's residual 3,377 → 5,505 operations for a time step that
// cannot use it: simulate refuses a moving support.)
//
// After derive(), Equations::model is the model as written, where a moving marker is still on the
// world: Kinematics::marker_position would give its position with u free and marker_velocity no
// velocity. The stages after derive() that read markers (loop closure, reactions, rolling) are
// therefore refused together with motion inputs (Model::validate).
#pragma once
#include "mbsgen/generator/mechanics/kinematics.hpp"
#include <functional>
#include <vector>

namespace mbsgen {

struct Equations;

/// What the motion inputs add to the equations; empty when the model has none.
struct PrescribedMotion {
  bool active = false;
  std::vector<std::size_t> inputs;    ///< the motion inputs' indices in Equations::u
  std::vector<GiNaC::symbol> rates;   ///< their rates u̇ (variables of the program), same order
  ExMatrix M;                         ///< f×k: M_yu, column k for inputs[k]
  std::vector<GiNaC::ex> residual;    ///< (k − q)_y with the support moving (u, u̇ free)
  std::vector<GiNaC::ex> outputs;     ///< z with the support moving
};

/// Splits the equations derived on with_motion_coordinates(model) into those of `model`'s own
/// coordinates (with the support at rest, as the nonlinear kernels take them) and the parts the
/// motion adds (Equations::motion).
void split_prescribed_motion(const Model& model, std::size_t bodies, Equations& eq);

}  // namespace mbsgen
