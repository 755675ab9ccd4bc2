#include "mbsgen/generator/linear/structural_zeros.hpp"

#include "mbsgen/generator/linear/linearize.hpp"

#include "linear/sample_points.hpp"
#include "symbolic/zero_proof.hpp"

#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <unordered_map>
#include <utility>

namespace mbsgen {

using GiNaC::ex;
using GiNaC::cos_SERIAL;
using GiNaC::sin_SERIAL;
using GiNaC::tan_SERIAL;
using detail::Proof;
using detail::Prover;

namespace {

// The matrices of the linear model, by name, in one list (the order of StructuralZeros).
struct Target {
  ExMatrix* matrix;
  ZeroPattern* pattern;
  // A symmetric or skew part, (A ± Aᵀ)/2 (linearize.cpp's split): entry (j, i) is ± entry (i, j)
  // as an expression, so it is zero where (i, j) is, and is not proved a second time. (Of a skew
  // part, x and −x can differ by a node in the proof's size count: an entry right at the budget
  // may be settled as its mirror was, where proving it anew would have said otherwise. Both are
  // sound: nothing becomes zero without a proof of one of the two.)
  bool mirrored = false;
  // The part is zero at the operating point as a whole, every entry proved so by linearize's
  // structure_of (lin.D_zero, G_zero, N_zero; with no more of the point substituted than here):
  // its entries are zero there without a second proof. (The 60-link per-link chain's 14,280
  // entries of G and N: 9 s of its generation.)
  bool zero_at_operating_point = false;
};

std::vector<Target> targets(LinearEquations& lin, StructuralZeros& z) {
  return {{&lin.M, &z.M},         {&lin.Q, &z.Q},        {&lin.K, &z.K},          {&lin.B, &z.B},
          {&lin.Cy, &z.Cy},       {&lin.Cv, &z.Cv},      {&lin.D, &z.D, true, lin.D_zero},
          {&lin.G, &z.G, true, lin.G_zero},
          {&lin.Ks, &z.Ks, true}, {&lin.N, &z.N, true, lin.N_zero},  {&lin.E, &z.E},          {&lin.A, &z.A},
          {&lin.Bx, &z.Bx},       {&lin.Cx, &z.Cx},      {&lin.Ca, &z.Ca},        {&lin.Du, &z.Du},
          {&lin.B1, &z.B1},       {&lin.B2, &z.B2},      {&lin.D1, &z.D1}};
}

// ---------------------------------------------------------------------------------------------
// Numerical screen

// Candidates for zeros: entries below 1e-30 of the largest entry of all matrices at two pseudo-random
// points (50 digits; the rounding of the program's sums is ~1e-50 of their terms). A nonzero
// analytic function is that small at both points only by a coincidence of measure zero, so every
// entry the screen calls nonzero is nonzero; the proof below settles the candidates. A point
// where evaluation fails (a pole) makes no candidates.
std::vector<ZeroPattern> screen(LinearEquations& lin, StructuralZeros& z, bool at_operating_point,
                                detail::SamplePoints& points) {
  std::vector<Target> ts = targets(lin, z);
  // Only the entries that are not already exact zeros (most of a large model's: evaluating all
  // f^2 of them made the screen quadratic in its cost per entry).
  std::vector<ex> entries;
  for (const Target& t : ts)
    for (const auto& row : *t.matrix)
      for (const ex& x : row)
        if (!x.is_zero()) entries.push_back(x);
  std::vector<ZeroPattern> cand;
  for (const Target& t : ts) {
    ZeroPattern p(t.matrix->size());
    for (std::size_t i = 0; i < p.size(); ++i) p[i].assign((*t.matrix)[i].size(), EntryZero::nonzero);
    cand.push_back(p);
  }
  const long digits = GiNaC::Digits;
  GiNaC::Digits = detail::PointEvaluator::kDigits;
  try {
    for (std::size_t point = 0; point < 2; ++point) {
      // (Called with at_operating_point only for a given operating point.) The points of the
      // symmetry test (linearize.cpp), whose values are kept.
      const std::vector<GiNaC::numeric> v = points.evaluate(at_operating_point, point, entries);
      // One scale for all matrices: a matrix that vanishes as a whole at the point (N = skew K of
      // a conservative model at rest) has only rounding noise for its largest entry, and a
      // tolerance relative to that noise found its zeros by the luck of the rounding.
      GiNaC::numeric scale = 0;
      for (const GiNaC::numeric& x : v) scale = std::max(scale, GiNaC::abs(x));
      const GiNaC::numeric tol = scale * GiNaC::numeric(10).power(-30);
      std::size_t at = 0;
      for (std::size_t m = 0; m < ts.size(); ++m) {
        const ExMatrix& A = *ts[m].matrix;
        for (std::size_t i = 0; i < A.size(); ++i)
          for (std::size_t j = 0; j < A[i].size(); ++j) {
            if (A[i][j].is_zero()) continue;  // nonzero in cand: not a candidate, as before
            const bool small = GiNaC::abs(v[at++]) <= tol;
            EntryZero& c = cand[m][i][j];
            if (point == 0) c = small ? EntryZero::everywhere : EntryZero::nonzero;
            else if (!small) c = EntryZero::nonzero;
          }
      }
    }
  } catch (const std::exception&) {
    for (auto& p : cand)
      for (auto& row : p) std::fill(row.begin(), row.end(), EntryZero::nonzero);
  }
  GiNaC::Digits = digits;
  return cand;
}

// What the proofs made of one entry: zero everywhere, at the operating point, or neither, and how
// many of its candidates stayed unproved (too large).
struct Outcome {
  EntryZero zero = EntryZero::nonzero;
  int unproved = 0;
};

// Proves entry x zero everywhere (a candidate there), else at the operating point `op` (a
// candidate there).
Outcome settle(Program& program, const ex& x, bool candidate_everywhere, bool candidate_at_op,
               Program::Substitution& op, Prover& prover) {
  Outcome o;
  if (candidate_everywhere) {
    const Proof p = prover.prove(program.inline_all(x));
    if (p == Proof::zero) return {EntryZero::everywhere, 0};
    if (p == Proof::too_large) ++o.unproved;
  }
  if (candidate_at_op) {
    const Proof p = prover.prove(program.inline_all(program.substitute(x, op)));
    if (p == Proof::zero) o.zero = EntryZero::at_operating_point;
    if (p == Proof::too_large) ++o.unproved;
  }
  return o;
}

}  // namespace

StructuralZeros find_structural_zeros(Equations& eq, LinearEquations& lin) {
  detail::SamplePoints points(eq, lin);
  return detail::find_structural_zeros(eq, lin, points);
}

StructuralZeros detail::find_structural_zeros(Equations& eq, LinearEquations& lin, SamplePoints& points) {
  StructuralZeros z;
  std::vector<Target> ts = targets(lin, z);
  for (const Target& t : ts) {
    t.pattern->assign(t.matrix->size(), {});
    for (std::size_t i = 0; i < t.matrix->size(); ++i)
      (*t.pattern)[i].assign((*t.matrix)[i].size(), EntryZero::nonzero);
  }
  const std::vector<ZeroPattern> everywhere = screen(lin, z, false, points);
  // A model with closed loops has its dependent coordinates refined by the kernels (Newton), not
  // equal to the given expressions bit for bit: they stay free in the proof, so that a zero at the
  // operating point holds for whatever values they take.
  const bool given = !lin.equilibrium;
  const std::vector<ZeroPattern> at_op =
      given ? screen(lin, z, true, points) : std::vector<ZeroPattern>(ts.size());

  // The operating point, substituted through the program once for all candidates.
  GiNaC::exmap op_values;
  for (std::size_t k = 0; k < eq.y.size(); ++k) {
    if (!std::binary_search(eq.loops.dependent.begin(), eq.loops.dependent.end(), k)) op_values[eq.y[k]] = lin.y0[k];
    op_values[eq.yd[k]] = lin.yd0[k];
  }
  Program::Substitution op(op_values);
  Prover prover;
  for (std::size_t m = 0; m < ts.size(); ++m) {
    ExMatrix& A = *ts[m].matrix;
    std::vector<std::vector<Outcome>> settled;  // of a mirrored matrix, for its lower triangle
    if (ts[m].mirrored) settled.assign(A.size(), std::vector<Outcome>(A.size()));
    for (std::size_t i = 0; i < A.size(); ++i)
      for (std::size_t j = 0; j < A[i].size(); ++j) {
        if (A[i][j].is_zero()) {
          (*ts[m].pattern)[i][j] = EntryZero::everywhere;
          continue;
        }
        Outcome o;
        if (ts[m].mirrored && j < i) {
          o = settled[j][i];  // ± the same expression, settled in an earlier row
        } else {
          const bool known_at_op = given && ts[m].zero_at_operating_point;
          o = settle(eq.program, A[i][j], everywhere[m][i][j] == EntryZero::everywhere,
                     given && !known_at_op && at_op[m][i][j] == EntryZero::everywhere, op, prover);
          if (known_at_op && o.zero == EntryZero::nonzero) o.zero = EntryZero::at_operating_point;
          if (ts[m].mirrored) settled[i][j] = o;
        }
        (*ts[m].pattern)[i][j] = o.zero;
        z.unproved += o.unproved;
        if (o.zero == EntryZero::everywhere) {
          A[i][j] = 0;
          ++z.everywhere;
        } else if (o.zero == EntryZero::at_operating_point) {
          ++z.at_operating_point;
        }
      }
  }
  return z;
}

std::vector<std::string> pattern_rows(const ZeroPattern& pattern) {
  std::vector<std::string> rows;
  for (const auto& row : pattern) {
    std::string s;
    for (EntryZero e : row) s += e == EntryZero::nonzero ? 'x' : e == EntryZero::everywhere ? '0' : 'o';
    rows.push_back(s);
  }
  return rows;
}

}  // namespace mbsgen
