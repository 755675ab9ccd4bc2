// Stage 3b: exact structural zeros of the linearized matrices (issue 14 §1).
//
// An entry of M, Q, K, B, C_y, C_v (or of D, G, K_s, N) that vanishes for every parameter value
// is computed by the program as a sum whose terms cancel only in exact arithmetic: emitted as an
// expression it evaluates to rounding noise (6.6e-24 in a zero block of a mass matrix, −2.2e-16
// in the stiffness column of a cyclic coordinate). This stage decides such entries exactly and
// replaces them by 0, in two kinds:
//
// - zero everywhere: the entry vanishes for all arguments (y0, ẏ0, p) of the linear kernels
//   (a cyclic coordinate's column of K). It becomes an exact 0 in every kernel.
// - zero at the operating point: with a `given` operating point, the entry vanishes once
//   (y0, ẏ0) = (y0(p), ẏ0(p)) for every p, but not elsewhere (couplings that vanish in the
//   reference configuration). The linear kernels return 0 for it when called at the model's
//   operating point (the arguments equal what the operating_point kernel returns) and the
//   general expression otherwise.
//
// Deciding: each entry is first screened numerically (two pseudo-random points, 50 digits; an
// entry that is not below 1e-30 of its matrix's largest entry at both is nonzero, which is
// certain), then a candidate is proved zero symbolically: the operating point substituted
// through the program, every intermediate written out, sin and cos of each argument replaced by
// symbols s, c with c² = 1 − s², the rational normal form's numerator expanded and reduced. Only
// a proved entry becomes 0; a candidate whose written-out form exceeds the size budget stays an
// expression and is counted as unproved (never a wrong zero).
#pragma once

#include "mbsgen/generator/mechanics/dynamics.hpp"

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace mbsgen {

struct LinearEquations;

/// Per entry: nonzero (or undecided), zero everywhere, zero at the operating point.
enum class EntryZero : char { nonzero = 0, everywhere = 1, at_operating_point = 2 };

using ZeroPattern = std::vector<std::vector<EntryZero>>;

/// The structural zeros of the linear matrices and how they were decided.
struct StructuralZeros {
  /// Patterns of M, Q, K, B, C_y, C_v, D, G, K_s, N (sizes as the matrices).
  ZeroPattern M, Q, K, B, Cy, Cv, D, G, Ks, N;
  ZeroPattern E, A, Bx, Cx;  ///< the descriptor matrices of a nonholonomic model
  ZeroPattern Ca, Du;        ///< outputs on ÿ and u (reactions.hpp, prescribed_motion.hpp)
  ZeroPattern B1, B2, D1;    ///< a moving support's rates and accelerations (prescribed_motion.hpp)
  std::size_t everywhere = 0;           ///< entries proved zero for all kernel arguments
  std::size_t at_operating_point = 0;   ///< entries proved zero at the operating point only
  std::size_t unproved = 0;             ///< numerically zero candidates not proved (kept)
  /// True when some entry is zero at the operating point only: the linear kernels then test
  /// whether they are called there.
  bool any_at_operating_point() const { return at_operating_point > 0; }
};

/// Decides the structural zeros of lin's matrices and writes the exact zeros into lin: entries
/// zero everywhere become 0 in M, Q, K, B, C_y, C_v, D, G, K_s, N; entries zero at the operating
/// point only are returned in the pattern (emit() writes them as conditional zeros).
StructuralZeros find_structural_zeros(Equations& eq, LinearEquations& lin);

/// A matrix's pattern as rows of characters: 'x' nonzero, '0' zero everywhere, 'o' zero at the
/// operating point (the manifest's "sparsity").
std::vector<std::string> pattern_rows(const ZeroPattern& pattern);

}  // namespace mbsgen
