// `mbsgen run`: generate, compile, cache and run a model's solver (run.cpp).
#pragma once

#include <string>
#include <vector>

namespace mbsgen::tool {

/// Runs the cached solver of model_file (building it first if needed) with args; returns its
/// exit code (or does not return: the solver replaces this process). Throws ModelError for a
/// bad model, std::exception for other failures.
int run_main(const std::string& model_file, const std::string& scene, std::vector<std::string> args);

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
