// `mbsgen linear modes|frf ...`: modes and frequency responses of raw Matrix Market matrices
// (issue 3 §5; documented in docs/cli.md).
#pragma once

#include <iosfwd>

namespace mbsgen::cli {

/// Runs `linear` with argv[0] == "linear" (or any program name). Writes results to `out` and
/// diagnostics to `err`. Returns 0 on success, 1 for bad data or an unsolvable model (unreadable
/// or malformed file, inconsistent dimensions, a pole with --on-pole error, ...), 2 for a usage
/// error (unknown option, missing required option, bad value).
int linear_main(int argc, char** argv, std::ostream& out, std::ostream& err);

/// Same with std::cout and std::cerr.
int linear_main(int argc, char** argv);

}  // namespace mbsgen::cli
