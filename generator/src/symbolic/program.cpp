#include "mbsgen/generator/symbolic/program.hpp"

#include "symbolic/type_test.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>

namespace mbsgen {

using GiNaC::ex;
using GiNaC::ex_to;

void Program::add_variable(const GiNaC::symbol& s) {
  if (!defs_.empty())
    throw std::logic_error("mbsgen::Program::add_variable: variables must precede definitions");
  if (variable_index_.find(s)) return;
  variable_index_.insert(s, variables_.size());
  variables_.push_back(s);
}

long Program::index_of(const ex& symbol) const {
  const std::size_t* k = def_index_.find(symbol);
  return k ? static_cast<long>(*k) : -1;
}

bool Program::bits_intersect(const Bits& a, const Bits& b) const {
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i)
    if (a[i] & b[i]) return true;
  return false;
}

Program::Bits Program::dependencies(const ex& e) const {
  Bits bits((variables_.size() + 63) / 64, 0);
  // Iterative walk: outputs can be long sums.
  std::vector<ex> stack{e};
  while (!stack.empty()) {
    ex x = stack.back();
    stack.pop_back();
    if (isa<GiNaC::symbol>(x)) {
      if (const std::size_t* d = def_index_.find(x)) {
        const Bits& b = deps_[*d];
        for (std::size_t i = 0; i < bits.size(); ++i) bits[i] |= b[i];
      } else if (const std::size_t* v = variable_index_.find(x)) {
        bits[*v / 64] |= std::uint64_t{1} << (*v % 64);
      }
      continue;
    }
    for (std::size_t i = 0; i < x.nops(); ++i) stack.push_back(x.op(i));
  }
  return bits;
}

