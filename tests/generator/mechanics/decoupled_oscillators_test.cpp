// A model of many decoupled oscillators (issue 14 §4: `mbsgen check` of 2,000 of them used to
// take minutes, its cost growing as n^3.2): each body on its own coordinate and its own spring to
// the ground. The test reads, derives, linearizes and checks 300 of them and compares the linear
// model with its closed form, exactly. It asserts nothing about time (bench/decoupled_oscillators.py
// writes the same model for timing, docs/generator.md).
#include "mbsgen/generator/linear/operating_point_check.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include <gtest/gtest.h>

#include <string>

namespace mbsgen {
namespace {

using GiNaC::ex;
using GiNaC::numeric;

// The model of bench/decoupled_oscillators.py: body i (mass 1 + i/n kg) moves along x by x_i; a
// spring of stiffness 100 i N/m and rest length L0 = 1 m joins it to a world marker at
// x = i - L0, so that x_i = i is its rest position.
std::string oscillators(int n) {
  const std::string N = std::to_string(n);
  std::string coordinates, bodies, markers, forces, position;
  for (int i = 1; i <= n; ++i) {
    const std::string I = std::to_string(i);
    coordinates += "  - {name: x" + I + ", unit: m}\n";
    bodies += "  - {name: b" + I + ", translation: [x" + I + ", 0, 0], mass: 1 + " + I + "/" + N +
              ", markers: [{name: p" + I + "}]}\n";
    markers += "  - {name: a" + I + ", position: [" + I + " - L0, 0, 0]}\n";
    forces += "  - {type: spring, between: [a" + I + ", p" + I + "], stiffness: " +
              std::to_string(100 * i) + ", rest_length: L0}\n";
    position += (i > 1 ? ", x" : "x") + I + ": " + I;
  }
  return "model: oscillators_" + N + "\nparameters:\n  L0: {value: 1, unit: m}\ncoordinates:\n" +
         coordinates + "bodies:\n" + bodies + "markers:\n" + markers + "forces:\n" + forces +
         "operating_point:\n  position: {" + position + "}\n";
}

TEST(DecoupledOscillators, ThreeHundredCheckAndLinearizeToTheClosedForm) {
  const int n = 300;
  const Model model = read_model_string(oscillators(n), "oscillators.yaml");
  ASSERT_EQ(model.coordinates().size(), static_cast<std::size_t>(n));
  Equations eq = derive(model);
  LinearEquations lin = linearize(eq);
  ASSERT_NO_THROW(check_operating_point(eq, lin));

  // Closed form: M = diag(1 + i/n), K = diag(100 i), Q = 0, exactly (L0 = 1 is exact).
  GiNaC::exmap at_op{{model.symbol("L0"), 1}};
  for (int i = 1; i <= n; ++i) at_op[model.symbol("x" + std::to_string(i))] = i;
  auto exact = [&](const ex& e) { return eq.program.inline_all(e).subs(at_op).normal(); };
  std::size_t nonzero_off_diagonal = 0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) {
    const int k = static_cast<int>(i) + 1;
    EXPECT_TRUE((exact(lin.M[i][i]) - (1 + numeric(k, n))).is_zero()) << "M" << i << i;
    EXPECT_TRUE((exact(lin.K[i][i]) - 100 * k).is_zero()) << "K" << i << i << " = " << exact(lin.K[i][i]);
    EXPECT_TRUE(lin.Q[i][i].is_zero()) << "Q" << i << i;
    // Decoupled: every off-diagonal entry is an exact zero of the derivation, not a small number.
    for (std::size_t j = 0; j < static_cast<std::size_t>(n); ++j)
      if (i != j && !(lin.M[i][j].is_zero() && lin.K[i][j].is_zero() && lin.Q[i][j].is_zero()))
        ++nonzero_off_diagonal;
  }
  EXPECT_EQ(nonzero_off_diagonal, 0u);
  EXPECT_TRUE(lin.D_zero && lin.G_zero && lin.N_zero);
}

// The checks still find a fault among many: one of 200 oscillators given 1 m away from its rest
// position fails at the operating point, naming its coordinate.
TEST(DecoupledOscillators, ANonEquilibriumIsFoundAmongMany) {
  std::string text = oscillators(200);
  const std::string wrong = "x150: 150";
  text.replace(text.find(wrong), wrong.size(), "x150: 151");
  const Model model = read_model_string(text, "oscillators.yaml");
  Equations eq = derive(model);
  LinearEquations lin = linearize(eq);
  try {
    check_operating_point(eq, lin);
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    // k_150 (x - x_rest) = 15000 N at 1 m from rest; the tolerance is 1e-9 of max|K| max(1, |y0|).
    EXPECT_NE(std::string(e.what()).find("the residual k - q is x150: 1.5e+04 "), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace mbsgen
