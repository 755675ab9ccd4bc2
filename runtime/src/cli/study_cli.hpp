// The solvers' `study` command (issue 20 §2; docs/studies.md): a design of experiments over named
// parameters, evaluated on every core and, under mpirun or srun, on every rank; percentile bands
// of a response, statistics of the modes and of responses at chosen frequencies, Sobol' indices.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "mbsgen/runtime/model/generated_model.hpp"

namespace mbsgen::cli {

struct StudyOptions {
  std::vector<std::string> set, parameters;
  std::string design = "monte-carlo", input, output, spacing = "log", method = "auto", format = "table";
  std::string samples_file, bands_file, sobol_file, plot;
  std::vector<double> at_hz;
  long samples = 0, points = 200, bootstrap = 200;
  std::uint64_t seed = 1;
  int modes = 0, threads = 0;
  double from = 0, to = 0;
};

/// Adds the subcommand `study` to app, its options stored in o.
CLI::App* add_study(CLI::App& app, StudyOptions& o);

/// Runs it (on rank 0 the summary and files; the other ranks only evaluate); throws
/// mbsgen::Error (NameError for unknown names), and returns 1 when every evaluation failed.
int run_study(const ModelKernels& k, StudyOptions o, std::ostream& out, std::ostream& err);

}  // namespace mbsgen::cli
