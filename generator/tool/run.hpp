// `mbsgen run`: generate, compile, cache and run a model's solver (run.cpp).
#pragma once

#include <string>
#include <vector>

namespace mbsgen::tool {

/// Runs the cached solver of model_file (building it first if needed) with args; returns its
/// exit code (or does not return: the solver replaces this process). Throws ModelError for a
/// bad model, std::exception for other failures.
int run_main(const std::string& model_file, const std::string& scene, std::vector<std::string> args);

}  // namespace mbsgen::tool
