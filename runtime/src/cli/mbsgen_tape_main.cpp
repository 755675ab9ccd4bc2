// mbsgen-tape TAPE [ARGS...]: the solver command line of the model in a tape file (model/tape.hpp),
// evaluated without a compiler — what `mbsgen run` answers with (issue 40 §1). Its messages name
// it `<model>-solve`, as the model's compiled solver's do.
#include <exception>
#include <iostream>
#include <string>

#include "mbsgen/runtime/cli/solver_cli.hpp"

int main(int argc, char** argv) try {
  if (argc < 2 || std::string(argv[1]).rfind('-', 0) == 0) {
    std::cerr << "usage: mbsgen-tape TAPE [info|modes|frf|static|sweep|matrices|simulate|study|outputs ARGS...]\n"
                 "  the solver of the model in TAPE (mbsgen generate --tape), without a compiler\n";
    return 2;
  }
  return mbsgen::cli::tape_solver_main(argv[1], argc - 1, argv + 1);
} catch (const std::exception& e) {
  std::cerr << "mbsgen-tape: error: " << e.what() << "\n";
  return 1;
}
