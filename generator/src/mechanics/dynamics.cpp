#include "mbsgen/generator/mechanics/dynamics.hpp"

#include "mbsgen/generator/mechanics/link_frame_dynamics.hpp"
#include "mbsgen/generator/mechanics/reactions.hpp"

#include <algorithm>
#include <utility>

namespace mbsgen {

using GiNaC::ex;

namespace {

Spatial wrench_at_origin(const Vec3& point, const Vec3& force, const Vec3& torque) {
  return {add(cross(point, force), torque), force};
}

}  // namespace

namespace {

bool has_reactions(const Model& model) {
  for (const auto& o : model.outputs())
    if (o.kind == OutputKind::reaction) return true;
  return false;
}

// Adds each body's gravity wrench, negated, −(c × m g, m g) about the world origin.
void add_gravity_wrenches(const Model& model, const Kinematics& kin, std::vector<Spatial>& wrench) {
  for (std::size_t i = 0; i < kin.bodies.size(); ++i) {
    const BodyKinematics& b = kin.bodies[i];
    for (const auto& g : model.gravity()) {
      Vec3 force = scale(b.inertia.m, g.g);
      wrench[i] = add(wrench[i], scale(-1, Spatial{cross(b.inertia.h, g.g), force}));
    }
  }
}

// Per-body wrench of inertia and gravity, I ā + V ×* I V − (c × m g, m g), about the world origin.
std::vector<Spatial> inertial_wrenches(const Model& model, Equations& eq) {
  Program& prog = eq.program;
  Kinematics& kin = eq.kinematics;
  const std::size_t nb = kin.bodies.size();
  std::vector<Spatial> wrench(nb);
  for (std::size_t i = 0; i < nb; ++i) {
    const BodyKinematics& b = kin.bodies[i];
    if (model.inertial_velocity_terms()) {  // I ā + V ×* I V: quadratic in ẏ
      Spatial IV = define(prog, apply(b.inertia, b.V));
      wrench[i] = add(apply(b.inertia, b.bias), cross_force(b.V, IV));
    }
  }
  add_gravity_wrenches(model, kin, wrench);
  return wrench;
}

// Per-body wrench of the applied forces, negated (the residual's sign), about the world origin.
std::vector<Spatial> applied_wrenches(const Model& model, Equations& eq) {
  Program& prog = eq.program;
  Kinematics& kin = eq.kinematics;
  std::vector<Spatial> wrench(kin.bodies.size());
  for (const auto& a : model.applied_forces()) {
    int b = model.body_index(model.marker(a.marker).body);
    if (b < 0) continue;  // a force on the ground does no work
    Vec3 F = a.force, L = a.torque;
    if (a.frame == ForceFrame::marker) {
      Mat3 S = kin.marker_frame(model, prog, a.marker);
      F = mul(S, F);
      L = mul(S, L);
    }
    Vec3 P = kin.marker_position(model, prog, a.marker);
    auto& w = wrench[static_cast<std::size_t>(b)];
    w = add(w, scale(-1, wrench_at_origin(P, F, L)));
  }
  return wrench;
}

// Per-body wrench: inertial minus applied, about the world origin.
std::vector<Spatial> body_wrenches(const Model& model, Equations& eq) {
  std::vector<Spatial> wrench = inertial_wrenches(model, eq);
  const std::vector<Spatial> applied = applied_wrenches(model, eq);
  for (std::size_t i = 0; i < wrench.size(); ++i) wrench[i] = define(eq.program, add(wrench[i], applied[i]));
  return wrench;
}

bool is_zero(const Spatial& s) {
  for (int a = 0; a < 3; ++a)
    if (!s.w[a].is_zero() || !s.v[a].is_zero()) return false;
  return true;
}

// (k − q)_j += φ_jᵀ F^c for per-body wrenches (world frame), F^c their subtree sums; into
// eq.residual, or into `residual` when given.
void project_wrenches(Equations& eq, std::vector<Spatial> Fc, std::vector<ex>* residual = nullptr) {
  Program& prog = eq.program;
  Kinematics& kin = eq.kinematics;
  std::vector<ex>& r = residual ? *residual : eq.residual;
  for (std::size_t i = Fc.size(); i-- > 0;) {
    if (is_zero(Fc[i])) continue;
    Fc[i] = define(prog, Fc[i]);
    for (const auto& col : kin.bodies[i].columns)
      r[static_cast<std::size_t>(col.coordinate)] += dot(col.phi, Fc[i]);
    const int p = kin.bodies[i].parent;
    if (p >= 0) Fc[static_cast<std::size_t>(p)] = add(Fc[static_cast<std::size_t>(p)], Fc[i]);
  }
}

// J̄_i column by column (coordinate j: the sum of the φ with coordinate j on i's root path),
// then M += J̄_iᵀ (Ī_i J̄_i) and k − q += J̄_iᵀ f̄_i for every body, no subtree sums.
void project_naive(Equations& eq, const std::vector<Spatial>& wrench) {
  Program& prog = eq.program;
  Kinematics& kin = eq.kinematics;
  const std::size_t f = eq.y.size();
  const std::size_t nb = kin.bodies.size();
  eq.residual.assign(f, 0);
  eq.M.assign(f, std::vector<ex>(f, 0));
  for (std::size_t i = 0; i < nb; ++i) {
    std::vector<std::pair<std::size_t, Spatial>> J;  // (coordinate, column), root path order
    for (int k = static_cast<int>(i); k >= 0; k = kin.bodies[static_cast<std::size_t>(k)].parent)
      for (const auto& col : kin.bodies[static_cast<std::size_t>(k)].columns) {
        auto j = static_cast<std::size_t>(col.coordinate);
        auto it = std::find_if(J.begin(), J.end(), [j](const auto& c) { return c.first == j; });
        if (it == J.end())
          J.emplace_back(j, col.phi);
        else
          it->second = add(it->second, col.phi);
      }
    std::vector<Spatial> IJ;
    for (auto& c : J) {
      c.second = define(prog, c.second);
      IJ.push_back(define(prog, apply(kin.bodies[i].inertia, c.second)));
    }
    for (std::size_t a = 0; a < J.size(); ++a) {
      eq.residual[J[a].first] += dot(J[a].second, wrench[i]);
      for (std::size_t b = 0; b < J.size(); ++b)
        if (J[a].first <= J[b].first) eq.M[J[a].first][J[b].first] += dot(J[a].second, IJ[b]);
    }
  }
  for (std::size_t j = 0; j < f; ++j)
    for (std::size_t k = j + 1; k < f; ++k) eq.M[k][j] = eq.M[j][k];
}

// Backward pass: composite wrenches and composite inertias; M from composite inertias.
void project_composite(Equations& eq, const std::vector<Spatial>& wrench) {
  Program& prog = eq.program;
  Kinematics& kin = eq.kinematics;
  const std::size_t f = eq.y.size();
  const std::size_t nb = kin.bodies.size();
  // Backward pass: composite wrenches and composite inertias.
  std::vector<Spatial> Fc = wrench;
  std::vector<SpatialInertia> Ic(nb);
  for (std::size_t i = 0; i < nb; ++i) Ic[i] = kin.bodies[i].inertia;
  for (std::size_t i = nb; i-- > 0;) {
    Fc[i] = define(prog, Fc[i]);
    Ic[i].m = prog.define(Ic[i].m);
    Ic[i].h = define(prog, Ic[i].h);
    Ic[i].J = define(prog, Ic[i].J);
    int p = kin.bodies[i].parent;
    if (p < 0) continue;
    auto up = static_cast<std::size_t>(p);
    Fc[up] = add(Fc[up], Fc[i]);
    Ic[up].m = Ic[up].m + Ic[i].m;
    Ic[up].h = add(Ic[up].h, Ic[i].h);
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) Ic[up].J[a][c] = Ic[up].J[a][c] + Ic[i].J[a][c];
  }

