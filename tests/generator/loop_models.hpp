// Closed-loop models built with the C++ API for the generator's tests (loop_closure_test.cpp,
// reactions_test.cpp).
#pragma once

#include "mbsgen/generator/model/model.hpp"

#include <string>
#include <vector>

namespace mbsgen::test {

using GiNaC::ex;

inline void add_bar(Model& m, const std::string& name, const std::string& parent, Vec3 translation, const ex& angle,
             const ex& mass, const ex& length) {
  Body b;
  b.name = name;
  b.parent = parent;
  b.translation = translation;
  b.rotations = {{Axis::z, angle}};
  b.mass = mass;
  b.com = {length / 2, 0, 0};
  b.inertia[1][1] = b.inertia[2][2] = mass * length * length / 12;
  m.add_body(b);
}

inline void add_marker(Model& m, const std::string& name, const std::string& body, Vec3 position) {
  Marker k;
  k.name = name;
  k.body = body;
  k.position = position;
  m.add_marker(k);
}

// A four-bar in the x–y plane under gravity −y: crank (th1) and rocker (th3) pivoted on the
// world at O = 0 and D = (a, 0), the coupler (th2, relative to the crank) joined to the
// rocker's tip by a revolute constraint. Equal crank and rocker (length l, mass mb) and a = the
// coupler's length make a parallelogram.
inline Model four_bar(double a, double l1, double l2, double l3, const LinearizationPoint& op,
               const std::vector<std::string>& independent = {}) {
  Model m("four_bar");
  const ex g = m.add_parameter("g", 9.81), mb = m.add_parameter("mb", 0.5), mc = m.add_parameter("mc", 0.8);
  const ex A = m.add_parameter("a", a), L1 = m.add_parameter("l1", l1), L2 = m.add_parameter("l2", l2),
           L3 = m.add_parameter("l3", l3);
  const ex t1 = m.add_coordinate("th1").position, t2 = m.add_coordinate("th2").position,
           t3 = m.add_coordinate("th3").position;
  add_bar(m, "crank", kWorld, zero_vec3(), t1, mb, L1);
  add_bar(m, "coupler", "crank", {L1, 0, 0}, t2, mc, L2);
  add_bar(m, "rocker", kWorld, {A, 0, 0}, t3, mb, L3);
  add_marker(m, "coupler_end", "coupler", {L2, 0, 0});
  add_marker(m, "rocker_tip", "rocker", {L3, 0, 0});
  Gravity gr;
  gr.g = {0, -g, 0};
  m.add_gravity(gr);
  Constraint c;
  c.name = "pin";
  c.kind = ConstraintKind::revolute;
  c.marker_a = "coupler_end";
  c.marker_b = "rocker_tip";
  m.add_constraint(c);
  std::vector<SceneItem> items;
  for (const auto& name : independent) items.push_back({name, {}});
  m.set_independent_coordinates(items);
  m.set_operating_point(op);
  m.validate();
  return m;
}

inline LinearizationPoint hanging() {
  LinearizationPoint op;
  op.position = {{"th1", -GiNaC::Pi / 2}, {"th2", GiNaC::Pi / 2}, {"th3", -GiNaC::Pi / 2}};
  return op;
}

// A point mass on two Cartesian coordinates (x, y) held at distance L from the origin by a
// distance constraint (or the same as an expression), hanging under gravity: SymPy's non-minimal
// pendulum (sympy/physics/mechanics/tests/test_linearize.py), A = [[0, 1], [−g/L, 0]].
inline Model cartesian_pendulum(bool as_expression, const std::vector<std::string>& independent = {}, bool twice = false) {
  Model m("pendulum");
  const ex g = m.add_parameter("g", 9.81), L = m.add_parameter("L", 0.7), mass = m.add_parameter("m", 1.3);
  const ex x = m.add_coordinate("x").position, y = m.add_coordinate("y").position;
  Body b;
  b.name = "bob";
  b.translation = {x, y, 0};
  b.mass = mass;
  m.add_body(b);
  add_marker(m, "pivot", kWorld, zero_vec3());
  add_marker(m, "bob_point", "bob", zero_vec3());
  Gravity gr;
  gr.g = {0, -g, 0};
  m.add_gravity(gr);
  for (int k = 0; k < (twice ? 2 : 1); ++k) {
    Constraint c;
    c.name = "rod" + std::to_string(k + 1);
    if (as_expression) {
      c.kind = ConstraintKind::expression;
      c.expression = x * x + y * y - L * L;
    } else {
      c.kind = ConstraintKind::distance;
      c.marker_a = "pivot";
      c.marker_b = "bob_point";
      c.length = L;
    }
    m.add_constraint(c);
  }
  std::vector<SceneItem> items;
  for (const auto& name : independent) items.push_back({name, {}});
  m.set_independent_coordinates(items);
  LinearizationPoint op;
  op.position = {{"x", 0}, {"y", -L}};
  m.set_operating_point(op);
  m.validate();
  return m;
}

}  // namespace mbsgen::test
