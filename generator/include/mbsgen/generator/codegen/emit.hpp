// Stage 4: emission of plain C++17 kernels and a JSON manifest.
//
// Kernels are `extern "C"` functions `<id>_<kernel>(inputs…, outputs…)` that write into caller
// buffers (matrices column-major), never allocate or throw, and return 0, or 1 when a result is
// not finite. ABI version kAbiVersion; see docs/generated-abi.md.
#pragma once

#include "mbsgen/generator/codegen/output_files.hpp"
#include "mbsgen/generator/linear/linearize.hpp"
#include "mbsgen/generator/model/scene.hpp"
#include "mbsgen/generator/codegen/version.hpp"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace mbsgen {

inline constexpr int kAbiVersion = 1;

struct EmitOptions {
  bool cse = true;
  /// The scene's name: empty, or the name of model.selection() (apply_scene); anything else is
  /// an error. The scene itself (kernels, effects) is the one the model was pruned for.
  std::string scene;
  std::string source_file;  ///< shown in the header; the model file as given
  /// C identifier prefix of the kernels (default: the model name, and `<model>_<scene>` for a
  /// scene other than "full"; '_' appended when that is a C++ keyword or `std`). An id given
  /// here must be a C identifier and not reserved (id_problem): emit() throws otherwise.
  std::string id;
  /// Kernels longer than a few thousand operations are cut into functions of bounded size (the
  /// compiler's time is superlinear in a function's size); with parts > 0 these functions go to
  /// `parts` files `<id>_part1.cpp` … `<id>_part<parts>.cpp` of about equal size, to compile in
  /// parallel (written even when empty, so that a build system can list them in advance).
  std::size_t parts = 0;
  /// Operations per part of a long kernel: GCC's compile time per operation is lowest near
  /// 2,500, but a kernel in parts of 2,500 passes many values through memory (the 40-coordinate
  /// chain's linear, 48,709 operations, -O2, same run: 34.4 µs in parts of 2,500, 26.2 in parts
  /// of 5,000, 24.6 in parts of 10,000, 23.0–24.8 whole; compiled in 20.5, 23.2, 60.1 and 66.5 s
  /// wall on 2 cores): 5,000 (docs/generator.md, "Compiling large models"); 0: no kernel is cut (tests compare the
  /// two forms bit for bit). Only kernels longer than kCutFactor × chunk_operations are cut: a
  /// kernel in parts passes its intermediates through memory, and a short one compiles quickly
  /// whole (the 20-coordinate chain's mass matrix, 2,916 operations: 1.6 µs in two parts, 1.0 µs
  /// whole; the 40-coordinate one's, 11,814 operations, 3.96 µs in parts, 2.97 µs whole, in
  /// bench/compile_scale.py's run on 6802824).
  std::size_t chunk_operations = 5000;
  static constexpr std::size_t kCutFactor = 4;
  /// Also emit `dynamics(y, yd, u, p, M, r)`: M(y) and k − q in one kernel, sharing the sines,
  /// cosines and link transforms the two compute (what a time step needs), and
  /// `dynamics_jacobian(y, yd, ydd, u, p, Ky, Kv)`: Ky = ∂(M ÿ + k − q)/∂y, Kv = ∂(k − q)/∂ẏ at any
  /// state (the iteration matrices of implicit integration; not for closed loops). Off by
  /// default: it compiles M and k − q again and the Jacobian is 2–3 times `linear`'s size.
  bool dynamics = false;
  /// Only the kernels a solver calls through ModelKernels (issue 40 §2): not `bodies` nor
  /// `linear_structured`, which are for consumers of the C API (`mbsgen run`'s solvers and tapes;
  /// the 30-link per-link chain's `bodies` is 17,174 operations, 359 kB of C++).
  bool solver_only = false;
};

struct KernelInfo {
  std::string name;
  std::string signature;
  std::size_t operations = 0;  ///< +, −, ×, ÷ and function calls in the emitted code
  std::size_t bytes = 0;       ///< its C++ (with its parts), as written
};

struct GeneratedCode {
  std::string id;  ///< C identifier prefix of the kernels
  std::string header, source, manifest;
  std::vector<std::string> parts;  ///< `<id>_part<k>.cpp` (EmitOptions::parts)
  std::vector<KernelInfo> kernels;
  /// The kernels as tape text, one after the other (emit_tape.hpp adds the model's names and
  /// sizes); empty for a model with closed loops, whose kernels only compiled code evaluates.
  std::string tape;
};

