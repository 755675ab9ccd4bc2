#include "mbsgen/generator/structural_zeros.hpp"

#include "mbsgen/generator/linearize.hpp"

#include "sample_points.hpp"

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
};

std::vector<Target> targets(LinearEquations& lin, StructuralZeros& z) {
  return {{&lin.M, &z.M},         {&lin.Q, &z.Q},        {&lin.K, &z.K},          {&lin.B, &z.B},
          {&lin.Cy, &z.Cy},       {&lin.Cv, &z.Cv},      {&lin.D, &z.D, true},    {&lin.G, &z.G, true},
          {&lin.Ks, &z.Ks, true}, {&lin.N, &z.N, true},  {&lin.E, &z.E},          {&lin.A, &z.A},
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

// ---------------------------------------------------------------------------------------------
// Symbolic proof

// Number of nodes of an expression's tree (shared subtrees counted each time), saturating at
// `limit`. The sizes of subtrees are kept by node, with the node: the written-out candidates
// share most of their subtrees (Program::inline_all), and walking each tree anew up to the budget
// took a third of a 40-link chain's generation once its 6,320 numerically zero entries of N
// were all candidates.
class TreeSize {
 public:
  explicit TreeSize(std::size_t limit) : limit_(limit) {}

  std::size_t operator()(const ex& root) {
    struct Frame {
      ex e;
      std::size_t next = 0, sum = 1;
    };
    std::vector<Frame> stack;
    std::size_t result = known(root);
    if (result > 0) return result;
    stack.push_back({root});
    while (!stack.empty()) {
      Frame& f = stack.back();
      if (f.sum < limit_ && f.next < f.e.nops()) {
        const ex child = f.e.op(f.next++);
        if (const std::size_t n = known(child)) {
          f.sum = std::min(limit_, f.sum + n);
        } else {
          stack.push_back({child});  // (f is not used after this)
        }
        continue;
      }
      const std::size_t n = std::min(limit_, f.sum);
      sizes_.emplace(&GiNaC::ex_to<GiNaC::basic>(f.e), std::make_pair(f.e, n));
      stack.pop_back();
      if (stack.empty())
        result = n;
      else
        stack.back().sum = std::min(limit_, stack.back().sum + n);
    }
    return result;
  }

 private:
  // The size of a leaf or of a node seen before; 0 otherwise.
  std::size_t known(const ex& e) const {
    if (e.nops() == 0) return 1;
    auto it = sizes_.find(&GiNaC::ex_to<GiNaC::basic>(e));
    return it == sizes_.end() ? 0 : it->second.second;
  }

  std::size_t limit_;
  // node → (the node, kept alive so that its address is not reused; its size)
  std::unordered_map<const GiNaC::basic*, std::pair<ex, std::size_t>> sizes_;
};

// sin(a), cos(a), tan(a) → s_a, c_a, s_a/c_a, one pair of symbols per argument a.
struct TrigToSymbols : GiNaC::map_function {
  std::map<ex, std::pair<GiNaC::symbol, GiNaC::symbol>, GiNaC::ex_is_less> pairs;
  const std::pair<GiNaC::symbol, GiNaC::symbol>& pair_of(const ex& a) {
    auto it = pairs.find(a);
    if (it == pairs.end()) it = pairs.emplace(a, std::make_pair(GiNaC::symbol(), GiNaC::symbol())).first;
    return it->second;
  }
  ex operator()(const ex& e) override {
    const bool s = is_ex_the_function(e, sin), c = is_ex_the_function(e, cos),
               t = is_ex_the_function(e, tan);
    if (s || c || t) {
      const ex arg = e.op(0).map(*this);
      const auto& [sa, ca] = pair_of(arg);
      return s ? ex(sa) : c ? ex(ca) : ex(sa) / ca;
    }
    return e.map(*this);
  }
};

// A polynomial in c_a of degree ≤ 1 for every argument a, using c² = 1 − s².
ex reduce_pythagoras(ex e, const TrigToSymbols& trig) {
  e = GiNaC::expand(e);
  for (const auto& [arg, sc] : trig.pairs) {
    const auto& [s, c] = sc;
    for (int d = e.degree(c); d >= 2; d = e.degree(c)) {
      const ex k = e.coeff(c, d);
      e = GiNaC::expand(e - k * GiNaC::pow(c, d) + k * GiNaC::pow(c, d - 2) * (1 - GiNaC::pow(s, 2)));
    }
  }
  return e;
}

// Written-out expressions beyond this many nodes are not expanded (expansion can swell them
// exponentially); their candidates stay unproved.
constexpr std::size_t kProofBudget = 20000;

// Nor are polynomials whose expansion could have more than this many terms
// (expanded_terms): the expansion's cost follows its terms (about 6 µs each in GiNaC), not the
// written-out size. The 6-link spatial chain's 66 symmetry proofs of K (structure_of in
// linearize.cpp; up to 48,896 terms each, 1.15 million in all) took 6 s of its 7 s generation,
// while from 7 links on they exceed the size budget and the chains generate in 0.2 s. The
// 5-link chain's (at most 7,120) and every shipped model's (at most 292) stay within it.
constexpr std::size_t kExpansionBudget = 10000;

// An upper bound of the number of terms of e expanded, saturating at `limit`: a sum's terms add,
// a product's multiply, a power with a positive integer exponent n raises its base's to n;
// anything else is one term.
std::size_t expanded_terms(const ex& e, std::size_t limit) {
  const auto times = [limit](std::size_t a, std::size_t b) { return b != 0 && a > limit / b ? limit : std::min(limit, a * b); };
  if (isa<GiNaC::add>(e)) {
    std::size_t t = 0;
    for (std::size_t i = 0; i < e.nops() && t < limit; ++i) t = std::min(limit, t + expanded_terms(e.op(i), limit));
    return t;
  }
  if (isa<GiNaC::mul>(e)) {
    std::size_t t = 1;
    for (std::size_t i = 0; i < e.nops() && t < limit; ++i) t = times(t, expanded_terms(e.op(i), limit));
    return t;
  }
  if (isa<GiNaC::power>(e) && isa<GiNaC::numeric>(e.op(1)) && GiNaC::ex_to<GiNaC::numeric>(e.op(1)).is_pos_integer()) {
    const std::size_t base = expanded_terms(e.op(0), limit);
    if (base <= 1) return base;
    std::size_t t = 1;
    for (GiNaC::numeric k = GiNaC::ex_to<GiNaC::numeric>(e.op(1)); k.is_positive() && t < limit; k -= 1) t = times(t, base);
    return t;
  }
  return 1;
}

// Whether e holds a power that is not a positive integer one (a division or a root).
bool holds_division(const ex& e) {
  std::vector<ex> stack{e};
  while (!stack.empty()) {
    const ex x = stack.back();
    stack.pop_back();
    if (isa<GiNaC::power>(x) &&
        !(isa<GiNaC::numeric>(x.op(1)) && GiNaC::ex_to<GiNaC::numeric>(x.op(1)).is_pos_integer()))
      return true;
    for (std::size_t i = 0; i < x.nops(); ++i) stack.push_back(x.op(i));
  }
  return false;
}

enum class Proof { zero, nonzero, too_large };

// A written-out candidate with sin, cos and tan of each argument as symbols, when it is within
// the budgets (kProofBudget, kExpansionBudget); nothing otherwise.
struct ProofForm {
  TrigToSymbols trig;
  ex symbolic;
};
std::optional<ProofForm> proof_form(const ex& written_out, TreeSize& written_size, bool bound_terms) {
  if (written_size(written_out) > kProofBudget) return std::nullopt;
  ProofForm f;
  f.symbolic = written_out.map(f.trig);
  // A polynomial's bound is checked before normal(), which expands it (its numerator is the
  // polynomial). A rational expression's terms can cancel over a common denominator: the Whipple
  // bicycle's proofs of 115,228 and 471,978 terms so counted have numerators of at most 108.
  if (bound_terms && !holds_division(f.symbolic) && expanded_terms(f.symbolic, kExpansionBudget + 1) > kExpansionBudget)
    return std::nullopt;
  return f;
}

Proof finish_proof(const ProofForm& f) {
  const ex numerator = GiNaC::normal(f.symbolic).numer();
  if (TreeSize(50 * kProofBudget + 1)(numerator) > 50 * kProofBudget) return Proof::too_large;
  return reduce_pythagoras(numerator, f.trig).is_zero() ? Proof::zero : Proof::nonzero;
}

// written_size: a TreeSize with the limit kProofBudget + 1, kept from one candidate to the next.
Proof prove_zero(const ex& written_out, TreeSize& written_size) {
  if (written_out.is_zero()) return Proof::zero;
  const std::optional<ProofForm> f = proof_form(written_out, written_size, true);
  return f ? finish_proof(*f) : Proof::too_large;
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
               Program::Substitution& op, TreeSize& written_size) {
  Outcome o;
  if (candidate_everywhere) {
    const Proof p = prove_zero(program.inline_all(x), written_size);
    if (p == Proof::zero) return {EntryZero::everywhere, 0};
    if (p == Proof::too_large) ++o.unproved;
  }
  if (candidate_at_op) {
    const Proof p = prove_zero(program.inline_all(program.substitute(x, op)), written_size);
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
  TreeSize written_size(kProofBudget + 1);
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
          o = settle(eq.program, A[i][j], everywhere[m][i][j] == EntryZero::everywhere,
                     given && at_op[m][i][j] == EntryZero::everywhere, op, written_size);
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

bool proved_zero(Program& program, const ex& e, bool bound_terms) {
  if (e.is_zero()) return true;
  TreeSize written_size(kProofBudget + 1);
  const std::optional<ProofForm> f = proof_form(program.inline_all(e), written_size, bound_terms);
  return f && finish_proof(*f) == Proof::zero;
}

bool all_proved_zero(Program& program, std::size_t count, const std::function<ex(std::size_t)>& entry) {
  // Every one within the budgets first: one beyond them decides, before any is expanded. The
  // written-out forms share their subtrees (inline_all); the forms with symbols for the sines and
  // cosines would not, so they are made again for the proofs, one at a time.
  TreeSize written_size(kProofBudget + 1);
  std::vector<ex> written;
  for (std::size_t k = 0; k < count; ++k) {
    const ex e = entry(k);
    if (e.is_zero()) continue;
    const ex written_out = program.inline_all(e);
    if (written_out.is_zero()) continue;
    if (!proof_form(written_out, written_size, true)) return false;
    written.push_back(written_out);
  }
  for (const ex& w : written)
    if (finish_proof(*proof_form(w, written_size, true)) != Proof::zero) return false;
  return true;
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
