// Exact symbolic checks of the derivation on small models: the generator's matrices, with all
// intermediates written out and exact rational parameters, must equal exact reference matrices.
#include "mbsgen/generator/codegen/cse.hpp"
#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/linear/linearize.hpp"
#include "mbsgen/generator/model/parametric_chains.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include <gtest/gtest.h>

namespace mbsgen {
namespace {

using GiNaC::ex;
using GiNaC::numeric;

// Three-link planar chain of docs/test-references.md, "The three-link chain" (SymPy 1.11
// KanesMethod, exact rationals): M, C, K at q = 0 must agree exactly.
TEST(Derivation, ThreeLinkChainMatchesSymPyExactly) {
  Model model = planar_chain(3);
  Equations eq = derive(model);
  LinearEquations lin = linearize(eq);
  GiNaC::exmap values;
  const std::map<std::string, numeric> p = {
      {"g", numeric(981, 100)}, {"m1", 1},  {"m2", numeric(3, 2)}, {"m3", 2},
      {"l1", numeric(1, 2)},    {"l2", numeric(2, 5)}, {"l3", numeric(3, 10)},
      {"k1", 10}, {"k2", 20}, {"k3", 30},
      {"c1", numeric(1, 10)}, {"c2", numeric(1, 5)}, {"c3", numeric(3, 10)}};
  for (const auto& [name, v] : p) values[model.symbol(name)] = v;
  for (const auto& s : eq.y) values[s] = 0;
  auto exact = [&](const ex& e) { return eq.program.inline_all(e).subs(values).normal(); };
  const numeric M_ref[3][3] = {{numeric(869, 200), numeric(111, 50), numeric(18, 25)},
                               {numeric(111, 50), numeric(61, 50), numeric(21, 50)},
                               {numeric(18, 25), numeric(21, 50), numeric(9, 50)}};
  const numeric K_ref[3][3] = {{numeric(20677, 400), numeric(981, 50), numeric(2943, 500)},
                               {numeric(981, 50), numeric(1981, 50), numeric(2943, 500)},
                               {numeric(2943, 500), numeric(2943, 500), numeric(17943, 500)}};
  const numeric C_ref[3] = {numeric(1, 10), numeric(1, 5), numeric(3, 10)};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      EXPECT_TRUE((exact(lin.M[i][j]) - M_ref[i][j]).is_zero()) << "M" << i << j << " = " << exact(lin.M[i][j]);
      EXPECT_TRUE((exact(lin.K[i][j]) - K_ref[i][j]).is_zero()) << "K" << i << j << " = " << exact(lin.K[i][j]);
      EXPECT_TRUE((exact(lin.Q[i][j]) - (i == j ? C_ref[i] : numeric(0))).is_zero())
          << "Q" << i << j << " = " << exact(lin.Q[i][j]);
    }
}

// The values a list of statements computes, exactly, at x = 3/7, y = 5/11 (each temporary's
// symbol stands for its value).
std::vector<ex> run(const std::vector<Statement>& statements, const GiNaC::symbol& x,
                    const GiNaC::symbol& y) {
  GiNaC::exmap env{{x, numeric(3, 7)}, {y, numeric(5, 11)}};
  std::vector<ex> outputs;
  for (const auto& s : statements) {
    const ex v = s.value.subs(env, GiNaC::subs_options::no_pattern);
    if (s.temporary) env[s.symbol] = v;
    else outputs.push_back(v);
  }
  return outputs;
}

// Temporaries with equal or opposite values (what specialising a kernel at y = y0 produces) are
// computed once; the outputs keep their exact values.
TEST(Cse, MergesEqualAndOppositeTemporaries) {
  const GiNaC::symbol x("x"), y("y"), t0("t0"), t1("t1"), t2("t2"), t3("t3"), t4("t4");
  CanonicalOrder order;
  const std::vector<std::pair<GiNaC::symbol, ex>> defs = {
      {t0, GiNaC::sin(x)}, {t1, t0 * y}, {t2, y * t0}, {t3, -(t0 * y)}, {t4, t1 + t3 * x}};
  std::vector<Statement> in;
  for (const auto& [t, v] : defs) {
    order.set_sign(t, order.sign(v));
    in.push_back({t.get_name(), v, true, t});
  }
  in.push_back({"out[0]", t1 * t2 + t3, false, ex()});
  in.push_back({"out[1]", t4 - t2, false, ex()});
  const std::vector<Statement> out = eliminate_common_subexpressions(in, order);
  std::vector<std::string> temporaries;
  for (const auto& s : out)
    if (s.temporary) temporaries.push_back(s.target);
  // t2 = t1 and t3 = −t1 are dropped; t0·y is computed once; t4 = t1 − t1·x is read only by
  // out[1] = t4 − t1, whose polynomial form −t1·x is computed directly.
  EXPECT_EQ(temporaries, (std::vector<std::string>{"t0", "t1"}));
  const std::vector<ex> before = run(in, x, y), after = run(out, x, y);
  ASSERT_EQ(after.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i)
    EXPECT_TRUE((before[i] - after[i]).expand().is_zero()) << before[i] << " vs " << after[i];
  const ex expected = -numeric(15, 77) * GiNaC::sin(ex(numeric(3, 7)));  // −x·y·sin x, exact
  EXPECT_TRUE((after[1] - expected).expand().is_zero()) << after[1];
}

}  // namespace
}  // namespace mbsgen


