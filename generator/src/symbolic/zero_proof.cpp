// Proofs that an expression of the program is zero for all values of its variables
// (symbolic/zero_proof.hpp).
#include "symbolic/zero_proof.hpp"

#include "symbolic/type_test.hpp"

#include <algorithm>
#include <map>
#include <optional>
#include <set>
#include <unordered_map>
#include <utility>
#include <vector>

namespace mbsgen {

using GiNaC::ex;
using GiNaC::cos_SERIAL;
using GiNaC::sin_SERIAL;
using GiNaC::tan_SERIAL;
using detail::kProofBudget;
using detail::Proof;
using detail::TreeSize;

namespace {

// Whether test(x) holds for a node x of e, each distinct node tested once. The nodes seen are
// kept alive, not only their addresses: a sum's or product's operand is often made anew by op()
// (c·x from the pair (x, c)) and freed after its visit, and a later one at the same address was
// taken for seen — a result that depended on the allocator, from run to run.
template <class Test>
bool any_node(const ex& e, Test&& test) {
  std::vector<ex> stack{e};
  std::unordered_map<const GiNaC::basic*, ex> seen;
  while (!stack.empty()) {
    const ex x = stack.back();
    stack.pop_back();
    if (x.nops() > 0 && !seen.emplace(&GiNaC::ex_to<GiNaC::basic>(x), x).second) continue;
    if (test(x)) return true;
    for (std::size_t i = 0; i < x.nops(); ++i) stack.push_back(x.op(i));
  }
  return false;
}

// Results kept by node, with the node: kept alive, its address is not taken by another.
template <class T>
using NodeMemo = std::unordered_map<const GiNaC::basic*, std::pair<ex, T>>;

// sin(a), cos(a), tan(a) → s_a, c_a, s_a/c_a, one pair of symbols per argument a; a node shared
// by several subtrees (or candidates) is mapped once, and its image is shared as it was.
struct TrigToSymbols : GiNaC::map_function {
  std::map<ex, std::pair<GiNaC::symbol, GiNaC::symbol>, GiNaC::ex_is_less> pairs;
  NodeMemo<ex> images;
  const std::pair<GiNaC::symbol, GiNaC::symbol>& pair_of(const ex& a) {
    auto it = pairs.find(a);
    if (it == pairs.end()) it = pairs.emplace(a, std::make_pair(GiNaC::symbol(), GiNaC::symbol())).first;
    return it->second;
  }
  ex operator()(const ex& e) override {
    if (e.nops() == 0) return e;
    const GiNaC::basic* node = &GiNaC::ex_to<GiNaC::basic>(e);
    if (const auto it = images.find(node); it != images.end()) return it->second.second;
    const bool s = is_ex_the_function(e, sin), c = is_ex_the_function(e, cos),
               t = is_ex_the_function(e, tan);
    ex image;
    if (s || c || t) {
      const ex arg = e.op(0).map(*this);
      const auto& [sa, ca] = pair_of(arg);
      image = s ? ex(sa) : c ? ex(ca) : ex(sa) / ca;
    } else {
      image = e.map(*this);
    }
    images.emplace(node, std::make_pair(e, image));
    return image;
  }
  // The (s, c) pairs, for reduce_pythagoras.
  std::vector<std::pair<ex, ex>> all_pairs() const {
    std::vector<std::pair<ex, ex>> v;
    for (const auto& [arg, sc] : pairs) v.emplace_back(sc.first, sc.second);
    return v;
  }
};

// Radicals as symbols: every power B^(p/q) with a rational, non-integer exponent becomes t^(p·Q/q),
// one symbol t = B^(1/Q) per base B (keyed by B expanded: (x − y)² and (y − x)² are one base) with
// Q the least common multiple of the denominators of B's exponents; a radical inside a base first.
// What makes the verdict independent of how GiNaC wrote the expression: left to normal(), B^(1/2)
// and B^(3/2) were two unrelated symbols, and whether a product such as B·B^(−3/2) had been
// combined into B^(−1/2) before (it depends on operand order, which follows hashes seeded by
// addresses) decided the proof. Only t^Q = B is used (reduce_radicals), never t = a root of B that
// holds for some values only (√(x²) is |x|, not x): sound, for every branch of the root.
class RadicalsToSymbols {
 public:
  struct Root {
    GiNaC::symbol t;
    GiNaC::numeric Q = 1;
    ex base;  // B with its own radicals as symbols, expanded (once replace() has run)
    bool has_base = false;
  };

