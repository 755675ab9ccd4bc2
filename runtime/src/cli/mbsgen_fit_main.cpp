// mbsgen-fit TAPE fit ARGS...: `fit` of the model in a tape file (issue 42). mbsgen-tape hands
// `fit` here, so that only a run that fits loads Ceres Solver.
#include <exception>
#include <iostream>
#include <string>

#include "cli/fit_cli.hpp"

int main(int argc, char** argv) try {
  if (argc < 2 || std::string(argv[1]).rfind('-', 0) == 0) {
    std::cerr << "usage: mbsgen-fit TAPE fit --data FILE --parameter NAME=LO:HI ...\n"
                 "  fits parameters of the model in TAPE (mbsgen tape MODEL) to measured data\n";
    return 2;
  }
  return mbsgen::cli::fit_main(argv[1], argc - 1, argv + 1);
} catch (const std::exception& e) {
  std::cerr << "mbsgen-fit: error: " << e.what() << "\n";
  return 1;
}
