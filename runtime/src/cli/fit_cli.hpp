// The command `fit` of a model's solver (issue 42; docs/fitting.md): parameters fitted to
// measured frequency responses and modal data. Built into the program mbsgen-fit only, which
// links Ceres Solver: a solver that does not fit does not load it.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "mbsgen/runtime/fit/fit.hpp"

namespace CLI {
class App;
}

namespace mbsgen::cli {

struct FitCliOptions {
  std::vector<std::string> data, parameters, set, profile;
  std::string input, output, format = "table", out_dir, plot;
  int starts = 1, threads = 0, max_iterations = 200, profile_points = 21;
  std::uint64_t seed = 1;
  bool no_fit = false;
};

/// Adds the subcommand `fit` and its options to app.
CLI::App* add_fit(CLI::App& app, FitCliOptions& o);

/// Runs it: 0 when the fit converged, 3 when it did not (the results printed and written, said
/// so); throws mbsgen::Error (NameError for unknown names, ParseError for bad data files).
int run_fit(const ModelKernels& k, const FitCliOptions& o, std::ostream& out, std::ostream& err);

/// mbsgen-fit TAPE fit ARGS: the model in a tape file, its command `fit`.
int fit_main(const std::string& tape_file, int argc, char** argv);

}  // namespace mbsgen::cli
