// Prescribed motion (prescribed_motion.hpp) in the derivation: a moving marker on the world is a
// driven body; a prescribed coordinate's terms are the free model's coupling blocks; a scene
// without a motion input holds that support still.
#include "mbsgen/generator/linear/linearize.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace {

using GiNaC::ex;
using mbsgen::Equations;
using mbsgen::LinearEquations;
using mbsgen::Model;
using mbsgen::read_model_string;

// The value of a linear-model entry with the default parameters at the operating point (y0, ẏ0).
double value(Equations& eq, const Model& model, const LinearEquations& lin, const ex& e) {
  GiNaC::exmap v;
  for (const auto& p : model.parameters()) v[p.symbol] = p.value;
  for (std::size_t k = 0; k < eq.y.size(); ++k) v[eq.y[k]] = lin.y0[k].subs(v);
  for (std::size_t k = 0; k < eq.yd.size(); ++k) v[eq.yd[k]] = lin.yd0[k].subs(v);
  return GiNaC::ex_to<GiNaC::numeric>(GiNaC::evalf(eq.program.inline_all(e).subs(v))).to_double();
}

const char* const kOscillatorOnAMarker = R"(model: oscillator_on_a_marker
parameters: {m: 2, k: 800, c: 8}
coordinates: [x]
inputs: [{name: xb, kind: motion}]
bodies:
  - {name: mass, translation: [x, 0, 0], mass: m, markers: [{name: mass_point}]}
markers:
  - {name: ground, position: [xb, 0, 0]}
forces:
  - {name: mount, type: bushing, between: [ground, mass_point], stiffness: {translation: [k, 0, 0]},
     damping: {translation: [c, 0, 0]}}
outputs:
  - {name: x_rel, type: position, marker: mass_point, relative_to: ground, direction: [1, 0, 0]}
  - {name: v_rel, type: velocity, marker: mass_point, relative_to: ground, direction: [1, 0, 0]}
scenes:
  - {name: held, analyses: [modes]}
)";

// A marker on the world that moves with a motion input (a road under a wheel) excites like the
// shaker table of models/textbook/base_excited_oscillator.yaml: B = k, B1 = c, B2 = 0, and the
// relative outputs take −1 of the support's displacement and rate.
TEST(PrescribedMotion, AMovingMarkerOnTheWorldIsADrivenSupport) {
  const Model model = read_model_string(kOscillatorOnAMarker, "oscillator_on_a_marker.yaml");
  Equations eq = mbsgen::derive(model);
  LinearEquations lin = mbsgen::linearize(eq);
  ASSERT_EQ(lin.B1.size(), 1u);
  EXPECT_EQ(value(eq, model, lin, lin.B[0][0]), 800.0);
  EXPECT_EQ(value(eq, model, lin, lin.B1[0][0]), 8.0);
  EXPECT_TRUE(lin.B2[0][0].is_zero());
  ASSERT_EQ(lin.Du.size(), 2u);
  EXPECT_EQ(value(eq, model, lin, lin.Du[0][0]), -1.0);
  EXPECT_TRUE(lin.Du[1][0].is_zero());
  EXPECT_EQ(value(eq, model, lin, lin.D1[1][0]), -1.0);
  EXPECT_TRUE(lin.D1[0][0].is_zero());
  EXPECT_EQ(eq.kinematics.bodies.size(), 1u) << "the marker's carrier body is not one of the model's";
}

// A scene without the motion input holds the support still: no B1, B2, and the model is the
// fixed oscillator.
TEST(PrescribedMotion, ASceneWithoutTheInputHoldsTheSupportStill) {
  const Model model = read_model_string(kOscillatorOnAMarker, "oscillator_on_a_marker.yaml");
  const Model held = mbsgen::apply_scene(model, "held");
  EXPECT_FALSE(held.has_motion_inputs());
  Equations eq = mbsgen::derive(held);
  LinearEquations lin = mbsgen::linearize(eq);
  EXPECT_TRUE(lin.B1.empty());
  EXPECT_EQ(value(eq, held, lin, lin.K[0][0]), 800.0);
}

