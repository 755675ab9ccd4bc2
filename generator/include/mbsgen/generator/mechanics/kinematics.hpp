// Stage 1 of the pipeline: the kinematics of every body as intermediates of a Program.
//
// Velocities are spatial vectors V = (ω, v_O) in the world frame: ω the angular velocity and
// v_O the velocity of the body point that momentarily coincides with the world origin. For a
// body i with parent p (seed eq. 3.3: r_i = r_p + S_p t_i, S_i = S_p R_i) this gives
//   V_i = V_p + Σ_k φ_ik ẏ_k,   φ_ik = (S_p ψω_k, S_p ψv_k + r_p × S_p ψω_k),
// where ψ_k = (ω_rel,k, ∂t/∂y_k − ω_rel,k × t) is the local motion of the joint in the parent
// frame. Only coordinates that appear in body i's own translation or rotation have a φ_ik, so
// the body Jacobians J̄_i are the sums of φ over the path to the root (Featherstone, Rigid Body
// Dynamics Algorithms, 2008, ch. 4–6, written here for arbitrary expression joints).
#pragma once

#include "mbsgen/generator/model/model.hpp"
#include "mbsgen/generator/symbolic/program.hpp"

#include <functional>
#include <vector>

namespace mbsgen {

using ExMatrix = std::vector<std::vector<GiNaC::ex>>;

/// A spatial motion (ω, v) or force (n, f) vector in the world frame, about the world origin.
struct Spatial {
  Vec3 w = zero_vec3();
  Vec3 v = zero_vec3();
};

/// The motion of one body's joint owing to one coordinate.
struct JointColumn {
  int coordinate = 0;
  Spatial phi;
};

/// Rigid-body inertia about the world origin, in the world frame: mass m, first moment
/// h = m c (c the centre of mass), and J = I_C + m([c]ᵀ[c]) the inertia about the origin.
struct SpatialInertia {
  GiNaC::ex m = 0;
  Vec3 h = zero_vec3();
  Mat3 J = zero_mat3();
};

struct BodyKinematics {
  int parent = -1;           ///< index of the parent body, -1 for the world
  Mat3 S = identity_mat3();  ///< body frame to world frame
  Vec3 r = zero_vec3();      ///< origin of the body frame [m]
  Vec3 com = zero_vec3();    ///< centre of mass in the world frame [m]
  Mat3 I_com = zero_mat3();  ///< inertia about the centre of mass, world frame [kg m²]
  std::vector<JointColumn> columns;  ///< φ_ik for the body's own coordinates
  Spatial V;                 ///< spatial velocity
  Spatial bias;              ///< spatial acceleration at ÿ = 0 (the ā of seed eq. 3.4)
  SpatialInertia inertia;
};

struct Kinematics {
  std::vector<BodyKinematics> bodies;
  /// World position [m] and frame (marker to world) of a marker.
  Vec3 marker_position(const Model& model, Program& program, const std::string& name) const;
  Mat3 marker_frame(const Model& model, Program& program, const std::string& name) const;
  /// World velocity [m/s] of a marker's point and the angular velocity of its frame.
  Vec3 marker_velocity(const Model& model, Program& program, const std::string& name) const;
  Vec3 marker_angular_velocity(const Model& model, const std::string& name) const;
  /// True when body a is body b or one of its ancestors.
  bool is_ancestor_or_self(int a, int b) const;
};

/// Applies `f` to every expression of the bodies' kinematics and drops the joint columns of the
/// coordinates from `n` on: the kinematics of the first n coordinates with the others fixed, as
/// the joint probes of reactions.hpp and the prescribed motion of prescribed_motion.hpp leave it.
void restrict_kinematics(Kinematics& kin, std::size_t n, const std::function<GiNaC::ex(const GiNaC::ex&)>& f);
/// Builds the kinematics of every body; registers nothing (the Program's variables are the
/// model's coordinates, rates, inputs and parameters, registered by the caller).
Kinematics compute_kinematics(const Model& model, Program& program);

// Small vector helpers on expressions (each component defined in the program when asked).
Vec3 cross(const Vec3& a, const Vec3& b);
GiNaC::ex dot(const Vec3& a, const Vec3& b);
Vec3 add(const Vec3& a, const Vec3& b);
Vec3 sub(const Vec3& a, const Vec3& b);
Vec3 scale(const GiNaC::ex& s, const Vec3& a);
Vec3 mul(const Mat3& A, const Vec3& x);
Vec3 mul_transposed(const Mat3& A, const Vec3& x);  ///< Aᵀ x
Mat3 mul(const Mat3& A, const Mat3& B);
Mat3 transpose(const Mat3& A);
Vec3 define(Program& program, const Vec3& a);
Mat3 define(Program& program, const Mat3& A);
Spatial define(Program& program, const Spatial& s);
/// Motion cross product V × m = (ω × m_w, ω × m_v + v × m_w).
Spatial cross_motion(const Spatial& V, const Spatial& m);
/// Force cross product V ×* f = (ω × n + v × f, ω × f).
Spatial cross_force(const Spatial& V, const Spatial& f);
/// I V = (J ω + h × v, m v − h × ω).
Spatial apply(const SpatialInertia& I, const Spatial& V);
Spatial add(const Spatial& a, const Spatial& b);
Spatial scale(const GiNaC::ex& s, const Spatial& a);
GiNaC::ex dot(const Spatial& motion, const Spatial& force);

}  // namespace mbsgen
