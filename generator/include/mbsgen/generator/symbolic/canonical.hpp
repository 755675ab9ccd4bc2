// A canonical form of GiNaC expressions that does not depend on GiNaC's hash values.
//
// GiNaC orders the operands of sums and products by hash, and some of its hashes come from
// addresses (type-name pointers), so both the stored operand order and the sign a sum carries
// inside a product ((a − b)·c or −(b − a)·c) can change from one build or run to the next.
// Everything that names intermediates or prints code goes through this class instead:
//  - key(e) depends only on the structure of ±e and on symbol names, never on GiNaC's order;
//  - sign(e) says whether e is +canonical(e) or −canonical(e), where canonical(e) is the form
//    whose sum terms, in key order, start with a positive coefficient.
// Symbols standing for intermediates carry the sign of their definition (set_sign): the code
// stores canonical values, so a temporary t defined as −canonical(v) is printed as −t.
#pragma once

#include "mbsgen/generator/symbolic/ex_table.hpp"

#include <ginac/ginac.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace mbsgen {

class CanonicalOrder {
 public:
  /// Compound expressions whose keys are remembered before the memo starts a new generation
  /// (see memo_size()). Keys are pure functions of the expression, so what is forgotten is only
  /// computed again: the capacity changes the time, never a key. 2^18 entries (about 15 MB)
  /// hold the working set of one kernel of the 80-coordinate spatial chain.
  static constexpr std::size_t kDefaultMemoCapacity = std::size_t{1} << 18;

  explicit CanonicalOrder(std::size_t memo_capacity = kDefaultMemoCapacity);

  struct Signed {
    std::uint64_t key;
    int sign;  // +1 or −1
  };
  Signed signed_key(const GiNaC::ex& e);
  std::uint64_t key(const GiNaC::ex& e) { return signed_key(e).key; }
  int sign(const GiNaC::ex& e) { return signed_key(e).sign; }

  /// e when sign(e) > 0, otherwise −e: the same representative for e and −e.
  GiNaC::ex representative(const GiNaC::ex& e) { return sign(e) > 0 ? e : GiNaC::ex(-e); }

  /// Declares that symbol s stands for an intermediate of the given sign. Must precede every
  /// key() of an expression containing s.
  void set_sign(const GiNaC::ex& s, int sign);

  /// The operands of e in canonical order (sorted by key for sums and products; as stored for
  /// everything else, whose operand order is meaningful).
  std::vector<GiNaC::ex> operands(const GiNaC::ex& e);

  /// True when a precedes b (ties, which need a 64-bit collision, fall back to GiNaC's order).
  bool less(const GiNaC::ex& a, const GiNaC::ex& b);

  /// Keys of compound expressions now remembered: at most twice the capacity (the generation
  /// being filled and the one before it, whose entries move forward when used again).
  std::size_t memo_size() const { return current_.size() + previous_.size(); }
  /// Symbols declared by set_sign (kept for good: a sign cannot be computed again).
  std::size_t signed_symbols() const { return signs_.size(); }

 private:
  Signed compute(const GiNaC::ex& e);
  void remember(const GiNaC::ex& e, Signed r);

  std::size_t capacity_;
  ExTable<Signed> signs_;              // symbols declared by set_sign
  ExTable<Signed> current_, previous_;  // compound expressions and numbers, two generations
};

/// Odd (f(−x) = −f(x)) and even (f(−x) = f(x)) functions of one argument, by GiNaC name.
bool odd_function(const std::string& name);
bool even_function(const std::string& name);

}  // namespace mbsgen
