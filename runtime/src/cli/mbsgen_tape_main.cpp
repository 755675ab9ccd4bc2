// mbsgen-tape TAPE [ARGS...]: the solver command line of the model in a tape file (model/tape.hpp),
// evaluated without a compiler — what `mbsgen run` answers with (issue 40 §1). Its messages name
// it `<model>-solve`, as the model's compiled solver's do. `fit` is handed to the program
// mbsgen-fit beside it (issue 42), which alone links Ceres Solver.
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>
#include <system_error>

#include "mbsgen/runtime/cli/solver_cli.hpp"

namespace {

// Replaces this process by mbsgen-fit (beside this program) with the same arguments; returns
// only when it cannot.
int exec_fit(char** argv) {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  const std::filesystem::path fit = self.parent_path() / "mbsgen-fit";
  if (ec || !std::filesystem::is_regular_file(fit, ec)) {
    std::cerr << "mbsgen-tape: fit: this build has no fit (built with MBSGEN_WITH_FIT=OFF, or without Ceres Solver: "
                 "scripts/deps.sh installs it)\n";
    return 1;
  }
  argv[0] = const_cast<char*>("mbsgen-fit");
  ::execv(fit.c_str(), argv);
  std::cerr << "mbsgen-tape: fit: cannot start " << fit << ": " << std::strerror(errno) << "\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 2 || std::string(argv[1]).rfind('-', 0) == 0) {
    std::cerr << "usage: mbsgen-tape TAPE [info|modes|frf|static|sweep|matrices|simulate|study|outputs|fit ARGS...]\n"
                 "  the solver of the model in TAPE (mbsgen generate --tape), without a compiler\n";
    return 2;
  }
  if (argc >= 3 && std::string(argv[2]) == "fit") return exec_fit(argv);
  return mbsgen::cli::tape_solver_main(argv[1], argc - 1, argv + 1);
} catch (const std::exception& e) {
  std::cerr << "mbsgen-tape: error: " << e.what() << "\n";
  return 1;
}