  // Residual k − q from the joints, M from composite inertias.
  eq.residual.assign(f, 0);
  struct Column { std::size_t body; const Spatial* phi; Spatial force; };
  std::vector<std::vector<Column>> by_coordinate(f);
  for (std::size_t i = 0; i < nb; ++i)
    for (const auto& col : kin.bodies[i].columns) {
      auto j = static_cast<std::size_t>(col.coordinate);
      eq.residual[j] += dot(col.phi, Fc[i]);
      by_coordinate[j].push_back({i, &col.phi, define(prog, apply(Ic[i], col.phi))});
    }
  eq.M.assign(f, std::vector<ex>(f, 0));
  for (std::size_t j = 0; j < f; ++j)
    for (std::size_t k = j; k < f; ++k) {
      ex m = 0;
      for (const auto& a : by_coordinate[j])
        for (const auto& b : by_coordinate[k]) {
          int ia = static_cast<int>(a.body), ib = static_cast<int>(b.body);
          if (kin.is_ancestor_or_self(ia, ib))
            m += dot(*a.phi, b.force);
          else if (kin.is_ancestor_or_self(ib, ia))
            m += dot(*b.phi, a.force);
        }
      eq.M[j][k] = eq.M[k][j] = m;
    }
}

// Conservative and dissipative elements (q = −∂V/∂y − ∂R/∂ẏ) and generalized forces: their
// terms of k − q, length f.
std::vector<ex> force_element_terms(const Model& model, Equations& eq) {
  Program& prog = eq.program;
  Kinematics& kin = eq.kinematics;
  const std::size_t f = eq.y.size();
  std::vector<ex> terms(f, 0);
  ex V = 0, R = 0;
  for (const auto& s : model.springs()) {
    Vec3 d = define(prog, sub(kin.marker_position(model, prog, s.marker_b),
                              kin.marker_position(model, prog, s.marker_a)));
    ex L2 = prog.define(dot(d, d));
    if (s.rest_length.is_zero())
      V += s.stiffness * L2 / 2;
    else
      V += s.stiffness * GiNaC::pow(GiNaC::sqrt(L2) - s.rest_length, 2) / 2;
  }
  for (const auto& dmp : model.dampers()) {
    Vec3 d = define(prog, sub(kin.marker_position(model, prog, dmp.marker_b),
                              kin.marker_position(model, prog, dmp.marker_a)));
    Vec3 dd = define(prog, sub(kin.marker_velocity(model, prog, dmp.marker_b),
                               kin.marker_velocity(model, prog, dmp.marker_a)));
    // L̇ = dᵀḋ / L, so R = ½ c (dᵀḋ)² / (dᵀd).
    ex Ldot_L = prog.define(dot(d, dd));
    R += dmp.damping * Ldot_L * Ldot_L / (2 * prog.define(dot(d, d)));
  }
  for (const auto& b : model.bushings()) {
    Mat3 Sa = kin.marker_frame(model, prog, b.marker_a);
    Mat3 Sb = kin.marker_frame(model, prog, b.marker_b);
    Vec3 ra = kin.marker_position(model, prog, b.marker_a);
    Vec3 rb = kin.marker_position(model, prog, b.marker_b);
    Vec3 d = define(prog, sub(rb, ra));
    Vec3 dr = define(prog, mul_transposed(Sa, d));
    Mat3 Srel = define(prog, mul(transpose(Sa), Sb));
    Vec3 theta = {(Srel[2][1] - Srel[1][2]) / 2, (Srel[0][2] - Srel[2][0]) / 2,
                  (Srel[1][0] - Srel[0][1]) / 2};
    theta = define(prog, theta);
    Vec3 wa = kin.marker_angular_velocity(model, b.marker_a);
    Vec3 wb = kin.marker_angular_velocity(model, b.marker_b);
    Vec3 va = kin.marker_velocity(model, prog, b.marker_a);
    Vec3 vb = kin.marker_velocity(model, prog, b.marker_b);
    // Rates in frame a: Δṙ = S_aᵀ(v_b − v_a − ω_a × d), ω_rel = S_aᵀ(ω_b − ω_a).
    Vec3 drdot = define(prog, mul_transposed(Sa, sub(sub(vb, va), cross(wa, d))));
    Vec3 wrel = define(prog, mul_transposed(Sa, sub(wb, wa)));
    for (int a = 0; a < 3; ++a) {
      V += b.k_translation[a] * dr[a] * dr[a] / 2 + b.k_rotation[a] * theta[a] * theta[a] / 2;
      R += b.d_translation[a] * drdot[a] * drdot[a] / 2 + b.d_rotation[a] * wrel[a] * wrel[a] / 2;
    }
  }
  if (!V.is_zero() || !R.is_zero()) {
    ex Vd = prog.define(V), Rd = prog.define(R);
    for (std::size_t j = 0; j < f; ++j)
      terms[j] += prog.diff(Vd, eq.y[j]) + prog.diff(Rd, eq.yd[j]);
  }
  for (const auto& g : model.generalized_forces())
    terms[static_cast<std::size_t>(model.coordinate_index(g.coordinate))] -= g.value;
  return terms;
}

// Conservative and dissipative elements (q = −∂V/∂y − ∂R/∂ẏ) and generalized forces, added to
// eq.residual and, when there is one, to eq.residual_kernel.
void add_force_elements(const Model& model, Equations& eq) {
  const std::vector<ex> terms = force_element_terms(model, eq);
  for (std::size_t j = 0; j < terms.size(); ++j) {
    eq.residual[j] += terms[j];
    if (!eq.residual_kernel.empty()) eq.residual_kernel[j] += terms[j];
  }
}

// A position or velocity output, absolute or relative to a marker R: directionᵀ S_Rᵀ (r − r_R)
// and its rate directionᵀ S_Rᵀ (v − v_R − ω_R × (r − r_R)).
ex motion_output(const Model& model, Equations& eq, const Output& o) {
  Program& prog = eq.program;
  Kinematics& kin = eq.kinematics;
  const bool position = o.kind == OutputKind::position;
  if (o.relative_to.empty())
    return dot(o.direction, position ? kin.marker_position(model, prog, o.marker)
                                     : kin.marker_velocity(model, prog, o.marker));
  const Mat3 SR = kin.marker_frame(model, prog, o.relative_to);
  const Vec3 d = define(prog, sub(kin.marker_position(model, prog, o.marker),
                                  kin.marker_position(model, prog, o.relative_to)));
  if (position) return dot(o.direction, mul_transposed(SR, d));
  const Vec3 v = sub(sub(kin.marker_velocity(model, prog, o.marker), kin.marker_velocity(model, prog, o.relative_to)),
                     cross(kin.marker_angular_velocity(model, o.relative_to), d));
  return dot(o.direction, mul_transposed(SR, define(prog, v)));
}

void derive_outputs(const Model& model, Equations& eq) {
  for (const auto& o : model.outputs()) {
    switch (o.kind) {
      case OutputKind::position:
      case OutputKind::velocity:
        eq.outputs.push_back(motion_output(model, eq, o));
        break;
      case OutputKind::coordinate:
        eq.outputs.push_back(eq.y[static_cast<std::size_t>(model.coordinate_index(o.coordinate))]);
        break;
      case OutputKind::rate:
        eq.outputs.push_back(eq.yd[static_cast<std::size_t>(model.coordinate_index(o.coordinate))]);
        break;
      case OutputKind::expression:
        eq.outputs.push_back(o.expression);
        break;
      case OutputKind::force:
        eq.outputs.push_back(force_output(model, eq, o));
        break;
      case OutputKind::reaction:  // reaction_outputs (reactions.hpp) writes it
        eq.outputs.push_back(0);
        break;
    }
  }

}

// The tree's equations of `model` (which may carry joint probes, reactions.hpp), with the
// accelerations ÿ of `original`'s coordinates as variables when its outputs need them.
Equations derive_tree(const Model& model, const Model& original, const DeriveOptions& options) {
  Equations eq;
  eq.model = &model;
  for (const auto& c : model.coordinates()) eq.y.push_back(c.position);
  for (const auto& c : model.coordinates()) eq.yd.push_back(c.velocity);
  eq.u = model.input_symbols();
  for (const auto& p : model.parameters()) eq.p.push_back(p.symbol);
  if (has_reactions(original))
    for (const auto& c : original.coordinates()) eq.ydd.push_back(GiNaC::symbol(c.name + "_ddot"));
  if (!eq.ydd.empty())
    eq.accelerations = eq.ydd;  // the original's coordinates: reaction_outputs drops the probes' (reactions.hpp)
  else
    for (const auto& c : model.coordinates()) eq.accelerations.push_back(GiNaC::symbol(c.name + "_ddot"));
  Program& prog = eq.program;
  for (const auto* group : {&eq.y, &eq.yd, &eq.u, &eq.p, &eq.ydd})
    for (const auto& s : *group) prog.add_variable(s);
  if (eq.ydd.empty())
    for (const auto& s : eq.accelerations) prog.add_variable(s);

  eq.kinematics = compute_kinematics(model, prog);
  Kinematics& kin = eq.kinematics;
  const std::size_t f = eq.y.size();
  const std::size_t nb = kin.bodies.size();

  switch (options.projection) {
    case Projection::composite:
    case Projection::link_frames: {
      // Decided on the model as written: the probes of reaction outputs (reactions.hpp) add
      // rotations about three axes, which would make every planar model with reactions spatial.
      if (options.projection == Projection::composite && !prefers_link_frames(original)) {
        project_composite(eq, body_wrenches(model, eq));
        break;
      }
      LinkFrameProjection link = project_link_frames(model, prog, eq.y, eq.yd);
      eq.M = std::move(link.M);
      eq.residual = std::move(link.residual);
      // Gravity and applied forces projected in the world frame (link_frame_dynamics.hpp).
      std::vector<Spatial> world = applied_wrenches(model, eq);
      const std::vector<Spatial> applied = world;
      add_gravity_wrenches(model, kin, world);
      project_wrenches(eq, world);
      // The kernels' form: gravity as the base's acceleration (Equations::residual_kernel).
      // (Not for reactions' joint probes, nor where loops or velocity constraints rebuild the
      // kernels from `residual`: derive() would clear it.)
      if (!model.gravity().empty() && !has_reactions(original) && model.constraints().empty() &&
          model.velocity_constraints().empty()) {
        Vec3 g = zero_vec3();
        for (const auto& field : model.gravity()) g = add(g, field.g);
        eq.residual_kernel = link_frame_residual_with_gravity(model, prog, eq.y, eq.yd, g);
        project_wrenches(eq, applied, &eq.residual_kernel);
      }
      break;
    }
    case Projection::world_composite:
      project_composite(eq, body_wrenches(model, eq));
      break;
    case Projection::naive:
      project_naive(eq, body_wrenches(model, eq));
      break;
  }
  add_force_elements(model, eq);
  derive_outputs(model, eq);

  // Body Jacobians (for the invariant M = J̄ᵀ M̄ J̄): J̄_i is the sum of φ along the root path,
  // and the centre-of-mass velocity is v_O + ω × c.
  eq.JT.assign(3 * nb, std::vector<ex>(f, 0));
  eq.JR.assign(3 * nb, std::vector<ex>(f, 0));
  for (std::size_t i = 0; i < nb; ++i)
    for (int k = static_cast<int>(i); k >= 0; k = kin.bodies[static_cast<std::size_t>(k)].parent)
      for (const auto& col : kin.bodies[static_cast<std::size_t>(k)].columns) {
        Vec3 vc = add(col.phi.v, cross(col.phi.w, kin.bodies[i].com));
        for (int a = 0; a < 3; ++a) {
          auto j = static_cast<std::size_t>(col.coordinate);
          eq.JT[3 * i + static_cast<std::size_t>(a)][j] += vc[a];
          eq.JR[3 * i + static_cast<std::size_t>(a)][j] += col.phi.w[a];
        }
      }
  return eq;
}

}  // namespace

