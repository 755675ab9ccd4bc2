#include <exception>
#include <iostream>

#include "mbsgen/runtime/cli/linear_cli.hpp"

// linear_main maps every exception to exit status 1 with a message; this is the last guard.
int main(int argc, char** argv) try {
  return mbsgen::cli::linear_main(argc, argv);
} catch (const std::exception& e) {
  std::cerr << "mbsgen linear: error: " << e.what() << "\n";
  return 1;
}
