// A model's kernels evaluated from a tape, without a compiler (issue 40 §1).
//
// `mbsgen generate --tape` (and `mbsgen run`) writes `<id>.tape`: the model's names, units,
// defaults and sizes, and per kernel the straight-line statements exactly as the generator
// prints them for the compiler. TapeModel reads it, translates every statement into register
// instructions with C++'s precedence and associativity (a - b + c is (a - b) + c, -a*b is
// (-a)*b, x*x*x is (x*x)*x), and evaluates them in double precision: the same IEEE operations in
// the same order as the compiled kernel, so the results are the same bit for bit (the test
// TapeModel.AgreesWithTheCompiledKernels checks every kernel of every shipped model). Its
// kernels() is a ModelKernels like a compiled model's, so GeneratedModel, the analyses and the
// solver command line work on it unchanged:
//
//     auto tape = mbsgen::TapeModel::load("double_pendulum.tape");
//     mbsgen::GeneratedModel model(tape->kernels());   // tape must outlive model
//     mbsgen::LinearModel lin = model.linear_model();
//
// A tape runs slower per call than compiled code (docs/generated-abi.md, "Tapes": the factor
// measured per kernel) and pays where kernels run a handful of times: modes, frequency
// responses, statics, sweeps. A model with closed loops has no tape. At most kMaxLoaded tapes
// are loaded at once (their kernels are plain C function pointers, bound to one of that many
// slots).
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "mbsgen/runtime/model/generated_model.hpp"

namespace mbsgen {

/// One kernel of a tape.
struct TapeKernelInfo {
  std::string name;
  /// The arguments in the C signature's order: inputs (read), then outputs (written), with
  /// their lengths.
  std::vector<std::pair<std::string, std::size_t>> inputs, outputs;
  std::size_t operations = 0;    ///< +, −, ×, ÷ and calls, as the generator counted them
  std::size_t instructions = 0;  ///< the tape's register instructions
  std::size_t bytes = 0;         ///< memory of its instructions and workspace
};

class TapeModel {
 public:
  static constexpr int kMaxLoaded = 64;

  /// Reads a tape file. ParseError (path:line: what) for a file that is not a tape of this
  /// runtime's ABI, or is damaged; Error when kMaxLoaded tapes are already loaded.
  static std::unique_ptr<TapeModel> load(const std::string& path);
  /// The same from the text of a tape; origin names it in messages.
  static std::unique_ptr<TapeModel> parse(const std::string& text, const std::string& origin);

  ~TapeModel();
  TapeModel(const TapeModel&) = delete;
  TapeModel& operator=(const TapeModel&) = delete;

  /// The model's kernels, names and defaults (ModelKernels::evaluation is "tape"); valid while
  /// this TapeModel lives.
  const ModelKernels& kernels() const;
  /// Every kernel of the tape, those ModelKernels has no field for included.
  const std::vector<TapeKernelInfo>& kernel_info() const;

  struct Impl;

 private:
  explicit TapeModel(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace mbsgen
