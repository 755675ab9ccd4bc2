// Kept at this path for the generated code: every `<id>_model.cpp` that mbsgen has written
// includes "mbsgen/runtime/linear_model.hpp" (docs/generated-abi.md), and committed copies of generated
// code in users' trees must go on compiling. The header itself is model/linear_model.hpp.
#pragma once

#include "mbsgen/runtime/model/linear_model.hpp"
