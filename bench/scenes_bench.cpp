// Scenes benchmark (issue 5 §5, docs/scenes.md): for the middle ear, the spinning rotor, the
// Jeffcott rotor and the planar chain, the full model against each of its scenes — generation time, operation
// counts of the emitted kernels, evaluation time of the `linear` kernel, and the time of a
// whole frequency sweep (kernel at the operating point, LinearModel, FrequencyResponse for every
// input column and every output row the scene keeps). Times are the best of 21 batches (kernel)
// and of 11 sweeps.
//
// Each case is generated in process, its kernels compiled with the C++ compiler the benchmark
// was built with (-O2, a shared library) and loaded with dlopen, so one program measures every
// scene without a build step per scene.
//
// Usage: scenes_bench [chain_links...]     (default: 10 20)
//
// Built by bench/CMakeLists.txt, inside `if(TARGET mbsgen_generator)`:
//   add_executable(scenes_bench scenes_bench.cpp)
//   target_link_libraries(scenes_bench PRIVATE mbsgen::generator mbsgen::runtime ${CMAKE_DL_LIBS})
//   target_compile_definitions(scenes_bench PRIVATE MBSGEN_BENCH_CXX="${CMAKE_CXX_COMPILER}"
//                                                   MBSGEN_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
//   mbsgen_set_warnings(scenes_bench)
#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/model/parametric_chains.hpp"
#include "mbsgen/generator/model/scene.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#ifndef MBSGEN_BENCH_CXX
#define MBSGEN_BENCH_CXX "c++"
#endif
#ifndef MBSGEN_SOURCE_DIR
#define MBSGEN_SOURCE_DIR "."
#endif

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

using LinearKernel = int (*)(const double*, const double*, const double*, double*, double*, double*,
                             double*, double*, double*);
