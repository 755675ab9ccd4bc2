// Common-subexpression elimination on GiNaC expressions (GiNaC has none built in).
#pragma once

#include "mbsgen/generator/canonical.hpp"

#include <ginac/ginac.h>

#include <string>
#include <vector>

namespace mbsgen {

/// An assignment `target = value` of straight-line code.
struct Statement {
  std::string target;  ///< a C++ lvalue ("t12", "M[3]") or a new temporary
  GiNaC::ex value;
  bool temporary = true;  ///< declare as `const double`
  GiNaC::ex symbol;       ///< for a temporary: the symbol that later statements use
};

/// Merges temporaries whose values are equal or opposite (kept: the first), then rewrites the
/// statements so that every non-trivial subexpression (a sum, product, power or
/// function call, not a lone symbol, number or c·symbol) that occurs more than once is computed
/// once into a new temporary `c<k>`, placed before its first use; e and −e count as the same
/// subexpression. Deterministic: operands are visited in `order`, which must know the signs of
/// the statements' intermediates; the new temporaries' signs are added to it.
std::vector<Statement> eliminate_common_subexpressions(const std::vector<Statement>& in,
                                                       CanonicalOrder& order);

}  // namespace mbsgen