  ex replace(const ex& e) {
    collect(e);
    return rewrite(e);
  }
  const std::vector<Root>& roots() const { return roots_; }

 private:
  static bool is_radical(const ex& e) {
    return isa<GiNaC::power>(e) && isa<GiNaC::numeric>(e.op(1)) &&
           GiNaC::ex_to<GiNaC::numeric>(e.op(1)).is_rational() && !GiNaC::ex_to<GiNaC::numeric>(e.op(1)).is_integer();
  }
  void collect(const ex& e) {
    any_node(e, [this](const ex& x) {
      if (is_radical(x)) {
        const ex key = GiNaC::expand(x.op(0));
        auto it = index_.find(key);
        if (it == index_.end()) {
          it = index_.emplace(key, roots_.size()).first;
          roots_.push_back({GiNaC::symbol(), 1, ex(), false});
        }
        Root& r = roots_[it->second];
        r.Q = GiNaC::lcm(r.Q, GiNaC::ex_to<GiNaC::numeric>(x.op(1)).denom());
      }
      return false;
    });
  }
  ex rewrite(const ex& e) {
    if (e.nops() == 0) return e;
    const auto done = rewritten_.find(e);
    if (done != rewritten_.end()) return done->second;
    ex result;
    if (is_radical(e)) {
      Root& r = roots_[index_.at(GiNaC::expand(e.op(0)))];
      if (!r.has_base) {
        r.base = GiNaC::expand(rewrite(e.op(0)));
        r.has_base = true;
      }
      result = GiNaC::pow(r.t, GiNaC::ex_to<GiNaC::numeric>(e.op(1)) * r.Q);
    } else {
      Operands f(*this);
      result = e.map(f);
    }
    rewritten_.emplace(e, result);
    return result;
  }
  struct Operands : GiNaC::map_function {
    explicit Operands(RadicalsToSymbols& r) : radicals(r) {}
    ex operator()(const ex& e) override { return radicals.rewrite(e); }
    RadicalsToSymbols& radicals;
  };

