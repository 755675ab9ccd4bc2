// Closed loops (issue 15 §5): generation time of the loaded four-bar and of planar ladders of N
// closed loops (parametric_chains.hpp), medians of 5 runs beside the tree chains' generation in the same run,
// and the operation counts of their kernels.
//   loops_bench [max_ladder_n]     the table (docs/generator.md, "Closed loops")
//   loops_bench --emit DIR         writes the four-bar's kernels (for loops_kernel_timing)
#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/model/parametric_chains.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

namespace {

struct Result {
  double seconds;
  mbsgen::GeneratedCode code;
};

Result run(const std::function<mbsgen::Model()>& make) {
  const auto t0 = std::chrono::steady_clock::now();
  mbsgen::Model model = make();
  mbsgen::Equations eq = mbsgen::derive(model);
  mbsgen::LinearEquations lin = mbsgen::linearize(eq);
  mbsgen::GeneratedCode code = mbsgen::emit(model, eq, lin);
  return {std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), code};
}

std::size_t ops(const mbsgen::GeneratedCode& code, const std::string& kernel) {
  for (const auto& k : code.kernels)
    if (k.name == kernel) return k.operations;
  return 0;
}

void row(const std::string& name, int coordinates, int equations, const std::function<mbsgen::Model()>& make) {
  std::vector<double> times;
  Result r{};
  for (int i = 0; i < 5; ++i) {
    r = run(make);
    times.push_back(r.seconds);
  }
  std::sort(times.begin(), times.end());
  std::printf("| %s | %d | %d | %.4f | %zu | %zu | %zu | %zu | %zu |\n", name.c_str(), coordinates, equations,
              times[2], ops(r.code, "constraints") + ops(r.code, "constraint_jacobian"), ops(r.code, "mass_matrix"),
              ops(r.code, "residual"), ops(r.code, "linear"), ops(r.code, "bodies"));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--emit") {
    mbsgen::Model model = mbsgen::four_bar_linkage();
    mbsgen::Equations eq = mbsgen::derive(model);
    mbsgen::LinearEquations lin = mbsgen::linearize(eq);
    mbsgen::write_generated(mbsgen::emit(model, eq, lin), argv[2]);
    return 0;
  }
  const int max_ladder = argc > 1 ? std::stoi(argv[1]) : 10;
  std::printf("| model | tree coordinates | constraint equations | generation median [s] | Phi + Phi_y ops | M ops | k-q ops | linear ops | bodies ops |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  row("planar chain 3 (tree, baseline)", 3, 0, [] { return mbsgen::planar_chain(3); });
  row("four-bar (loaded)", 3, 2, [] { return mbsgen::four_bar_linkage(); });
  for (int n : {1, 2, 5, 10, 20})
    if (n <= max_ladder)
      row("ladder " + std::to_string(n), 3 * n, 2 * n, [n] { return mbsgen::ladder(n); });
  return 0;
}
