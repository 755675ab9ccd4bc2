// Checks of a parsed expression that need to know where each part of it was written (internal to
// the model reader, issue 14 §6, §7): constants that double cannot hold, inputs that do not enter
// linearly, and the function calls and powers whose derivatives Model::validate() checks at the
// operating point.
//
// The reader parses with one placeholder symbol per number or name written (yaml_reader.cpp), so
// that every subexpression of the placeholder tree is one span of the text: its leaves, and the
// function call it is, when it is one.
#pragma once

#include "symbolic/checked_subs.hpp"

#include <ginac/ginac.h>

#include <algorithm>
#include <cfloat>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace mbsgen::detail {

/// A placeholder's value and where its token is ([begin, end) in the expression text).
struct Leaf {
  GiNaC::ex value;
  std::size_t begin = 0, end = 0;
  std::size_t index = 0;  ///< order in the text
};

/// A function call as written: `name(` at begin, its `)` at end - 1; the placeholders of its
/// arguments are first_leaf … last_leaf (indices); depth counts the calls and parentheses
/// around it.
struct Call {
  std::string name;
  std::size_t begin = 0, end = 0;
  std::size_t first_leaf = 0, last_leaf = 0;
  std::size_t depth = 0;
  bool used = false;
};

/// A call or power of a model expression, with its text as written and its 0-based offset.
struct ExpressionSite {
  GiNaC::ex node;  ///< in the model's symbols
  std::string text;
  std::size_t offset = 0;
};

/// The parts of one expression: the placeholder tree, its leaves and calls, and the text.
class SiteLocator {
 public:
  SiteLocator(const std::string& text, std::map<GiNaC::ex, Leaf, GiNaC::ex_is_less> leaves,
              std::vector<Call> calls)
      : text_(text), leaves_(std::move(leaves)), calls_(std::move(calls)) {
    for (const auto& [placeholder, leaf] : leaves_) values_[placeholder] = leaf.value;
  }

  const GiNaC::exmap& values() const { return values_; }

  /// The subexpression in the model's symbols.
  GiNaC::ex value(const GiNaC::ex& tree) const { return checked_subs(tree, values_); }

  /// Whether a model symbol (a leaf that is a symbol) occurs in the subexpression.
  bool has_symbol(const GiNaC::ex& tree) const {
    if (GiNaC::is_a<GiNaC::symbol>(tree)) {
      auto it = leaves_.find(tree);
      return it != leaves_.end() && GiNaC::is_a<GiNaC::symbol>(it->second.value);
    }
    for (std::size_t i = 0; i < tree.nops(); ++i)
      if (has_symbol(tree.op(i))) return true;
    return false;
  }

  /// Whether one of `symbols` occurs in the subexpression.
  bool has_any(const GiNaC::ex& tree, const std::set<GiNaC::ex, GiNaC::ex_is_less>& symbols) const {
    if (GiNaC::is_a<GiNaC::symbol>(tree)) {
      auto it = leaves_.find(tree);
      return it != leaves_.end() && symbols.count(it->second.value) != 0;
    }
    for (std::size_t i = 0; i < tree.nops(); ++i)
      if (has_any(tree.op(i), symbols)) return true;
    return false;
  }

  /// The span of the text a subexpression was written in, [begin, end): its call, or its
  /// leaves widened to balanced parentheses.
  std::pair<std::size_t, std::size_t> span(const GiNaC::ex& tree) {
    if (const Call* c = call_of(tree)) return {c->begin, c->end};
    std::size_t lo = std::string::npos, hi = 0, first = 0, last = 0;
    leaf_range(tree, lo, hi, first, last);
    if (lo == std::string::npos) return {0, text_.size()};
    auto depth = [&](std::size_t a, std::size_t b) {
      long d = 0, low = 0;
      for (std::size_t i = a; i < b; ++i) {
        d += text_[i] == '(' ? 1 : text_[i] == ')' ? -1 : 0;
        low = std::min(low, d);
      }
      return std::make_pair(d, low);
    };
    // Widen left over unmatched ')' and right over unmatched '('.
    while (lo > 0 && depth(lo, hi).second < 0) {
      const std::size_t p = text_.rfind('(', lo - 1);
      lo = p == std::string::npos ? 0 : p;
    }
    while (hi < text_.size() && depth(lo, hi).first > 0) {
      const std::size_t p = text_.find(')', hi);
      hi = p == std::string::npos ? text_.size() : p + 1;
    }
    return {lo, hi};
  }

  ExpressionSite site(const GiNaC::ex& tree) {
    const auto [b, e] = span(tree);
    return {value(tree), text_.substr(b, e - b), b};
  }