namespace mbsgen {
namespace {

// Exact structural zeros (issue 14 §1) and the manifest's sparsity, for the heavy top in steady
// precession. From its Lagrangian (models/textbook/heavy_top_precession.yaml), with s = sin θ,
// c = cos θ: M = [[I1 s² + I3 c², 0, I3 c], [0, I1, 0], [I3 c, 0, I3]] for every θ; psi and phi
// are cyclic, so K's columns of psi and phi vanish for every state; K(psi, theta) and
// K(phi, theta) are θ̇ times a function of θ (d/dt of the momenta p_psi, p_phi), zero at the
// steady precession (θ̇ = 0) only.
TEST(StructuralZeros, HeavyTopPatternFollowsFromTheLagrangian) {
  const Model model = read_model_file(std::string(MBSGEN_SOURCE_DIR) + "/models/textbook/heavy_top_precession.yaml");
  Equations eq = derive(model);
  LinearEquations lin = linearize(eq);
  EXPECT_EQ(pattern_rows(lin.zeros.M), (std::vector<std::string>{"x0x", "0x0", "x0x"}));
  EXPECT_EQ(pattern_rows(lin.zeros.K), (std::vector<std::string>{"0o0", "0x0", "0o0"}));
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(lin.K[i][0].is_zero()) << i;
    EXPECT_TRUE(lin.K[i][2].is_zero()) << i;
  }
  EXPECT_EQ(lin.zeros.unproved, 0u);
  // Zeros at the operating point only are not written into the general matrices.
  EXPECT_FALSE(lin.K[0][1].is_zero());
  // The manifest records the pattern.
  const GeneratedCode code = emit(model, eq, lin, EmitOptions{});
  EXPECT_NE(code.manifest.find("\"K\": [\"0o0\", \"0x0\", \"0o0\"]"), std::string::npos) << code.manifest;
  EXPECT_NE(code.source.find("  if (at_operating_point(y0[0], op0) && at_operating_point(y0[1], op1) && "
                             "at_operating_point(y0[2], op2) && at_operating_point(yd0[0], op3) && "
                             "at_operating_point(yd0[1], op4) && at_operating_point(yd0[2], op5)) {"),
            std::string::npos);
}

// A numerically tiny entry that is not zero (a constant 1e-40 in the model) stays an
// expression: the symbolic proof, not the 50-digit screen, decides.
TEST(StructuralZeros, TinyButNonzeroEntriesAreKept) {
  const Model model = read_model_string(R"(model: tiny
parameters: {m: 1, k: 100}
coordinates: [x, y]
bodies:
  - {name: b, translation: [x, y, 0], mass: m}
forces:
  - {type: generalized, coordinate: x, value: -k*x - 1e-40*k*y}
  - {type: generalized, coordinate: y, value: -k*y}
)",
                                          "tiny.yaml");
  Equations eq = derive(model);
  LinearEquations lin = linearize(eq);
  EXPECT_EQ(pattern_rows(lin.zeros.K), (std::vector<std::string>{"xx", "0x"}));
  EXPECT_FALSE(lin.K[0][1].is_zero());
}

// A matrix that vanishes as a whole at the operating point: N = skew K of the 8-link spatial
// chain hanging at rest. Gravity and the joint springs are conservative, so K at rest is the
// Hessian of the potential and symmetric (Lagrange); N is zero in every entry there. (For any y0
// too, but from 8 links on the written-out entries exceed the proof's budget.) The screen's
// tolerance was relative to the matrix's own largest entry, rounding noise, and found 140 of
// the 240 entries by the luck of the rounding.
TEST(StructuralZeros, MatrixVanishingAsAWholeIsZeroInEveryEntry) {
  const Model model = spatial_chain(8);  // (derive keeps a pointer to it)
  Equations eq = derive(model);
  LinearEquations lin = linearize(eq);
  ASSERT_EQ(lin.zeros.N.size(), 16u);
  for (std::size_t i = 0; i < 16; ++i)
    for (std::size_t j = 0; j < 16; ++j) EXPECT_NE(lin.zeros.N[i][j], EntryZero::nonzero) << i << ", " << j;
}

