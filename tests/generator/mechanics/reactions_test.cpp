// Reaction forces (reactions.hpp): joint loads of a double pendulum at a state that is not an
// equilibrium against a Newton–Euler computation by hand, static loads that equal the weight
// they carry, and the loads at the cut joints of closed loops.
#include "mbsgen/generator/linear/linearize.hpp"
#include "mbsgen/generator/mechanics/reactions.hpp"
#include "mbsgen/generator/model/scene.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include "loop_models.hpp"

#include <gtest/gtest.h>

#include <array>
#include <fstream>
#include <iterator>
#include <cmath>
#include <map>
#include <string>

namespace {

using namespace mbsgen;
using GiNaC::ex;

// z_i at a state: coordinates, rates and accelerations by name (the tree's, or the independent
// ones of a model with loops), the dependent coordinates of loops closed by the generator.
double output(Equations& eq, std::size_t i, const std::map<std::string, double>& y,
              const std::map<std::string, double>& yd = {}, const std::map<std::string, double>& ydd = {}) {
  const long digits = GiNaC::Digits;
  GiNaC::Digits = 50;
  GiNaC::exmap v;
  for (const auto& p : eq.model->parameters()) v[p.symbol] = GiNaC::numeric(p.value);
  for (const auto& [x, s] : eq.loops.closed_at_defaults) v[x] = s;
  const auto& coords = eq.model->coordinates();
  for (std::size_t k = 0; k < coords.size(); ++k) {
    if (auto it = y.find(coords[k].name); it != y.end()) v[eq.y[k]] = it->second;
    v[eq.yd[k]] = yd.count(coords[k].name) ? yd.at(coords[k].name) : 0.0;
    if (!eq.ydd.empty()) v[eq.ydd[k]] = ydd.count(coords[k].name) ? ydd.at(coords[k].name) : 0.0;
  }
  for (const auto& u : eq.u) v[u] = 0;
  const double d = GiNaC::ex_to<GiNaC::numeric>(GiNaC::evalf(eq.program.inline_all(eq.outputs[i]).subs(v))).to_double();
  GiNaC::Digits = digits;
  return d;
}

void reaction(Model& m, const std::string& name, const std::string& of, ForceQuantity q, Vec3 direction) {
  Output o;
  o.name = name;
  o.kind = OutputKind::reaction;
  o.reaction_of = of;
  o.quantity = q;
  o.direction = direction;
  m.add_output(o);
}

// Two point masses on massless rods, rotating about z: q1 absolute, q2 relative.
Model double_pendulum() {
  Model m("double_pendulum");
  const ex g = m.add_parameter("g", 9.81), m1 = m.add_parameter("m1", 1.5), m2 = m.add_parameter("m2", 0.7),
           l1 = m.add_parameter("l1", 0.6), l2 = m.add_parameter("l2", 0.4);
  const ex q1 = m.add_coordinate("q1").position, q2 = m.add_coordinate("q2").position;
  Body b1;
  b1.name = "upper";
  b1.rotations = {{Axis::z, q1}};
  b1.mass = m1;
  b1.com = {l1, 0, 0};
  m.add_body(b1);
  Body b2;
  b2.name = "lower";
  b2.parent = "upper";
  b2.translation = {l1, 0, 0};
  b2.rotations = {{Axis::z, q2}};
  b2.mass = m2;
  b2.com = {l2, 0, 0};
  m.add_body(b2);
  Gravity gr;
  gr.g = {0, -g, 0};
  m.add_gravity(gr);
  for (const char* body : {"upper", "lower"}) {
    reaction(m, std::string(body) + "_fx", body, ForceQuantity::force, {1, 0, 0});
    reaction(m, std::string(body) + "_fy", body, ForceQuantity::force, {0, 1, 0});
    reaction(m, std::string(body) + "_fz", body, ForceQuantity::force, {0, 0, 1});
    reaction(m, std::string(body) + "_tz", body, ForceQuantity::torque, {0, 0, 1});
  }
  m.validate();
  return m;
}

// Newton–Euler by hand at an arbitrary state (the accelerations need not satisfy the equations
// of motion: the loads are those the joints must transmit for that motion). Point masses: the
// joint force on a subtree is Σ m (a − g); its moment about the joint is Σ (r − P) × m (a − g).
TEST(Reactions, DoublePendulumJointsAgainstNewtonEuler) {
  Model m = double_pendulum();
  Equations eq = derive(m);
  const double g = 9.81, m1 = 1.5, m2 = 0.7, l1 = 0.6, l2 = 0.4;
  const double q1 = 0.7, q2 = -1.2, w1 = 1.3, w2 = -0.4, a1 = 2.1, a2 = -3.3;
  using V2 = std::array<double, 2>;
  auto e = [](double t) { return V2{std::cos(t), std::sin(t)}; };
  auto ep = [](double t) { return V2{-std::sin(t), std::cos(t)}; };
  const double t2 = q1 + q2, w12 = w1 + w2, a12 = a1 + a2;
  const V2 r1{l1 * e(q1)[0], l1 * e(q1)[1]};
  const V2 r2{r1[0] + l2 * e(t2)[0], r1[1] + l2 * e(t2)[1]};
  const V2 acc1{l1 * (a1 * ep(q1)[0] - w1 * w1 * e(q1)[0]), l1 * (a1 * ep(q1)[1] - w1 * w1 * e(q1)[1])};
  const V2 acc2{acc1[0] + l2 * (a12 * ep(t2)[0] - w12 * w12 * e(t2)[0]),
                acc1[1] + l2 * (a12 * ep(t2)[1] - w12 * w12 * e(t2)[1])};
  const V2 f1{m1 * acc1[0], m1 * (acc1[1] + g)}, f2{m2 * acc2[0], m2 * (acc2[1] + g)};  // m (a − g)
  auto cross = [](const V2& r, const V2& f) { return r[0] * f[1] - r[1] * f[0]; };
  const double expected[8] = {f1[0] + f2[0], f1[1] + f2[1], 0, cross(r1, f1) + cross(r2, f2),
                              f2[0], f2[1], 0, cross({r2[0] - r1[0], r2[1] - r1[1]}, f2)};
  const std::map<std::string, double> y{{"q1", q1}, {"q2", q2}}, yd{{"q1", w1}, {"q2", w2}},
      ydd{{"q1", a1}, {"q2", a2}};
  for (std::size_t i = 0; i < 8; ++i)
    // 1e-12 N (or N m): both sides are a few roundings of loads of order 10.
    EXPECT_NEAR(output(eq, i, y, yd, ydd), expected[i], 1e-12) << m.outputs()[i].name;
}

// At rest in the hanging position the joints carry the weight below them, and no torque.
TEST(Reactions, StaticLoadsEqualTheWeightCarried) {
  Model m = double_pendulum();
  Equations eq = derive(m);
  const double g = 9.81, m1 = 1.5, m2 = 0.7;
  const std::map<std::string, double> hanging{{"q1", -M_PI / 2}, {"q2", 0}};
  EXPECT_NEAR(output(eq, 1, hanging), (m1 + m2) * g, 1e-12);
  EXPECT_NEAR(output(eq, 5, hanging), m2 * g, 1e-12);
  for (std::size_t i : {0u, 2u, 3u, 4u, 6u, 7u}) EXPECT_NEAR(output(eq, i, hanging), 0, 1e-12) << i;
}

// The same loads through the linear model: C_a and D_u are the derivatives of the reaction
// with respect to ÿ and u; at the hanging rest C_y q_s + C_a q̈_s equals the exact load's change
// to first order (checked against a central difference of the expression).
TEST(Reactions, LinearRowsMatchTheNonlinearLoad) {
  Model m = double_pendulum();
  Equations eq = derive(m);
  LinearizationPoint op;
  op.position = {{"q1", -GiNaC::Pi / 2}, {"q2", 0}};
  m.set_operating_point(op);
  Equations eq2 = derive(m);
  LinearEquations lin = linearize(eq2);
  ASSERT_EQ(lin.Ca.size(), 8u);
  const double h = 1e-6;
  for (std::size_t i = 0; i < 8; ++i)
    for (std::size_t j = 0; j < 2; ++j) {
      const std::string q = m.coordinates()[j].name;
      std::map<std::string, double> plus{{"q1", -M_PI / 2}, {"q2", 0}}, minus = plus, rest = plus;
      plus[q] += h, minus[q] -= h;
      const double dz_dy = (output(eq2, i, plus) - output(eq2, i, minus)) / (2 * h);
      const double dz_da = output(eq2, i, rest, {}, {{q, 1.0}}) - output(eq2, i, rest);  // linear in ÿ
      GiNaC::exmap v;
      for (const auto& p : m.parameters()) v[p.symbol] = p.value;
      v[eq2.y[0]] = -M_PI / 2, v[eq2.y[1]] = 0;
      auto num = [&](const ex& e) {
        return GiNaC::ex_to<GiNaC::numeric>(GiNaC::evalf(eq2.program.inline_all(e).subs(v))).to_double();
      };
      // Central differences with h = 1e-6: truncation ~h² and rounding ~1e-16/h of loads ~10.
      EXPECT_NEAR(num(lin.Cy[i][j]), dz_dy, 1e-8) << m.outputs()[i].name << " " << q;
      EXPECT_NEAR(num(lin.Ca[i][j]), dz_da, 1e-12) << m.outputs()[i].name << " " << q;
    }
  (void)eq;
}

// Parallelogram four-bar hanging at rest: the uniform coupler (m_c) hangs from the crank's tip
// and the pin, m_c g/2 each (moments about either end); crank and rocker (m_b) carry their weight
// and that half. The pin's load on the rocker (marker b) is (0, −m_c g/2); the world's load on the
// rocker through its joint includes the pin's share (Φ_probeᵀ λ in reactions.hpp).
TEST(Reactions, ParallelogramFourBarCarriesTheCoupler) {
  Model m = test::four_bar(0.3, 0.2, 0.3, 0.2, test::hanging());
  for (const char* of : {"pin", "crank", "rocker", "coupler"}) {
    reaction(m, std::string(of) + "_fx", of, ForceQuantity::force, {1, 0, 0});
    reaction(m, std::string(of) + "_fy", of, ForceQuantity::force, {0, 1, 0});
  }
  Equations eq = derive(m);
  const double g = 9.81, mb = 0.5, mc = 0.8;
  const std::map<std::string, double> y{{"th1", -M_PI / 2}, {"th2", M_PI / 2}, {"th3", -M_PI / 2}};
  const double expected[8] = {0, -mc * g / 2, 0, (mb + mc / 2) * g, 0, (mb + mc / 2) * g, 0, mc * g / 2};
  for (std::size_t i = 0; i < 8; ++i)
    // 1e-12 N: loads of order 5 N, computed through the loop's elimination in 50 digits.
    EXPECT_NEAR(output(eq, i, y), expected[i], 1e-12) << m.outputs()[i].name;
}

// The rod of the Cartesian pendulum holds the bob's weight.
TEST(Reactions, RodOfTheCartesianPendulumHoldsTheBob) {
  Model m = test::cartesian_pendulum(false);
  reaction(m, "rod_fx", "rod1", ForceQuantity::force, {1, 0, 0});
  reaction(m, "rod_fy", "rod1", ForceQuantity::force, {0, 1, 0});
  Equations eq = derive(m);
  const std::map<std::string, double> y{{"x", 0}, {"y", -0.7}};
  EXPECT_NEAR(output(eq, 0, y), 0, 1e-13);
  EXPECT_NEAR(output(eq, 1, y), 1.3 * 9.81, 1e-12);
}

}  // namespace

