// The tape and the compiled kernels agree bit for bit (issue 40 §1), on every shipped model of
// generated/models.txt: the tapes `mbsgen generate --tape` wrote beside the fresh kernels (the
// fixture generated_code_is_current), the compiled kernels those of the libraries the build made
// from the same generator. Every kernel ModelKernels has a field for is called through both
// ModelKernels (the tape's through its trampolines) with the same arguments — at the operating
// point with the default parameters (where the exact zeros there are set) and at a state and
// parameters away from it — and every output word and status is compared. Equal operations in
// equal order give equal IEEE results, so the tolerance is zero.
#include "mbsgen/runtime/model/tape.hpp"

#include "tape_models.hpp"  // tape_models(): id and kernels of each shipped model (CMake)

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <cstring>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

using mbsgen::ModelKernels;

// Calls kernel `name` of k with argv (inputs, then outputs, as in its C signature); -100 when k
// does not have it.
int invoke(const ModelKernels& k, const std::string& name, std::vector<double*>& a) {
  auto* v = a.data();
  if (name == "operating_point") return k.operating_point ? k.operating_point(v[0], v[1], v[2]) : -100;
  if (name == "linear") return k.linear ? k.linear(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]) : -100;
  if (name == "residual") return k.residual ? k.residual(v[0], v[1], v[2], v[3], v[4]) : -100;
  if (name == "mass_matrix") return k.mass_matrix ? k.mass_matrix(v[0], v[1], v[2]) : -100;
  if (name == "output_terms") return k.output_terms ? k.output_terms(v[0], v[1], v[2], v[3], v[4]) : -100;
  if (name == "outputs") return k.outputs ? k.outputs(v[0], v[1], v[2], v[3]) : -100;
  if (name == "descriptor") return k.descriptor ? k.descriptor(v[0], v[1], v[2], v[3], v[4], v[5], v[6]) : -100;
  if (name == "reduced") return k.reduced ? k.reduced(v[0], v[1], v[2], v[3], v[4], v[5], v[6]) : -100;
  if (name == "reduced_parts") return k.reduced_parts ? k.reduced_parts(v[0], v[1], v[2]) : -100;
  if (name == "dynamics") return k.dynamics ? k.dynamics(v[0], v[1], v[2], v[3], v[4], v[5]) : -100;
  if (name == "dynamics_jacobian")
    return k.dynamics_jacobian ? k.dynamics_jacobian(v[0], v[1], v[2], v[3], v[4], v[5], v[6]) : -100;
  if (name == "outputs_general") return k.outputs_general ? k.outputs_general(v[0], v[1], v[2], v[3], v[4], v[5]) : -100;
  if (name == "excitation") return k.excitation ? k.excitation(v[0], v[1], v[2], v[3], v[4], v[5]) : -100;
  if (name == "sensitivity")
    return k.sensitivity ? k.sensitivity(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], v[9], v[10], v[11],
                                         v[12], v[13], v[14], v[15])
                         : -100;
  if (name == "operating_point_sensitivity")
    return k.operating_point_sensitivity ? k.operating_point_sensitivity(v[0], v[1], v[2], v[3], v[4]) : -100;
  if (name == "physical") return k.physical ? k.physical(v[0], v[1]) : -100;
  return -200;  // not a kernel of ModelKernels
}

std::vector<std::string> strings(const char* const* a, int n) {
  std::vector<std::string> s;
  for (int i = 0; a && i < n; ++i) s.push_back(a[i] ? a[i] : "(null)");
  return s;
}

