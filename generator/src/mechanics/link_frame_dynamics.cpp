#include "mbsgen/generator/mechanics/link_frame_dynamics.hpp"

#include <algorithm>
#include <cstddef>
#include <utility>

namespace mbsgen {

using GiNaC::ex;

namespace {

// One frame of the tree of steps (header): a translation or a rotation of its parent step.
struct Step {
  int parent = -1;                // parent step, -1 for the world
  bool translation = false;       // else a rotation
  Vec3 t = zero_vec3();           // translation: the origin in the parent step's axes [m]
  Mat3 R = identity_mat3();       // rotation: the step's axes in the parent step's axes
  int axis = -1;                  // elementary rotation about this axis (0, 1, 2), or -1
  std::vector<std::pair<std::size_t, Spatial>> columns;  // (coordinate k, s_k in this frame)
  Spatial vJ;                     // v_J = Σ s_k ẏ_k
  bool massive = false;           // bodies' inertia attached to this frame
  SpatialInertia I;               // their inertia about the origin, in this frame (constant)
};

Mat3 elementary_rotation(Axis axis, const ex& c, const ex& s) {
  Mat3 R = identity_mat3();
  const int k = static_cast<int>(axis), i = (k + 1) % 3, j = (k + 2) % 3;
  R[i][i] = c;
  R[i][j] = -s;
  R[j][i] = s;
  R[j][j] = c;
  return R;
}

// Motion vector (ω, v) of the parent step's frame expressed in step's frame.
Spatial motion_to_child(const Step& step, const Spatial& m) {
  if (step.translation) return {m.w, add(m.v, cross(m.w, step.t))};
  return {mul_transposed(step.R, m.w), mul_transposed(step.R, m.v)};
}

// Force vector (n, f) of step's frame expressed in the parent step's frame.
Spatial force_to_parent(const Step& step, const Spatial& f) {
  if (step.translation) return {add(f.w, cross(step.t, f.v)), f.v};
  return {mul(step.R, f.w), mul(step.R, f.v)};
}

// Symmetric J' = R J Rᵀ for an elementary R about axis k: 27 operations for a full J.
Mat3 rotate_elementary(Program& prog, const Mat3& J, const Mat3& R, int k) {
  const int i = (k + 1) % 3, j = (k + 2) % 3;
  const ex c = R[i][i], s = R[j][i];
  Mat3 Jp;
  Jp[k][k] = J[k][k];
  Jp[k][i] = Jp[i][k] = prog.define(c * J[k][i] - s * J[k][j]);
  Jp[k][j] = Jp[j][k] = prog.define(s * J[k][i] + c * J[k][j]);
  const ex Bii = prog.define(c * J[i][i] - s * J[j][i]);
  const ex Bij = prog.define(c * J[i][j] - s * J[j][j]);
  Jp[i][i] = prog.define(c * Bii - s * Bij);
  Jp[i][j] = Jp[j][i] = prog.define(s * Bii + c * Bij);
  // Not J_ii + J_jj − J'_ii (the trace is invariant): that loses J'_jj ≪ J_ii to rounding, even at
  // θ = 0, where this form is exact.
  const ex Bji = prog.define(s * J[i][i] + c * J[j][i]);
  const ex Bjj = prog.define(s * J[i][j] + c * J[j][j]);
  Jp[j][j] = prog.define(s * Bji + c * Bjj);
  return Jp;
}

// The inertia I (step's frame, about its origin) in the parent step's frame, about its origin.
SpatialInertia inertia_to_parent(Program& prog, const Step& step, const SpatialInertia& I) {
  SpatialInertia P;
  P.m = I.m;
  if (step.translation) {
    // J_P = J_O − [t][h_O] − [h_P][t] with h_P = h_O + m t (parallel axes, h not at the centre):
    // J_P,ab = J_O,ab + δ_ab t·(h_O + h_P) − h_O,a t_b − t_a h_P,b. On the diagonal the a-th term
    // of the dot product cancels the last two, so it is left out rather than added and taken
    // away again: J_P,aa = J_O,aa + Σ_{c≠a} t_c (h_O,c + h_P,c), exactly J_O,aa along t's axis.
    const Vec3& t = step.t;
    P.h = define(prog, add(I.h, scale(I.m, t)));
    Vec3 arm;  // t_c (h_O,c + h_P,c)
    for (int c = 0; c < 3; ++c) arm[c] = t[c].is_zero() ? ex(0) : prog.define(t[c] * (I.h[c] + P.h[c]));
    for (int a = 0; a < 3; ++a)
      for (int b = a; b < 3; ++b) {
        ex shift = 0;
        if (a == b) {
          for (int c = 0; c < 3; ++c)
            if (c != a) shift += arm[c];
        } else {
          shift = -I.h[a] * t[b] - t[a] * P.h[b];
        }
        P.J[a][b] = P.J[b][a] = prog.define(I.J[a][b] + shift);
      }
    return P;
  }
  P.h = define(prog, mul(step.R, I.h));
  if (step.axis >= 0) {
    P.J = rotate_elementary(prog, I.J, step.R, step.axis);
    return P;
  }
  const Mat3 RJ = define(prog, mul(step.R, I.J));
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b)
      P.J[a][b] = P.J[b][a] = prog.define(RJ[a][0] * step.R[b][0] + RJ[a][1] * step.R[b][1] +
                                          RJ[a][2] * step.R[b][2]);
  return P;
}

SpatialInertia add_inertia(const SpatialInertia& a, const SpatialInertia& b) {
  SpatialInertia c;
  c.m = a.m + b.m;
  c.h = add(a.h, b.h);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) c.J[i][j] = a.J[i][j] + b.J[i][j];
  return c;
}

