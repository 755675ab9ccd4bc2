// Closed kinematic loops (loop_closure.hpp): the reduced linear model against closed forms, the
// choice of independent coordinates, and the errors for singular, redundant and badly given
// constraints. Models are built with the C++ API and evaluated in process (50 digits).
#include "mbsgen/generator/linearize.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

namespace {

using namespace mbsgen;
using GiNaC::ex;

// A value of the linear model at the operating point with the default parameter values: the
// dependent coordinates are those closed to 50 digits by the generator.
double value(Equations& eq, const LinearEquations& lin, const ex& e) {
  const long digits = GiNaC::Digits;
  GiNaC::Digits = 50;
  GiNaC::exmap v;
  for (const auto& p : eq.model->parameters()) v[p.symbol] = GiNaC::numeric(p.value);
  for (std::size_t k = 0; k < eq.y.size(); ++k) {
    auto closed = eq.loops.closed_at_defaults.find(eq.y[k]);
    v[eq.y[k]] = closed != eq.loops.closed_at_defaults.end() ? closed->second : GiNaC::evalf(lin.y0[k].subs(v));
    v[eq.yd[k]] = 0;
  }
  const double d = GiNaC::ex_to<GiNaC::numeric>(GiNaC::evalf(eq.program.inline_all(e).subs(v))).to_double();
  GiNaC::Digits = digits;
  return d;
}

void add_bar(Model& m, const std::string& name, const std::string& parent, Vec3 translation, const ex& angle,
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

void add_marker(Model& m, const std::string& name, const std::string& body, Vec3 position) {
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
Model four_bar(double a, double l1, double l2, double l3, const OperatingPoint& op,
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

OperatingPoint hanging() {
  OperatingPoint op;
  op.position = {{"th1", -GiNaC::Pi / 2}, {"th2", GiNaC::Pi / 2}, {"th3", -GiNaC::Pi / 2}};
  return op;
}

// A point mass on two Cartesian coordinates (x, y) held at distance L from the origin by a
// distance constraint (or the same as an expression), hanging under gravity: SymPy's non-minimal
// pendulum (sympy/physics/mechanics/tests/test_linearize.py), A = [[0, 1], [−g/L, 0]].
Model cartesian_pendulum(bool as_expression, const std::vector<std::string>& independent = {}, bool twice = false) {
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
  OperatingPoint op;
  op.position = {{"x", 0}, {"y", -L}};
  m.set_operating_point(op);
  m.validate();
  return m;
}

double omega2(Model& m, double* mass = nullptr) {
  Equations eq = derive(m);
  LinearEquations lin = linearize(eq);
  EXPECT_EQ(lin.M.size(), 1u);
  const double M = value(eq, lin, lin.M[0][0]), K = value(eq, lin, lin.K[0][0]);
  if (mass) *mass = M;
  return K / M;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ModelError& e) {
    return e.message();
  }
  return "(no error)";
}

// Parallelogram: the coupler translates on a circle of radius l, so T = ½ (2·m l²/3 + m_c l²) θ̇²
// and V = −(m + m_c) g l cos θ: ω² = g (m + m_c) / (l (2m/3 + m_c)). The cut pin carries part of
// the coupler's weight (λ ≠ 0), so the geometric stiffness is part of this.
TEST(LoopClosure, ParallelogramFourBarMatchesClosedForm) {
  const double l = 0.2, mb = 0.5, mc = 0.8, g = 9.81;
  const double w2 = g * (mb + mc) / (l * (2 * mb / 3 + mc)), mass = 2 * mb * l * l / 3 + mc * l * l;
  for (const char* independent : {"", "th1", "th2", "th3"}) {
    Model m = four_bar(0.3, l, 0.3, l, hanging(), *independent ? std::vector<std::string>{independent}
                                                                : std::vector<std::string>{});
    double M = 0;
    // 1e-14: the closed form evaluated in double against a 50-digit evaluation (a few roundings).
    EXPECT_NEAR(omega2(m, &M) / w2, 1, 1e-14) << independent;
    // With θ̇2 = −θ̇1 (the coupler does not turn), the reduced mass is the same for every choice.
    EXPECT_NEAR(M / mass, 1, 1e-14) << independent;
  }
}

TEST(LoopClosure, PlanarRevoluteDropsItsOutOfPlaneEquations) {
  Model m = four_bar(0.3, 0.2, 0.3, 0.2, hanging());
  Equations eq = derive(m);
  ASSERT_TRUE(eq.loops.active);
  ASSERT_EQ(eq.loops.equations.size(), 2u);
  EXPECT_EQ(eq.loops.equations[0].component, "x");
  EXPECT_EQ(eq.loops.equations[1].component, "y");
  ASSERT_EQ(eq.loops.dropped.size(), 3u);
  for (const auto& [e, why] : eq.loops.dropped) EXPECT_NE(why.find("identically zero"), std::string::npos);
  EXPECT_EQ(eq.loops.independent.size(), 1u);
  EXPECT_TRUE(eq.loops.chosen);
  EXPECT_FALSE(eq.loops.redundant);
}

// The whole stiffness of the Cartesian pendulum is geometric: gravity is linear in y (K_tree = 0)
// and ω² = g/L comes from −λ ∂²Φ/∂x² with λ = −m g the rod force.
TEST(LoopClosure, CartesianPendulumEqualsTheSimplePendulum) {
  for (bool as_expression : {false, true}) {
    Model m = cartesian_pendulum(as_expression);
    double M = 0;
    EXPECT_NEAR(omega2(m, &M) / (9.81 / 0.7), 1, 1e-14) << as_expression;
    EXPECT_NEAR(M / 1.3, 1, 1e-15);
    Equations eq = derive(m);
    ASSERT_EQ(eq.loops.independent.size(), 1u);
    EXPECT_EQ(m.coordinates()[eq.loops.independent[0]].name, "x");  // y moves the rod's length
  }
}

TEST(LoopClosure, RedundantConstraintsAreDroppedAndSaidSo) {
  Model m = cartesian_pendulum(false, {}, true);
  Equations eq = derive(m);
  EXPECT_TRUE(eq.loops.redundant);
  ASSERT_EQ(eq.loops.equations.size(), 1u);
  ASSERT_EQ(eq.loops.dropped.size(), 1u);
  EXPECT_NE(eq.loops.dropped[0].second.find("the reaction forces are not unique"), std::string::npos);
  EXPECT_NEAR(omega2(m) / (9.81 / 0.7), 1, 1e-14);
}

// Crank and coupler stretched along x with the rocker in line: every constraint gradient is
// along y, so the Jacobian has rank 1 at this dead point (rank 2 elsewhere).
TEST(LoopClosure, DeadPointIsNamed) {
  OperatingPoint op;
  op.position = {{"th1", 0}, {"th2", 0}, {"th3", 0}};
  const std::string e = error_of([&] {
    Model m = four_bar(0.4, 0.1, 0.35, 0.05, op);
    derive(m);
  });
  // At the dead point the gradient of the x equation vanishes (every motion is along y).
  EXPECT_NE(e.find("the constraint Jacobian is singular at the operating point: the gradients of the "
                   "equations 'pin' (x) (in the coordinates th1, th2, th3) are linearly dependent (or "
                   "zero) there"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("dead point"), std::string::npos) << e;
}

TEST(LoopClosure, GivenOperatingPointMustCloseTheLoop) {
  OperatingPoint op = hanging();
  op.position["th3"] = -GiNaC::Pi / 2 + GiNaC::numeric(1, 100);
  const std::string e = error_of([&] {
    Model m = four_bar(0.3, 0.2, 0.3, 0.2, op);
    derive(m);
  });
  // The rocker's tip moves by l·sin 0.01 ≈ 2.0e-3 m in x (and l·(1 − cos 0.01) ≈ 1e-5 m in y):
  // the first equation reported is x.
  EXPECT_NE(e.find("the operating point does not close constraint 'pin' (x)"), std::string::npos) << e;
  EXPECT_NE(e.find("its residual is"), std::string::npos) << e;
}

TEST(LoopClosure, BadIndependentCoordinatesAreRefused) {
  std::string e = error_of([&] { Model m = cartesian_pendulum(false, {"y"}); derive(m); });
  EXPECT_NE(e.find("the coordinates x cannot be found from the listed independent ones at the operating "
                   "point"), std::string::npos) << e;
  EXPECT_NE(e.find("independent coordinates that work: x"), std::string::npos) << e;
  e = error_of([&] { Model m = cartesian_pendulum(false, {"x", "y"}); derive(m); });
  EXPECT_NE(e.find("the constraints leave 1 independent coordinates; 2 are listed"), std::string::npos) << e;
}

TEST(LoopClosure, LockedMechanismIsRefused) {
  Model m("locked");
  const ex x = m.add_coordinate("x").position;
  Body b;
  b.name = "block";
  b.translation = {x, 0, 0};
  b.mass = 1;
  m.add_body(b);
  Constraint c;
  c.name = "stop";
  c.kind = ConstraintKind::expression;
  c.expression = x;
  m.add_constraint(c);
  m.validate();
  const std::string e = error_of([&] { derive(m); });
  EXPECT_NE(e.find("the constraints leave no degree of freedom: 1 independent equations in 1 coordinates"),
            std::string::npos) << e;
}

}  // namespace
