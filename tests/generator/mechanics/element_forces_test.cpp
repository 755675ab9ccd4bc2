// Outputs of type force (reactions.hpp, force_output): the loads springs, dampers and bushings put
// on the body of their marker b, against closed forms and against the generalized forces the same
// elements put on the coordinates (virtual work).
#include "mbsgen/generator/linear/linearize.hpp"
#include "mbsgen/generator/model/scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>

namespace {

using namespace mbsgen;
using GiNaC::ex;

double number(Equations& eq, const ex& e, const GiNaC::exmap& at) {
  GiNaC::exmap v = at;
  for (const auto& p : eq.model->parameters()) v[p.symbol] = GiNaC::numeric(p.value);
  return GiNaC::ex_to<GiNaC::numeric>(GiNaC::evalf(eq.program.inline_all(e).subs(v))).to_double();
}

Marker marker(const std::string& name, const std::string& body, Vec3 position = zero_vec3()) {
  Marker m;
  m.name = name;
  m.body = body;
  m.position = position;
  return m;
}

Output force(const std::string& name, std::vector<std::string> elements, Vec3 direction,
             ForceQuantity q = ForceQuantity::force) {
  Output o;
  o.name = name;
  o.kind = OutputKind::force;
  o.elements = std::move(elements);
  o.direction = direction;
  o.quantity = q;
  return o;
}

// A mass on (x, y) below an anchor, on a spring of rest length L0 and a damper.
Model spring_mass() {
  Model m("spring_mass");
  const ex g = m.add_parameter("g", 9.81), mass = m.add_parameter("m", 2.0), k = m.add_parameter("k", 500.0),
           L0 = m.add_parameter("L0", 0.3), c = m.add_parameter("c", 4.0);
  const ex x = m.add_coordinate("x").position, y = m.add_coordinate("y").position;
  Body b;
  b.name = "mass";
  b.translation = {x, y, 0};
  b.mass = mass;
  m.add_body(b);
  m.add_marker(marker("anchor", kWorld));
  m.add_marker(marker("hook", "mass"));
  m.add_spring({"spring", "anchor", "hook", k, L0, {}});
  m.add_damper({"damper", "anchor", "hook", c, {}});
  Gravity gr;
  gr.g = {0, -g, 0};
  m.add_gravity(gr);
  m.add_output(force("spring_fy", {"spring"}, {0, 1, 0}));
  m.add_output(force("spring_fx", {"spring"}, {1, 0, 0}));
  m.add_output(force("damper_fy", {"damper"}, {0, 1, 0}));
  m.add_output(force("both_fy", {"spring", "damper"}, {0, 1, 0}));
  LinearizationPoint op;
  op.position = {{"x", 0}, {"y", -(L0 + mass * g / k)}};
  m.set_operating_point(op);
  m.validate();
  return m;
}

// Hanging at rest, the spring holds the weight; at a general state the spring's load is
// k (L − L0) towards the anchor and the damper's c L̇ against the stretching rate.
TEST(ElementForces, SpringAndDamperLoads) {
  Model m = spring_mass();
  Equations eq = derive(m);
  const double g = 9.81, mass = 2.0, k = 500.0, L0 = 0.3, c = 4.0;
  GiNaC::exmap rest{{eq.y[0], 0}, {eq.y[1], -(L0 + mass * g / k)}, {eq.yd[0], 0}, {eq.yd[1], 0}};
  EXPECT_NEAR(number(eq, eq.outputs[0], rest), mass * g, 1e-12);
  const double x = 0.3, y = -0.5, vx = 0.7, vy = -1.1, L = std::hypot(x, y), Ldot = (x * vx + y * vy) / L;
  GiNaC::exmap state{{eq.y[0], x}, {eq.y[1], y}, {eq.yd[0], vx}, {eq.yd[1], vy}};
  // 1e-12 N of loads of order 100 N (doubles against 50-digit-free double evaluation: a few ulps).
  EXPECT_NEAR(number(eq, eq.outputs[0], state), -k * (L - L0) * y / L, 1e-12);
  EXPECT_NEAR(number(eq, eq.outputs[1], state), -k * (L - L0) * x / L, 1e-12);
  EXPECT_NEAR(number(eq, eq.outputs[2], state), -c * Ldot * y / L, 1e-12);
  EXPECT_NEAR(number(eq, eq.outputs[3], state), -k * (L - L0) * y / L - c * Ldot * y / L, 1e-12);
}

// A scene without the dampers: a force output keeps the active elements only.
TEST(ElementForces, SceneKeepsTheActiveElements) {
  Model m = spring_mass();
  Scene s;
  s.name = "undamped";
  s.analyses = {Analysis::frf};
  s.without = {{"dampers", {}}};
  m.add_scene(s);
  const Model pruned = apply_scene(m, "undamped");
  Equations eq = derive(pruned);
  GiNaC::exmap state{{eq.y[0], 0.3}, {eq.y[1], -0.5}, {eq.yd[0], 0.7}, {eq.yd[1], -1.1}};
  const double L = std::hypot(0.3, -0.5);
  EXPECT_NEAR(number(eq, eq.outputs[3], state), -500.0 * (L - 0.3) * -0.5 / L, 1e-12);  // spring only
  EXPECT_EQ(number(eq, eq.outputs[2], state), 0);                                     // no damper left
}

// A massless body free in space (x, y, z, rotations a, b, c) on a bushing to the world: the
// elements' loads on the body, through the body's Jacobians, are the generalized forces, so
// k − q + J_rᵀ F + J_ωᵀ τ = 0 at any state (virtual work; no inertia).
TEST(ElementForces, BushingLoadsDoTheVirtualWorkOfItsGeneralizedForces) {
  Model m("bushing_body");
  std::vector<ex> q;
  for (const char* n : {"x", "y", "z", "a", "b", "c"}) q.push_back(m.add_coordinate(n).position);
  Body body;
  body.name = "body";
  body.translation = {q[0], q[1], q[2]};
  body.rotations = {{Axis::x, q[3]}, {Axis::y, q[4]}, {Axis::z, q[5]}};
  m.add_body(body);
  m.add_marker(marker("ground", kWorld, {GiNaC::numeric(1, 10), 0, GiNaC::numeric(-1, 5)}));
  m.add_marker(marker("mount", "body", {GiNaC::numeric(3, 10), GiNaC::numeric(-1, 10), 0}));
  Bushing bu;
  bu.name = "bushing";
  bu.marker_a = "ground";
  bu.marker_b = "mount";
  bu.k_translation = {100, 200, 300};
  bu.k_rotation = {10, 20, 30};
  bu.d_translation = {1, 2, 3};
  bu.d_rotation = {GiNaC::numeric(1, 10), GiNaC::numeric(2, 10), GiNaC::numeric(3, 10)};
  m.add_bushing(bu);
  for (int i = 0; i < 3; ++i) {
    Vec3 e = zero_vec3();
    e[static_cast<std::size_t>(i)] = 1;
    m.add_output(force("F" + std::to_string(i), {"bushing"}, e));
    m.add_output(force("T" + std::to_string(i), {"bushing"}, e, ForceQuantity::torque));
  }
  m.validate();
  Equations eq = derive(m);
  const double values[6] = {0.05, -0.02, 0.03, 0.2, -0.15, 0.1}, rates[6] = {0.3, -0.1, 0.2, 0.5, 0.4, -0.6};
  GiNaC::exmap state;
  for (std::size_t k = 0; k < 6; ++k) state[eq.y[k]] = values[k], state[eq.yd[k]] = rates[k];
  const Vec3 r = eq.kinematics.marker_position(m, eq.program, "mount");
  double F[3], T[3];
  for (int i = 0; i < 3; ++i) {
    F[i] = number(eq, eq.outputs[static_cast<std::size_t>(2 * i)], state);
    T[i] = number(eq, eq.outputs[static_cast<std::size_t>(2 * i + 1)], state);
  }
  for (std::size_t j = 0; j < 6; ++j) {
    double work = number(eq, eq.residual[j], state);
    for (std::size_t i = 0; i < 3; ++i) {
      work += F[i] * number(eq, eq.program.diff(r[i], eq.y[j]), state);
      work += T[i] * number(eq, eq.JR[i][j], state);
    }
    // Loads of order 10 N: 1e-12 is a few roundings of the sums.
    EXPECT_NEAR(work, 0, 1e-12) << m.coordinates()[j].name;
  }
}

}  // namespace
