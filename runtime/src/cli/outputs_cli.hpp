// `outputs` of the solvers (issue 39 §4): every output, joint loads included, at any state.
#pragma once

#include <CLI/CLI.hpp>

#include <ostream>
#include <string>
#include <vector>

#include "mbsgen/runtime/model/generated_model.hpp"

namespace mbsgen::cli {

struct OutputsOptions {
  std::vector<std::string> set;    ///< NAME=VALUE parameters
  std::vector<std::string> state;  ///< NAME=VALUE, NAME_dot=VALUE, NAME_ddot=VALUE or INPUT=VALUE
  std::string format = "table";
};

/// Adds the subcommand `outputs` to app.
CLI::App* add_outputs(CLI::App& app, OutputsOptions& o);

/// Prints the outputs at the state given by o.state (each entry not given: the operating point's
/// y0 and ẏ0, ÿ = 0, u = 0). Throws NameError for an unknown or repeated name or a bad value,
/// Error for a model with nonholonomic constraints (GeneratedModel::outputs_at).
int run_outputs(const ModelKernels& k, const OutputsOptions& o, std::ostream& out);

}  // namespace mbsgen::cli
