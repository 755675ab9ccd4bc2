// Generation benchmark (issue 2 §7): time to derive, linearize and emit the N-link planar and
// spatial chains, and the operation counts of the emitted kernels. Reports the median of
// several runs. Usage: generation_bench [max_planar_n] [max_spatial_n] [repeats]
//        generation_bench --emit DIR   writes the planar 10-link chain's kernels (for kernel_timing)
#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/model/parametric_chains.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

namespace {

struct Result {
  double seconds;
  mbsgen::GeneratedCode code;
};

Result run(bool planar, int n, bool cse) {
  auto t0 = std::chrono::steady_clock::now();
  mbsgen::Model model = planar ? mbsgen::planar_chain(n) : mbsgen::spatial_chain(n);
  mbsgen::Equations eq = mbsgen::derive(model);
  mbsgen::LinearEquations lin = mbsgen::linearize(eq);
  mbsgen::EmitOptions options;
  options.cse = cse;
  mbsgen::GeneratedCode code = mbsgen::emit(model, eq, lin, options);
  return {std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), code};
}

std::size_t ops(const mbsgen::GeneratedCode& code, const std::string& kernel) {
  for (const auto& k : code.kernels)
    if (k.name == kernel) return k.operations;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--emit") {
    mbsgen::Model model = mbsgen::planar_chain(10);
    mbsgen::Equations eq = mbsgen::derive(model);
    mbsgen::LinearEquations lin = mbsgen::linearize(eq);
    mbsgen::EmitOptions options;
    options.id = "planar_chain_10";
    mbsgen::write_generated(mbsgen::emit(model, eq, lin, options), argv[2]);
    return 0;
  }
  const int max_planar = argc > 1 ? std::stoi(argv[1]) : 40;
  const int max_spatial = argc > 2 ? std::stoi(argv[2]) : 40;
  const int repeats = argc > 3 ? std::stoi(argv[3]) : 3;
  std::printf("| chain | N | coordinates | generation median [s] | M ops | k-q ops | M + k-q ops | linear (M,Q,K,B,C) ops | linear ops without CSE |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (bool planar : {true, false}) {
    for (int n : {2, 5, 10, 20, 40}) {
      if (n > (planar ? max_planar : max_spatial)) continue;
      std::vector<double> times;
      Result r{};
      for (int i = 0; i < repeats; ++i) {
        r = run(planar, n, true);
        times.push_back(r.seconds);
      }
      std::sort(times.begin(), times.end());
      Result plain = run(planar, n, false);
      std::size_t m = ops(r.code, "mass_matrix"), k = ops(r.code, "residual");
      std::printf("| %s | %d | %d | %.3f | %zu | %zu | %zu | %zu | %zu |\n", planar ? "planar" : "spatial", n,
                  planar ? n : 2 * n, times[times.size() / 2], m, k, m + k, ops(r.code, "linear"),
                  ops(plain.code, "linear"));
      std::fflush(stdout);
    }
  }
  return 0;
}
