// The solvers' `simulate` command (docs/cli.md): time integration of the nonlinear equations
// (simulation.hpp), written as CSV or JSON, with a plot of chosen series.
#pragma once

#include <CLI/CLI.hpp>

#include <ostream>
#include <string>
#include <vector>

#include "mbsgen/runtime/model/generated_model.hpp"

namespace mbsgen::cli {

struct SimulateOptions {
  std::vector<std::string> set, initial, inputs, show, atol_of;
  double duration = 0, step = 0, rtol = 1e-8, atol = 1e-10;
  std::string format = "csv", plot, method = "bdf";
  bool difference_quotients = false, statistics = false;
};

/// Adds the subcommand `simulate` to app, its options stored in o.
CLI::App* add_simulate(CLI::App& app, SimulateOptions& o);

/// Runs it; throws mbsgen::Error (NameError for bad names or input specifications).
int run_simulate(const ModelKernels& k, const SimulateOptions& o, std::ostream& out, std::ostream& err);

}  // namespace mbsgen::cli