using OperatingPointKernel = int (*)(const double*, double*, double*);

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The fastest of several runs: on a shared machine the other runs measure the neighbours.
double best(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

struct Loaded {
  int n = 0, nu = 0, nr = 0;
  std::vector<double> p;
  LinearKernel linear = nullptr;
  OperatingPointKernel operating_point = nullptr;
};

// Writes the kernels, compiles them into a shared library and loads it.
Loaded compile_and_load(const mbsgen::GeneratedCode& code, const mbsgen::Model& model, const fs::path& dir) {
  mbsgen::write_generated(code, dir.string());
  const fs::path lib = dir / ("lib" + code.id + ".so");
  const std::string command = std::string(MBSGEN_BENCH_CXX) + " -O2 -std=c++17 -shared -fPIC -o '" +
                              lib.string() + "' '" + (dir / (code.id + ".cpp")).string() + "'";
  if (std::system(command.c_str()) != 0) throw std::runtime_error("compiling failed: " + command);
  void* handle = dlopen(lib.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) throw std::runtime_error(std::string("dlopen: ") + dlerror());
  Loaded k;
  k.n = static_cast<int>(model.coordinates().size());
  k.nu = static_cast<int>(model.inputs().size());
  k.nr = static_cast<int>(model.outputs().size());
  for (const auto& q : model.parameters()) k.p.push_back(q.value);
  k.linear = reinterpret_cast<LinearKernel>(dlsym(handle, (code.id + "_linear").c_str()));
  k.operating_point =
      reinterpret_cast<OperatingPointKernel>(dlsym(handle, (code.id + "_operating_point").c_str()));
  if (!k.linear || !k.operating_point) throw std::runtime_error("missing kernels in " + lib.string());
  return k;
}

struct Row {
  std::string model, scene;
  double generation_s = 0;
  std::size_t linear_ops = 0, all_ops = 0;
  std::string kernels;
  double linear_us = 0;
  double sweep_ms = -1;  // < 0: the scene asks for no frf
  int solves = 0;        // input columns × frequencies
  double modes_ms = -1;  // < 0: the scene asks for no modes
  std::string modes_method;
};

Row measure(const mbsgen::Model& model, const std::string& scene, const std::string& label,
            const fs::path& dir, const Eigen::VectorXd& omega) {
  Row row;
  row.model = label;
  row.scene = scene;
  const auto t0 = Clock::now();
  const mbsgen::Model pruned = mbsgen::apply_scene(model, scene);
  mbsgen::Equations eq = mbsgen::derive(pruned);
  mbsgen::LinearEquations lin = mbsgen::linearize(eq);
  mbsgen::EmitOptions options;
  options.id = "bench_" + label + "_" + scene;
  const mbsgen::GeneratedCode code = mbsgen::emit(pruned, eq, lin, options);
  row.generation_s = seconds_since(t0);
  for (const auto& k : code.kernels) {
    if (k.name == "linear") row.linear_ops = k.operations;
    row.all_ops += k.operations;
    row.kernels += (row.kernels.empty() ? "" : " ") + k.name;
  }

  const Loaded k = compile_and_load(code, pruned, dir);
  const auto n = static_cast<Eigen::Index>(k.n);
  Eigen::VectorXd y0(n), yd0(n);
  k.operating_point(k.p.data(), y0.data(), yd0.data());
  Eigen::MatrixXd M(n, n), Q(n, n), K(n, n), B(n, k.nu), Cy(k.nr, n), Cv(k.nr, n);
  auto evaluate = [&] {
    return k.linear(y0.data(), yd0.data(), k.p.data(), M.data(), Q.data(), K.data(), B.data(),
                    Cy.data(), Cv.data());
  };
  // Kernel: the best of 21 batches of calls, each batch about 20 ms.
  int calls = 1;
  for (auto t = Clock::now(); seconds_since(t) < 0.02; calls *= 2)
    for (int i = 0; i < calls; ++i) evaluate();
  std::vector<double> per_call;
  for (int batch = 0; batch < 21; ++batch) {
    const auto t = Clock::now();
    for (int i = 0; i < calls; ++i) evaluate();
    per_call.push_back(seconds_since(t) / calls);
  }
  row.linear_us = best(per_call) * 1e6;

  const auto& analyses = pruned.selection().analyses;
  const bool frf = std::find(analyses.begin(), analyses.end(), mbsgen::Analysis::frf) != analyses.end();
  if (std::find(analyses.begin(), analyses.end(), mbsgen::Analysis::modes) != analyses.end()) {
    // All eigenvalues: the kernel at the operating point and the quadratic eigensolver, which
    // takes its symmetric path when Q is exactly zero and M, K exactly symmetric.
    std::vector<double> times;
    mbsgen::QuadraticEigenSolver solver(n);
    for (int rep = 0; rep < 11; ++rep) {
      const auto t = Clock::now();
      if (evaluate() != 0) throw std::runtime_error("non-finite linear model");
      solver.compute(M, Q, K);
      times.push_back(seconds_since(t));
    }
    row.modes_ms = best(times) * 1e3;
    row.modes_method = solver.method();
  }
  if (frf && k.nu > 0 && k.nr > 0) {
    // A whole sweep: the kernel at the operating point, the linear model, and the response of
    // every output row the scene keeps to every input column it keeps.
    std::vector<double> times;
    for (int rep = 0; rep < 11; ++rep) {
      const auto t = Clock::now();
      if (evaluate() != 0) throw std::runtime_error("non-finite linear model");
      const mbsgen::LinearModel lm(M, Q, K, B, Cy, Cv);
      mbsgen::FrequencyResponse fr(lm);
      for (Eigen::Index j = 0; j < k.nu; ++j) fr.compute(omega, j);
      times.push_back(seconds_since(t));
    }
    row.sweep_ms = best(times) * 1e3;
    row.solves = k.nu * static_cast<int>(omega.size());
  }
  return row;
}

// The planar N-link chain of parametric_chains.hpp with an excitation and an output on every link: a
// horizontal force F<i> at mass i and its horizontal position x<i>; the scene frf_tip keeps the
// force at the tip and the tip's position only.
mbsgen::Model excited_chain(int n) {
  mbsgen::Model model = mbsgen::planar_chain(n);
  for (int i = 1; i <= n; ++i) {
    const std::string s = std::to_string(i);
    const GiNaC::ex F = model.add_input("F" + s, "N");
    mbsgen::Marker mass;
    mass.name = "mass" + s;
    mass.body = "link" + s;
    mass.position = {0, -model.symbol("l" + s), 0};
    model.add_marker(mass);
    mbsgen::AppliedForce force;
    force.name = "force" + s;
    force.marker = mass.name;
    force.force = {F, 0, 0};
    model.add_applied_force(force);
    mbsgen::Output x;
    x.name = "x" + s;
    x.kind = mbsgen::OutputKind::position;
    x.marker = mass.name;
    x.direction = {1, 0, 0};
    model.add_output(x);
  }
  mbsgen::Scene tip;
  tip.name = "frf_tip";
  tip.analyses = {mbsgen::Analysis::frf};
  tip.inputs = std::vector<mbsgen::SceneItem>{{"F" + std::to_string(n), {}}};
  tip.outputs = std::vector<mbsgen::SceneItem>{{"x" + std::to_string(n), {}}};
  model.add_scene(tip);
  return model;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> links;
  for (int i = 1; i < argc; ++i) links.push_back(std::stoi(argv[i]));
  if (links.empty()) links = {10, 20};
  const fs::path dir = fs::temp_directory_path() / "mbsgen_scenes_bench";
  fs::create_directories(dir);
  // 1000 log-spaced frequencies per case: 0.1–100 Hz for the rotors and chains, 100 Hz–10 kHz
  // (the `transfer` scene's range) for the middle ear.
  auto frequencies = [](double from_hz, double to_hz) {
    Eigen::VectorXd omega(1000);
    for (Eigen::Index i = 0; i < omega.size(); ++i)
      omega[i] = 2 * std::acos(-1.0) * from_hz *
                 std::pow(to_hz / from_hz, static_cast<double>(i) / static_cast<double>(omega.size() - 1));
    return omega;
  };

  struct Case {
    std::string label;
    mbsgen::Model model;
    Eigen::VectorXd omega;
  };
  std::vector<Case> cases;
  const std::string models = std::string(MBSGEN_SOURCE_DIR) + "/models/";
  cases.push_back({"middle_ear", mbsgen::read_model_file(models + "middle_ear/middle_ear.yaml"), frequencies(100, 1e4)});
  cases.push_back({"rotor_disk", mbsgen::read_model_file(models + "textbook/rotor_disk.yaml"), frequencies(0.1, 100)});
  cases.push_back({"jeffcott_rotor", mbsgen::read_model_file(models + "textbook/jeffcott_rotor.yaml"), frequencies(0.1, 100)});
  for (int n : links) cases.push_back({"chain" + std::to_string(n), excited_chain(n), frequencies(0.1, 100)});

  std::printf("| model | scene | kernels | generation [s] | linear ops | all kernels ops | linear [us] | modes [ms] (method) | sweep [ms] | solves |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& c : cases) {
    std::vector<std::string> scenes = {mbsgen::kFullScene};
    for (const auto& s : c.model.scenes()) scenes.push_back(s.name);
    for (const auto& s : scenes) {
      const Row r = measure(c.model, s, c.label, dir, c.omega);
      char sweep[32] = "-", modes[64] = "-";
      if (r.sweep_ms >= 0) std::snprintf(sweep, sizeof sweep, "%.3f", r.sweep_ms);
      if (r.modes_ms >= 0) std::snprintf(modes, sizeof modes, "%.3f (%s)", r.modes_ms, r.modes_method.c_str());
      std::printf("| %s | %s | %s | %.3f | %zu | %zu | %.3f | %s | %s | %d |\n", r.model.c_str(), r.scene.c_str(),
                  r.kernels.c_str(), r.generation_s, r.linear_ops, r.all_ops, r.linear_us, modes, sweep,
                  r.solves);
      std::fflush(stdout);
    }
  }
  return 0;
}