  std::vector<Root> roots_;
  std::map<ex, std::size_t, GiNaC::ex_is_less> index_;
  std::map<ex, ex, GiNaC::ex_is_less> rewritten_;
};

// A polynomial in c_a of degree ≤ 1 for every argument a, using c² = 1 − s², and of degree < Q in
// every radical t = B^(1/Q), using t^Q = B (B may hold other radicals and sines: repeated until
// none applies).
ex reduce_pythagoras(ex e, const std::vector<std::pair<ex, ex>>& trig, const std::vector<RadicalsToSymbols::Root>& roots = {}) {
  e = GiNaC::expand(e);
  for (bool changed = true; changed;) {
    changed = false;
    for (const RadicalsToSymbols::Root& r : roots) {
      const int Q = r.Q.to_int();
      for (int d = e.degree(r.t); d >= Q; d = e.degree(r.t)) {
        const ex k = e.coeff(r.t, d);
        e = GiNaC::expand(e - k * GiNaC::pow(r.t, d) + k * GiNaC::pow(r.t, d - Q) * r.base);
        changed = true;
      }
    }
    for (const auto& [s, c] : trig) {
      for (int d = e.degree(c); d >= 2; d = e.degree(c)) {
        const ex k = e.coeff(c, d);
        e = GiNaC::expand(e - k * GiNaC::pow(c, d) + k * GiNaC::pow(c, d - 2) * (1 - GiNaC::pow(s, 2)));
      }
    }
  }
  return e;
}

// Nor are polynomials whose expansion could have more than this many terms
// (expanded_terms): the expansion's cost follows its terms (about 6 µs each in GiNaC), not the
// written-out size. The 6-link spatial chain's 66 symmetry proofs of K (structure_of in
// linearize.cpp; up to 48,896 terms each, 1.15 million in all) took 6 s of its 7 s generation,
// while from 7 links on they exceed the size budget and the chains generate in 0.2 s. The
// 5-link chain's (at most 7,120) and every shipped model's (at most 292) stay within it.
constexpr std::size_t kExpansionBudget = 10000;

// An upper bound of the number of terms of e expanded, saturating at `limit`: a sum's terms add,
// a product's multiply, a power with a positive integer exponent n raises its base's to n;
// anything else is one term. With `known`, the bound of every node is kept there (for one limit)
// and a node seen before is not walked again.
std::size_t expanded_terms(const ex& e, std::size_t limit, NodeMemo<std::size_t>* known = nullptr) {
  if (e.nops() == 0) return 1;
  if (known)
    if (const auto it = known->find(&GiNaC::ex_to<GiNaC::basic>(e)); it != known->end()) return it->second.second;
  const auto times = [limit](std::size_t a, std::size_t b) { return b != 0 && a > limit / b ? limit : std::min(limit, a * b); };
  std::size_t t = 1;
  if (isa<GiNaC::add>(e)) {
    t = 0;
    for (std::size_t i = 0; i < e.nops() && t < limit; ++i) t = std::min(limit, t + expanded_terms(e.op(i), limit, known));
  } else if (isa<GiNaC::mul>(e)) {
    for (std::size_t i = 0; i < e.nops() && t < limit; ++i) t = times(t, expanded_terms(e.op(i), limit, known));
  } else if (isa<GiNaC::power>(e) && isa<GiNaC::numeric>(e.op(1)) && GiNaC::ex_to<GiNaC::numeric>(e.op(1)).is_pos_integer()) {
    const std::size_t base = expanded_terms(e.op(0), limit, known);
    t = base;
    if (base > 1) {
      t = 1;
      for (GiNaC::numeric k = GiNaC::ex_to<GiNaC::numeric>(e.op(1)); k.is_positive() && t < limit; k -= 1) t = times(t, base);
    }
  }
  if (known) known->emplace(&GiNaC::ex_to<GiNaC::basic>(e), std::make_pair(e, t));
  return t;
}

// Whether test(x) holds for a node x of e, with every node's answer kept in `known` (for one test)
// and a node seen before not walked again.
template <class Test>
bool any_node_known(const ex& e, const Test& test, NodeMemo<bool>& known) {
  if (e.nops() == 0) return test(e);
  const GiNaC::basic* node = &GiNaC::ex_to<GiNaC::basic>(e);
  if (const auto it = known.find(node); it != known.end()) return it->second.second;
  bool holds = test(e);
  for (std::size_t i = 0; i < e.nops() && !holds; ++i) holds = any_node_known(e.op(i), test, known);
  known.emplace(node, std::make_pair(e, holds));
  return holds;
}

// A power that is not a positive integer one (a division or a root), or, with tan_divides, a
// tangent (which the proof form writes s/c).
bool divides(const ex& x, bool tan_divides) {
  return (isa<GiNaC::power>(x) && !(isa<GiNaC::numeric>(x.op(1)) && GiNaC::ex_to<GiNaC::numeric>(x.op(1)).is_pos_integer())) ||
         (tan_divides && is_ex_the_function(x, tan));
}

// Whether e holds a node that divides(…, tan_divides).
bool holds_division(const ex& e, bool tan_divides = false) {
  return any_node(e, [tan_divides](const ex& x) { return divides(x, tan_divides); });
}

// A written-out candidate with sin, cos and tan of each argument as symbols, when it is within
// the budgets (kProofBudget, kExpansionBudget); nothing otherwise.
struct ProofForm {
  TrigToSymbols trig;
  RadicalsToSymbols radicals;
  ex symbolic;
  bool division = false;  // holds_division(symbolic)
};
std::optional<ProofForm> proof_form(const ex& written_out, TreeSize& written_size, bool bound_terms) {
  if (written_size(written_out) > kProofBudget) return std::nullopt;
  ProofForm f;
  f.symbolic = f.radicals.replace(written_out.map(f.trig));
  f.division = holds_division(f.symbolic);
  // A polynomial's bound is checked before normal(), which expands it (its numerator is the
  // polynomial). A rational expression's terms can cancel over a common denominator: the Whipple
  // bicycle's proofs of 115,228 and 471,978 terms so counted have numerators of at most 108.
  if (bound_terms && !f.division && expanded_terms(f.symbolic, kExpansionBudget + 1) > kExpansionBudget)
    return std::nullopt;
  return f;
}

Proof finish_proof(const ProofForm& f) {
  // A polynomial (no division or root: proof_form has bounded its expansion) is zero iff its
  // expansion is; normal() would reach the same numerator through gcd computations that cost
  // the 60-link chain's symmetry proofs about 15 s (2026-11-29).
  if (!f.division) return reduce_pythagoras(f.symbolic, f.trig.all_pairs(), f.radicals.roots()).is_zero() ? Proof::zero : Proof::nonzero;
  const ex numerator = GiNaC::normal(f.symbolic).numer();
  if (TreeSize(50 * kProofBudget + 1)(numerator) > 50 * kProofBudget) return Proof::too_large;
  return reduce_pythagoras(numerator, f.trig.all_pairs(), f.radicals.roots()).is_zero() ? Proof::zero : Proof::nonzero;
}

}  // namespace

struct detail::Prover::Shared {
  TreeSize written_size{kProofBudget + 1};
  NodeMemo<std::size_t> terms;  // expanded_terms with the limit kExpansionBudget + 1
  NodeMemo<bool> division;      // holds_division with tan_divides
  NodeMemo<bool> trigonometric;  // whether a node holds a sine, cosine or tangent
  TrigToSymbols trig;

