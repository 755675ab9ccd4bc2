// The sensitivity stage (generator/src/linear/sensitivity.cpp, issue 20 §1): the derivatives it forms
// against the expressions written out and differentiated by GiNaC, the scene's choice of
// parameters, and the refusals with their place in the model file.
#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/linear/linearize.hpp"
#include "mbsgen/generator/linear/sensitivity.hpp"
#include "mbsgen/generator/model/scene.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include <gtest/gtest.h>

#include <string>

namespace {

using mbsgen::Model;
using mbsgen::read_model_string;

const char* const kPendulum = R"(model: spring_pendulum
parameters:
  m: {value: 1.5, unit: kg}
  l: {value: 0.8, unit: m}
  g: {value: 9.81, unit: m/s^2}
  k: {value: 20, unit: N m/rad}
coordinates:
  - {name: phi, unit: rad}
bodies:
  - name: bob
    rotation: [{z: phi}]
    mass: m
    com: [0, -l, 0]
forces:
  - {type: gravity, g: [0, -g, 0]}
  - {name: spring, type: generalized, coordinate: phi, value: -k*phi, category: springs}
scenes:
  - name: stiffness
    analyses: [modes, sensitivity]
    sensitivity: [k, l]
)";

// K = m g l + k, M = m l² (a point mass at rest): dK/dm = g l, dK/dl = m g, dK/dk = 1,
// dM/dl = 2 m l; exactly, as GiNaC differentiates the written-out entries.
TEST(SensitivityStage, DerivativesOfTheWrittenOutEntries) {
  const Model model = read_model_string(kPendulum, "spring_pendulum.yaml");
  mbsgen::Equations eq = mbsgen::derive(model);
  const mbsgen::LinearEquations lin = mbsgen::linearize(eq);
  const mbsgen::LinearSensitivity s = mbsgen::linear_sensitivity(eq, lin, {});
  ASSERT_EQ(s.parameters.size(), 4u);
  EXPECT_FALSE(s.moving_point);
  for (const auto& d : s.matrices) {
    if (d.name != "M" && d.name != "K") continue;
    const mbsgen::ExMatrix& A = d.name == "M" ? lin.M : lin.K;
    for (std::size_t j = 0; j < 4; ++j) {
      const GiNaC::ex expect = eq.program.inline_all(A[0][0]).diff(eq.p[j]);
      EXPECT_TRUE((eq.program.inline_all(d.values[j]) - expect).expand().is_zero())
          << d.name << " by " << eq.p[j] << ": " << eq.program.inline_all(d.values[j]) << " vs " << expect;
    }
  }
}

// The scene's parameters, in the model's order, make the kernel's; the header names them.
TEST(SensitivityStage, TheSceneChoosesTheParameters) {
  const Model scene = mbsgen::apply_scene(read_model_string(kPendulum, "spring_pendulum.yaml"), "stiffness");
  EXPECT_EQ(scene.selection().sensitivity_parameters, (std::vector<std::string>{"l", "k"}));
  mbsgen::Equations eq = mbsgen::derive(scene);
  const mbsgen::LinearEquations lin = mbsgen::linearize(eq);
  mbsgen::EmitOptions options;
  options.scene = "stiffness";
  const mbsgen::GeneratedCode code = mbsgen::emit(scene, eq, lin, options);
  EXPECT_NE(code.header.find("spring_pendulum_stiffness_n_sensitivity_parameters = 2"), std::string::npos) << code.header;
  EXPECT_NE(code.source.find("sensitivity_parameter_names[] = {\"l\", \"k\""), std::string::npos);
  EXPECT_EQ(code.header.find("_operating_point_sensitivity("), std::string::npos);  // a given point that does not move
  EXPECT_NE(code.header.find("_sensitivity(const double* y0"), std::string::npos);
}

// The full model has the sensitivity kernel only when asked (issue 40 §2): by the parameters named,
// in the model's order, or by all; an unknown name and a pruned scene are refused.
TEST(SensitivityStage, TheFullModelHasItOnlyWhenAsked) {
  auto generate = [](const Model& model) {
    mbsgen::Equations eq = mbsgen::derive(model);
    const mbsgen::LinearEquations lin = mbsgen::linearize(eq);
    return mbsgen::emit(model, eq, lin, {});
  };
  Model model = read_model_string(kPendulum, "spring_pendulum.yaml");
  const mbsgen::GeneratedCode plain = generate(model);
  EXPECT_EQ(plain.header.find("_sensitivity("), std::string::npos);
  EXPECT_EQ(plain.header.find("HAS_SENSITIVITY"), std::string::npos);
  model.request_sensitivity({"k", "m"});
  const mbsgen::GeneratedCode asked = generate(model);
  EXPECT_NE(asked.header.find("spring_pendulum_n_sensitivity_parameters = 2"), std::string::npos) << asked.header;
  EXPECT_NE(asked.source.find("sensitivity_parameter_names[] = {\"m\", \"k\""), std::string::npos);
  model.request_sensitivity({});
  EXPECT_NE(generate(model).header.find("spring_pendulum_n_sensitivity_parameters = 4"), std::string::npos);
  try {
    model.request_sensitivity({"kk"});
    FAIL() << "an unknown parameter was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("has no parameter 'kk'"), std::string::npos) << e.what();
  }
  Model scene = mbsgen::apply_scene(read_model_string(kPendulum, "spring_pendulum.yaml"), "stiffness");
  EXPECT_THROW(scene.request_sensitivity({}), std::invalid_argument);
}

// A sensitivity list without the analysis, and an unknown name, are refused at their place.
TEST(SensitivityStage, RefusedWithTheirPlace) {
  std::string text = kPendulum;
  const std::string without = text.replace(text.find("[modes, sensitivity]"), 20, "[modes]");
  try {
    (void)mbsgen::apply_scene(read_model_string(without, "a.yaml"), "stiffness");
    FAIL() << "accepted a sensitivity list without the analysis";
  } catch (const mbsgen::ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("a.yaml:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("does not ask for the analysis 'sensitivity'"), std::string::npos) << e.what();
  }
  std::string typo = kPendulum;
  typo.replace(typo.find("[k, l]"), 6, "[kk, l]");
  try {
    (void)mbsgen::apply_scene(read_model_string(typo, "b.yaml"), "stiffness");
    FAIL() << "accepted an unknown parameter";
  } catch (const mbsgen::ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown parameter 'kk'"), std::string::npos) << e.what();
  }
}

}  // namespace
