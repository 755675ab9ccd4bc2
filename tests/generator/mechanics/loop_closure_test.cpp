// Closed kinematic loops (loop_closure.hpp): the reduced linear model against closed forms, the
// choice of independent coordinates, and the errors for singular, redundant and badly given
// constraints. Models are built with the C++ API and evaluated in process (50 digits).
#include "mbsgen/generator/linear/linearize.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include "loop_models.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

namespace {

using namespace mbsgen;
using namespace mbsgen::test;
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
  LinearizationPoint op;
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
  LinearizationPoint op = hanging();
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
  EXPECT_NE(e.find("the constraints leave 1 independent coordinate; 2 are listed"), std::string::npos) << e;
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

namespace {

// A rigid body free in space (x, y, z and rotations a, b, c about x, y, z) hung from the world by
// a spherical joint at its top: the physical pendulum about two axes and a free spin about the
// vertical, ω² = m g d / (I + m d²); with a revolute joint about x instead, the swing about x only.
Model hung_body(ConstraintKind kind) {
  Model m("hung_body");
  const double mass = 1.2, d = 0.4;
  m.add_parameter("g", 9.81);
  const ex x = m.add_coordinate("x").position, y = m.add_coordinate("y").position, z = m.add_coordinate("z").position;
  const ex a = m.add_coordinate("a").position, b = m.add_coordinate("b").position, c = m.add_coordinate("c").position;
  Body body;
  body.name = "body";
  body.translation = {x, y, z};
  body.rotations = {{Axis::x, a}, {Axis::y, b}, {Axis::z, c}};
  body.mass = mass;
  body.com = {0, 0, -d};
  body.inertia[0][0] = GiNaC::numeric(3, 100);
  body.inertia[1][1] = GiNaC::numeric(2, 100);
  body.inertia[2][2] = GiNaC::numeric(1, 100);
  m.add_body(body);
  Marker pivot, top;
  pivot.name = "pivot";
  pivot.body = kWorld;
  top.name = "top";
  top.body = "body";
  if (kind == ConstraintKind::revolute) {  // the hinge axis z_a along x
    Mat3 R = zero_mat3();
    R[0][2] = 1, R[1][1] = 1, R[2][0] = -1;  // rotation by π/2 about y
    pivot.rotation = top.rotation = R;
  }
  m.add_marker(pivot);
  m.add_marker(top);
  Gravity gr;
  gr.g = {0, 0, -m.symbol("g")};
  m.add_gravity(gr);
  Constraint joint;
  joint.name = "joint";
  joint.kind = kind;
  joint.marker_a = "pivot";
  joint.marker_b = "top";
  m.add_constraint(joint);
  m.validate();
  return m;
}

TEST(LoopClosure, SphericalJointMakesAPhysicalPendulumInSpace) {
  Model m = hung_body(ConstraintKind::spherical);
  Equations eq = derive(m);
  ASSERT_EQ(eq.loops.equations.size(), 3u);
  LinearEquations lin = linearize(eq);
  ASSERT_EQ(lin.M.size(), 3u);
  std::vector<std::string> names;
  for (std::size_t k : lin.coordinates) names.push_back(m.coordinates()[k].name);
  EXPECT_EQ(names, (std::vector<std::string>{"a", "b", "c"}));
  const double mgd = 1.2 * 9.81 * 0.4, md2 = 1.2 * 0.16;
  // At rest the swings and the spin decouple: M and K diagonal (exact zeros), ω² = K/M.
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j)
      if (i != j) {
        EXPECT_EQ(value(eq, lin, lin.M[i][j]), 0) << i << j;
      }
  EXPECT_NEAR(value(eq, lin, lin.K[0][0]) / value(eq, lin, lin.M[0][0]) / (mgd / (0.03 + md2)), 1, 1e-14);
  EXPECT_NEAR(value(eq, lin, lin.K[1][1]) / value(eq, lin, lin.M[1][1]) / (mgd / (0.02 + md2)), 1, 1e-14);
  EXPECT_EQ(value(eq, lin, lin.K[2][2]), 0);  // the spin about the vertical: no stiffness
  EXPECT_NEAR(value(eq, lin, lin.M[2][2]), 0.01, 1e-16);
}

TEST(LoopClosure, RevoluteJointInSpaceLeavesOneSwing) {
  Model m = hung_body(ConstraintKind::revolute);
  Equations eq = derive(m);
  ASSERT_EQ(eq.loops.equations.size(), 5u);
  LinearEquations lin = linearize(eq);
  ASSERT_EQ(lin.M.size(), 1u);
  EXPECT_EQ(m.coordinates()[lin.coordinates[0]].name, "a");
  const double mgd = 1.2 * 9.81 * 0.4, md2 = 1.2 * 0.16;
  EXPECT_NEAR(value(eq, lin, lin.K[0][0]) / value(eq, lin, lin.M[0][0]) / (mgd / (0.03 + md2)), 1, 1e-14);
}

// The four-bar of models/linkages/four_bar.yaml with its pin's markers lifted out of the plane by
// the same height written two ways (√2·√3 and √6): the pin's z equation is zero, its gradient
// is proved zero, but the equation itself is not proved zero. It is identically satisfied and
// its reaction is zero: dropped without the warning that the reactions are not unique (issue 39
// §1; before, "redundant in every configuration … not unique").
std::string four_bar_text(const std::string& z_coupler, const std::string& z_rocker) {
  return R"(model: lifted
parameters: {g: 9.81, a: 0.4, l1: 0.1, l2: 0.35, l3: 0.25, m: 0.3}
coordinates: [th1, th2, th3]
bodies:
  - {name: crank, rotation: [{z: th1}], mass: m, com: [l1/2, 0, 0], inertia: {yy: m*l1^2/12, zz: m*l1^2/12}}
  - name: coupler
    parent: crank
    translation: [l1, 0, 0]
    rotation: [{z: th2}]
    mass: m
    com: [l2/2, 0, 0]
    inertia: {yy: m*l2^2/12, zz: m*l2^2/12}
    markers: [{name: coupler_end, position: [l2, 0, )" + z_coupler + R"(]}]
  - name: rocker
    translation: [a, 0, 0]
    rotation: [{z: th3}]
    mass: m
    com: [l3/2, 0, 0]
    inertia: {yy: m*l3^2/12, zz: m*l3^2/12}
    markers: [{name: rocker_tip, position: [l3, 0, )" + z_rocker + R"(]}]
forces: [{type: gravity, g: [0, -g, 0]}]
constraints: [{name: pin, type: revolute, between: [coupler_end, rocker_tip]}]
independent_coordinates: [th1]
operating_point: {type: equilibrium, position: {th1: 1.0, th2: -0.45, th3: 1.95}}
)";
}