// A two-link planar pendulum (relative angles a, b) with its first joint prescribed: the
// equation of b is the free model's row b, so B = −K_ba, B1 = −Q_ba, B2 = −M_ba of the free
// model, and M, K are its (b, b) entries (Jourdain: the virtual displacements are δb only).
TEST(PrescribedMotion, APrescribedCoordinateGivesTheFreeModelsCouplings) {
  auto model_text = [](bool prescribed) {
    return std::string("model: two_links\nparameters: {m1: 1.5, m2: 0.7, l1: 0.9, l2: 0.6, g: 9.81, c: 0.3, k: 4}\n") +
           (prescribed ? "coordinates: [b]\ninputs: [{name: a, kind: motion}]\n" : "coordinates: [a, b]\n") +
           R"(bodies:
  - {name: one, rotation: [{z: 0.4 + a}], mass: m1, com: [0, -l1, 0]}
  - {name: two, parent: one, translation: [0, -l1, 0], rotation: [{z: b}], mass: m2, com: [0, -l2, 0],
     inertia: {xx: 0.005, yy: 0.005, zz: 0.01}}
forces:
  - {type: gravity, g: [0, -g, 0]}
  - {type: generalized, coordinate: b, value: -k*b - c*b_dot - c*a_dot}
)";
  };
  const Model free = read_model_string(model_text(false), "free.yaml");
  const Model driven = read_model_string(model_text(true), "driven.yaml");
  Equations ef = mbsgen::derive(free), ed = mbsgen::derive(driven);
  LinearEquations lf = mbsgen::linearize(ef), ld = mbsgen::linearize(ed);
  auto near = [](double a, double b) { return std::abs(a - b) <= 1e-14 * std::max(std::abs(a), std::abs(b)); };
  EXPECT_TRUE(near(value(ed, driven, ld, ld.M[0][0]), value(ef, free, lf, lf.M[1][1])));
  EXPECT_TRUE(near(value(ed, driven, ld, ld.K[0][0]), value(ef, free, lf, lf.K[1][1])));
  EXPECT_TRUE(near(value(ed, driven, ld, ld.B[0][0]), -value(ef, free, lf, lf.K[1][0])));
  EXPECT_TRUE(near(value(ed, driven, ld, ld.B1[0][0]), -value(ef, free, lf, lf.Q[1][0])));
  EXPECT_TRUE(near(value(ed, driven, ld, ld.B2[0][0]), -value(ef, free, lf, lf.M[1][0])));
  EXPECT_NE(value(ef, free, lf, lf.M[1][0]), 0.0);
  EXPECT_NE(value(ef, free, lf, lf.K[1][0]), 0.0);
}

