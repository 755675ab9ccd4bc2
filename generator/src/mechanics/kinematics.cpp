#include "mbsgen/generator/mechanics/kinematics.hpp"

#include <set>

namespace mbsgen {

using GiNaC::ex;

Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
ex dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 scale(const ex& s, const Vec3& a) { return {s * a[0], s * a[1], s * a[2]}; }
Vec3 mul(const Mat3& A, const Vec3& x) {
  Vec3 y;
  for (int i = 0; i < 3; ++i) y[i] = A[i][0] * x[0] + A[i][1] * x[1] + A[i][2] * x[2];
  return y;
}
Vec3 mul_transposed(const Mat3& A, const Vec3& x) {
  Vec3 y;
  for (int i = 0; i < 3; ++i) y[i] = A[0][i] * x[0] + A[1][i] * x[1] + A[2][i] * x[2];
  return y;
}
Mat3 mul(const Mat3& A, const Mat3& B) {
  Mat3 C;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) C[i][j] = A[i][0] * B[0][j] + A[i][1] * B[1][j] + A[i][2] * B[2][j];
  return C;
}
Mat3 transpose(const Mat3& A) {
  Mat3 T;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) T[i][j] = A[j][i];
  return T;
}
Vec3 define(Program& program, const Vec3& a) {
  return {program.define(a[0]), program.define(a[1]), program.define(a[2])};
}
Mat3 define(Program& program, const Mat3& A) {
  Mat3 D;
  for (int i = 0; i < 3; ++i) D[i] = define(program, A[i]);
  return D;
}
Spatial define(Program& program, const Spatial& s) {
  return {define(program, s.w), define(program, s.v)};
}
Spatial cross_motion(const Spatial& V, const Spatial& m) {
  return {cross(V.w, m.w), add(cross(V.w, m.v), cross(V.v, m.w))};
}
Spatial cross_force(const Spatial& V, const Spatial& f) {
  return {add(cross(V.w, f.w), cross(V.v, f.v)), cross(V.w, f.v)};
}
Spatial apply(const SpatialInertia& I, const Spatial& V) {
  return {add(mul(I.J, V.w), cross(I.h, V.v)), sub(scale(I.m, V.v), cross(I.h, V.w))};
}
Spatial add(const Spatial& a, const Spatial& b) { return {add(a.w, b.w), add(a.v, b.v)}; }
Spatial scale(const ex& s, const Spatial& a) { return {scale(s, a.w), scale(s, a.v)}; }
ex dot(const Spatial& motion, const Spatial& force) {
  return dot(motion.w, force.w) + dot(motion.v, force.v);
}

namespace {

Mat3 elementary(Axis axis, const ex& c, const ex& s) {
  Mat3 R = identity_mat3();
  int i = 0, j = 0;
  switch (axis) {
    case Axis::x: i = 1; j = 2; break;
    case Axis::y: i = 2; j = 0; break;
    case Axis::z: i = 0; j = 1; break;
  }
  R[i][i] = c;
  R[i][j] = -s;
  R[j][i] = s;
  R[j][j] = c;
  return R;
}

Vec3 unit(Axis axis) {
  Vec3 e = zero_vec3();
  e[static_cast<int>(axis)] = 1;
  return e;
}

// Symbols of an expression.
void symbols_of(const ex& e, std::set<ex, GiNaC::ex_is_less>& out) {
  if (GiNaC::is_a<GiNaC::symbol>(e)) {
    out.insert(e);
    return;
  }
  for (std::size_t i = 0; i < e.nops(); ++i) symbols_of(e.op(i), out);
}

}  // namespace

bool Kinematics::is_ancestor_or_self(int a, int b) const {
  for (int k = b; k >= 0; k = bodies[static_cast<std::size_t>(k)].parent)
    if (k == a) return true;
  return false;
}

Vec3 Kinematics::marker_position(const Model& model, Program& program, const std::string& name) const {
  const Marker& m = model.marker(name);
  int b = model.body_index(m.body);
  if (b < 0) return m.position;
  const BodyKinematics& k = bodies[static_cast<std::size_t>(b)];
  return define(program, add(k.r, mul(k.S, m.position)));
}

Mat3 Kinematics::marker_frame(const Model& model, Program& program, const std::string& name) const {
  const Marker& m = model.marker(name);
  int b = model.body_index(m.body);
  if (b < 0) return m.rotation;
  return define(program, mul(bodies[static_cast<std::size_t>(b)].S, m.rotation));
}

Vec3 Kinematics::marker_velocity(const Model& model, Program& program, const std::string& name) const {
  const Marker& m = model.marker(name);
  int b = model.body_index(m.body);
  if (b < 0) return zero_vec3();
  const BodyKinematics& k = bodies[static_cast<std::size_t>(b)];
  // v_P = v_O + ω × r_P for the body's spatial velocity (ω, v_O).
  return define(program, add(k.V.v, cross(k.V.w, marker_position(model, program, name))));
}

Vec3 Kinematics::marker_angular_velocity(const Model& model, const std::string& name) const {
  int b = model.body_index(model.marker(name).body);
  return b < 0 ? zero_vec3() : bodies[static_cast<std::size_t>(b)].V.w;
}