SpatialInertia define_inertia(Program& prog, const SpatialInertia& I) {
  SpatialInertia D;
  D.m = prog.define(I.m);
  D.h = define(prog, I.h);
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) D.J[i][j] = D.J[j][i] = prog.define(I.J[i][j]);
  return D;
}

// A body's inertia about its frame's origin, in its frame: h = m c, J = I_C + m(|c|² E − c cᵀ).
SpatialInertia body_inertia(Program& prog, const Body& body) {
  SpatialInertia I;
  I.m = body.mass;
  const Vec3 c = define(prog, body.com);
  I.h = define(prog, scale(body.mass, c));
  const ex c2 = dot(c, c);
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b)
      I.J[a][b] = I.J[b][a] =
          prog.define(body.inertia[a][b] + body.mass * ((a == b ? c2 : ex(0)) - c[a] * c[b]));
  return I;
}

// The motion columns of a step and its joint velocity v_J.
void add_columns(Program& prog, Step& step, const Mat3& R_dependent, const ex& angle,
                 const std::vector<GiNaC::symbol>& y, const std::vector<GiNaC::symbol>& yd) {
  for (std::size_t k = 0; k < y.size(); ++k) {
    Spatial s;
    if (step.translation) {
      if (!(prog.depends_on(step.t[0], y[k]) || prog.depends_on(step.t[1], y[k]) ||
            prog.depends_on(step.t[2], y[k])))
        continue;
      s.v = define(prog, Vec3{prog.diff(step.t[0], y[k]), prog.diff(step.t[1], y[k]),
                              prog.diff(step.t[2], y[k])});
    } else if (step.axis >= 0) {
      if (!prog.depends_on(angle, y[k])) continue;
      s.w[static_cast<std::size_t>(step.axis)] = prog.diff(angle, y[k]);
    } else {
      bool depends = false;
      for (const auto& row : R_dependent)
        for (const auto& x : row) depends = depends || prog.depends_on(x, y[k]);
      if (!depends) continue;
      Mat3 dR;  // ω = vee(Rᵀ ∂R/∂y_k) in the step's own axes
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) dR[a][b] = prog.diff(step.R[a][b], y[k]);
      const Mat3 W = mul(transpose(step.R), dR);
      s.w = define(prog, Vec3{W[2][1], W[0][2], W[1][0]});
    }
    bool zero = true;
    for (int a = 0; a < 3; ++a) zero = zero && s.w[a].is_zero() && s.v[a].is_zero();
    if (zero) continue;
    step.columns.emplace_back(k, s);
    step.vJ = add(step.vJ, scale(yd[k], s));
  }
  step.vJ = define(prog, step.vJ);
}