namespace {

// A block on a frictionless guide inclined at α in the x–y plane: a free planar body (x, y, θ)
// held by a prismatic constraint whose axis z_a is along the guide; a spring along the guide from
// an anchor on it, gravity −y. One degree of freedom: ω² = k/m (the transverse stiffness of the
// spring's preload acts against the constraint), and the guide's load on the block is the normal
// force m g cos α along the guide's upward normal (−sin α, cos α).
TEST(Reactions, BlockOnAnInclinedGuide) {
  const double alpha = 0.5, mass = 2.0, k = 300.0, g = 9.81, L0 = 0.2;
  Model m("incline");
  m.add_parameter("g", g);
  const ex x = m.add_coordinate("x").position, y = m.add_coordinate("y").position, th = m.add_coordinate("th").position;
  Body b;
  b.name = "block";
  b.translation = {x, y, 0};
  b.rotations = {{Axis::z, th}};
  b.mass = mass;
  b.inertia[0][0] = b.inertia[1][1] = b.inertia[2][2] = 0.01;
  m.add_body(b);
  const std::vector<ElementaryRotation> along = {{Axis::z, alpha}, {Axis::y, GiNaC::Pi / 2}};  // z_a = (cos α, sin α, 0)
  Marker guide;
  guide.name = "guide";
  guide.body = kWorld;
  Marker on_block = guide;
  on_block.name = "on_block";
  on_block.body = "block";
  for (Marker* mk : {&guide, &on_block}) {
    Mat3 R = identity_mat3();
    for (const auto& r : along) {
      Mat3 E = identity_mat3();
      const int i = r.axis == Axis::z ? 0 : 2, j = r.axis == Axis::z ? 1 : 0;
      E[i][i] = E[j][j] = GiNaC::cos(r.angle);
      E[i][j] = -GiNaC::sin(r.angle);
      E[j][i] = GiNaC::sin(r.angle);
      R = mul(R, E);
    }
    mk->rotation = R;
    m.add_marker(*mk);
  }
  Marker anchor;
  anchor.name = "anchor";
  anchor.body = kWorld;
  anchor.position = {-std::cos(alpha), -std::sin(alpha), 0};  // 1 m down the guide
  m.add_marker(anchor);
  m.add_spring({"spring", "anchor", "on_block", k, L0, {}});
  Gravity gr;
  gr.g = {0, -g, 0};
  m.add_gravity(gr);
  Constraint c;
  c.name = "slide";
  c.kind = ConstraintKind::prismatic;
  c.marker_a = "guide";
  c.marker_b = "on_block";
  m.add_constraint(c);
  reaction(m, "normal_x", "slide", ForceQuantity::force, {1, 0, 0});
  reaction(m, "normal_y", "slide", ForceQuantity::force, {0, 1, 0});
  // Equilibrium along the guide: the compressed spring pushes up the slope, k (L0 − L) = m g sin α
  // with L = 1 + s.
  const double s = L0 - mass * g * std::sin(alpha) / k - 1.0;
  LinearizationPoint op;
  op.position = {{"x", s * std::cos(alpha)}, {"y", s * std::sin(alpha)}, {"th", 0}};
  m.set_operating_point(op);
  Equations eq = derive(m);
  ASSERT_EQ(eq.loops.equations.size(), 2u);  // y (transverse) and rx (turning); x, ry, rz vanish
  LinearEquations lin = linearize(eq);
  ASSERT_EQ(lin.M.size(), 1u);
  GiNaC::exmap v;
  for (const auto& p : m.parameters()) v[p.symbol] = p.value;
  v[eq.y[0]] = s * std::cos(alpha), v[eq.y[1]] = s * std::sin(alpha), v[eq.y[2]] = 0;
  auto num = [&](const ex& e) {
    return GiNaC::ex_to<GiNaC::numeric>(GiNaC::evalf(eq.program.inline_all(e).subs(v))).to_double();
  };
  // 1e-12: the closed form against a double evaluation of the kernels' expressions.
  EXPECT_NEAR(num(lin.K[0][0]) / num(lin.M[0][0]) / (k / mass), 1, 1e-12);
  const std::map<std::string, double> at{{"x", s * std::cos(alpha)}, {"y", s * std::sin(alpha)}, {"th", 0}};
  EXPECT_NEAR(output(eq, 0, at), -mass * g * std::cos(alpha) * std::sin(alpha), 1e-12);
  EXPECT_NEAR(output(eq, 1, at), mass * g * std::cos(alpha) * std::cos(alpha), 1e-12);
}

// A point mass on three Cartesian coordinates held in the plane z = 0 by a planar constraint,
// with springs along x and y and gravity −z: two modes sqrt(k_x/m), sqrt(k_y/m), and the plane
// carries the weight.
TEST(Reactions, PointOnAPlane) {
  Model m("plane");
  const ex x = m.add_coordinate("x").position, y = m.add_coordinate("y").position, z = m.add_coordinate("z").position;
  Body b;
  b.name = "bead";
  b.translation = {x, y, z};
  b.mass = 0.5;
  m.add_body(b);
  Marker floor;
  floor.name = "floor";
  floor.body = kWorld;
  m.add_marker(floor);
  Marker point;
  point.name = "point";
  point.body = "bead";
  m.add_marker(point);
  m.add_generalized_force({"spring_x", "x", -80 * x, {}, Category::springs});
  m.add_generalized_force({"spring_y", "y", -20 * y, {}, Category::springs});
  Gravity gr;
  gr.g = {0, 0, -9.81};
  m.add_gravity(gr);
  Constraint c;
  c.name = "plane";
  c.kind = ConstraintKind::planar;
  c.marker_a = "floor";
  c.marker_b = "point";
  m.add_constraint(c);
  reaction(m, "normal", "plane", ForceQuantity::force, {0, 0, 1});
  m.validate();
  Equations eq = derive(m);
  ASSERT_EQ(eq.loops.equations.size(), 1u);  // z; the bead cannot turn: rx, ry vanish
  LinearEquations lin = linearize(eq);
  ASSERT_EQ(lin.M.size(), 2u);
  GiNaC::exmap v{{eq.y[0], 0}, {eq.y[1], 0}, {eq.y[2], 0}};
  auto num = [&](const ex& e) {
    return GiNaC::ex_to<GiNaC::numeric>(GiNaC::evalf(eq.program.inline_all(e).subs(v))).to_double();
  };
  EXPECT_EQ(num(lin.M[0][1]), 0);
  EXPECT_NEAR(num(lin.K[0][0]) / num(lin.M[0][0]), 160, 1e-12);
  EXPECT_NEAR(num(lin.K[1][1]) / num(lin.M[1][1]), 40, 1e-12);
  EXPECT_NEAR(output(eq, 0, {{"x", 0}, {"y", 0}, {"z", 0}}), 0.5 * 9.81, 1e-13);
}

}  // namespace

