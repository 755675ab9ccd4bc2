// Stage 2, the default projection: M and the inertial part of k − q in link frames.
//
// Every body's placement (model.hpp, Body: r_i = r_p + S_p t_i, S_i = S_p R_1 … R_n) is split
// into steps, each a frame of its own: the translation t_i (axes of the parent), then one frame
// per elementary rotation R_j (or one for a rotation_matrix). In its own frame a step's motion
// subspace is s_k = (∂θ/∂y_k e_axis, 0) for a rotation by θ about a coordinate axis,
// (0, ∂t/∂y_k) for the translation, and (vee(Rᵀ ∂R/∂y_k), 0) for a rotation matrix: exact unit
// vectors for the usual joints, whatever the joint (several coordinates in one angle, coordinates
// in translations and rotation matrices are handled alike, no fallback). Spatial vectors are
// expressed in the step's axes about its origin, and pass between neighbouring steps through one
// elementary rotation or one translation. Body inertias are constants in their own frames.
//
//   M_jk = Σ s_jᵀ (ᵖX*_c … I^c s_k)   composite-rigid-body algorithm: I^c propagated child to
//                                        parent, the force I^c s_k walked up the ancestors;
//   (k − q)_j = Σ s_jᵀ F^c            recursive Newton–Euler: velocities and bias accelerations
//                                        forward, body wrenches I a + v ×* I v, summed backward.
// (Featherstone, Rigid Body Dynamics Algorithms, 2008, §4.4 for c_J = ∘S ẏ + v × v_J, §5.3 RNEA,
// §6.2 CRBA.) Gravity and applied forces at markers are not included: they are projected in the
// world frame (dynamics.cpp), the residual being linear in the wrenches. Gravity as the base
// acceleration −g costs fewer operations (6-link spatial chain: residual 1,095 against 1,466), but
// the gravity stiffness then nests rotations down and back up the chain, and the proof that K
// is symmetric for every y0 (structural_zeros.hpp) exceeds its budget: 132 exact zeros of N lost.
// So the linearization differentiates the world-frame form, and only the residual and dynamics
// kernels, evaluated and never differentiated, take the other (link_frame_residual_with_gravity).
#pragma once

#include "mbsgen/generator/mechanics/kinematics.hpp"
#include "mbsgen/generator/model/model.hpp"
#include "mbsgen/generator/symbolic/program.hpp"

#include <vector>

namespace mbsgen {

/// The link-frame projection of a model's tree.
struct LinkFrameProjection {
  ExMatrix M;                       ///< f×f mass matrix M(y) [kg, kg m, kg m²]
  std::vector<GiNaC::ex> residual;  ///< inertial part of k(y, ẏ) − q(y, ẏ), length f
};

/// Whether derive() takes this projection for `model` (Projection::composite): yes unless
///  - the model is planar in the sense that every rotation is elementary about one common axis
///    (or there are none): world axes are then already 2-D, and the residual would pay for both
///    routes, link frames for inertia and world frames for gravity and applied forces
///    (chain3_sympy: 164 operations against 123; the planar chain's linear kernel at N = 2 came
///    out above SymPy's 31, a test's bound);
///  - the model has nonholonomic constraints (rolling, velocity constraints): the exact zeros of
///    its descriptor model are proved on written-out expressions, which the nesting of link
///    frames makes larger than the proof's budget (rolling disk: 3 zeros everywhere lost; the
///    Whipple bicycle's reduced Q₀₀, unproved either way, came out as rounding noise instead of
///    0, and Table 2's eigenvalues moved by 1e-11).
/// Such models take the world-frame route (Projection::world_composite) as a whole.
bool prefers_link_frames(const Model& model);

/// M and the inertial residual (zero when model.inertial_velocity_terms() is false) of `model`
/// (validated), as intermediates of `program`, whose variables the caller registered. y, yd: the
/// model's coordinates and rates (length f).
LinkFrameProjection project_link_frames(const Model& model, Program& program,
                                        const std::vector<GiNaC::symbol>& y,
                                        const std::vector<GiNaC::symbol>& yd);

/// The inertial residual of `model` with a uniform gravity field g included as the base's
/// acceleration −g (Featherstone 2008, §5.3): k − q of inertia and gravity, the same function as
/// project_link_frames' residual plus gravity projected in the world frame, in fewer operations
/// (dynamics.hpp, Equations::residual_kernel).
std::vector<GiNaC::ex> link_frame_residual_with_gravity(const Model& model, Program& program,
                                                        const std::vector<GiNaC::symbol>& y,
                                                        const std::vector<GiNaC::symbol>& yd, const Vec3& g);

}  // namespace mbsgen