class KernelsAhead;

/// Emits the kernels model.selection().kernels of the derived and linearized model. The header
/// defines `<id>_HAS_<KERNEL>` (e.g. `<id>_HAS_LINEAR`) for each emitted kernel and declares
/// only those; the manifest lists the scene's analyses, effects, kernels with their operation
/// counts, and whether D, G and N are structurally zero.
/// ahead: what emit_ahead started for this model and options, or nullptr.
GeneratedCode emit(const Model& model, Equations& eq, const LinearEquations& lin,
                   const EmitOptions& options = {}, KernelsAhead* ahead = nullptr);

/// The kernels that need only the derivation (mass_matrix, residual, dynamics and bodies, those
/// the scene emits), emitted in a child process while the caller derives and linearizes: pass it
/// to emit(), which takes their code from it and emits the others. GiNaC cannot share
/// expressions between threads; the child (fork) derives the model on its own, on a second
/// processor (issue 17 §1; the times are in docs/generator.md). Peak memory is that of both
/// processes: the child's is the derivation's and these kernels'.
///
/// The code is the same, byte for byte, as emit() alone writes: emit() takes a kernel emitted
/// ahead only when the caller's has the same fingerprint (its expressions and the definitions
/// they need, by GiNaC's hashes, which the child made from the same state, and its symbols'
/// names), and emits it itself where no child could be started (fork or memfd_create failed,
/// one processor) or the child failed. A model with closed loops or rolling constraints has no
/// such kernels. emit() waits for the child at the first of these kernels (without a time limit)
/// and stops a child whose result it did not take; a KernelsAhead not passed to emit() kills its
/// child when destroyed.
class KernelsAhead {
 public:
  KernelsAhead();
  KernelsAhead(KernelsAhead&&) noexcept;
  KernelsAhead& operator=(KernelsAhead&&) noexcept;
  ~KernelsAhead();
  /// Kernels emit() took from the child.
  std::size_t taken() const;

  struct State;  // emit.cpp

 private:
  friend KernelsAhead emit_ahead(const Model& model, const EmitOptions& options);
  friend GeneratedCode emit(const Model& model, Equations& eq, const LinearEquations& lin, const EmitOptions& options,
                            KernelsAhead* ahead);
  std::unique_ptr<State> state_;
};

/// Starts emitting ahead for model (already pruned to options.scene, as for emit()). Call it
/// right before derive(model), with the options emit() will get: the child's derivation starts
/// from the caller's state. In a process with other threads, none may hold a lock at the call
/// that the child needs (glibc resets only its stdio and malloc locks in the child).
KernelsAhead emit_ahead(const Model& model, const EmitOptions& options = {});

/// `<id>.hpp`, `<id>.cpp`, `<id>.json` in dir, for write_files (output_files.hpp).
std::vector<OutputFile> generated_files(const GeneratedCode& code, const std::string& dir);

/// Writes `<id>.hpp`, `<id>.cpp`, `<id>.json` into dir (created if missing), all or nothing
/// (write_files). Files whose content is unchanged are not touched, so a build system does not
/// recompile them.
void write_generated(const GeneratedCode& code, const std::string& dir);

/// Writes content to path atomically (write_files): leaves the file untouched when its content
/// is already that; throws std::runtime_error, and writes nothing, when path exists and was not
/// written by mbsgen: nothing the user wrote is overwritten.
void write_atomically(const std::filesystem::path& path, const std::string& content);

/// A double as a C++ literal that round-trips (%.17g, with ".0" added to integers).
std::string format_double(double v);

/// The parameters of the sensitivity kernel: the scene's, or all, in the model's order.
std::vector<std::string> sensitivity_parameter_names(const Model& model);

/// A C identifier made from a model name.
std::string identifier(const std::string& name);

/// Why id cannot be the prefix of generated kernels (EmitOptions::id, `mbsgen generate --id`):
/// not a C identifier, or a C++ keyword or reserved name (reserved_identifier, escape.hpp); empty
/// when it can. emit() refuses such an id, and appends '_' to a model name that is reserved.
std::string id_problem(const std::string& id);

}  // namespace mbsgen
