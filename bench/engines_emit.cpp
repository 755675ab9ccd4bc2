// Writes the kernels of the N-link spatial chains (mbsgen::spatial_chain) that
// bench/engines_bench.cpp times against MuJoCo and Orocos KDL, with the ids spatial_chain_N.
// Files whose content is unchanged are left untouched (write_generated), so the build recompiles
// a chain's kernels only when the generator's output changed.
//
//   engines_emit DIR N...
#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/model/parametric_chains.hpp"

#include <cstdio>
#include <exception>
#include <string>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: engines_emit DIR N...\n");
    return 2;
  }
  try {
    for (int i = 2; i < argc; ++i) {
      const int n = std::stoi(argv[i]);
      mbsgen::Model model = mbsgen::spatial_chain(n);
      mbsgen::Equations eq = mbsgen::derive(model);
      mbsgen::LinearEquations lin = mbsgen::linearize(eq);
      mbsgen::EmitOptions options;
      options.id = "spatial_chain_" + std::to_string(n);
      options.dynamics = true;  // "M+bias": M and k − q in one call
      mbsgen::write_generated(mbsgen::emit(model, eq, lin, options), argv[1]);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "engines_emit: %s\n", e.what());
    return 1;
  }
  return 0;
}