TEST(LoopClosure, ZeroGradientEquationThatHoldsIsNotARedundancy) {
  Model m = read_model_string(four_bar_text("sqrt(2)*sqrt(3)", "sqrt(6)"), "lifted.yaml");
  Equations eq = derive(m);
  EXPECT_FALSE(eq.loops.redundant);
  ASSERT_EQ(eq.loops.equations.size(), 2u);
  bool z_dropped = false;
  for (const auto& [e, why] : eq.loops.dropped) {
    EXPECT_EQ(why.find("not unique"), std::string::npos) << e.component << ": " << why;
    if (e.component == "z") z_dropped = why.rfind("identically satisfied", 0) == 0;
  }
  EXPECT_TRUE(z_dropped);
}

// A dependent equation is dropped only where it holds; the pin's z rows that differ by 1 cm can
// never hold: an error naming the constraint and the residual (tests/data/bad_models has the
// complete messages of the contradictions).
TEST(LoopClosure, ZeroGradientEquationThatCannotHoldIsRefused) {
  const std::string e = error_of([&] {
    Model m = read_model_string(four_bar_text("0.01", "0"), "lifted.yaml");
    derive(m);
  });
  EXPECT_NE(e.find("constraint 'pin' (z) cannot hold: its gradient vanishes in every configuration (residual -0.01 m "
                   "at the operating point closed onto the others"),
            std::string::npos)
      << e;
}

// A rod and an expression constraint that say the same thing (x² + y² = L²): consistent, so the
// second is dropped as redundant, with the warning that the reactions are not unique, and the
// pendulum is the simple pendulum (ω² = g/L for the bob of mass m at L, 1e-14: 50 digits).
TEST(LoopClosure, ConsistentRedundantConstraintIsStillAccepted) {
  Model m = read_model_string(R"(model: twice
parameters: {g: 9.81, L: 0.7, m: 1.3}
coordinates: [x, y]
bodies: [{name: bob, translation: [x, y, 0], mass: m, markers: [{name: bob_point}]}]
markers: [{name: pivot}]
forces: [{type: gravity, g: [0, -g, 0]}]
constraints:
  - {name: rod, type: distance, between: [pivot, bob_point], length: L}
  - {name: circle, type: expression, expression: (x^2 + y^2 - L^2)/(2*L)}
independent_coordinates: [x]
operating_point: {type: given, position: {x: 0, y: -L}}
)",
                              "twice.yaml");
  Equations eq = derive(m);
  EXPECT_TRUE(eq.loops.redundant);
  ASSERT_EQ(eq.loops.dropped.size(), 1u);
  EXPECT_EQ(eq.loops.dropped[0].first.constraint, "circle");
  EXPECT_NE(eq.loops.dropped[0].second.find("the reaction forces are not unique"), std::string::npos);
  EXPECT_NEAR(omega2(m) / (9.81 / 0.7), 1, 1e-14);
}

}  // namespace
