// A model's kernels as a tape (issue 40 §1): the text the runtime's TapeModel
// (mbsgen/runtime/model/tape.hpp) evaluates without a compiler. It holds what ModelKernels holds —
// the names, units, defaults and sizes, and per kernel its arguments and its straight-line
// statements exactly as emit() prints them for the compiler — so that the tape and the compiled
// kernels do the same floating-point operations in the same order (docs/generated-abi.md,
// "Tapes"). A model with closed loops has no tape.
#pragma once

#include "mbsgen/generator/codegen/emit.hpp"

#include <string>

namespace mbsgen {

/// The tape of code (what emit() returned for model): empty when code has none (closed loops).
/// The other arguments as emit_api's.
std::string emit_tape(const Model& model, const LinearEquations& lin, const GeneratedCode& code,
                      const std::string& scene, double from_hz = 0, double to_hz = 0, int points = 0,
                      bool linear_spacing = false);

}  // namespace mbsgen