namespace {

// A scene that asks for one joint load probes that joint only: the other reactions are pruned
// with their outputs, and the load is the same as in the full model (at ẏ = 0: a scene about rest
// drops the velocity-quadratic inertia terms, docs/scenes.md).
TEST(Reactions, SceneProbesOnlyTheLoadsItAsksFor) {
  Model m = double_pendulum();
  Scene s;
  s.name = "upper_load";
  s.analyses = {Analysis::frf};
  s.outputs = std::vector<SceneItem>{{"upper_fy", {}}};
  m.add_scene(s);
  const Model pruned = apply_scene(m, "upper_load");
  EXPECT_EQ(probed_bodies(pruned), std::vector<std::string>{"upper"});
  Equations full = derive(m), scene = derive(pruned);
  ASSERT_EQ(scene.outputs.size(), 1u);
  const std::map<std::string, double> y{{"q1", 0.3}, {"q2", 0.2}}, yd{}, ydd{{"q2", 1.5}};
  EXPECT_NEAR(output(scene, 0, y, yd, ydd), output(full, 1, y, yd, ydd), 1e-13);
}

// Two pendulums on their own pivots geared by an `expression` constraint th3 = 2 th1 (issue 39
// §1): the constraint's generalized force Φ_yᵀ λ acts through the coordinates it names, like an
// actuator in each of their joints, so it is part of those joints' loads: each joint carries the
// whole torque its pendulum needs (λ Φ_th3 = λ on B's, and, where the motion obeys the dynamics,
// λ Φ_th1 = −2 λ on A's), and no force beyond its pendulum's own (a geometric loop would add the
// loop's force there). Against Newton–Euler by hand for point masses on fixed pivots:
// F = m r̈ − m g, τ = (r − p) × F, r̈ = l α (−s, c) − l ω² (c, s).
TEST(Reactions, ExpressionConstraintActsThroughTheJointsOfItsCoordinates) {
  const double g = 9.81, mA = 1.5, lA = 0.6, mB = 0.7, lB = 0.4;
  const Model m = read_model_string(R"(model: geared
parameters: {g: 9.81, mA: 1.5, lA: 0.6, mB: 0.7, lB: 0.4, a: 1.0}
coordinates: [th1, th3]
bodies:
  - {name: A, rotation: [{z: th1}], mass: mA, com: [lA, 0, 0]}
  - {name: B, translation: [a, 0, 0], rotation: [{z: th3}], mass: mB, com: [lB, 0, 0]}
forces:
  - {type: gravity, g: [0, -g, 0]}
constraints:
  - {name: gear, type: expression, expression: th3 - 2*th1}
independent_coordinates: [th1]
outputs:
  - {name: A_fx, type: reaction, of: A, direction: [1, 0, 0]}
  - {name: A_fy, type: reaction, of: A, direction: [0, 1, 0]}
  - {name: A_tz, type: reaction, of: A, direction: [0, 0, 1], quantity: torque}
  - {name: B_fx, type: reaction, of: B, direction: [1, 0, 0]}
  - {name: B_fy, type: reaction, of: B, direction: [0, 1, 0]}
  - {name: B_tz, type: reaction, of: B, direction: [0, 0, 1], quantity: torque}
  - {name: gear_lambda, type: reaction, of: gear, direction: [1, 0, 0]}
operating_point: {type: given, position: {th1: 0.3, th3: 0.6}}
)",
                                    "geared.yaml");
  Equations eq = derive(m);
  const double th1 = 0.3, th3 = 0.6, w1 = 0.5, w3 = 2 * w1;
  auto load = [&](double mass, double l, double th, double w, double alpha, double out[3]) {
    const double c = std::cos(th), s = std::sin(th);
    const double ax = l * (-alpha * s - w * w * c), ay = l * (alpha * c - w * w * s);
    out[0] = mass * ax;
    out[1] = mass * ay + mass * g;
    out[2] = l * (c * out[1] - s * out[0]);
  };
  // An arbitrary acceleration, and the one of the dynamics: τ_A + 2 τ_B = 0 (the gear does no work).
  const double dynamic = -(mA * g * lA * std::cos(th1) + 2 * mB * g * lB * std::cos(th3)) / (mA * lA * lA + 4 * mB * lB * lB);
  for (const double alpha1 : {0.7, dynamic}) {
    double A[3], B[3];
    load(mA, lA, th1, w1, alpha1, A);
    load(mB, lB, th3, w3, 2 * alpha1, B);
    const std::map<std::string, double> y{{"th1", th1}, {"th3", th3}}, yd{{"th1", w1}, {"th3", w3}},
        ydd{{"th1", alpha1}};
    const double expected[7] = {A[0], A[1], A[2], B[0], B[1], B[2], B[2]};
    // 1e-13: loads of order 10 N (N m) evaluated in 50 digits against the closed form in double.
    for (std::size_t i = 0; i < 7; ++i)
      EXPECT_NEAR(output(eq, i, y, yd, ydd), expected[i], 1e-13) << m.outputs()[i].name << " alpha " << alpha1;
    if (alpha1 == dynamic) {  // the gear's generalized force on th1 is all A's joint carries
      EXPECT_NEAR(output(eq, 2, y, yd, ydd), -2 * output(eq, 6, y, yd, ydd), 1e-13);
    }
  }
}

