#include "mbsgen/generator/cse.hpp"

#include <unordered_map>

namespace mbsgen {

using GiNaC::ex;

namespace {

bool trivial(const ex& e) {
  if (GiNaC::is_a<GiNaC::symbol>(e) || GiNaC::is_a<GiNaC::numeric>(e) ||
      GiNaC::is_a<GiNaC::constant>(e))
    return true;
  return GiNaC::is_a<GiNaC::mul>(e) && e.nops() == 2 && GiNaC::is_a<GiNaC::numeric>(e.op(1)) &&
         GiNaC::is_a<GiNaC::symbol>(e.op(0));
}

using ExMap = std::unordered_map<ex, ex, std::hash<GiNaC::ex>, GiNaC::ex_is_equal>;
using Counts = std::unordered_map<ex, int, std::hash<GiNaC::ex>, GiNaC::ex_is_equal>;

// Counts occurrences by representative, so that e and −e are one subexpression.
void count(const ex& e, Counts& counts, CanonicalOrder& order) {
  if (trivial(e)) return;
  int& c = counts[order.representative(e)];
  if (++c > 1) return;  // its children are counted once: they will be inside the temporary
  for (std::size_t i = 0; i < e.nops(); ++i) count(e.op(i), counts, order);
}

struct Rewriter : GiNaC::map_function {
  const Counts& counts;
  CanonicalOrder& order;
  ExMap replaced;  // representative -> temporary
  ExMap visited;   // expression -> rewritten expression
  std::vector<Statement>* out = nullptr;
  int next = 0;

  Rewriter(const Counts& c, CanonicalOrder& o) : counts(c), order(o) {}

  // Children in canonical order, so that temporaries are numbered independently of GiNaC's order.
  ex map_children(const ex& e) {
    if (e.nops() == 0) return e;
    for (const ex& child : order.operands(e)) (*this)(child);
    return e.map(*this);
  }

  ex operator()(const ex& e) override {
    if (trivial(e)) return e;
    if (auto it = visited.find(e); it != visited.end()) return it->second;
    const int sign = order.sign(e);
    const ex rep = sign > 0 ? e : ex(-e);
    ex result;
    if (auto it = replaced.find(rep); it != replaced.end()) {
      result = sign * it->second;
    } else if (auto c = counts.find(rep); c != counts.end() && c->second > 1) {
      // −e is usually e with its sign absorbed (a sum's terms, a product's coefficient); an odd
      // power of a negative-signed base, e.g. t^-1, stays the product (t^-1)·(−1), whose child
      // is e itself: map e's children instead of recursing into e forever.
      bool wraps = false;
      if (sign < 0 && GiNaC::is_a<GiNaC::mul>(rep))
        for (std::size_t i = 0; i < rep.nops(); ++i) wraps = wraps || rep.op(i).is_equal(e);
      ex mapped = wraps ? ex(-map_children(e)) : map_children(rep);
      GiNaC::symbol tmp("c" + std::to_string(next++));
      order.set_sign(tmp, order.sign(mapped));
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

}  // namespace

namespace {

// Temporaries with equal (or opposite) values become one: specialising a kernel at an operating
// point makes distinct intermediates equal (t18 = t1*p[2] beside t2 = t1*p[2] once y = y0).
// In statement order, each value with the earlier merges put in; a temporary whose value an
// earlier one already holds is dropped and its symbol stands for ±that one from then on.
std::vector<Statement> merge_equal_temporaries(const std::vector<Statement>& in,
                                               CanonicalOrder& order) {
  // Puts the merges into an expression: a hash lookup per symbol and a memo per subtree (GiNaC's
  // subs compares against an ordered map at every node, 3× slower on the 80-coordinate chain).
  struct Replace : GiNaC::map_function {
    ExMap merged;  // dropped symbol -> ±the symbol that holds its value
    ExMap memo;
    ex operator()(const ex& e) override {
      if (GiNaC::is_a<GiNaC::symbol>(e)) {
        const auto it = merged.find(e);
        return it == merged.end() ? e : it->second;
      }
      if (e.nops() == 0) return e;
      if (auto it = memo.find(e); it != memo.end()) return it->second;
      const ex r = e.map(*this);
      memo.emplace(e, r);
      return r;
    }
  } replace;
  std::vector<Statement> out;
  out.reserve(in.size());
  ExMap first;  // representative of a temporary's value -> ±its symbol, = the value
  ExMap& merged = replace.merged;
  for (const auto& s : in) {
    const ex v = merged.empty() ? s.value : replace(s.value);
    if (s.temporary && !trivial(v)) {
      const int sign = order.sign(v);
      const ex rep = sign > 0 ? v : ex(-v);
      if (auto it = first.find(rep); it != first.end()) {
        merged[s.symbol] = sign * it->second;
        continue;
      }
      first.emplace(rep, sign * s.symbol);
    }
    out.push_back({s.target, v, s.temporary, s.symbol});
  }
  return out;
}

}  // namespace

std::vector<Statement> eliminate_common_subexpressions(const std::vector<Statement>& in0,
                                                       CanonicalOrder& order) {
  const std::vector<Statement> in = merge_equal_temporaries(in0, order);
  Counts counts;
  for (const auto& s : in) {
    // The top of a statement is computed once anyway; count only its parts.
    if (trivial(s.value)) continue;
    for (std::size_t i = 0; i < s.value.nops(); ++i) count(s.value.op(i), counts, order);
  }
  std::vector<Statement> out;
  out.reserve(in.size());
  Rewriter rewrite(counts, order);
  rewrite.out = &out;
  for (const auto& s : in) {
    ex v = trivial(s.value) ? s.value : rewrite.map_children(s.value);
    out.push_back({s.target, v, s.temporary, s.symbol});
  }
  return out;
}

}  // namespace mbsgen
