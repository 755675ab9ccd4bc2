#include "mbsgen/generator/mechanics/reactions.hpp"

#include "mbsgen/generator/mechanics/dynamics.hpp"

#include <algorithm>
#include <set>

namespace mbsgen {

using GiNaC::ex;

namespace {

Mat3 rotation(Axis axis, const ex& angle) {
  Mat3 R = identity_mat3();
  const int i = axis == Axis::x ? 1 : axis == Axis::y ? 2 : 0, j = axis == Axis::x ? 2 : axis == Axis::y ? 0 : 1;
  R[i][i] = R[j][j] = GiNaC::cos(angle);
  R[i][j] = -GiNaC::sin(angle);
  R[j][i] = GiNaC::sin(angle);
  return R;
}

Vec3 column(const Mat3& A, int c) { return {A[0][c], A[1][c], A[2][c]}; }

// A name for a new symbol of `model`, derived from `base`.
std::string fresh(const Model& model, std::string base) {
  while (model.symbol_table().count(base)) base += "_";
  return base;
}

bool is_constraint(const Model& model, const std::string& name) {
  for (const auto& c : model.constraints())
    if (c.name == name) return true;
  return false;
}

}  // namespace

std::vector<std::string> probed_bodies(const Model& model) {
  std::vector<std::string> bodies;
  for (const auto& o : model.outputs())
    if (o.kind == OutputKind::reaction && !is_constraint(model, o.reaction_of) &&
        std::find(bodies.begin(), bodies.end(), o.reaction_of) == bodies.end())
      bodies.push_back(o.reaction_of);
  return bodies;
}

Model with_joint_probes(const Model& model, const std::vector<std::string>& bodies) {
  Model probed = model;
  static const char* const kNames[6] = {"sx", "sy", "sz", "rx", "ry", "rz"};
  for (const auto& name : bodies) {
    ex q[6];
    for (int k = 0; k < 6; ++k)
      q[k] = probed.add_coordinate(fresh(probed, "probe_" + name + "_" + kNames[k]), "").position;
    Body& b = probed.bodies_[static_cast<std::size_t>(probed.body_index(name))];
    for (int a = 0; a < 3; ++a) b.translation[static_cast<std::size_t>(a)] += q[a];
    const Mat3 Rs = [&] {
      Mat3 R = rotation(Axis::x, q[3]);
      R = mul(R, rotation(Axis::y, q[4]));
      return mul(R, rotation(Axis::z, q[5]));
    }();
    if (b.rotation_matrix) {
      b.rotation_matrix = mul(Rs, *b.rotation_matrix);
    } else {
      b.rotations.insert(b.rotations.begin(), {{Axis::x, q[3]}, {Axis::y, q[4]}, {Axis::z, q[5]}});
    }
  }
  return probed;
}

void strip_joint_probes(const Model& model, Equations& eq, JointProbes& probes) {
  Program& prog = eq.program;
  const std::size_t n = model.coordinates().size(), all = eq.y.size();
  GiNaC::exmap zero;
  std::vector<GiNaC::symbol> probe_y;
  for (std::size_t c = n; c < all; ++c) {
    zero[eq.y[c]] = 0;
    zero[eq.yd[c]] = 0;
    probe_y.push_back(eq.y[c]);
  }
  Program::Substitution sub(zero);
  auto at0 = [&](const ex& e) { return prog.substitute(e, sub); };
  // The probes' rows (M ÿ + k − q)_probe with the tree's accelerations.
  for (std::size_t c = n; c < all; ++c) {
    ex row = eq.residual[c];
    for (std::size_t j = 0; j < n; ++j)
      if (!eq.M[c][j].is_zero()) row += eq.M[c][j] * eq.ydd[j];
    probes.rows.push_back(prog.define(at0(prog.define(row))));
  }
  probes.probed = eq.kinematics;
  probes.symbols = probe_y;
  for (std::size_t k = 0; k < probes.bodies.size(); ++k) probes.first.push_back(n + 6 * k);

  restrict_equations(eq, n, at0);
}

namespace {

// The load a loop constraint's multipliers put on the body of its marker b (world frame):
// force and torque (model.hpp, Constraint: the gradient of each equation with respect to b's
// motion). An expression constraint has no body: its "force" is (λ, 0, 0).
struct Load {
  Vec3 force = zero_vec3(), torque = zero_vec3();
};

Load constraint_load(const Model& model, Equations& eq, const Constraint& c, const std::vector<ex>& lambda) {
  Program& prog = eq.program;
  const LoopClosure& loops = eq.loops;
  auto multiplier = [&](const char* component) -> ex {
    for (std::size_t k = 0; k < loops.equations.size(); ++k)
      if (loops.equations[k].constraint == c.name && loops.equations[k].component == component) return lambda[k];
    return 0;  // an equation dropped as identically zero carries nothing
  };
  Load load;
  if (c.kind == ConstraintKind::expression) {
    load.force = {multiplier(""), 0, 0};
    return load;
  }
  const Kinematics& kin = eq.kinematics;
  const Mat3 Sa = kin.marker_frame(model, prog, c.marker_a), Sb = kin.marker_frame(model, prog, c.marker_b);
  const Vec3 xa = column(Sa, 0), ya = column(Sa, 1), za = column(Sa, 2);
  const Vec3 xb = column(Sb, 0), yb = column(Sb, 1), zb = column(Sb, 2);
  // Φ = u_a·v_b puts the torque λ (v_b × u_a) on b.
  auto couple = [&](const Vec3& ua, const Vec3& vb, const char* component) {
    load.torque = add(load.torque, scale(multiplier(component), cross(vb, ua)));
  };
  switch (c.kind) {
    case ConstraintKind::spherical:
    case ConstraintKind::revolute:
      load.force = {multiplier("x"), multiplier("y"), multiplier("z")};
      if (c.kind == ConstraintKind::revolute) couple(scale(-1, ya), zb, "rx"), couple(xa, zb, "ry");
      break;
    case ConstraintKind::prismatic:
      load.force = add(scale(multiplier("x"), xa), scale(multiplier("y"), ya));
      couple(za, yb, "rx"), couple(xa, zb, "ry"), couple(ya, xb, "rz");
      break;
    case ConstraintKind::planar:
      load.force = scale(multiplier("z"), za);
      couple(scale(-1, ya), zb, "rx"), couple(xa, zb, "ry");
      break;
    case ConstraintKind::distance: {
      const Vec3 d = sub(kin.marker_position(model, prog, c.marker_b), kin.marker_position(model, prog, c.marker_a));
      load.force = scale(multiplier("length") / c.length, d);
      break;
    }
    case ConstraintKind::expression:
    case ConstraintKind::rolling:  // refused by Model::validate_velocity_constraints
      break;
  }
  return load;
}

// The multipliers at any state: Φ_ydᵀ λ = (M ÿ + h)_d with the tree's ÿ (eq.ydd).
std::vector<ex> multipliers(Equations& eq) {
  const LoopClosure& loops = eq.loops;
  std::vector<ex> rhs;
  for (std::size_t d : loops.dependent) {
    ex s = eq.residual[d];
    for (std::size_t j = 0; j < eq.y.size(); ++j)
      if (!eq.M[d][j].is_zero()) s += eq.M[d][j] * eq.ydd[j];
    rhs.push_back(eq.program.define(s));
  }
  return loops.solve_transposed(eq.program, rhs);
}

// The load the parent exerts on a probed body through its joint (world frame; torque about the
// body frame's origin): the probes' rows less the loop constraints' share, turned from the parent
// frame into the world frame.
Load joint_load(const Model& model, Equations& eq, const JointProbes& probes, std::size_t k,
                const std::vector<ex>& lambda) {
  Program& prog = eq.program;
  std::vector<ex> g(probes.rows.begin() + static_cast<long>(6 * k), probes.rows.begin() + static_cast<long>(6 * k + 6));
  if (eq.loops.active) {
    // Φ_probe from the constraint equations written with the probes' kinematics.
    const std::vector<ConstraintEquation> probed = constraint_equations(model, prog, probes.probed);
    GiNaC::exmap zero;
    for (const auto& s : probes.symbols) zero[s] = 0;
    Program::Substitution sub(zero);
    for (std::size_t e = 0; e < eq.loops.equations.size(); ++e) {
      const ConstraintEquation& kept = eq.loops.equations[e];
      for (const auto& candidate : probed) {
        if (candidate.constraint != kept.constraint || candidate.component != kept.component) continue;
        for (int a = 0; a < 6; ++a) {
          const ex dphi = prog.substitute(prog.diff(candidate.phi, probes.symbols[6 * k + static_cast<std::size_t>(a)]), sub);
          if (!dphi.is_zero()) g[static_cast<std::size_t>(a)] -= dphi * lambda[e];
        }
      }
    }
  }
  const int parent = eq.kinematics.bodies[static_cast<std::size_t>(model.body_index(probes.bodies[k]))].parent;
  const Mat3 Sp = parent < 0 ? identity_mat3() : eq.kinematics.bodies[static_cast<std::size_t>(parent)].S;
  Load load;
  load.force = mul(Sp, Vec3{g[0], g[1], g[2]});
  load.torque = mul(Sp, Vec3{g[3], g[4], g[5]});
  return load;
}

}  // namespace

namespace {

// The load of one force element on the body of its marker b (world frame; torque about b's point).
Load element_load(const Model& model, Equations& eq, const std::string& name) {
  Program& prog = eq.program;
  const Kinematics& kin = eq.kinematics;
  auto between = [&](const std::string& a, const std::string& b) {
    return define(prog, sub(kin.marker_position(model, prog, b), kin.marker_position(model, prog, a)));
  };
  Load load;
  for (const auto& s : model.springs())
    if (s.name == name) {
      const Vec3 d = between(s.marker_a, s.marker_b);
      const ex L = prog.define(GiNaC::sqrt(dot(d, d)));
      load.force = s.rest_length.is_zero() ? scale(-s.stiffness, d)
                                           : scale(prog.define(-s.stiffness * (L - s.rest_length) / L), d);
    }
  for (const auto& c : model.dampers())
    if (c.name == name) {
      const Vec3 d = between(c.marker_a, c.marker_b);
      const Vec3 dd = define(prog, sub(kin.marker_velocity(model, prog, c.marker_b), kin.marker_velocity(model, prog, c.marker_a)));
      load.force = scale(prog.define(-c.damping * dot(d, dd) / dot(d, d)), d);
    }
  for (const auto& b : model.bushings())
    if (b.name == name) {
      const Mat3 Sa = kin.marker_frame(model, prog, b.marker_a), Sb = kin.marker_frame(model, prog, b.marker_b);
      const Vec3 d = between(b.marker_a, b.marker_b);
      const Vec3 dr = define(prog, mul_transposed(Sa, d));
      const Mat3 R = define(prog, mul(transpose(Sa), Sb));
      const Vec3 theta = define(prog, Vec3{(R[2][1] - R[1][2]) / 2, (R[0][2] - R[2][0]) / 2, (R[1][0] - R[0][1]) / 2});
      const Vec3 wa = kin.marker_angular_velocity(model, b.marker_a), wb = kin.marker_angular_velocity(model, b.marker_b);
      const Vec3 drdot = define(prog, mul_transposed(Sa, sub(sub(kin.marker_velocity(model, prog, b.marker_b),
                                                                 kin.marker_velocity(model, prog, b.marker_a)),
                                                             cross(wa, d))));
      const Vec3 wrel = define(prog, mul_transposed(Sa, sub(wb, wa)));
      Vec3 f = zero_vec3(), kr = zero_vec3(), dr_w = zero_vec3();
      for (std::size_t i = 0; i < 3; ++i) {
        f[i] = b.k_translation[i] * dr[i] + b.d_translation[i] * drdot[i];
        kr[i] = b.k_rotation[i] * theta[i];
        dr_w[i] = b.d_rotation[i] * wrel[i];
      }
      // ∂θ/∂φ_b = ½ (tr R·E − R) S_aᵀ: the torque is its transpose on K_r θ.
      const ex trace = R[0][0] + R[1][1] + R[2][2];
      Vec3 t = zero_vec3();
      for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t j = 0; j < 3; ++j) t[i] += ((i == j ? trace : ex(0)) - R[j][i]) * kr[j] / 2;
      load.force = scale(-1, mul(Sa, f));
      load.torque = scale(-1, mul(Sa, add(t, dr_w)));
    }
  return load;
}

std::string marker_b_of(const Model& model, const std::string& element) {
  for (const auto& s : model.springs())
    if (s.name == element) return s.marker_b;
  for (const auto& d : model.dampers())
    if (d.name == element) return d.marker_b;
  for (const auto& b : model.bushings())
    if (b.name == element) return b.marker_b;
  return "";
}

}  // namespace

