// A straight-line program of intermediate quantities t_k = f_k(leaves, t_0 … t_{k-1}).
//
// Multibody kinematics nests deeply (S_i = S_p R_i over the whole tree); written out as one
// expression per entry it swells exponentially. The generator instead names every non-trivial
// intermediate once (`define`), and differentiates and substitutes *through* those names with
// memoisation (`diff`, `substitute`): total derivatives are forward-mode automatic
// differentiation done symbolically, so their cost is linear in the size of the program.
#pragma once

#include "mbsgen/generator/symbolic/canonical.hpp"
#include "mbsgen/generator/symbolic/ex_table.hpp"

#include <ginac/ginac.h>

#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace mbsgen {

class Program {
 public:
  struct Definition {
    GiNaC::symbol symbol;
    GiNaC::ex value;
  };

  /// Registers an independent variable (a coordinate, rate, input or parameter). All variables
  /// must be registered before the first `define`.
  void add_variable(const GiNaC::symbol& s);

  /// Names `e` as an intermediate and returns its symbol; numbers, symbols and c·symbol are
  /// returned as they are. Functions and non-integer powers in e are named once each, and an
  /// expression holding them that was defined before returns its old symbol; an expression
  /// without them is named anew (emission merges equal temporaries).
  GiNaC::ex define(const GiNaC::ex& e);

  /// Total derivative de/dx through the intermediates (x a registered variable).
  GiNaC::ex diff(const GiNaC::ex& e, const GiNaC::symbol& x);

  /// True when e depends on the variable x, directly or through intermediates.
  bool depends_on(const GiNaC::ex& e, const GiNaC::symbol& x);

  /// Replaces variables by values throughout the program (constants propagate), memoised per
  /// `Substitution` object, so a whole kernel can be specialised at once.
  class Substitution {
   public:
    explicit Substitution(GiNaC::exmap values) : values_(std::move(values)) {}

   private:
    friend class Program;
    GiNaC::exmap values_;
    std::vector<std::uint64_t> mask_;
    std::unordered_map<std::size_t, GiNaC::ex> memo_;
    std::unordered_map<std::uint64_t, GiNaC::ex> diff_memo_;  // diff_at of intermediates
  };
  GiNaC::ex substitute(const GiNaC::ex& e, Substitution& s);

  /// substitute(diff(e, x), s), formed without the derivative at a general point: the chain
  /// rule's factors are substituted first, so a term that vanishes at the point (a product with
  /// a rate that s sets to 0) is never differentiated. The linearization at rest needs ∂r/∂ẏ at
  /// ẏ = 0, where the general derivatives of the velocity-quadratic terms were most of the work
  /// (40-link chain: 1.36 s of Q against 0.49 s of K). x may be one of the variables s sets.
  GiNaC::ex diff_at(const GiNaC::ex& e, const GiNaC::symbol& x, Substitution& s);

  /// e with every intermediate written out (for exact checks on small models only).
  GiNaC::ex inline_all(const GiNaC::ex& e);

  const std::vector<Definition>& definitions() const { return defs_; }
  /// The canonical form shared with CSE and emission; each intermediate's symbol carries the
  /// sign of its definition.
  CanonicalOrder& order() { return order_; }
  /// Index of an intermediate symbol in definitions(), or -1 for anything else.
  long index_of(const GiNaC::ex& symbol) const;
  std::size_t variable_count() const { return variables_.size(); }

 private:
  using Bits = std::vector<std::uint64_t>;
  Bits dependencies(const GiNaC::ex& e) const;
  std::size_t variable(const GiNaC::symbol& x, const char* caller) const;
  void collect_intermediates(const GiNaC::ex& e, std::vector<std::size_t>& out) const;
  GiNaC::ex intern_functions(const GiNaC::ex& e);
  GiNaC::ex define_node(const GiNaC::ex& e);
  GiNaC::ex define_plain(const GiNaC::ex& e);  // define() of e without functions and roots
  GiNaC::ex add_definition(const GiNaC::ex& e);
  GiNaC::ex diff_intermediate(std::size_t k, std::size_t variable);
  GiNaC::ex substitute_intermediate(std::size_t k, Substitution& s);
  GiNaC::ex diff_at_intermediate(std::size_t k, std::size_t variable, Substitution& s);
  bool bits_intersect(const Bits& a, const Bits& b) const;

  std::vector<GiNaC::symbol> variables_;
  ExTable<std::size_t> variable_index_;
  std::vector<Definition> defs_;
  std::vector<Bits> deps_;
  ExTable<std::size_t> def_index_;
  ExTable<GiNaC::ex> interned_;
  CanonicalOrder order_;  // intermediates are numbered in this order, not in GiNaC's
  std::unordered_map<std::uint64_t, GiNaC::ex> diff_memo_;
  std::unordered_map<std::size_t, GiNaC::ex> inline_memo_;
  // The chain rule's factors of intermediate k: ∂f_k/∂t_j for the intermediates t_j of its value
  // (j ascending) and ∂f_k/∂x for the variables it holds itself. They do not depend on the
  // variable differentiated by, so each is formed once, not once per variable.
  struct ChainFactors {
    std::vector<std::pair<std::size_t, GiNaC::ex>> intermediates;
    std::vector<std::pair<std::size_t, GiNaC::ex>> variables;
  };
  std::vector<std::unique_ptr<ChainFactors>> chain_factors_;
  const ChainFactors& chain_factors(std::size_t k);
  // The chain rule's factors of an expression: for each intermediate and variable it holds, its
  // partial, differentiating only the operands of a sum that hold that symbol (the same
  // expression as value.diff(s), whose other terms would differentiate to 0). With `only` ≥ 0,
  // the partial of that variable alone among the variables.
  ChainFactors factors_of(const GiNaC::ex& value, long only = -1) const;
};

}  // namespace mbsgen