// The steps of every body, parents before children; body_step[i] is the frame of body i (-1 when
// it is fixed to the world).
std::vector<Step> build_steps(const Model& model, Program& prog, const std::vector<GiNaC::symbol>& y,
                              const std::vector<GiNaC::symbol>& yd) {
  std::vector<Step> steps;
  std::vector<int> body_step(model.bodies().size(), -1);
  for (std::size_t i = 0; i < model.bodies().size(); ++i) {
    const Body& body = model.bodies()[i];
    const int p = model.body_index(body.parent);
    int node = p < 0 ? -1 : body_step[static_cast<std::size_t>(p)];
    const Vec3 t = define(prog, body.translation);
    if (!(t[0].is_zero() && t[1].is_zero() && t[2].is_zero())) {
      Step step;
      step.parent = node;
      step.translation = true;
      step.t = t;
      add_columns(prog, step, {}, 0, y, yd);
      steps.push_back(step);
      node = static_cast<int>(steps.size()) - 1;
    }
    auto push_rotation = [&](Step step, const ex& angle) {
      step.parent = node;
      add_columns(prog, step, step.R, angle, y, yd);
      steps.push_back(step);
      node = static_cast<int>(steps.size()) - 1;
    };
    if (body.rotation_matrix) {
      Step step;
      step.R = define(prog, *body.rotation_matrix);
      push_rotation(step, 0);
    } else {
      for (const auto& rot : body.rotations) {
        const ex angle = prog.define(rot.angle);
        if (angle.is_zero()) continue;
        Step step;
        step.axis = static_cast<int>(rot.axis);
        step.R = elementary_rotation(rot.axis, prog.define(GiNaC::cos(angle)),
                                     prog.define(GiNaC::sin(angle)));
        push_rotation(step, angle);
      }
    }
    body_step[i] = node;
    if (node < 0) continue;  // fixed to the world
    const SpatialInertia I = body_inertia(prog, body);
    bool zero = I.m.is_zero();
    for (const auto& row : I.J)
      for (const auto& x : row) zero = zero && x.is_zero();
    if (zero) continue;  // massless
    Step& frame = steps[static_cast<std::size_t>(node)];
    frame.I = frame.massive ? add_inertia(frame.I, I) : I;
    frame.massive = true;
  }
  return steps;
}

// Composite inertias I^c of every step's subtree, in the step's frame.
std::vector<SpatialInertia> composite_inertias(Program& prog, const std::vector<Step>& steps) {
  std::vector<SpatialInertia> Ic(steps.size());
  std::vector<bool> any(steps.size(), false);
  for (std::size_t n = 0; n < steps.size(); ++n)
    if (steps[n].massive) Ic[n] = steps[n].I, any[n] = true;
  for (std::size_t n = steps.size(); n-- > 0;) {
    if (!any[n]) continue;
    Ic[n] = define_inertia(prog, Ic[n]);
    const int p = steps[n].parent;
    if (p < 0) continue;
    const auto up = static_cast<std::size_t>(p);
    const SpatialInertia moved = inertia_to_parent(prog, steps[n], Ic[n]);
    Ic[up] = any[up] ? add_inertia(Ic[up], moved) : moved;
    any[up] = true;
  }
  return Ic;
}

// M by the composite-rigid-body algorithm: for each column s_b of step B, F = I^c_B s_b walked up
// the ancestors; s_aᵀ F at every column a on the way (at B itself, every column pair once).
ExMatrix crba(Program& prog, const std::vector<Step>& steps, const std::vector<SpatialInertia>& Ic,
              std::size_t f) {
  // Contributions to the upper triangle (j ≤ k), summed in a fixed order.
  ExMatrix M(f, std::vector<ex>(f, 0));
  auto contribute = [&](std::size_t j, std::size_t k, const ex& x) {
    M[std::min(j, k)][std::max(j, k)] += x;
  };
  std::vector<bool> columns_above(steps.size(), false);  // a column on the step or an ancestor
  for (std::size_t n = 0; n < steps.size(); ++n)
    columns_above[n] = !steps[n].columns.empty() ||
                       (steps[n].parent >= 0 && columns_above[static_cast<std::size_t>(steps[n].parent)]);
  for (std::size_t B = 0; B < steps.size(); ++B) {
    const auto& cols = steps[B].columns;
    for (std::size_t b = 0; b < cols.size(); ++b) {
      Spatial F = define(prog, apply(Ic[B], cols[b].second));
      for (std::size_t a = 0; a <= b; ++a)  // a step's columns have distinct coordinates
        contribute(cols[a].first, cols[b].first, dot(cols[a].second, F));
      for (std::size_t n = B;;) {
        const int p = steps[n].parent;
        if (p < 0 || !columns_above[static_cast<std::size_t>(p)]) break;
        // Not named after a translation, so that s_aᵀ F shows its terms: a coordinate in two
        // steps' angles (an absolute angle θ₂ − θ₁) then cancels exactly in the sum of M_jk.
        F = force_to_parent(steps[n], F);
        if (!steps[n].translation) F = define(prog, F);
        n = static_cast<std::size_t>(p);
        for (const auto& [j, s] : steps[n].columns) {
          const ex x = dot(s, F);
          contribute(j, cols[b].first, x);
          if (j == cols[b].first) contribute(j, j, x);  // (a, b) and (b, a) on the diagonal
        }
      }
    }
  }
  for (std::size_t j = 0; j < f; ++j)
    for (std::size_t k = j; k < f; ++k) M[k][j] = M[j][k];
  return M;
}

}  // namespace