void expect_same_description(const ModelKernels& t, const ModelKernels& c) {
  EXPECT_STREQ(t.model, c.model);
  EXPECT_STREQ(t.scene, c.scene);
  EXPECT_EQ(t.abi_version, c.abi_version);
  EXPECT_EQ(t.n_coordinates, c.n_coordinates);
  EXPECT_EQ(t.n_inputs, c.n_inputs);
  EXPECT_EQ(t.n_outputs, c.n_outputs);
  EXPECT_EQ(t.n_parameters, c.n_parameters);
  EXPECT_EQ(t.at_rest, c.at_rest);
  EXPECT_EQ(t.equilibrium, c.equilibrium);
  EXPECT_EQ(t.default_from_hz, c.default_from_hz);
  EXPECT_EQ(t.default_to_hz, c.default_to_hz);
  EXPECT_EQ(t.default_points, c.default_points);
  EXPECT_EQ(t.default_linear_spacing, c.default_linear_spacing);
  EXPECT_STREQ(t.generator_version, c.generator_version);
  EXPECT_EQ(strings(t.coordinate_names, t.n_coordinates), strings(c.coordinate_names, c.n_coordinates));
  EXPECT_EQ(strings(t.coordinate_units, t.n_coordinates), strings(c.coordinate_units, c.n_coordinates));
  EXPECT_EQ(strings(t.parameter_names, t.n_parameters), strings(c.parameter_names, c.n_parameters));
  EXPECT_EQ(strings(t.parameter_units, t.n_parameters), strings(c.parameter_units, c.n_parameters));
  EXPECT_EQ(strings(t.input_names, t.n_inputs), strings(c.input_names, c.n_inputs));
  EXPECT_EQ(strings(t.input_units, t.n_inputs), strings(c.input_units, c.n_inputs));
  EXPECT_EQ(strings(t.output_names, t.n_outputs), strings(c.output_names, c.n_outputs));
  EXPECT_EQ(strings(t.output_units, t.n_outputs), strings(c.output_units, c.n_outputs));
  EXPECT_EQ(strings(t.input_kinds, t.n_inputs), strings(c.input_kinds, c.n_inputs));
  for (int i = 0; i < c.n_parameters; ++i) EXPECT_EQ(t.parameter_defaults[i], c.parameter_defaults[i]) << i;
  EXPECT_EQ(t.n_speeds, c.n_speeds);
  EXPECT_EQ(strings(t.speed_names, t.n_speeds), strings(c.speed_names, c.n_speeds));
  EXPECT_EQ(t.n_reduced, c.n_reduced);
  EXPECT_EQ(strings(t.reduced_coordinate_names, t.n_reduced), strings(c.reduced_coordinate_names, c.n_reduced));
  EXPECT_EQ(strings(t.reduced_part_names, t.n_reduced_parts), strings(c.reduced_part_names, c.n_reduced_parts));
  if (c.sensitivity || !t.sensitivity) {
    EXPECT_EQ(t.n_sensitivity_parameters, c.n_sensitivity_parameters);
    EXPECT_EQ(strings(t.sensitivity_parameter_names, t.n_sensitivity_parameters),
              strings(c.sensitivity_parameter_names, c.n_sensitivity_parameters));
  } else {  // without the symbolic kernel, the tape's by forward mode: by every parameter
    EXPECT_EQ(strings(t.sensitivity_parameter_names, t.n_sensitivity_parameters),
              strings(c.parameter_names, c.n_parameters));
  }
  EXPECT_EQ(t.n_checks, c.n_checks);
  EXPECT_EQ(strings(t.check_kinds, t.n_checks), strings(c.check_kinds, c.n_checks));
  EXPECT_EQ(strings(t.check_labels, t.n_checks), strings(c.check_labels, c.n_checks));
  EXPECT_EQ(strings(t.check_units, t.n_checks), strings(c.check_units, c.n_checks));
  EXPECT_EQ(strings(t.check_parameters, t.n_checks), strings(c.check_parameters, c.n_checks));
  EXPECT_STREQ(t.evaluation, "tape");
  EXPECT_EQ(c.evaluation, nullptr);
}

// The compiled model's kernels that the tape lacks (or has in excess), by name.
void expect_same_kernels(const ModelKernels& t, const ModelKernels& c) {
  const std::vector<std::pair<const char*, std::pair<bool, bool>>> present = {
      {"operating_point", {!!t.operating_point, !!c.operating_point}}, {"linear", {!!t.linear, !!c.linear}},
      {"residual", {!!t.residual, !!c.residual}}, {"mass_matrix", {!!t.mass_matrix, !!c.mass_matrix}},
      {"output_terms", {!!t.output_terms, !!c.output_terms}}, {"outputs", {!!t.outputs, !!c.outputs}},
      {"descriptor", {!!t.descriptor, !!c.descriptor}}, {"reduced", {!!t.reduced, !!c.reduced}},
      {"reduced_parts", {!!t.reduced_parts, !!c.reduced_parts}}, {"dynamics", {!!t.dynamics, !!c.dynamics}},
      {"dynamics_jacobian", {!!t.dynamics_jacobian, !!c.dynamics_jacobian}},
      {"outputs_general", {!!t.outputs_general, !!c.outputs_general}},
      {"excitation", {!!t.excitation, !!c.excitation}}, {"sensitivity", {!!t.sensitivity, !!c.sensitivity}},
      {"operating_point_sensitivity", {!!t.operating_point_sensitivity, !!c.operating_point_sensitivity}},
      {"physical", {!!t.physical, !!c.physical}}};
  const bool forward_mode = !c.sensitivity && t.sensitivity;  // (ForwardSensitivities… below)
  for (const auto& [name, has] : present) {
    if (!forward_mode || std::string(name).find("sensitivity") == std::string::npos) {
      EXPECT_EQ(has.first, has.second) << "kernel " << name;
    }
  }
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b, std::string& where) {
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(double)) != 0) {
      char s[120];
      std::snprintf(s, sizeof s, "[%zu]: tape %.17g, compiled %.17g", i, a[i], b[i]);
      where = s;
      return false;
    }
  return true;
}