void restrict_equations(Equations& eq, std::size_t n, const std::function<ex(const ex&)>& f) {
  eq.y.resize(n);
  eq.yd.resize(n);
  if (eq.accelerations.size() > n) eq.accelerations.resize(n);
  eq.M.resize(n);
  for (auto& row : eq.M) {
    row.resize(n);
    for (auto& x : row) x = f(x);
  }
  for (std::vector<ex>* v : {&eq.residual, &eq.residual_kernel}) {
    if (v->size() > n) v->resize(n);
    for (auto& x : *v) x = f(x);
  }
  for (auto& x : eq.outputs) x = f(x);
  for (ExMatrix* J : {&eq.JT, &eq.JR})
    for (auto& row : *J) {
      row.resize(n);
      for (auto& x : row) x = f(x);
    }
  restrict_kinematics(eq.kinematics, n, f);
}

Equations derive(const Model& model, const DeriveOptions& options) {
  model.validate();
  // Joint loads: the tree with probes in the asked joints, then the probes removed (reactions.hpp).
  JointProbes probes;
  probes.bodies = probed_bodies(model);
  const Model probed = probes.bodies.empty() ? Model(model.name()) : with_joint_probes(model, probes.bodies);
  // Motion inputs: the tree with them as coordinates, then split (prescribed_motion.hpp; models
  // with motion inputs have no reaction outputs, Model::validate).
  const bool motion = model.has_motion_inputs();
  const Model moving = motion ? with_motion_coordinates(model) : Model(model.name());
  Equations eq = derive_tree(motion ? moving : probes.bodies.empty() ? model : probed, model, options);
  if (!probes.bodies.empty()) strip_joint_probes(model, eq, probes);
  if (motion) split_prescribed_motion(model, model.bodies().size(), eq);
  eq.model = &model;
  // Closed loops: the constraint stage, the reactions, and the equations in the independent
  // coordinates.
  eq.loops = close_loops(model, eq);
  if (has_reactions(model)) reaction_outputs(eq, probes);
  reduce_equations(eq);
  eq.nonholonomic = nonholonomic_constraints(model, eq);
  // The kernels' form of k − q is the tree's: the loops' and the descriptor form's kernels are
  // built from `residual` as those stages leave it.
  if (eq.loops.active || eq.nonholonomic.active) eq.residual_kernel.clear();
  return eq;
}

}  // namespace mbsgen
