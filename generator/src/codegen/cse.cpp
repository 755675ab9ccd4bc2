#include "mbsgen/generator/codegen/cse.hpp"

#include "symbolic/type_test.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <optional>
#include <unordered_map>

namespace mbsgen {

using GiNaC::ex;
using GiNaC::ex_to;

namespace {

bool trivial(const ex& e) {
  if (isa<GiNaC::symbol>(e) || isa<GiNaC::numeric>(e) || isa<GiNaC::constant>(e)) return true;
  return isa<GiNaC::mul>(e) && e.nops() == 2 && isa<GiNaC::numeric>(e.op(1)) && isa<GiNaC::symbol>(e.op(0));
}

bool integer_power(const ex& e) {
  return isa<GiNaC::power>(e) && isa<GiNaC::numeric>(e.op(1)) && ex_to<GiNaC::numeric>(e.op(1)).is_integer();
}

// The sign CppPrinter (emit.cpp) writes e with: −1 when it writes −e (a negation wherever that
// cannot go into a sum or product around it). That is e's canonical sign: the printer leads a
// sum with its canonically first term and negates the whole when that term is negative.
int printed_sign(const ex& e, CanonicalOrder& order) { return order.sign(e); }

// Looked up for every node of every statement: open addressing (ex_table.hpp).
using ExMap = ExTable<ex>;
using Counts = ExTable<int>;
using Index = std::unordered_map<ex, std::size_t, std::hash<GiNaC::ex>, GiNaC::ex_is_equal>;

// Puts replacements (symbol → expression) into expressions: a hash lookup per symbol and a memo
// per subtree (GiNaC's subs compares against an ordered map at every node, 3× slower on the
// 80-coordinate chain). A symbol is replaced only after its definition, which no earlier
// statement reads, so the memo never holds a stale subtree.
struct Replace : GiNaC::map_function {
  ExMap replaced;
  ExMap memo;
  ex operator()(const ex& e) override {
    if (isa<GiNaC::symbol>(e)) {
      const ex* r = replaced.find(e);
      return r ? *r : e;
    }
    if (e.nops() == 0 || replaced.empty()) return e;
    if (const ex* m = memo.find(e)) return *m;
    const ex r = e.map(*this);
    memo.emplace(e, r);
    return r;
  }
};

// The statements (by index) whose symbols e reads, each once, in order.
std::vector<std::size_t> references(const ex& e, const Index& index) {
  std::vector<std::size_t> out;
  std::vector<ex> stack{e};
  while (!stack.empty()) {
    const ex x = stack.back();
    stack.pop_back();
    if (isa<GiNaC::symbol>(x)) {
      if (auto it = index.find(x); it != index.end()) out.push_back(it->second);
      continue;
    }
    for (std::size_t i = 0; i < x.nops(); ++i) stack.push_back(x.op(i));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// Without the temporaries that no output reads, directly or through others.
std::vector<Statement> drop_unread(std::vector<Statement> in) {
  Index index;
  for (std::size_t j = 0; j < in.size(); ++j)
    if (in[j].temporary) index.emplace(in[j].symbol, j);
  std::vector<char> live(in.size(), 0);
  for (std::size_t j = in.size(); j-- > 0;) {
    if (in[j].temporary && !live[j]) continue;
    live[j] = 1;
    for (std::size_t r : references(in[j].value, index)) live[r] = 1;
  }
  std::vector<Statement> out;
  out.reserve(in.size());
  for (std::size_t j = 0; j < in.size(); ++j)
    if (live[j]) out.push_back(std::move(in[j]));
  return out;
}

// ---- Operation counts ------------------------------------------------------------------------

// Operations of e as CppPrinter (emit.cpp) writes it: n − 1 per sum of n terms, one per factor
// of a product after the first (numbers other than ±1 included), a division per negative power,
// k − 1 per power k, one per call, and a negation per negative argument of a call other than an
// odd or even function (whose sign the printer moves outside) and of a root.
std::size_t cost(const ex& e, CanonicalOrder& order) {
  if (isa<GiNaC::add>(e)) {
    std::size_t n = e.nops() - 1;
    for (std::size_t i = 0; i < e.nops(); ++i) n += cost(e.op(i), order);
    return n;
  }
  if (isa<GiNaC::mul>(e)) {
    std::size_t n = 0, num = 0, den = 0;
    for (std::size_t i = 0; i < e.nops(); ++i) {
      const ex& f = e.op(i);
      if (isa<GiNaC::numeric>(f)) {
        num += !(f.is_equal(1) || f.is_equal(-1));
      } else if (integer_power(f) && ex_to<GiNaC::numeric>(f.op(1)).is_negative()) {
        ++den;
        n += cost(GiNaC::pow(f.op(0), -f.op(1)), order);
      } else {
        ++num;
        n += cost(f, order);
      }
    }
    return n + (num > 0 ? num - 1 : 0) + den;
  }
  if (isa<GiNaC::power>(e)) {
    const ex& x = e.op(1);
    if (integer_power(e)) {
      const long k = ex_to<GiNaC::numeric>(x).to_long();
      return cost(e.op(0), order) + static_cast<std::size_t>(std::labs(k) - 1) + (k < 0);
    }
    std::size_t n = cost(e.op(0), order) + (printed_sign(e.op(0), order) < 0);
    if (x.is_equal(GiNaC::numeric(1, 2))) return n + 1;
    if (x.is_equal(GiNaC::numeric(-1, 2))) return n + 2;
    return n + 1 + cost(x, order) + (printed_sign(x, order) < 0);
  }
  if (isa<GiNaC::function>(e)) {
    const std::string name = ex_to<GiNaC::function>(e).get_name();
    const bool moves_sign = e.nops() == 1 && (odd_function(name) || even_function(name));
    std::size_t n = 1;
    for (std::size_t i = 0; i < e.nops(); ++i) n += cost(e.op(i), order) + (!moves_sign && printed_sign(e.op(i), order) < 0);
    return n;
  }
  return 0;
}

// Operations of the statements as CppPrinter writes them: their values' and a negation for each
// output of negative sign and each temporary whose value's sign differs from its symbol's (the
// code stores canonical values, canonical.hpp).
std::size_t kernel_cost(const std::vector<Statement>& statements, CanonicalOrder& order) {
  std::size_t n = 0;
  for (const auto& s : statements)
    n += cost(s.value, order) + (printed_sign(s.value, order) != (s.temporary ? order.sign(s.symbol) : 1));
  return n;
}

// ---- Common subtrees -------------------------------------------------------------------------

ex count(const ex& e, Counts& counts, CanonicalOrder& order);

// Counts e's children. A child that is ±e's own value (−x is the product x·(−1), whose child is
// x) is not a second occurrence: its children are counted instead. (Counted, x occurred twice
// wherever GiNaC happened to store a sum as a − x rather than x − a, an order that follows
// hashes which change from run to run: the kernels differed between runs.)
void count_children(const ex& e, const ex& rep, Counts& counts, CanonicalOrder& order) {
  for (std::size_t i = 0; i < e.nops(); ++i) {
    const ex& child = e.op(i);
    if (!trivial(child) && order.representative(child).is_equal(rep))
      count_children(child, rep, counts, order);
    else
      count(child, counts, order);
  }
}

// Counts occurrences by representative, so that e and −e are one subexpression; returns e's.
ex count(const ex& e, Counts& counts, CanonicalOrder& order) {
  if (trivial(e)) return e;
  const ex rep = order.representative(e);
  int& c = counts[rep];
  if (++c > 1) return rep;  // its children are counted once: they will be inside the temporary
  count_children(e, rep, counts, order);
  return rep;
}

struct Rewriter : GiNaC::map_function {
  const Counts& counts;
  CanonicalOrder& order;
  ExMap replaced;  // representative -> ±the temporary that holds it
  ExMap visited;   // expression -> rewritten expression
  ExMap aliases;   // dropped temporary -> ±the temporary that holds its value
  std::vector<Statement>* out = nullptr;
  int next = 0;

  Rewriter(const Counts& c, CanonicalOrder& o) : counts(c), order(o) {}

  // Children in canonical order, so that temporaries are numbered independently of GiNaC's order.
  ex map_children(const ex& e) {
    if (e.nops() == 0) return e;
    for (const ex& child : order.operands(e)) (*this)(child);
    return e.map(*this);
  }

  // A lone symbol, number or c·symbol with the aliases put in.
  ex alias(const ex& e) const {
    if (aliases.empty()) return e;
    if (isa<GiNaC::symbol>(e)) {
      const ex* a = aliases.find(e);
      return a ? *a : e;
    }
    if (isa<GiNaC::mul>(e)) return alias(e.op(0)) * alias(e.op(1));
    return e;
  }

  ex operator()(const ex& e) override {
    if (trivial(e)) return alias(e);
    if (const ex* v = visited.find(e)) return *v;
    const int sign = order.sign(e);
    const ex rep = sign > 0 ? e : ex(-e);
    ex result;
    if (const ex* r = replaced.find(rep)) {
      result = sign * *r;
    } else if (const int* c = counts.find(rep); c && *c > 1) {
      // −e is usually e with its sign absorbed (a sum's terms, a product's coefficient); an odd
      // power of a negative-signed base, e.g. t^-1, stays the product (t^-1)·(−1), whose child
      // is e itself: map e's children instead of recursing into e forever.
      bool wraps = false;
      if (sign < 0 && isa<GiNaC::mul>(rep))
        for (std::size_t i = 0; i < rep.nops(); ++i) wraps = wraps || rep.op(i).is_equal(e);
      ex mapped = wraps ? ex(-map_children(e)) : map_children(rep);
      GiNaC::symbol tmp("c" + std::to_string(next++));
      order.set_sign(tmp, printed_sign(mapped, order));
      out->push_back({tmp.get_name(), mapped, true, tmp});
      replaced.emplace(rep, tmp);
      result = sign * tmp;
    } else {
      result = map_children(e);
    }
    visited.emplace(e, result);
    return result;
  }
};

// Every non-trivial subexpression that occurs more than once is computed once: by the first
// temporary whose whole value it is, when no statement before that one needs it (later
// temporaries with that value are dropped), otherwise by a new temporary `c<k>` before its first
// use.
//
// Signs: the code stores canonical values (canonical.hpp), so a temporary whose symbol's sign
// differs from its value's is defined with a negation, and an output that is −t alone is written
// with one. Each temporary gets the symbol sign that needs fewer (a new symbol when that changes
// it).
std::vector<Statement> share_subtrees(const std::vector<Statement>& in, CanonicalOrder& order) {
  Counts counts;
  // Per temporary: outputs ±t (weight 1, a negation each when its sign is −) and terms ±t of
  // output sums (weight 1/4, to break ties: they may decide the sign of the sum).
  std::unordered_map<ex, std::pair<double, double>, std::hash<GiNaC::ex>, GiNaC::ex_is_equal> as_output;  // +t, −t
  auto note = [&](const ex& e, double weight) {
    if (isa<GiNaC::symbol>(e)) {
      as_output[e].first += weight;
    } else if (trivial(e) && isa<GiNaC::mul>(e)) {
      auto& n = as_output[e.op(0)];
      (ex_to<GiNaC::numeric>(e.op(1)).is_negative() ? n.second : n.first) += weight;
    }
  };
  std::vector<ex> reps;  // of the statements' values
  reps.reserve(in.size());
  for (const auto& s : in) {
    reps.push_back(count(s.value, counts, order));
    if (s.temporary) continue;
    note(s.value, 1);
    if (isa<GiNaC::add>(s.value))
      for (std::size_t i = 0; i < s.value.nops(); ++i) note(s.value.op(i), 0.25);
  }
  std::vector<Statement> out;
  out.reserve(in.size());
  Rewriter rewrite(counts, order);
  rewrite.out = &out;
  for (std::size_t j = 0; j < in.size(); ++j) {
    const Statement& s = in[j];
    if (trivial(s.value)) {
      out.push_back({s.target, rewrite.alias(s.value), s.temporary, s.symbol});
      continue;
    }
    const int sign = order.sign(s.value);
    const ex& rep = reps[j];
    const bool repeated = *counts.find(rep) > 1;
    if (const ex* r = repeated ? rewrite.replaced.find(rep) : nullptr) {
      if (s.temporary) {
        rewrite.aliases.emplace(s.symbol, sign * *r);
      } else {
        out.push_back({s.target, sign * *r, false, s.symbol});
      }
      continue;
    }
    if (!s.temporary) {  // an output whose value occurs elsewhere too gets a new temporary
      out.push_back({s.target, rewrite(s.value), false, s.symbol});
      continue;
    }
    const ex v = rewrite.map_children(s.value);
    const int natural = printed_sign(v, order);
    const auto it = as_output.find(s.symbol);
    const auto [plus, minus] = it == as_output.end() ? std::make_pair(0.0, 0.0) : it->second;
    // With the natural sign an output −t costs a negation (t when natural < 0); with the other
    // sign the definition does.
    const int chosen = (natural > 0 ? minus : plus) > 1 + (natural > 0 ? plus : minus) ? -natural : natural;
    ex symbol = s.symbol;
    if (chosen != order.sign(s.symbol)) {
      const GiNaC::symbol fresh(s.target);
      order.set_sign(fresh, chosen);
      rewrite.aliases.emplace(s.symbol, fresh);
      symbol = fresh;
    }
    out.push_back({s.target, v, true, symbol});
    if (repeated) rewrite.replaced.emplace(rep, sign * symbol);
  }
  return out;
}

// Temporaries with equal (or opposite) values become one: specialising a kernel at an operating
// point makes distinct intermediates equal (t18 = t1*p[2] beside t2 = t1*p[2] once y = y0).
// In statement order, each value with the earlier merges put in; a temporary whose value an
// earlier one already holds is dropped and its symbol stands for ±that one from then on.
std::vector<Statement> merge_equal_temporaries(const std::vector<Statement>& in, CanonicalOrder& order) {
  Replace replace;
  std::vector<Statement> out;
  out.reserve(in.size());
  ExMap first;  // representative of a temporary's value -> ±its symbol, = the value
  for (const auto& s : in) {
    const ex v = replace(s.value);
    if (s.temporary && isa<GiNaC::numeric>(v)) {  // a − a once merged: the constant stands in
      replace.replaced[s.symbol] = v;
      continue;
    }
    if (s.temporary && !trivial(v)) {
      const int sign = order.sign(v);
      const ex rep = sign > 0 ? v : ex(-v);
      if (const ex* f = first.find(rep)) {
        replace.replaced[s.symbol] = sign * *f;
        continue;
      }
      first.emplace(rep, sign * s.symbol);
    }
    out.push_back({s.target, v, s.temporary, s.symbol});
  }
  return out;
}

}  // namespace

namespace {

// ---- Bounded polynomial forms ----------------------------------------------------------------
// The program computes positions and rotations body by body in world axes, so even a short
// chain's entries are long roundabout sums: M₂₂ = m₂ l₂² of the double pendulum came out as
// t59 − t2·t61 + t3·t60 over products of sin q₁, cos q₁, sin q₂, cos q₂. Written out as a
// polynomial in the kernel's atoms (parameters, coordinates, calls, and every quantity too large
// to write out), with exact cancellation and sin² x + cos² x = 1, such an entry is often much
// smaller. Each temporary's polynomial is built from those of its operands, with at most
// kMaxTerms terms (a larger one is an atom of the others), so this is linear in the kernel size.

constexpr std::size_t kMaxTerms = 24;
// Terms allowed on the way, before cancellation and sin² + cos² = 1: x² + y² of a point three
// links out is 2 × 49 products, 56 terms once combined and 7 in the end. (A larger bound helps
// little and costs generation time.)
constexpr std::size_t kMaxWork = 64;
// Temporaries tried per monomial when looking for one whose polynomial a value contains (the
// latest ones: kinematics builds on what it just computed).
constexpr std::size_t kCandidates = 8;
// Kernels up to this many statements get polynomial forms. They pay on short chains (a planar
// 2-link chain's linear kernel: 48 operations without, 31 with), where the polynomials are short;
// on long ones they change the count by ±1 % and would take a third of the generation time (a
// point's coordinates have 2^k terms k links out, so few polynomials are short).
constexpr std::size_t kMaxStatementsSimplified = 2000;

using Powers = std::vector<std::pair<std::uint32_t, int>>;  // (atom, exponent ≠ 0), by atom
struct Term {
  Powers powers;
  GiNaC::numeric coefficient;
};
using Poly = std::vector<Term>;  // by powers, no zero coefficient

// Sorts and combines equal monomials; nullopt when more than `limit` remain.
std::optional<Poly> normalise(Poly p, std::size_t limit = kMaxWork) {
  std::sort(p.begin(), p.end(), [](const Term& a, const Term& b) { return a.powers < b.powers; });
  Poly out;
  for (auto& t : p) {
    if (!out.empty() && out.back().powers == t.powers) {
      out.back().coefficient += t.coefficient;
      if (out.back().coefficient.is_zero()) out.pop_back();
    } else {
      out.push_back(std::move(t));
    }
  }
  if (out.size() > limit) return std::nullopt;
  return out;
}

Powers multiply_powers(const Powers& a, const Powers& b) {
  Powers r;
  r.reserve(a.size() + b.size());
  std::size_t i = 0, j = 0;
  while (i < a.size() || j < b.size()) {
    if (j == b.size() || (i < a.size() && a[i].first < b[j].first)) {
      r.push_back(a[i++]);
    } else if (i == a.size() || b[j].first < a[i].first) {
      r.push_back(b[j++]);
    } else {
      const int k = a[i].second + b[j].second;
      if (k != 0) r.push_back({a[i].first, k});
      ++i, ++j;
    }
  }
  return r;
}

std::optional<Poly> multiply(const Poly& a, const Poly& b) {
  // Products far beyond the bound do not cancel back under it in kinematics.
  if (a.size() * b.size() > kMaxWork) return std::nullopt;
  Poly p;
  p.reserve(a.size() * b.size());
  for (const auto& x : a)
    for (const auto& y : b) p.push_back({multiply_powers(x.powers, y.powers), x.coefficient * y.coefficient});
  return normalise(std::move(p));
}

// Symbols that stand for polynomials, to be found inside others (sub-sums), by first monomial.
struct SubSums {
  std::map<Powers, std::vector<ex>> anchors;
  std::unordered_map<ex, Poly, std::hash<GiNaC::ex>, GiNaC::ex_is_equal> polys;
  void add(const ex& symbol, const Poly& p) {
    polys.emplace(symbol, p);
    if (p.size() >= 2) anchors[p.front().powers].push_back(symbol);
  }
};

class PolynomialForms {
 public:
  explicit PolynomialForms(CanonicalOrder& order) : order_(order) {}

  // A temporary's polynomial; none: the temporary is an atom of the others' polynomials.
  void define(const ex& symbol, const ex& value, const std::optional<Poly>& p) {
    if (p) {
      temporaries_.add(symbol, *p);
    } else {
      atom(symbol, value);
    }
  }

  // e as a polynomial in the atoms, with sin² + cos² = 1 applied; nullopt when too large.
  std::optional<Poly> of(const ex& e) {
    std::optional<Poly> p = convert(e);
    if (!p) return p;
    collapse_pythagoras(*p);
    if (p->size() > kMaxTerms) return std::nullopt;
    return p;
  }

  const SubSums& temporaries() const { return temporaries_; }

  // p as a sum of multiples of symbols of `sums` whose polynomials it contains (other than
  // `exclude`; each round the one that cancels most terms, at least two) and the rest, which
  // expression() factors greedily (the atom common to most terms first).
  struct Plan {
    std::vector<std::pair<GiNaC::numeric, ex>> sums;  // r·symbol
    Poly rest;
  };
  Plan plan(Poly p, const ex& exclude, const SubSums& sums) const {
    Plan out;
    for (int round = 0; round < 4 && p.size() >= 2 && !sums.anchors.empty(); ++round) {
      const ex* best = nullptr;
      GiNaC::numeric best_ratio;
      std::size_t most = 1;
      for (const auto& t : p) {
        const auto it = sums.anchors.find(t.powers);
        if (it == sums.anchors.end()) continue;
        const std::vector<ex>& list = it->second;
        for (std::size_t c = list.size() > kCandidates ? list.size() - kCandidates : 0; c < list.size(); ++c) {
          if (list[c].is_equal(exclude)) continue;
          const Poly& q = sums.polys.at(list[c]);
          std::vector<GiNaC::numeric> ratios;  // p's coefficient over q's, for each of q's terms
          std::size_t i = 0;
          for (const auto& u : q) {
            while (i < p.size() && p[i].powers < u.powers) ++i;
            if (i == p.size() || p[i].powers != u.powers) break;
            ratios.push_back(p[i].coefficient / u.coefficient);
          }
          if (ratios.size() < q.size()) continue;
          for (const auto& r : ratios) {
            const auto n = static_cast<std::size_t>(std::count(ratios.begin(), ratios.end(), r));
            if (n > most) best = &list[c], best_ratio = r, most = n;
          }
        }
      }
      if (!best) break;
      out.sums.push_back({best_ratio, *best});
      Poly rest = p;
      for (const auto& u : sums.polys.at(*best)) rest.push_back({u.powers, -best_ratio * u.coefficient});
      p = *normalise(std::move(rest));
    }
    out.rest = std::move(p);
    return out;
  }

  // Operations of expression(plan) (as cost() counts them, signs aside), without building it.
  std::size_t cost(const Plan& plan) const {
    std::size_t n = plan.rest.empty() ? 0 : factor_cost(plan.rest);
    const std::size_t parts = plan.sums.size() + !plan.rest.empty();
    n += parts > 0 ? parts - 1 : 0;
    for (const auto& [r, symbol] : plan.sums) n += !(r == 1 || r == -1);
    return n;
  }

  // The atoms plan reads, and its sum symbols.
  template <class F>
  void for_each_read(const Plan& plan, F f) const {
    for (const auto& [r, symbol] : plan.sums) f(symbol);
    for (const auto& t : plan.rest)
      for (const auto& [a, k] : t.powers) f(atoms_[a]);
  }

  ex expression(const Plan& plan) const {
    GiNaC::exvector parts;
    for (const auto& [r, symbol] : plan.sums) parts.push_back(r * symbol);
    parts.push_back(factor(plan.rest));
    return GiNaC::add(parts);
  }

 private:
  CanonicalOrder& order_;
  std::vector<ex> atoms_;
  std::vector<std::size_t> atom_cost_;  // operations to compute an atom that is not a symbol
  std::unordered_map<ex, std::uint32_t, std::hash<GiNaC::ex>, GiNaC::ex_is_equal> atom_index_;
  SubSums temporaries_;
  // sin x and cos x by argument x: atoms, −1 while unseen.
  std::unordered_map<ex, std::pair<long, long>, std::hash<GiNaC::ex>, GiNaC::ex_is_equal> trig_;
  std::vector<long> cosine_;  // by atom: for sin x, the atom cos x (once both are seen), else −1

  std::uint32_t atom(const ex& a, const ex& value) {
    if (auto it = atom_index_.find(a); it != atom_index_.end()) return it->second;
    const auto k = static_cast<std::uint32_t>(atoms_.size());
    atoms_.push_back(a);
    atom_index_.emplace(a, k);
    atom_cost_.push_back(isa<GiNaC::symbol>(a) ? 0 : mbsgen::cost(a, order_));
    if (isa<GiNaC::function>(value) && value.nops() == 1) {
      const std::string name = ex_to<GiNaC::function>(value).get_name();
      if (name == "sin" || name == "cos") {
        auto& pair = trig_.emplace(value.op(0), std::make_pair(-1L, -1L)).first->second;
        (name == "sin" ? pair.first : pair.second) = k;
        if (pair.first >= 0 && pair.second >= 0) {
          cosine_.resize(atoms_.size(), -1);
          cosine_[static_cast<std::size_t>(pair.first)] = pair.second;
        }
      }
    }
    return k;
  }

  Poly leaf(const ex& a) { return Poly{{Powers{{atom(a, a), 1}}, GiNaC::numeric(1)}}; }

  std::optional<Poly> convert(const ex& e) {
    if (isa<GiNaC::numeric>(e)) {
      const GiNaC::numeric& n = ex_to<GiNaC::numeric>(e);
      if (!n.is_real()) return leaf(e);
      return n.is_zero() ? Poly{} : Poly{{Powers{}, n}};
    }
    if (isa<GiNaC::symbol>(e)) {
      if (auto it = temporaries_.polys.find(e); it != temporaries_.polys.end()) return it->second;
      return leaf(e);
    }
    if (isa<GiNaC::add>(e)) {
      // Operands in canonical order, not GiNaC's (which follows hashes that change from run to
      // run): atoms are numbered as first met, and the numbering breaks the factoring's ties.
      Poly sum;
      for (const ex& op : order_.operands(e)) {
        std::optional<Poly> t = convert(op);
        if (!t) return std::nullopt;
        sum.insert(sum.end(), t->begin(), t->end());
        if (sum.size() > kMaxWork) return std::nullopt;
      }
      return normalise(std::move(sum));
    }
    if (isa<GiNaC::mul>(e)) {
      std::optional<Poly> product = Poly{{Powers{}, GiNaC::numeric(1)}};
      for (const ex& op : order_.operands(e)) {
        if (!product) break;
        std::optional<Poly> f = convert(op);
        if (!f) return std::nullopt;
        product = multiply(*product, *f);
      }
      return product;
    }
    if (integer_power(e)) {
      const long k = ex_to<GiNaC::numeric>(e.op(1)).to_long();
      if (k < 0) {  // a division: the base stays whole
        const ex& b = e.op(0);
        return Poly{{Powers{{atom(b, b), static_cast<int>(k)}}, GiNaC::numeric(1)}};
      }
      const std::optional<Poly> base = convert(e.op(0));
      std::optional<Poly> p = Poly{{Powers{}, GiNaC::numeric(1)}};
      for (long i = 0; i < k && p && base; ++i) p = multiply(*p, *base);
      return base ? p : std::nullopt;
    }
    return leaf(e);
  }

  // a·A·sin²x + a·A·cos²x → a·A, until no such pair is left (never the other way, 1 − cos²x,
  // which would cancel digits near x = 0).
  void collapse_pythagoras(Poly& p) const {
    if (cosine_.empty() || p.size() < 2) return;
    auto shifted = [](Powers w, std::uint32_t a, int dk) {
      auto it = std::find_if(w.begin(), w.end(), [a](const auto& x) { return x.first >= a; });
      if (it != w.end() && it->first == a) {
        it->second += dk;
        if (it->second == 0) w.erase(it);
      } else {
        w.insert(it, {a, dk});
      }
      return w;
    };
    const bool squares = std::any_of(p.begin(), p.end(), [&](const Term& t) {
      return std::any_of(t.powers.begin(), t.powers.end(), [&](const auto& x) {
        return x.second >= 2 && x.first < cosine_.size() && cosine_[x.first] >= 0;
      });
    });
    if (!squares) return;
    std::map<Powers, GiNaC::numeric> terms;
    for (auto& t : p) terms.emplace(std::move(t.powers), t.coefficient);
    // Finds a pair a·A·sin²x, a·A·cos²x and replaces it by a·A; false when there is none.
    auto collapse_one = [&] {
      for (auto it = terms.begin(); it != terms.end(); ++it) {
        for (const auto& [s, k] : it->first) {
          if (k < 2 || s >= cosine_.size() || cosine_[s] < 0) continue;
          const auto partner = terms.find(shifted(shifted(it->first, s, -2), static_cast<std::uint32_t>(cosine_[s]), 2));
          if (partner == terms.end() || partner->second != it->second) continue;
          const GiNaC::numeric a = it->second;
          Powers reduced = shifted(it->first, s, -2);
          terms.erase(partner);
          terms.erase(it);
          const auto [r, inserted] = terms.emplace(std::move(reduced), a);
          if (!inserted && (r->second += a).is_zero()) terms.erase(r);
          return true;
        }
      }
      return false;
    };
    while (collapse_one()) {
    }
    p.clear();
    for (auto& [w, a] : terms) p.push_back({w, a});
  }

  ex monomial(const Term& t) const {
    GiNaC::exvector f{t.coefficient};
    for (const auto& [a, k] : t.powers) f.push_back(k == 1 ? atoms_[a] : GiNaC::pow(atoms_[a], k));
    return GiNaC::mul(f);
  }

  // The atom in most terms of p (positive exponent; ties: the first atom), if in two or more.
  static std::optional<std::uint32_t> common_atom(const Poly& p) {
    std::map<std::uint32_t, std::size_t> count;
    for (const auto& t : p)
      for (const auto& [a, k] : t.powers)
        if (k > 0) ++count[a];
    std::optional<std::uint32_t> best;
    std::size_t most = 1;
    for (const auto& [a, n] : count)
      if (n > most) best = a, most = n;
    return best;
  }

  // p's terms with atom a (divided by a) and without.
  static std::pair<Poly, Poly> split(Poly p, std::uint32_t a) {
    Poly with, without;
    for (auto& t : p) {
      auto it = std::find_if(t.powers.begin(), t.powers.end(), [a](const auto& x) { return x.first == a; });
      if (it != t.powers.end() && it->second > 0) {
        if (--it->second == 0) t.powers.erase(it);
        with.push_back(std::move(t));
      } else {
        without.push_back(std::move(t));
      }
    }
    return {std::move(with), std::move(without)};
  }

  // The atom in most terms is factored out of those terms, and so on recursively on both parts.
  ex factor(const Poly& p) const {
    if (p.empty()) return 0;
    if (p.size() == 1) return monomial(p[0]);
    const std::optional<std::uint32_t> a = common_atom(p);
    if (!a) {
      GiNaC::exvector terms;
      for (const auto& t : p) terms.push_back(monomial(t));
      return GiNaC::add(terms);
    }
    const auto [with, without] = split(p, *a);
    return atoms_[*a] * factor(with) + factor(without);
  }

  std::size_t monomial_cost(const Term& t) const {
    std::size_t n = 0, factors = !(t.coefficient == 1 || t.coefficient == -1);
    for (const auto& [a, k] : t.powers) {
      n += atom_cost_[a] + static_cast<std::size_t>(std::abs(k) - 1);
      if (k > 0) ++factors;
      else ++n;  // a division
    }
    return n + (factors > 0 ? factors - 1 : 0);
  }

  std::size_t factor_cost(const Poly& p) const {
    if (p.size() == 1) return monomial_cost(p[0]);
    const std::optional<std::uint32_t> a = common_atom(p);
    if (!a) {
      std::size_t n = p.size() - 1;
      for (const auto& t : p) n += monomial_cost(t);
      return n;
    }
    const auto [with, without] = split(p, *a);
    // a·with: one product unless with is ±1; + without: one sum unless empty.
    const bool unit = with.size() == 1 && with[0].powers.empty() && (with[0].coefficient == 1 || with[0].coefficient == -1);
    return atom_cost_[*a] + factor_cost(with) + !unit + (without.empty() ? 0 : 1 + factor_cost(without));
  }
};

bool polynomial_node(const ex& e) {
  return isa<GiNaC::numeric>(e) || isa<GiNaC::symbol>(e) || isa<GiNaC::add>(e) || isa<GiNaC::mul>(e) ||
         integer_power(e);
}

// The statements' polynomials (PolynomialForms; none for a lone symbol, a number or a call).
struct Polynomials {
  explicit Polynomials(CanonicalOrder& order) : forms(order) {}
  PolynomialForms forms;
  std::vector<std::optional<Poly>> of;  // per statement
  std::vector<double> own;              // per statement: its cost with its share of what it reads
};

// Each statement's value or its polynomial form, whichever costs less. A value's cost counts
// its own operations and a share of each temporary it reads (that temporary's cost over its
// readers), so that a value takes its polynomial form when that saves the temporaries only it
// reads. Temporaries that became a lone symbol or number are put into their readers, and
// unread ones dropped.
std::vector<Statement> simplify_polynomials(const std::vector<Statement>& in, Polynomials& polys,
                                            CanonicalOrder& order) {
  polys.own.assign(in.size(), 0.0);
  std::vector<double>& own = polys.own;
  Index index;
  std::vector<std::vector<std::size_t>> reads(in.size());
  std::vector<std::size_t> readers(in.size(), 0);
  for (std::size_t j = 0; j < in.size(); ++j) {
    reads[j] = references(in[j].value, index);
    for (std::size_t r : reads[j]) ++readers[r];
    if (in[j].temporary) index.emplace(in[j].symbol, j);
  }
  auto share = [&](const std::vector<std::size_t>& rs) {
    double c = 0;
    for (std::size_t r : rs) c += own[r] / static_cast<double>(std::max<std::size_t>(readers[r], 1));
    return c;
  };
  PolynomialForms& forms = polys.forms;
  polys.of.assign(in.size(), std::nullopt);
  std::vector<ex> values(in.size());
  for (std::size_t j = 0; j < in.size(); ++j) {
    const Statement& s = in[j];
    values[j] = s.value;
    own[j] = static_cast<double>(cost(s.value, order)) + share(reads[j]);
    std::optional<Poly>& p = polys.of[j];
    // A temporary that is a lone symbol or number is one already; an output may be ±a temporary.
    if (polynomial_node(s.value) && (!trivial(s.value) || !s.temporary)) p = forms.of(s.value);
    if (p) {
      const PolynomialForms::Plan plan = forms.plan(*p, s.value, forms.temporaries());
      std::vector<std::size_t> plan_reads;
      forms.for_each_read(plan, [&](const ex& a) {
        const std::vector<std::size_t> r = references(a, index);
        plan_reads.insert(plan_reads.end(), r.begin(), r.end());
      });
      std::sort(plan_reads.begin(), plan_reads.end());
      plan_reads.erase(std::unique(plan_reads.begin(), plan_reads.end()), plan_reads.end());
      const double c = static_cast<double>(forms.cost(plan)) + share(plan_reads);
      if (c < own[j]) values[j] = forms.expression(plan), own[j] = c;
    }
    if (s.temporary) forms.define(s.symbol, s.value, p);
  }
  Replace replace;
  std::vector<Statement> out;
  out.reserve(in.size());
  for (std::size_t j = 0; j < in.size(); ++j) {
    const Statement& s = in[j];
    const ex v = replace(values[j]);
    if (s.temporary && trivial(v)) {
      replace.replaced[s.symbol] = v;
    } else {
      out.push_back({s.target, v, s.temporary, s.symbol});
    }
  }
  return drop_unread(std::move(out));
}

// Every output that has a polynomial written as one, the smaller ones first, each as a sum of
// multiples of the smaller ones it contains and the rest factored (a short chain's M₁₁ = M₁₂ +
// …): the form of SymPy's expressions, better than the program's roundabout one where the
// polynomials are short. The outputs that others contain get temporaries named after them (M_4).
std::optional<std::vector<Statement>> polynomial_outputs(const std::vector<Statement>& in,
                                                         const Polynomials& polys, CanonicalOrder& order) {
  // The entries of output buffers, "M[4]"; each may be held by a temporary named after it, "M_4"
  // (not after its rank: then a scene's kernel prints its shared part as the full model's does).
  auto entry_name = [](const std::string& target) {
    const std::size_t open = target.find('[');
    if (open == std::string::npos || open == 0 || target.back() != ']') return std::string();
    for (std::size_t i = 0; i < open; ++i)
      if (!(std::isalnum(static_cast<unsigned char>(target[i])) || target[i] == '_')) return std::string();
    for (std::size_t i = open + 1; i + 1 < target.size(); ++i)
      if (!std::isdigit(static_cast<unsigned char>(target[i]))) return std::string();
    return target.substr(0, open) + "_" + target.substr(open + 1, target.size() - open - 2);
  };
  std::vector<std::size_t> outputs;
  for (std::size_t j = 0; j < in.size(); ++j)
    if (!in[j].temporary && polys.of[j] && !polys.of[j]->empty() && !entry_name(in[j].target).empty())
      outputs.push_back(j);
  std::stable_sort(outputs.begin(), outputs.end(),
                   [&](std::size_t a, std::size_t b) { return polys.of[a]->size() < polys.of[b]->size(); });
  SubSums sums;
  std::vector<GiNaC::symbol> held;  // the value of outputs[k]
  std::vector<PolynomialForms::Plan> plans;
  // Estimates: each plan's operations, and each output's cost with its share of what it reads
  // (simplify_polynomials). Both are rough (shares of temporaries that end up unread, plans
  // counted before common subtrees are shared): written out only within 1.5× of the current
  // form, and then kept only if its exact count is lower (eliminate_common_subexpressions).
  double estimate = 0, current = 0;
  std::vector<char> written(in.size(), 0);
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    held.emplace_back(entry_name(in[outputs[k]].target));
    plans.push_back(polys.forms.plan(*polys.of[outputs[k]], ex(), sums));
    sums.add(held[k], *polys.of[outputs[k]]);
    estimate += static_cast<double>(polys.forms.cost(plans[k]));
    written[outputs[k]] = 1;
  }
  for (std::size_t j = 0; j < in.size(); ++j) {
    if (in[j].temporary) continue;
    current += polys.own[j];
    if (!written[j]) estimate += polys.own[j];
  }
  if (estimate >= 1.5 * current) return std::nullopt;
  std::vector<ex> values;
  Index index;
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    values.push_back(polys.forms.expression(plans[k]));
    index.emplace(held[k], k);
  }
  std::vector<char> read(outputs.size(), 0);
  for (const ex& v : values)
    for (std::size_t r : references(v, index)) read[r] = 1;
  std::vector<Statement> out;
  for (const auto& s : in)
    if (s.temporary) out.push_back(s);
  std::vector<ex> output_value(in.size());
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    output_value[outputs[k]] = values[k];
    if (!read[k]) continue;
    order.set_sign(held[k], printed_sign(values[k], order));
    out.push_back({held[k].get_name(), values[k], true, held[k]});
    output_value[outputs[k]] = held[k];
  }
  for (std::size_t j = 0; j < in.size(); ++j)
    if (!in[j].temporary) out.push_back({in[j].target, written[j] ? output_value[j] : in[j].value, false, in[j].symbol});
  return drop_unread(std::move(out));
}

}  // namespace

std::vector<Statement> eliminate_common_subexpressions(const std::vector<Statement>& in0, CanonicalOrder& order) {
  const std::vector<Statement> in = merge_equal_temporaries(in0, order);
  if (in.size() > kMaxStatementsSimplified) return share_subtrees(in, order);
  Polynomials polys(order);
  std::vector<Statement> best = share_subtrees(simplify_polynomials(in, polys, order), order);
  if (std::optional<std::vector<Statement>> written = polynomial_outputs(in, polys, order)) {
    std::vector<Statement> shared = share_subtrees(*written, order);
    if (kernel_cost(shared, order) < kernel_cost(best, order)) best = std::move(shared);
  }
  return best;
}

}  // namespace mbsgen
