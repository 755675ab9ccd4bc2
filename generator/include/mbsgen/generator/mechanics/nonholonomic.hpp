// Stage 2c: nonholonomic constraints (rolling wheels, skates) (docs/generator.md, "Rolling
// contact and steady motions").
//
// Velocity constraints A(y) ẏ + a(y) = 0 (m of them, model.hpp VelocityConstraint, and two per
// rolling wheel: the contact point's velocity along the ground is zero) cannot be integrated into
// constraints on positions: the coordinates keep their number, the speeds do not. After the
// loops (loop_closure.hpp: ẏ = T ẏ_i), the rates of the independent coordinates split into
// independent speeds w (s of them) and dependent ones with B = A T regular in the latter:
//   ẏ_i = N w + n,   N = [E; −B_d⁻¹ B_s],   n = [0; −B_d⁻¹ a].
// The equations of motion are the tree's projected with (T N)ᵀ, which removes the loops'
// multipliers λ and the constraint forces Aᵀμ (d'Alembert–Lagrange for nonholonomic systems).
//
// The linear model of a constrained steady motion: linear/constrained_linearization.hpp.
#pragma once

#include "mbsgen/generator/mechanics/loop_closure.hpp"

#include <string>
#include <vector>

namespace mbsgen {

struct Equations;

/// A rolling wheel's geometry (model.hpp, ConstraintKind::rolling), world frame: centre C, axle
/// a, ground normal n, the contact point's offset d = P − C = −r (n − (n·a) a)/|n × a| and the
/// contact condition n·C = r |n × a|, written Φ = ((n·C)² − r² |n × a|²)/(2r) (program expressions).
struct RollingGeometry {
  Vec3 centre, axle, normal, offset;
  GiNaC::ex height;
};
RollingGeometry rolling_geometry(const Model& model, Program& program, const Kinematics& kin, const Constraint& c);

/// One scalar velocity constraint: value = A_k(y) ẏ + a_k(y).
struct VelocityEquation {
  std::string constraint;  ///< the model's name (a velocity or rolling constraint)
  std::string component;   ///< rolling: "t1", "t2" (the ground's tangent directions); else ""
  GiNaC::ex value;
};

struct Nonholonomic {
  bool active = false;
  std::vector<VelocityEquation> equations;  ///< m
  ExMatrix A;                               ///< m×n (tree coordinates)
  std::vector<GiNaC::ex> a;                 ///< m
  /// Coordinate indices (ascending) whose rates are the independent speeds w, and those whose
  /// rates follow from the constraints; together the independent coordinates of the loops.
  std::vector<std::size_t> speeds, dependent_speeds;
  bool chosen = false;  ///< speeds chosen by mbsgen (not listed in the model)
  SymbolicLU lu;        ///< of B_d = (A T)_d
};

/// Builds the velocity constraints of a derived model (after close_loops), chooses or checks the
/// independent speeds at the operating point with the default parameter values, and checks that
/// the operating point's rates satisfy the constraints. Inactive without such constraints.
/// Throws ModelError for dependent rates the model gives inconsistently, singular constraints.
Nonholonomic nonholonomic_constraints(const Model& model, Equations& eq);

}  // namespace mbsgen
