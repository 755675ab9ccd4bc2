// Writes the generated kernels of a model built through the C++ API (parametric_chains.hpp), for its full
// model or one of its scenes, optionally with the kernels cut into parts (EmitOptions::parts,
// chunk_operations; 0 operations: none cut); a full model also gets the dynamics kernel
// (EmitOptions::dynamics):
//   gen_api_models planar|spatial|four_bar|ladder N ID OUT_DIR [SCENE [PARTS [CHUNK_OPERATIONS]]]
#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/model/parametric_chains.hpp"
#include "mbsgen/generator/model/scene.hpp"

#include <iostream>
#include <string>

int main(int argc, char** argv) {
  if (argc < 5 || argc > 8) {
    std::cerr << "usage: gen_api_models planar|spatial|four_bar|ladder N ID OUT_DIR [SCENE [PARTS [CHUNK_OPERATIONS]]]\n";
    return 2;
  }
  const std::string kind = argv[1];
  const int n = std::stoi(argv[2]);
  const mbsgen::Model chain = kind == "planar"     ? mbsgen::planar_chain(n)
                              : kind == "four_bar" ? mbsgen::four_bar_linkage()
                              : kind == "ladder"   ? mbsgen::ladder(n)
                                                   : mbsgen::spatial_chain(n);
  const mbsgen::Model model = mbsgen::apply_scene(chain, argc >= 6 ? argv[5] : mbsgen::kFullScene);
  mbsgen::Equations eq = mbsgen::derive(model);
  mbsgen::LinearEquations lin = mbsgen::linearize(eq);
  mbsgen::EmitOptions options;
  options.id = argv[3];
  options.dynamics = model.selection().full;
  if (argc >= 7) options.parts = std::stoul(argv[6]);
  if (argc >= 8) options.chunk_operations = std::stoul(argv[7]);
  mbsgen::write_generated(mbsgen::emit(model, eq, lin, options), argv[4]);
  return 0;
}