ex force_output(const Model& model, Equations& eq, const Output& o) {
  Vec3 v = zero_vec3();
  for (const auto& name : o.elements) {
    const Load load = element_load(model, eq, name);
    v = add(v, o.quantity == ForceQuantity::force ? load.force : load.torque);
  }
  if (o.force_frame == ForceFrame::marker && !o.elements.empty())
    v = mul_transposed(eq.kinematics.marker_frame(model, eq.program, marker_b_of(model, o.elements.front())), v);
  return eq.program.define(dot(o.direction, v));
}

void reaction_outputs(Equations& eq, JointProbes& probes) {
  const Model& model = *eq.model;
  Program& prog = eq.program;
  std::vector<ex> lambda;
  if (eq.loops.active) lambda = multipliers(eq);
  for (std::size_t i = 0; i < model.outputs().size(); ++i) {
    const Output& o = model.outputs()[i];
    if (o.kind != OutputKind::reaction) continue;
    Load load;
    const auto probe = std::find(probes.bodies.begin(), probes.bodies.end(), o.reaction_of);
    if (probe != probes.bodies.end()) {
      load = joint_load(model, eq, probes, static_cast<std::size_t>(probe - probes.bodies.begin()), lambda);
    } else {
      for (const auto& c : model.constraints())
        if (c.name == o.reaction_of) load = constraint_load(model, eq, c, lambda);
    }
    Vec3 v = o.quantity == ForceQuantity::force ? load.force : load.torque;
    if (!o.frame_marker.empty()) v = mul_transposed(eq.kinematics.marker_frame(model, prog, o.frame_marker), v);
    eq.outputs[i] = prog.define(dot(o.direction, v));
  }
}

}  // namespace mbsgen
