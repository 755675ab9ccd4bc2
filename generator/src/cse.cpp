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

using Counts = std::unordered_map<ex, int, std::hash<GiNaC::ex>, GiNaC::ex_is_equal>;

void count(const ex& e, Counts& counts) {
  if (trivial(e)) return;
  int& c = counts[e];
  if (++c > 1) return;  // its children are counted once: they will be inside the temporary
  for (std::size_t i = 0; i < e.nops(); ++i) count(e.op(i), counts);
}

struct Rewriter : GiNaC::map_function {
  const Counts& counts;
  std::unordered_map<ex, ex, std::hash<GiNaC::ex>, GiNaC::ex_is_equal> replaced;
  std::vector<Statement>* out = nullptr;
  int next = 0;

  explicit Rewriter(const Counts& c) : counts(c) {}

  ex operator()(const ex& e) override {
    if (trivial(e)) return e;
    if (auto it = replaced.find(e); it != replaced.end()) return it->second;
    ex mapped = e.nops() > 0 ? e.map(*this) : e;
    auto c = counts.find(e);
    if (c != counts.end() && c->second > 1) {
      GiNaC::symbol tmp("c" + std::to_string(next++));
      out->push_back({tmp.get_name(), mapped, true, tmp});
      replaced.emplace(e, tmp);
      return tmp;
    }
    return mapped;
  }
};

}  // namespace

std::vector<Statement> eliminate_common_subexpressions(const std::vector<Statement>& in) {
  Counts counts;
  for (const auto& s : in) {
    // The top of a statement is computed once anyway; count only its parts.
    if (trivial(s.value)) continue;
    for (std::size_t i = 0; i < s.value.nops(); ++i) count(s.value.op(i), counts);
  }
  std::vector<Statement> out;
  out.reserve(in.size());
  Rewriter rewrite(counts);
  rewrite.out = &out;
  for (const auto& s : in) {
    ex v = trivial(s.value) || s.value.nops() == 0 ? s.value : s.value.map(rewrite);
    out.push_back({s.target, v, s.temporary, s.symbol});
  }
  return out;
}

}  // namespace mbsgen