bool prefers_link_frames(const Model& model) {
  if (!model.velocity_constraints().empty()) return false;
  for (const auto& c : model.constraints())
    if (c.kind == ConstraintKind::rolling) return false;
  int axis = -1;
  for (const auto& body : model.bodies()) {
    if (body.rotation_matrix) return true;
    for (const auto& rot : body.rotations) {
      if (axis >= 0 && axis != static_cast<int>(rot.axis)) return true;
      axis = static_cast<int>(rot.axis);
    }
  }
  return false;
}

namespace {

// k − q of the inertia (RNEA) with the base accelerating at `base` (world axes): zero, or −g for
// a uniform gravity field g, which the body wrenches I a + v ×* I v then include.
std::vector<ex> rnea(Program& prog, const std::vector<Step>& steps, const std::vector<GiNaC::symbol>& y,
                     const std::vector<GiNaC::symbol>& yd, bool quadratic, const Spatial& base) {
  const std::size_t f = y.size(), ns = steps.size();
  // Forward: velocities v and bias accelerations a (ÿ = 0).
  std::vector<Spatial> v(ns), a(ns), F(ns);
  for (std::size_t n = 0; n < ns; ++n) {
    const Step& step = steps[n];
    const int p = step.parent;
    a[n] = motion_to_child(step, p < 0 ? base : a[static_cast<std::size_t>(p)]);
    if (quadratic) {
      const Spatial vx = p < 0 ? Spatial{} : define(prog, motion_to_child(step, v[static_cast<std::size_t>(p)]));
      v[n] = define(prog, add(vx, step.vJ));
      Spatial cJ;  // ∘S ẏ: the rate of the step's own v_J at constant ẏ
      for (std::size_t k = 0; k < f; ++k)
        if (prog.depends_on(step.vJ.w[0], y[k]) || prog.depends_on(step.vJ.w[1], y[k]) ||
            prog.depends_on(step.vJ.w[2], y[k]) || prog.depends_on(step.vJ.v[0], y[k]) ||
            prog.depends_on(step.vJ.v[1], y[k]) || prog.depends_on(step.vJ.v[2], y[k])) {
          Spatial d;
          for (int c = 0; c < 3; ++c) {
            d.w[c] = prog.diff(step.vJ.w[c], y[k]);
            d.v[c] = prog.diff(step.vJ.v[c], y[k]);
          }
          cJ = add(cJ, scale(yd[k], d));
        }
      a[n] = add(add(a[n], cJ), cross_motion(vx, step.vJ));  // v × v_J = (X v_p) × v_J
    }
    a[n] = define(prog, a[n]);
  }

  // Body wrenches I a + v ×* I v, summed backward; (k − q)_j = Σ s_jᵀ F^c.
  for (std::size_t n = 0; n < ns; ++n)
    if (steps[n].massive) {
      F[n] = apply(steps[n].I, a[n]);
      if (quadratic) F[n] = add(F[n], cross_force(v[n], define(prog, apply(steps[n].I, v[n]))));
    }
  std::vector<ex> residual(f, 0);
  for (std::size_t n = ns; n-- > 0;) {
    F[n] = define(prog, F[n]);
    for (const auto& [k, s] : steps[n].columns) residual[k] += dot(s, F[n]);
    if (steps[n].parent >= 0) {
      const auto up = static_cast<std::size_t>(steps[n].parent);
      F[up] = add(F[up], force_to_parent(steps[n], F[n]));
    }
  }
  return residual;
}

}  // namespace

LinkFrameProjection project_link_frames(const Model& model, Program& prog,
                                        const std::vector<GiNaC::symbol>& y,
                                        const std::vector<GiNaC::symbol>& yd) {
  const std::vector<Step> steps = build_steps(model, prog, y, yd);
  LinkFrameProjection out;
  out.M = crba(prog, steps, composite_inertias(prog, steps), y.size());
  // Gravity is not here (header).
  out.residual = rnea(prog, steps, y, yd, model.inertial_velocity_terms(), Spatial{});
  return out;
}

std::vector<ex> link_frame_residual_with_gravity(const Model& model, Program& prog,
                                                 const std::vector<GiNaC::symbol>& y,
                                                 const std::vector<GiNaC::symbol>& yd, const Vec3& g) {
  const std::vector<Step> steps = build_steps(model, prog, y, yd);
  return rnea(prog, steps, y, yd, model.inertial_velocity_terms(), Spatial{zero_vec3(), scale(-1, g)});
}

}  // namespace mbsgen