  /// The call a function node or a power (sqrt, pow) of the tree was written as, or nullptr
  /// (a power written with '^'). Nodes must be asked in pre-order: of an outer and an inner call
  /// over the same arguments (sqrt(abs(x))), the first asked gets the outer.
  const Call* call_of(const GiNaC::ex& tree) {
    if (auto it = matched_.find(tree); it != matched_.end()) return it->second;
    const bool function = GiNaC::is_a<GiNaC::function>(tree);
    if (!function && !GiNaC::is_a<GiNaC::power>(tree)) return nullptr;
    std::size_t lo = std::string::npos, hi = 0, first = SIZE_MAX, last = 0;
    leaf_range(tree, lo, hi, first, last);
    const std::string name = function ? GiNaC::ex_to<GiNaC::function>(tree).get_name() : "";
    Call* best = nullptr;
    for (Call& c : calls_) {
      if (c.used || c.first_leaf != first || c.last_leaf != last) continue;
      if (function ? c.name != name : (c.name != "sqrt" && c.name != "pow")) continue;
      if (!best || c.depth < best->depth) best = &c;
    }
    if (best) best->used = true;
    matched_[tree] = best;
    return best;
  }

 private:
  void leaf_range(const GiNaC::ex& tree, std::size_t& lo, std::size_t& hi, std::size_t& first,
                  std::size_t& last) const {
    if (GiNaC::is_a<GiNaC::symbol>(tree)) {
      if (auto it = leaves_.find(tree); it != leaves_.end()) {
        lo = std::min(lo, it->second.begin);
        hi = std::max(hi, it->second.end);
        first = std::min(first, it->second.index);
        last = std::max(last, it->second.index);
      }
      return;
    }
    for (std::size_t i = 0; i < tree.nops(); ++i) leaf_range(tree.op(i), lo, hi, first, last);
  }

  const std::string& text_;
  std::map<GiNaC::ex, Leaf, GiNaC::ex_is_less> leaves_;
  std::vector<Call> calls_;
  GiNaC::exmap values_;
  std::map<GiNaC::ex, const Call*, GiNaC::ex_is_less> matched_;
};

/// Thrown with the offset of the part at fault (the reader turns it into an ExpressionError).
struct SiteError {
  std::size_t offset;
  std::string message;
};

// ---------------------------------------------------------------------------------------------
// Constants that double cannot hold

/// "" when |x| is 0 or within double's normal range, else why not.
inline std::string double_range_problem(const GiNaC::numeric& x) {
  if (!x.is_real() || x.is_zero()) return "";
  const GiNaC::numeric a = GiNaC::abs(x);
  if (a > GiNaC::numeric(DBL_MAX))
    return " is beyond the range of double (about 1.8e308): the generated code would compute inf";
  if (a < GiNaC::numeric(DBL_MIN))
    return " is below the range of double (about 2.2e-308): the generated code would lose it";
  return "";
}

/// Refuses a constant part of the expression (numbers, Pi, functions of them) whose value leaves
/// double's range, at the smallest such part (1e400 in 1e400*x), or a number of the whole
/// expression that does (1e200*x*1e200), at the expression.
inline void check_constants(SiteLocator& at, const GiNaC::ex& tree, const GiNaC::ex& whole) {
  struct Walk {
    SiteLocator& at;
    // True when the constant part `t` is out of range (and throws for the smallest such part).
    bool bad(const GiNaC::ex& t) {
      if (at.has_symbol(t)) {
        for (std::size_t i = 0; i < t.nops(); ++i) bad(t.op(i));
        return false;
      }
      GiNaC::ex v;
      std::string why;
      try {
        v = checked_evalf(at.value(t));
        if (GiNaC::is_a<GiNaC::numeric>(v)) why = double_range_problem(GiNaC::ex_to<GiNaC::numeric>(v));
      } catch (const EvaluationError&) {
        return false;  // the reader's own evaluation reports these, with their own words
      }
      if (why.empty()) return false;
      for (std::size_t i = 0; i < t.nops(); ++i) bad(t.op(i));  // a smaller part first
      const ExpressionSite s = at.site(t);
      throw SiteError{s.offset, s.text + why};
    }
  } walk{at};
  walk.bad(tree);
  for (GiNaC::const_preorder_iterator i = whole.preorder_begin(); i != whole.preorder_end(); ++i)
    if (GiNaC::is_a<GiNaC::numeric>(*i)) {
      const std::string why = double_range_problem(GiNaC::ex_to<GiNaC::numeric>(*i));
      if (!why.empty()) {
        throw SiteError{0, "the constant " + checked_subs_impl::describe(GiNaC::ex_to<GiNaC::numeric>(*i)) +
                               " of this expression" + why};
      }
    }
}

// ---------------------------------------------------------------------------------------------
// Inputs enter linearly