// Calls one kernel of both with inputs from `value` (by argument name) and compares.
void compare_kernel(const mbsgen::TapeKernelInfo& info, const ModelKernels& t, const ModelKernels& c,
                    const std::function<double(const std::string&, std::size_t)>& value, const std::string& at) {
  std::vector<std::vector<double>> in, out_t, out_c;
  for (const auto& [name, n] : info.inputs) {
    in.emplace_back(n + 1);  // (+1: never a null pointer)
    for (std::size_t i = 0; i < n; ++i) in.back()[i] = value(name, i);
  }
  for (const auto& [name, n] : info.outputs) {
    out_t.emplace_back(n + 1, 7.0);  // the same garbage in both: a zero_fill kernel writes every entry
    out_c.emplace_back(n + 1, 7.0);
  }
  std::vector<double*> a_t, a_c;
  for (auto& v : in) a_t.push_back(v.data()), a_c.push_back(v.data());
  for (auto& v : out_t) a_t.push_back(v.data());
  for (auto& v : out_c) a_c.push_back(v.data());
  const int st = invoke(t, info.name, a_t), sc = invoke(c, info.name, a_c);
  if (st == -200) return;  // not one of ModelKernels' kernels
  ASSERT_EQ(st, sc) << info.name << " at " << at;
  for (std::size_t o = 0; o < out_t.size(); ++o) {
    std::string where;
    EXPECT_TRUE(same_bits(out_t[o], out_c[o], where))
        << info.name << " " << info.outputs[o].first << where << " at " << at;
  }
}