// The same at a steady motion: a disk spinning at rate w0 on a gimbal (tilts a1, a2, spin s),
// with a1 prescribed. The gyroscopic coupling I_p w0 between the tilts is in Q of the free model,
// so B1 = −Q_(a2, s),a1 carries it, and B = −K, B2 = −M as before.
TEST(PrescribedMotion, APrescribedCoordinateAtASteadyMotionCarriesTheGyroscopicCoupling) {
  auto model_text = [](bool prescribed) {
    return std::string("model: gimbal\nparameters: {It: 0.3, Ip: 0.5, k: 40, c: 0.2, w0: 30}\n") +
           (prescribed ? "coordinates: [a2, s]\ninputs: [{name: a1, kind: motion}]\n" : "coordinates: [a1, a2, s]\n") +
           R"(bodies:
  - {name: disk, rotation: [{x: a1}, {y: a2}, {z: s}], mass: 2, inertia: {xx: It, yy: It, zz: Ip}}
forces:
  - {type: generalized, coordinate: a2, value: -k*a2 - c*a2_dot - k*a1}
operating_point:
  type: given
  velocity: {s: w0}
)";
  };
  const Model free = read_model_string(model_text(false), "free.yaml");
  const Model driven = read_model_string(model_text(true), "driven.yaml");
  Equations ef = mbsgen::derive(free), ed = mbsgen::derive(driven);
  LinearEquations lf = mbsgen::linearize(ef), ld = mbsgen::linearize(ed);
  ASSERT_FALSE(ld.at_rest);
  auto near = [](double a, double b) { return std::abs(a - b) <= 1e-14 * std::max({std::abs(a), std::abs(b), 1e-300}); };
  for (std::size_t i = 0; i < 2; ++i) {  // driven rows a2, s = free rows 1, 2
    SCOPED_TRACE(i);
    EXPECT_TRUE(near(value(ed, driven, ld, ld.B[i][0]), -value(ef, free, lf, lf.K[i + 1][0])));
    EXPECT_TRUE(near(value(ed, driven, ld, ld.B1[i][0]), -value(ef, free, lf, lf.Q[i + 1][0])));
    EXPECT_TRUE(near(value(ed, driven, ld, ld.B2[i][0]), -value(ef, free, lf, lf.M[i + 1][0])));
    for (std::size_t j = 0; j < 2; ++j) {
      EXPECT_TRUE(near(value(ed, driven, ld, ld.Q[i][j]), value(ef, free, lf, lf.Q[i + 1][j + 1])));
      EXPECT_TRUE(near(value(ed, driven, ld, ld.K[i][j]), value(ef, free, lf, lf.K[i + 1][j + 1])));
    }
  }
  // The gyroscopic coupling: Q_(a2, a1) = ±Ip w0 = ±15 (the sign depends on the axes' order).
  EXPECT_EQ(std::abs(value(ef, free, lf, lf.Q[1][0])), 15.0);
}

// A marker on the world that turns with a motion input (a rotating anchor): through a bushing's
// torsional spring and damper about z, B = k_r and B1 = d_r on the rotor's angle.
TEST(PrescribedMotion, ATurningMarkerOnTheWorldExcitesThroughItsRotation) {
  const Model model = read_model_string(R"(model: turning_anchor
parameters: {J: 0.01, kr: 3, dr: 0.02}
coordinates: [phi]
inputs: [{name: r, kind: motion}]
markers:
  - {name: anchor, rotation: [{z: r}]}
bodies:
  - {name: rotor, rotation: [{z: phi}], mass: 1, inertia: {xx: 0.006, yy: 0.006, zz: J}, markers: [{name: hub}]}
forces:
  - {type: bushing, between: [anchor, hub], stiffness: {rotation: [0, 0, kr]}, damping: {rotation: [0, 0, dr]}}
)",
                                        "turning_anchor.yaml");
  Equations eq = mbsgen::derive(model);
  LinearEquations lin = mbsgen::linearize(eq);
  EXPECT_EQ(value(eq, model, lin, lin.K[0][0]), 3.0);
  EXPECT_EQ(value(eq, model, lin, lin.B[0][0]), 3.0);
  EXPECT_EQ(value(eq, model, lin, lin.B1[0][0]), 0.02);
  EXPECT_TRUE(lin.B2[0][0].is_zero()) << "the anchor has no mass";
}

// A carrier body's name never clashes with an element of the model.
TEST(PrescribedMotion, TheCarrierOfAMovingMarkerTakesAFreeName) {
  std::string text = kOscillatorOnAMarker;
  text.replace(text.find("outputs:\n"), 9, "outputs:\n  - {name: support_of_ground, type: coordinate, coordinate: x}\n");
  const Model model = read_model_string(text, "oscillator_on_a_marker.yaml");
  Equations eq = mbsgen::derive(model);
  LinearEquations lin = mbsgen::linearize(eq);
  EXPECT_EQ(value(eq, model, lin, lin.B[0][0]), 800.0);
}

}  // namespace
