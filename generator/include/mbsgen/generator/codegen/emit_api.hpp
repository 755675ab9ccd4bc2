// The typed C++ API over a model's generated kernels (issue 4): `<id>_model.hpp` declares, in
// namespace <id>, a Parameters struct with the model's defaults, enums naming coordinates,
// inputs and outputs, and functions returning the runtime's GeneratedModel and LinearModel;
// `<id>_model.cpp` fills the mbsgen::ModelKernels descriptor (mbsgen/runtime/model/generated_model.hpp)
// that the solver command line works on.
#pragma once

#include "mbsgen/generator/codegen/emit.hpp"

#include <string>

namespace mbsgen {

struct GeneratedApi {
  std::string id;
  std::string header, source;
};

/// model: the model as generated (for a scene, the scene's model); code: what emit() returned
/// for it; from_hz, to_hz: the scene's default frequency range (0, 0 for none).
GeneratedApi emit_api(const Model& model, const LinearEquations& lin, const GeneratedCode& code,
                      const std::string& scene, double from_hz = 0, double to_hz = 0,
                      int points = 0, bool linear_spacing = false);

/// `<id>_model.hpp` and `<id>_model.cpp` in dir, for write_files (output_files.hpp).
std::vector<OutputFile> api_files(const GeneratedApi& api, const std::string& dir);

/// Writes `<id>_model.hpp` and `<id>_model.cpp` into dir, both or neither; unchanged files are
/// not touched.
void write_api(const GeneratedApi& api, const std::string& dir);

/// Writes the five files of `mbsgen generate` (write_generated's three and write_api's two)
/// into dir, all or nothing (write_files): every target is checked before any is written.
void write_generated(const GeneratedCode& code, const GeneratedApi& api, const std::string& dir);

}  // namespace mbsgen