// The four-bar of models/linkages/four_bar.yaml (whose pin reactions are checked against the
// reference in its header) closed instead by the pin's two equations written as `expression`
// constraints, Φ = r_tip − r_end in x and y: the same Φ, so the same multipliers, λ = the pin's
// force on the rocker f. The expressions act through the coordinates, not at the pin: the crank's
// joint carries what its subtree (crank and coupler) needs without the pin's −f on the coupler's
// end, F_expr(crank) = F_pin(crank) − f, and the rocker's without the pin's +f,
// F_expr(rocker) = F_pin(rocker) + f (issue 39 §1: the reason the loop's force is not in these
// loads, as docs/model-format.md says).
TEST(Reactions, FourBarClosedByExpressionsAgainstThePin) {
  const std::string file = std::string(MBSGEN_SOURCE_DIR) + "/models/linkages/four_bar.yaml";
  Model pin = read_model_file(file);
  std::ifstream in(file);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto replace = [&](const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  };
  replace("  - {name: pin, type: revolute, between: [coupler_end, rocker_tip]}",
          "  - {name: pin_x, type: expression, expression: a + l3*cos(th3) - l1*cos(th1) - l2*cos(th1 + th2)}\n"
          "  - {name: pin_y, type: expression, expression: l3*sin(th3) - l1*sin(th1) - l2*sin(th1 + th2)}");
  replace("{name: pin_fx, type: reaction, of: pin,", "{name: pin_fx, type: reaction, of: pin_x,");
  replace("{name: pin_fy, type: reaction, of: pin, direction: [0, 1, 0]", "{name: pin_fy, type: reaction, of: pin_y, direction: [1, 0, 0]");
  Model expr = read_model_string(text, "four_bar_expressions.yaml");
  for (Model* m : {&pin, &expr}) {
    reaction(*m, "rocker_fx", "rocker", ForceQuantity::force, {1, 0, 0});
    reaction(*m, "rocker_fy", "rocker", ForceQuantity::force, {0, 1, 0});
  }
  Equations ep = derive(pin), ee = derive(expr);
  // Outputs: pin_fx pin_fy pivot_fx pivot_fy crank_angle rocker_fx rocker_fy. A state off the
  // equilibrium (the guess th1 = 1, rates and accelerations given), the loop closed by the generator.
  const std::map<std::string, double> y{{"th1", 1.0}}, yd{{"th1", 0.8}}, ydd{{"th1", -1.3}};
  auto out = [&](Equations& eq, std::size_t i) { return output(eq, i, y, yd, ydd); };
  const double fx = out(ep, 0), fy = out(ep, 1);
  // 1e-12 N: loads of a few N through two eliminations in 50 digits, the loops closed to 50 digits.
  EXPECT_NEAR(out(ee, 0), fx, 1e-12);
  EXPECT_NEAR(out(ee, 1), fy, 1e-12);
  EXPECT_GT(std::hypot(fx, fy), 0.1);  // the pin carries a load here: the comparison means something
  EXPECT_NEAR(out(ee, 2), out(ep, 2) - fx, 1e-12);
  EXPECT_NEAR(out(ee, 3), out(ep, 3) - fy, 1e-12);
  EXPECT_NEAR(out(ee, 5), out(ep, 5) + fx, 1e-12);
  EXPECT_NEAR(out(ee, 6), out(ep, 6) + fy, 1e-12);
}

}  // namespace
