// `mbsgen run`: generate, compile, cache and run a model's solver (run.cpp).
#pragma once

#include <string>
#include <vector>

namespace mbsgen::tool {

/// Runs args on model_file's cached tape, in this process (issue 40 §1: no compiler), or, for
/// simulate and study, a model with closed loops, or when `compiled`, on its cached compiled
/// solver (building either first if needed); returns the exit code (or does not return: the
/// compiled solver replaces this process). Throws ModelError for a bad model, std::exception for
/// other failures. debug: a compiled solver with the runtime's debug information (a cache entry
/// of its own; without it the solver is linked without).
int run_main(const std::string& model_file, const std::string& scene, std::vector<std::string> args,
             bool compiled = false, bool debug = false);

/// `mbsgen tape MODEL [--scene NAME]`: makes sure model_file's tape is in the cache (generating
/// it as `mbsgen run` does) and prints its path on stdout; exit 3, with a message, for a model
/// with closed loops (no tape). For programs that load the tape themselves (the Python package,
/// mbsgen::TapeModel). Throws as run_main.
int tape_main(const std::string& model_file, const std::string& scene);
/// `mbsgen kernels MODEL [--scene NAME]`: makes sure the model's kernels are in the cache compiled
/// as a shared library (exporting `const mbsgen::ModelKernels* mbsgen_model_kernels()`; any model,
/// closed loops included) and prints its path. For programs that load compiled kernels (the Python
/// package). Throws as run_main.
int kernels_main(const std::string& model_file, const std::string& scene);
/// A T made by make() and never destroyed. The derivation of a large model is millions of GiNaC
/// nodes, and freeing them one by one took 5 % of a 40-link chain's generation; the process's
/// exit reclaims them at once. A global list keeps them reachable (no leak for LeakSanitizer).
template <class T, class Make>
T& kept_until_exit(Make&& make) {
  static auto* kept = new std::vector<const void*>;
  T* p = new T(make());
  kept->push_back(p);
  return *p;
}

}  // namespace mbsgen::tool