/// Whether `e` is linear in the symbol u: u occurs in no function and in no power other than
/// a non-negative integer one, and ∂²e/∂u² = 0 (expanded: powers of u above 8 are called
/// nonlinear without expanding, so that (x + y + u)^1000 cannot make it slow).
inline bool linear_in(const GiNaC::ex& e, const GiNaC::symbol& u) {
  if (!e.has(u)) return true;
  for (GiNaC::const_preorder_iterator i = e.preorder_begin(); i != e.preorder_end(); ++i) {
    if (!i->has(u)) continue;
    if (GiNaC::is_a<GiNaC::function>(*i)) return false;
    if (GiNaC::is_a<GiNaC::power>(*i)) {
      const GiNaC::ex n = i->op(1);
      if (n.has(u) || !GiNaC::is_a<GiNaC::numeric>(n) || !GiNaC::ex_to<GiNaC::numeric>(n).is_nonneg_integer() ||
          GiNaC::ex_to<GiNaC::numeric>(n) > 8)
        return false;
    }
  }
  return GiNaC::expand(e.diff(u, 2)).is_zero();
}

/// The part of the placeholder tree where an input enters nonlinearly, or nothing: a function
/// or a non-integer power of an input, an input in an exponent, an input squared, a product of
/// two factors holding inputs.
inline std::optional<GiNaC::ex> nonlinear_part(SiteLocator& at, const GiNaC::ex& t,
                                               const std::set<GiNaC::ex, GiNaC::ex_is_less>& inputs) {
  if (!at.has_any(t, inputs)) return std::nullopt;
  if (GiNaC::is_a<GiNaC::function>(t)) return t;
  if (GiNaC::is_a<GiNaC::power>(t)) {
    if (at.has_any(t.op(1), inputs)) return t;
    const GiNaC::ex n = at.value(t.op(1));
    if (!GiNaC::is_a<GiNaC::numeric>(n) || !(n - 1).is_zero()) return t;
  }
  if (GiNaC::is_a<GiNaC::mul>(t)) {
    std::size_t holding = 0;
    for (std::size_t i = 0; i < t.nops(); ++i) {
      const GiNaC::ex f = t.op(i);
      if (!at.has_any(f, inputs)) continue;
      ++holding;
      // A division by an input (x/F): the quotient, as written, is the part to show.
      if (GiNaC::is_a<GiNaC::power>(f) && !at.has_any(f.op(1), inputs)) {
        const GiNaC::ex n = at.value(f.op(1));
        if (GiNaC::is_a<GiNaC::numeric>(n) && GiNaC::ex_to<GiNaC::numeric>(n).is_negative()) return t;
      }
    }
    if (holding > 1) return t;
  }
  for (std::size_t i = 0; i < t.nops(); ++i)
    if (auto part = nonlinear_part(at, t.op(i), inputs)) return part;
  return std::nullopt;
}

/// Refuses an expression in which an input does not enter linearly (B = −∂q/∂u is the whole
/// effect of an input only then), at the part where it enters.
inline void check_linear_inputs(SiteLocator& at, const GiNaC::ex& tree, const GiNaC::ex& whole,
                                const std::vector<GiNaC::symbol>& inputs) {
  for (const GiNaC::symbol& u : inputs) {
    // Linear as written (no part where u enters nonlinearly), or after simplification.
    const std::optional<GiNaC::ex> part = nonlinear_part(at, tree, {u});
    if (!part || linear_in(whole, u)) continue;
    const ExpressionSite s = at.site(*part);
    throw SiteError{s.offset, "input '" + u.get_name() + "' enters nonlinearly" +
                                  (s.text.empty() ? "" : " in " + s.text) +
                                  " (inputs must enter forces linearly, as c*" + u.get_name() +
                                  " with c free of inputs: the linear model keeps only -dq/du at "
                                  "u = 0)"};
  }
}

/// Every function call and every power with an exponent other than a non-negative integer, in
/// pre-order, whose value depends on a model symbol (what Model::validate() checks at the
/// operating point).
inline void collect_sites(SiteLocator& at, const GiNaC::ex& tree, std::vector<ExpressionSite>& out) {
  if (!at.has_symbol(tree)) return;
  bool site = GiNaC::is_a<GiNaC::function>(tree);
  if (GiNaC::is_a<GiNaC::power>(tree)) {
    const GiNaC::ex n = at.value(tree.op(1));
    site = !GiNaC::is_a<GiNaC::numeric>(n) || !GiNaC::ex_to<GiNaC::numeric>(n).is_nonneg_integer();
  }
  if (site) out.push_back(at.site(tree));
  for (std::size_t i = 0; i < tree.nops(); ++i) collect_sites(at, tree.op(i), out);
}

}  // namespace mbsgen::detail
