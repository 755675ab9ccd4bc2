#include "mbsgen/runtime/linear_cli.hpp"
int main(int argc, char** argv) { return mbsgen::cli::linear_main(argc, argv); }