Kinematics compute_kinematics(const Model& model, Program& program) {
  Kinematics kin;
  const auto& coords = model.coordinates();
  kin.bodies.resize(model.bodies().size());
  for (std::size_t i = 0; i < model.bodies().size(); ++i) {
    const Body& body = model.bodies()[i];
    BodyKinematics& k = kin.bodies[i];
    k.parent = model.body_index(body.parent);
    const BodyKinematics* parent = k.parent >= 0 ? &kin.bodies[static_cast<std::size_t>(k.parent)] : nullptr;
    const Mat3 S_p = parent ? parent->S : identity_mat3();
    const Vec3 r_p = parent ? parent->r : zero_vec3();

    // Local rotation R and the axes ω_rel = Σ_j (R_1…R_{j−1}) e_j θ̇_j of its angles.
    Vec3 t = define(program, body.translation);
    Mat3 R = identity_mat3();
    std::vector<std::pair<Vec3, ex>> axes;  // (axis in the parent frame, angle)
    if (body.rotation_matrix) {
      R = define(program, *body.rotation_matrix);
    } else {
      for (const auto& rot : body.rotations) {
        ex angle = program.define(rot.angle);
        axes.emplace_back(define(program, mul(R, unit(rot.axis))), angle);
        ex c = program.define(GiNaC::cos(angle));
        ex s = program.define(GiNaC::sin(angle));
        R = define(program, mul(R, elementary(rot.axis, c, s)));
      }
    }
    k.S = parent ? define(program, mul(S_p, R)) : R;
    k.r = parent ? define(program, add(r_p, mul(S_p, t))) : t;

    // The coordinates this body's own joint depends on.
    std::set<ex, GiNaC::ex_is_less> syms;
    for (const auto& x : body.translation) symbols_of(x, syms);
    for (const auto& rot : body.rotations) symbols_of(rot.angle, syms);
    if (body.rotation_matrix)
      for (const auto& row : *body.rotation_matrix)
        for (const auto& x : row) symbols_of(x, syms);

    Spatial local_rate;  // ψ ẏ in the parent frame
    for (std::size_t c = 0; c < coords.size(); ++c) {
      const GiNaC::symbol& y = coords[c].position;
      if (!syms.count(y)) continue;
      Vec3 w = zero_vec3();
      if (body.rotation_matrix) {
        // ω_rel,k = vee(∂R/∂y_k Rᵀ).
        Mat3 dR;
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) dR[a][b] = program.diff(R[a][b], y);
        Mat3 W = mul(dR, transpose(R));
        w = {W[2][1], W[0][2], W[1][0]};
      } else {
        for (const auto& [axis, angle] : axes) w = add(w, scale(program.diff(angle, y), axis));
      }
      w = define(program, w);
      Vec3 dt = {program.diff(t[0], y), program.diff(t[1], y), program.diff(t[2], y)};
      Spatial psi{w, define(program, sub(dt, cross(w, t)))};
      local_rate = add(local_rate, scale(coords[c].velocity, psi));
      Spatial phi;
      phi.w = define(program, mul(S_p, psi.w));
      phi.v = define(program, add(mul(S_p, psi.v), cross(r_p, phi.w)));
      k.columns.push_back({static_cast<int>(c), phi});
    }
    local_rate = define(program, local_rate);

    // V_i = V_p + φ_i ẏ; bias_i = bias_p + V_p × (φ_i ẏ) + X_p (ψ̇ ẏ) with ψ̇ from local coordinates.
    Spatial joint_rate;
    for (const auto& col : k.columns)
      joint_rate = add(joint_rate, scale(coords[static_cast<std::size_t>(col.coordinate)].velocity, col.phi));
    joint_rate = define(program, joint_rate);
    Spatial V_p = parent ? parent->V : Spatial{};
    k.V = define(program, add(V_p, joint_rate));

    Spatial psi_dot;
    for (const auto& col : k.columns) {
      const Coordinate& q = coords[static_cast<std::size_t>(col.coordinate)];
      Spatial d;
      for (int a = 0; a < 3; ++a) {
        d.w[a] = program.diff(local_rate.w[a], q.position);
        d.v[a] = program.diff(local_rate.v[a], q.position);
      }
      psi_dot = add(psi_dot, scale(q.velocity, d));
    }
    psi_dot = define(program, psi_dot);
    Spatial X_psi_dot;
    X_psi_dot.w = mul(S_p, psi_dot.w);
    X_psi_dot.v = add(mul(S_p, psi_dot.v), cross(r_p, define(program, X_psi_dot.w)));
    Spatial bias_p = parent ? parent->bias : Spatial{};
    k.bias = define(program, add(add(bias_p, cross_motion(V_p, joint_rate)), X_psi_dot));

    // Inertia about the world origin.
    k.com = define(program, add(k.r, mul(k.S, body.com)));
    k.I_com = define(program, mul(mul(k.S, body.inertia), transpose(k.S)));
    SpatialInertia& I = k.inertia;
    I.m = body.mass;
    I.h = define(program, scale(body.mass, k.com));
    ex c2 = dot(k.com, k.com);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        I.J[a][b] = program.define(k.I_com[a][b] + (a == b ? body.mass * c2 : ex(0)) -
                                   I.h[a] * k.com[b]);  // J = I_C + m(|c|² E − c cᵀ)
  }
  return kin;
}

void restrict_kinematics(Kinematics& kin, std::size_t n, const std::function<GiNaC::ex(const GiNaC::ex&)>& f) {
  auto vec = [&](Vec3& v) {
    for (auto& x : v) x = f(x);
  };
  auto mat = [&](Mat3& A) {
    for (auto& row : A) vec(row);
  };
  for (BodyKinematics& b : kin.bodies) {
    mat(b.S), vec(b.r), vec(b.com), mat(b.I_com);
    vec(b.V.w), vec(b.V.v), vec(b.bias.w), vec(b.bias.v);
    b.inertia.m = f(b.inertia.m), vec(b.inertia.h), mat(b.inertia.J);
    std::vector<JointColumn> kept;
    for (JointColumn col : b.columns)
      if (static_cast<std::size_t>(col.coordinate) < n) {
        vec(col.phi.w), vec(col.phi.v);
        kept.push_back(col);
      }
    b.columns = kept;
  }
}

}  // namespace mbsgen