// A spatial tree with every kind of term both forms of k − q must carry alike: a translated and
// rotated root, a massless gimbal, a rotation_matrix body, a body fixed to the world, two gravity
// fields, an applied force and torque in a moving marker's frame, a spring, a damper, a bushing
// and a generalized force.
const char* const kEveryTerm = R"(model: every_term
parameters:
  g: {value: 9.81}
  m: {value: 1.5}
  l: {value: 0.4}
coordinates: [a, b, c, d]
bodies:
  - {name: base, translation: [0.1, l, 0.2], rotation: [{z: a}], mass: m, com: [0.1, 0, 0.05],
     inertia: {xx: 0.02, yy: 0.03, zz: 0.04, xy: 0.001}}
  - {name: gimbal, parent: base, translation: [0, 0, l], rotation: [{x: b}]}
  - name: arm
    parent: gimbal
    rotation_matrix: [[cos(c), 0, sin(c)], [0, 1, 0], [-sin(c), 0, cos(c)]]
    mass: 2*m
    com: [0, l/2, 0.03]
    inertia: {xx: 0.05, yy: 0.01, zz: 0.05, yz: 0.002}
    markers:
      - {name: tip, position: [0, l, 0], rotation: [{x: 0.3}]}
  - {name: slider, parent: arm, translation: [d, l, 0], mass: 0.5, inertia: {xx: 0.001, yy: 0.001, zz: 0.001}}
  - {name: post, translation: [1, 0, 0], mass: 3}
markers:
  - {name: anchor, position: [0.5, 0.5, 0]}
forces:
  - {type: gravity, g: [0, 0, -g]}
  - {type: gravity, g: [0.5, 0, 0]}
  - {type: applied, marker: tip, frame: marker, force: [1, 2, 3], torque: [0.1, 0, 0.2]}
  - {type: spring, between: [anchor, tip], stiffness: 30, rest_length: 0.2}
  - {type: damper, between: [anchor, tip], damping: 0.4}
  - {type: bushing, between: [anchor, tip], stiffness: {translation: [5, 6, 7], rotation: [1, 2, 3]},
     damping: {rotation: [0.1, 0.1, 0.1]}}
  - {type: generalized, coordinate: d, value: -2*d}
)";

// The residual kernels' form of k − q (Equations::residual_kernel: gravity as the base's
// acceleration, link frames) against the form the linearization differentiates (gravity
// projected in the world frame), both written out and evaluated with 50 digits at a point with
// every coordinate, rate and parameter distinct: equal to 1e-40 of the largest entry (the values
// are O(1)–O(1e3), the intermediates' rounding ~1e-45 of them). Planar models (the world-frame
// route) have no second form.
TEST(Derivation, KernelResidualWithGravityAsBaseAccelerationEqualsWorldFrameForm) {
  const std::string dir = std::string(MBSGEN_SOURCE_DIR) + "/models/";
  std::vector<Model> models;
  models.push_back(spatial_chain(3));
  models.push_back(read_model_string(kEveryTerm, "every_term.yaml"));
  for (const char* file : {"textbook/sleeping_top.yaml", "textbook/spherical_pendulum_conical.yaml",
                           "textbook/heavy_top_precession.yaml", "robots/puma560.yaml"})
    models.push_back(read_model_file(dir + file));
  struct Digits {  // restored however the test ends
    long saved = GiNaC::Digits;
    ~Digits() { GiNaC::Digits = saved; }
  } digits;
  GiNaC::Digits = 50;
  for (const Model& model : models) {
    SCOPED_TRACE(model.name());
    Equations eq = derive(model);
    ASSERT_EQ(eq.residual_kernel.size(), eq.residual.size());
    GiNaC::exmap point;
    int k = 0;
    for (const auto* group : {&eq.y, &eq.yd, &eq.u, &eq.p})
      for (const auto& s : *group) {
        point[s] = numeric(7 + 3 * k, 11 + k % 5);  // 0.64, 0.83, …
        ++k;
      }
    auto value = [&](const ex& e) {
      return GiNaC::ex_to<numeric>(GiNaC::evalf(eq.program.inline_all(e).subs(point, GiNaC::subs_options::no_pattern)));
    };
    numeric scale = 0;
    std::vector<numeric> world, kernel;
    for (std::size_t j = 0; j < eq.residual.size(); ++j) {
      world.push_back(value(eq.residual[j]));
      kernel.push_back(value(eq.residual_kernel[j]));
      scale = std::max(scale, GiNaC::abs(world.back()));
    }
    EXPECT_GT(scale, numeric(1, 10));
    for (std::size_t j = 0; j < world.size(); ++j)
      EXPECT_LE(GiNaC::abs(world[j] - kernel[j]), scale * numeric(10).power(-40)) << j;
  }
  const Model planar = planar_chain(3);
  EXPECT_TRUE(derive(planar).residual_kernel.empty());
}

}  // namespace
}  // namespace mbsgen
