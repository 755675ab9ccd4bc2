// Common-subexpression elimination on GiNaC expressions (GiNaC has none built in), with
// polynomial simplification of small kernels.
#pragma once

#include "mbsgen/generator/symbolic/canonical.hpp"

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

/// Rewrites straight-line code into code with the same values (to rounding) and fewer
/// operations (+, −, ×, ÷ and calls as the emitter counts them):
///  1. temporaries whose values are equal or opposite are merged (kept: the first);
///  2. in kernels of up to a few thousand statements, each value is also written as a polynomial
///     in the kernel's leaves (parameters, coordinates, calls, and the temporaries too large to
///     write out), with exact cancellation and sin²x + cos²x = 1, as sums of earlier temporaries
///     it contains and the rest factored; a value takes that form where it costs less, and the
///     outputs are tried all in that form (as SymPy's expressions are: shorter on short chains);
///  3. every non-trivial subexpression (a sum, product, power or function call, not a lone
///     symbol, number or c·symbol) that occurs more than once is computed once, by the first
///     temporary whose value it is or a new temporary `c<k>` before its first use; e and −e
///     count as the same subexpression;
///  4. each temporary's symbol gets the sign that needs the fewer negations (the code stores
///     canonical values, canonical.hpp); new symbols get the sign of their values.
/// Temporaries that no output reads any more are dropped. Deterministic: operands are visited
/// in `order`, which must know the signs of the statements' intermediates; the new temporaries'
/// signs are added to it. Linear in the size of the code.
std::vector<Statement> eliminate_common_subexpressions(const std::vector<Statement>& in,
                                                       CanonicalOrder& order);

}  // namespace mbsgen
