// A tree for the test architecture_map_rejects: runtime/model/ including runtime/cli/, which
// docs/architecture.md forbids (the numerical core never depends on the command lines).
#include <vector>

#include "mbsgen/runtime/cli/solver_cli.hpp"