TEST(TapeModel, AgreesWithTheCompiledKernelsOfEveryShippedModel) {
  std::size_t compared = 0;
  for (const auto& [id, kernels] : tape_models()) {
    SCOPED_TRACE(id);
    const std::string path = std::string(MBSGEN_FRESH_DIR) + "/" + id + "/" + id + ".tape";
    std::unique_ptr<mbsgen::TapeModel> tape;
    try {
      tape = mbsgen::TapeModel::load(path);
    } catch (const mbsgen::Error& e) {
      if (kernels().assemble) continue;  // closed loops: no tape (`mbsgen generate --tape` refuses)
      FAIL() << e.what();
    }
    ASSERT_EQ(kernels().assemble, nullptr) << "a model with closed loops has a tape";
    const ModelKernels& t = tape->kernels();
    const ModelKernels& c = kernels();
    expect_same_description(t, c);
    expect_same_kernels(t, c);
    // The operating point at the default parameters, and a state and parameters away from it.
    const std::size_t f = static_cast<std::size_t>(c.n_coordinates);
    std::vector<double> p(c.parameter_defaults, c.parameter_defaults + c.n_parameters), y0(f + 1), yd0(f + 1);
    ASSERT_EQ(c.operating_point(p.data(), y0.data(), yd0.data()), 0);
    std::mt19937_64 random(42);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<double> noise(4096);
    for (double& x : noise) x = u(random);
    for (int away = 0; away < 2; ++away) {
      auto value = [&](const std::string& name, std::size_t i) {
        const double d = away ? 0.1 * noise[(i * 7 + name.size() * 131) % noise.size()] : 0.0;
        if (name == "p") return p[i] * (1 + 0.1 * d);
        if (name == "y0" || name == "y") return y0[i] + d;
        if (name == "yd0" || name == "yd") return yd0[i] + d;
        return noise[(i * 13 + name.size() * 17) % noise.size()];  // ydd, u, dy0, dyd0
      };
      for (const auto& info : tape->kernel_info()) {
        compare_kernel(info, t, c, value, away ? "a state away from the operating point" : "the operating point");
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 100u);
}

// The tape's sensitivities by forward mode (issue 40 §2) against the symbolic sensitivity kernel,
// on every shipped model that has one: the tapes with their symbolic kernels taken out, so that
// forward mode answers, through GeneratedModel::linear_sensitivities as `modes --sensitivity`
// uses it (the operating point's derivatives included; along the named parameters only). Two ways of differentiating, each in
// double precision: they agree to the rounding of the chains of operations that compute them,
// bounded here as 1e-13 of the largest entry of the two blocks (500 units in the last place;
// measured on 2026-11-29: 2.4e-16 at most over the 10 models and every parameter).
std::string without_kernel(std::string text, const std::string& name) {
  const std::size_t from = text.find("\nkernel " + name + " ");
  if (from == std::string::npos) return text;
  const std::size_t to = text.find("\nend\n", from);
  return text.erase(from, to + 4 - from);
}

double largest_difference = 0;  // relative to the block's largest entry, over every comparison

void expect_close(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, const std::string& what) {
  ASSERT_EQ(a.rows(), b.rows()) << what;
  ASSERT_EQ(a.cols(), b.cols()) << what;
  if (a.size() == 0) return;
  const double scale = std::max(a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff());
  if (scale > 0) largest_difference = std::max(largest_difference, (a - b).cwiseAbs().maxCoeff() / scale);
  EXPECT_LE((a - b).cwiseAbs().maxCoeff(), 1e-13 * scale) << what << ": forward mode\n" << a << "\nsymbolic\n" << b;
}

TEST(TapeModel, ForwardSensitivitiesAgreeWithTheSymbolicKernel) {
  int models = 0;
  for (const auto& [id, kernels] : tape_models()) {
    const ModelKernels& c = kernels();
    if (!c.sensitivity || c.assemble) continue;
    SCOPED_TRACE(id);
    std::ifstream in(std::string(MBSGEN_FRESH_DIR) + "/" + id + "/" + id + ".tape");
    std::stringstream text;
    text << in.rdbuf();
    const auto tape = mbsgen::TapeModel::parse(
        without_kernel(without_kernel(text.str(), "sensitivity"), "operating_point_sensitivity"), id);
    const ModelKernels& t = tape->kernels();
    ASSERT_NE(t.sensitivity, nullptr);
    EXPECT_EQ(t.n_sensitivity_parameters, t.n_parameters);  // forward mode: by every parameter
    mbsgen::GeneratedModel by_tape(t), by_kernel(c);
    const mbsgen::OperatingPoint op = by_kernel.operating_point();
    const std::vector<std::string> names = strings(c.sensitivity_parameter_names, c.n_sensitivity_parameters);
    const auto a = by_tape.linear_sensitivities(by_tape.operating_point(), names);
    const auto b = by_kernel.linear_sensitivities(op, names);
    ASSERT_EQ(a.size(), b.size());
    // Along two parameters only, in the other order (sensitivity_along: a pass per chosen
    // parameter, issue 42): each direction's arithmetic is its own, so the very same numbers.
    const auto two = by_tape.linear_sensitivities(by_tape.operating_point(), {names.back(), names.front()});
    ASSERT_EQ(two.size(), 2u);
    EXPECT_EQ(two[0].parameter, a.back().parameter);
    EXPECT_TRUE(two[0].K == a.back().K && two[0].M == a.back().M && two[0].B == a.back().B && two[0].dy0 == a.back().dy0);
    EXPECT_TRUE(two[1].K == a.front().K && two[1].Q == a.front().Q && two[1].C_y == a.front().C_y &&
                two[1].dy0 == a.front().dy0);
    for (std::size_t j = 0; j < a.size(); ++j) {
      const std::string what = "d/d" + a[j].parameter;
      using S = mbsgen::MatrixSensitivity;
      const std::initializer_list<std::pair<const char*, Eigen::MatrixXd S::*>> matrices = {
          {"M", &S::M},     {"Q", &S::Q}, {"K", &S::K},   {"B", &S::B},   {"C_y", &S::C_y}, {"C_v", &S::C_v},
          {"C_a", &S::C_a}, {"D", &S::D}, {"B1", &S::B1}, {"B2", &S::B2}, {"D1", &S::D1}};
      for (const auto& [name, m] : matrices) expect_close(a[j].*m, b[j].*m, what + " " + name);
      expect_close(a[j].dy0, b[j].dy0, what + " y0");
      expect_close(a[j].dyd0, b[j].dyd0, what + " yd0");
    }
    ++models;
  }
  EXPECT_GE(models, 8);
  std::cout << "forward mode against the symbolic kernels of " << models << " models: largest difference "
            << largest_difference << " of the block's largest entry\n";
}

}  // namespace
