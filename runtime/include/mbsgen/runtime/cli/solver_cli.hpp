// The command line of a model-specific solver (issue 4 §4; docs/cli.md "Model solvers"):
// `<target>-solve ARGS` and `mbsgen run MODEL -- ARGS` both end here.
//
//   modes    [--set NAME=VALUE]... [--format table|json|csv] [--shapes] [--all]
//   frf      --input U --output Z [--from HZ --to HZ --points N] [--spacing log|linear]
//            [--method auto|direct|banded|hessenberg|modal|real] [--on-pole flag|error]
//            [--format table|json|csv] [--plot FILE.svg|FILE.png] [--set NAME=VALUE]...
//   static   [--set NAME=VALUE]... [--format table|json]
//   matrices [--set NAME=VALUE]... [--format json|mtx] [--out DIR]
//   info     model, scene, coordinates, parameters with values, inputs, outputs
#pragma once

#include <iosfwd>
#include <string>

#include "mbsgen/runtime/model/generated_model.hpp"

namespace mbsgen::cli {

/// Runs the solver for `kernels`; argv[0] is the program name shown in messages. Results go to
/// `out`, diagnostics and progress (only when stderr is a terminal) to `err`. Returns 0 on
/// success, 1 for a model or computation error (no equilibrium, a pole with --on-pole error, a
/// non-finite kernel value, a plot that cannot be written), 2 for a usage error (unknown option,
/// unknown parameter, input or output, malformed number or range).
int solver_main(const ModelKernels& kernels, int argc, char** argv, std::ostream& out,
                std::ostream& err);

/// Same with std::cout and std::cerr.
int solver_main(const ModelKernels& kernels, int argc, char** argv);

/// The solver of the model in a tape file (model/tape.hpp), evaluated without a compiler: what
/// `mbsgen run` answers with (issue 40 §1, through the program mbsgen-tape). argv[0] is replaced
/// by `<model>-solve`. A tape that cannot be read: a message, 1.
int tape_solver_main(const std::string& tape_file, int argc, char** argv);

}  // namespace mbsgen::cli