  bool divides(const ex& written_out) {
    return any_node_known(written_out, [](const ex& x) { return mbsgen::divides(x, true); }, division);
  }
};

detail::Prover::Prover() : shared_(std::make_unique<Shared>()) {}
detail::Prover::~Prover() = default;

bool detail::Prover::within_budgets(const ex& written_out) {
  // As proof_form(written_out, …, true) decides.
  if (shared_->written_size(written_out) > kProofBudget) return false;
  return shared_->divides(written_out) ||
         expanded_terms(written_out, kExpansionBudget + 1, &shared_->terms) <= kExpansionBudget;
}

Proof detail::Prover::prove(const ex& written_out) {
  if (written_out.is_zero()) return Proof::zero;
  if (!within_budgets(written_out)) return Proof::too_large;
  Shared& s = *shared_;
  // A rational expression or a radical: normal() of this candidate alone, as proof_form makes it.
  if (s.divides(written_out)) return finish_proof(*proof_form(written_out, s.written_size, false));
  // A polynomial: expanded and reduced by c² = 1 − s² for the arguments whose cosine it holds, as
  // finish_proof does, with its sines and cosines as the symbols of earlier candidates.
  const bool trigonometric = any_node_known(
      written_out, [](const ex& x) { return is_ex_the_function(x, sin) || is_ex_the_function(x, cos) || is_ex_the_function(x, tan); },
      s.trigonometric);
  const ex polynomial = GiNaC::expand(trigonometric ? s.trig(written_out) : written_out);
  std::vector<std::pair<ex, ex>> pairs;
  if (!s.trig.pairs.empty()) {
    std::set<ex, GiNaC::ex_is_less> symbols;
    any_node(polynomial, [&symbols](const ex& x) {
      if (isa<GiNaC::symbol>(x)) symbols.insert(x);
      return false;
    });
    for (const auto& [arg, sc] : s.trig.pairs)
      if (symbols.count(sc.second) > 0) pairs.emplace_back(sc.first, sc.second);
  }
  return reduce_pythagoras(polynomial, pairs).is_zero() ? Proof::zero : Proof::nonzero;
}

bool proved_zero(Program& program, const ex& e, bool bound_terms) {
  if (e.is_zero()) return true;
  TreeSize written_size(kProofBudget + 1);
  const std::optional<ProofForm> f = proof_form(program.inline_all(e), written_size, bound_terms);
  return f && finish_proof(*f) == Proof::zero;
}

bool all_proved_zero(Program& program, std::size_t count, const std::function<ex(std::size_t)>& entry) {
  // Every one within the budgets first: one beyond them decides, before any is expanded. The
  // written-out forms share their subtrees (inline_all), and so do their proofs (Prover).
  detail::Prover prover;
  std::vector<ex> written;
  for (std::size_t k = 0; k < count; ++k) {
    const ex e = entry(k);
    if (e.is_zero()) continue;
    const ex written_out = program.inline_all(e);
    if (written_out.is_zero()) continue;
    if (!prover.within_budgets(written_out)) return false;
    written.push_back(written_out);
  }
  for (const ex& w : written)
    if (prover.prove(w) != Proof::zero) return false;
  return true;
}

}  // namespace mbsgen