void Program::collect_intermediates(const ex& e, std::vector<std::size_t>& out) const {
  std::vector<ex> stack{e};
  while (!stack.empty()) {
    ex x = stack.back();
    stack.pop_back();
    if (isa<GiNaC::symbol>(x)) {
      if (const std::size_t* d = def_index_.find(x)) out.push_back(*d);
      continue;
    }
    for (std::size_t i = 0; i < x.nops(); ++i) stack.push_back(x.op(i));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

namespace {

// Functions (sin, cos, sqrt, …) and non-integer powers: what define() names on its own.
bool internable(const ex& e) {
  return isa<GiNaC::function>(e) ||
         (isa<GiNaC::power>(e) &&
          !(isa<GiNaC::numeric>(e.op(1)) && ex_to<GiNaC::numeric>(e.op(1)).is_integer()));
}

bool holds_internable(const ex& e) {
  std::vector<ex> stack{e};
  while (!stack.empty()) {
    const ex x = stack.back();
    stack.pop_back();
    if (internable(x)) return true;
    for (std::size_t i = 0; i < x.nops(); ++i) stack.push_back(x.op(i));
  }
  return false;
}

bool trivial(const ex& e) {  // a number, a symbol or c·symbol: never named
  return isa<GiNaC::numeric>(e) || isa<GiNaC::symbol>(e) ||
         (isa<GiNaC::mul>(e) && e.nops() == 2 && isa<GiNaC::numeric>(e.op(1)) &&
          isa<GiNaC::symbol>(e.op(0)));
}

// The chain rule's sum ∂e/∂x + Σ_j ∂e/∂t_j dt_j/dx over `factors` (Program::ChainFactors), each
// partial through at() (the identity for a general derivative, a substitution for one at a
// point), dt_j/dx from derivative(j); a partial or a derivative that is 0 drops its term, and a
// partial that is 0 drops it before dt_j/dx is formed. Summed once: adding term by term rebuilt
// the sum each time.
template <class Factors, class At, class Derivative>
ex chain_rule(const Factors& factors, std::size_t variable, At at, Derivative derivative) {
  GiNaC::exvector terms;
  for (const auto& [v, d] : factors.variables)
    if (v == variable) terms.push_back(at(d));
  for (const auto& [j, p] : factors.intermediates) {
    const ex partial = at(p);
    if (partial.is_zero()) continue;
    const ex dt = derivative(j);
    if (!dt.is_zero()) terms.push_back(partial * dt);
  }
  return GiNaC::add(terms);
}

}  // namespace

// Functions (sin, cos, sqrt, …) and non-integer powers become intermediates of their own, so
// that sin and cos of each angle are computed once however often derivatives recreate them.
ex Program::intern_functions(const ex& e) {
  if (isa<GiNaC::symbol>(e) || isa<GiNaC::numeric>(e)) return e;
  const bool named = internable(e);
  if (!named && e.nops() == 0) return e;
  if (const ex* r = interned_.find(e)) return *r;
  struct InternChildren : GiNaC::map_function {
    Program* self;
    explicit InternChildren(Program* p) : self(p) {}
    ex operator()(const ex& x) override { return self->intern_functions(x); }
  } intern_children(this);
  // Children first, in canonical order, so that the numbering of new intermediates does not
  // depend on GiNaC's operand order; the map below then finds them interned.
  for (const ex& child : order_.operands(e)) intern_functions(child);
  ex mapped = e.nops() > 0 ? e.map(intern_children) : e;
  ex result = mapped;
  if (named) result = define_node(mapped);
  if (!interned_.find(e)) interned_.insert(e, result);
  return result;
}

ex Program::define(const ex& e0) {
  if (isa<GiNaC::numeric>(e0) || isa<GiNaC::symbol>(e0)) return e0;
  // Without functions and roots there is nothing to intern: no walk that hashes every node
  // (most definitions are derivatives, polynomials in the intermediates).
  return holds_internable(e0) ? define_node(intern_functions(e0)) : define_plain(e0);
}

ex Program::define_node(const ex& e) {
  if (trivial(e)) return e;
  const ex* known = interned_.find(e);
  if (known && isa<GiNaC::symbol>(*known)) return *known;
  const bool recorded = known != nullptr;
  const ex t = add_definition(e);
  if (!recorded) interned_.insert(e, t);  // (an entry already there is kept, as emplace did)
  return t;
}

ex Program::define_plain(const ex& e) {
  if (trivial(e)) return e;
  // The form interning gave an expression with functions has its symbol; an expression without
  // any is named anew (intern_functions records it as itself, not as a symbol), and CSE merges
  // equal temporaries when a kernel is emitted.
  if (const ex* known = interned_.find(e); known && isa<GiNaC::symbol>(*known)) return *known;
  return add_definition(e);
}

ex Program::add_definition(const ex& e) {
  GiNaC::symbol t("t" + std::to_string(defs_.size()));
  order_.set_sign(t, order_.sign(e));
  deps_.push_back(dependencies(e));
  defs_.push_back({t, e});
  def_index_.insert(t, defs_.size() - 1);
  return t;
}

std::size_t Program::variable(const GiNaC::symbol& x, const char* caller) const {
  const std::size_t* v = variable_index_.find(x);
  if (!v)
    throw std::logic_error(std::string("mbsgen::Program::") + caller +
                           ": not a registered variable: " + x.get_name());
  return *v;
}

bool Program::depends_on(const ex& e, const GiNaC::symbol& x) {
  const std::size_t var = variable(x, "depends_on");
  Bits b = dependencies(e);
  return (b[var / 64] >> (var % 64)) & 1u;
}

ex Program::diff_intermediate(std::size_t k, std::size_t variable) {
  if (!((deps_[k][variable / 64] >> (variable % 64)) & 1u)) return 0;
  const std::uint64_t key = static_cast<std::uint64_t>(k) * variables_.size() + variable;
  if (auto it = diff_memo_.find(key); it != diff_memo_.end()) return it->second;
  // dt_k/dx = ∂f_k/∂x + Σ_j ∂f_k/∂t_j dt_j/dx, summed once. The factors are kept per intermediate
  // (ChainFactors: the same expressions as differentiating f_k for each x anew, in a fraction of
  // the time); an intermediate t_j that does not depend on x contributes nothing.
  const ChainFactors& factors = chain_factors(k);  // stable: owned by a unique_ptr
  const ex sum = chain_rule(factors, variable, [](const ex& p) { return p; },
                            [&](std::size_t j) { return diff_intermediate(j, variable); });
  // A value holds functions and roots only at its top (define() names those inside), and the
  // derivative of one that holds none holds none either: nothing to intern.
  const ex d = internable(defs_[k].value) ? define(sum) : define_plain(sum);
  diff_memo_.emplace(key, d);
  return d;
}

const Program::ChainFactors& Program::chain_factors(std::size_t k) {
  if (chain_factors_.size() <= k) chain_factors_.resize(defs_.size());
  if (!chain_factors_[k]) chain_factors_[k] = std::make_unique<ChainFactors>(factors_of(defs_[k].value));
  return *chain_factors_[k];
}

Program::ChainFactors Program::factors_of(const ex& value, long only) const {
  // The operands of a sum that hold each intermediate and variable (all of a value that is not
  // a sum), so that each partial differentiates only those: a long sum's other terms would
  // differentiate to 0.
  const bool sum = isa<GiNaC::add>(value);
  const std::size_t n = sum ? value.nops() : 1;
  std::map<std::size_t, std::vector<std::size_t>> of_intermediate, of_variable;
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<ex> stack{sum ? value.op(i) : value};
    while (!stack.empty()) {
      const ex y = stack.back();
      stack.pop_back();
      if (isa<GiNaC::symbol>(y)) {
        if (const std::size_t* d = def_index_.find(y)) of_intermediate[*d].push_back(i);
        else if (const std::size_t* v = variable_index_.find(y); v && (only < 0 || *v == static_cast<std::size_t>(only)))
          of_variable[*v].push_back(i);
        continue;
      }
      for (std::size_t c = 0; c < y.nops(); ++c) stack.push_back(y.op(c));
    }
  }
  auto partial = [&](const GiNaC::symbol& s, std::vector<std::size_t> terms) -> ex {
    if (!sum) return value.diff(s);
    terms.erase(std::unique(terms.begin(), terms.end()), terms.end());
    GiNaC::exvector v;
    v.reserve(terms.size());
    for (std::size_t i : terms) v.push_back(value.op(i).diff(s));
    return GiNaC::add(v);
  };
  ChainFactors factors;
  for (const auto& [j, terms] : of_intermediate) factors.intermediates.emplace_back(j, partial(defs_[j].symbol, terms));
  for (const auto& [v, terms] : of_variable) factors.variables.emplace_back(v, partial(variables_[v], terms));
  return factors;
}

ex Program::diff(const ex& e, const GiNaC::symbol& x) {
  const std::size_t var = variable(x, "diff");
  if (isa<GiNaC::numeric>(e)) return 0;
  if (isa<GiNaC::symbol>(e)) {
    if (e.is_equal(x)) return 1;
    if (const std::size_t* d = def_index_.find(e)) return diff_intermediate(*d, var);
    return 0;
  }
  return chain_rule(factors_of(e, static_cast<long>(var)), var, [](const ex& p) { return p; },
                    [&](std::size_t k) { return diff_intermediate(k, var); });
}

ex Program::substitute_intermediate(std::size_t k, Substitution& s) {
  if (!bits_intersect(deps_[k], s.mask_)) return defs_[k].symbol;
  if (auto it = s.memo_.find(k); it != s.memo_.end()) return it->second;
  ex value = defs_[k].value;
  ex r = define(substitute(value, s));
  s.memo_.emplace(k, r);
  return r;
}

ex Program::substitute(const ex& e, Substitution& s) {
  if (isa<GiNaC::numeric>(e)) return e;
  if (s.mask_.empty()) {
    s.mask_.assign((variables_.size() + 63) / 64, 0);
    for (const auto& [key, value] : s.values_) {
      const std::size_t* v = variable_index_.find(key);
      if (!v) throw std::logic_error("mbsgen::Program::substitute: not a registered variable");
      s.mask_[*v / 64] |= std::uint64_t{1} << (*v % 64);
    }
  }
  std::vector<std::size_t> ts;
  collect_intermediates(e, ts);
  // Only the variables e holds itself: copying every value per call made a model's f^2 entries
  // cost f^3 (issue 14 §4: 2,000 decoupled oscillators).
  GiNaC::exmap m;
  if (s.values_.size() <= 8) {
    m = s.values_;
  } else {
    std::vector<ex> stack{e};
    while (!stack.empty()) {
      const ex x = stack.back();
      stack.pop_back();
      if (isa<GiNaC::symbol>(x)) {
        if (auto v = s.values_.find(x); v != s.values_.end()) m.insert(*v);
        continue;
      }
      for (std::size_t i = 0; i < x.nops(); ++i) stack.push_back(x.op(i));
    }
  }
  for (std::size_t k : ts) {
    ex r = substitute_intermediate(k, s);
    if (!r.is_equal(defs_[k].symbol)) m[defs_[k].symbol] = r;
  }
  return e.subs(m, GiNaC::subs_options::no_pattern);
}

ex Program::diff_at_intermediate(std::size_t k, std::size_t variable, Substitution& s) {
  if (!((deps_[k][variable / 64] >> (variable % 64)) & 1u)) return 0;
  const std::uint64_t key = static_cast<std::uint64_t>(k) * variables_.size() + variable;
  if (auto it = s.diff_memo_.find(key); it != s.diff_memo_.end()) return it->second;
  // dt_k/dx at the point = ∂f_k/∂x + Σ_j ∂f_k/∂t_j dt_j/dx, each factor at the point; a factor
  // that vanishes there drops its term before dt_j/dx is formed.
  const ChainFactors& factors = chain_factors(k);  // stable: owned by a unique_ptr
  const ex d = define(chain_rule(factors, variable, [&](const ex& p) { return substitute(p, s); },
                                 [&](std::size_t j) { return diff_at_intermediate(j, variable, s); }));
  s.diff_memo_.emplace(key, d);
  return d;
}

ex Program::diff_at(const ex& e, const GiNaC::symbol& x, Substitution& s) {
  const std::size_t var = variable(x, "diff_at");
  if (isa<GiNaC::numeric>(e)) return 0;
  if (isa<GiNaC::symbol>(e)) {
    if (e.is_equal(x)) return 1;
    if (const std::size_t* d = def_index_.find(e)) return diff_at_intermediate(*d, var, s);
    return 0;
  }
  return chain_rule(factors_of(e, static_cast<long>(var)), var, [&](const ex& p) { return substitute(p, s); },
                    [&](std::size_t k) { return diff_at_intermediate(k, var, s); });
}

ex Program::inline_all(const ex& e) {
  std::vector<std::size_t> ts;
  collect_intermediates(e, ts);
  GiNaC::exmap m;
  for (std::size_t k : ts) {
    auto it = inline_memo_.find(k);
    if (it == inline_memo_.end()) {
      ex value = defs_[k].value;
      it = inline_memo_.emplace(k, inline_all(value)).first;
    }
    m[defs_[k].symbol] = it->second;
  }
  return e.subs(m, GiNaC::subs_options::no_pattern);
}

}  // namespace mbsgen
