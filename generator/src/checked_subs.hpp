// Substitution that GiNaC can neither leak in nor hang on (internal to the generator: the model
// reader builds every parsed expression with it, and evaluates expressions at the default
// parameter values with it, as Model::validate does).
//
// GiNaC evaluates each node as it is built. When that evaluation throws (power(0, -1): a division
// by zero, met by ex::subs in power::subs, mul::combine_ex_with_coeff_to_pair, …), GiNaC 1.8
// leaks the node; and it evaluates exact powers however large ((10^9999)^(10^9999) runs out of
// memory). checked_subs rebuilds an expression bottom-up with the values put in, one node at a
// time, and refuses such a power before GiNaC evaluates it; a function's evaluation that throws
// (log(0), tan(Pi/2)) is built on the stack, where GiNaC does not leak.
#pragma once

#include <ginac/ginac.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace mbsgen::detail {

/// Why checked_subs refused: `where()` is the subexpression of the original expression at fault.
class EvaluationError : public std::runtime_error {
 public:
  EvaluationError(const GiNaC::ex& where, const std::string& what)
      : std::runtime_error(what), where_(where) {}
  const GiNaC::ex& where() const { return where_; }

 private:
  GiNaC::ex where_;
};

/// The largest exact power checked_subs evaluates: its numbers have at most this many bits.
inline constexpr std::uint64_t kMaxPowerBits = std::uint64_t{1} << 20;  // 315653 digits

namespace checked_subs_impl {

// The largest binary length of a number in `e` (bases of powers only: GiNaC keeps a numeric
// power's exponent below 1, so exponents add no length to the numbers of a result).
inline int max_bits(const GiNaC::ex& e) {
  if (GiNaC::is_a<GiNaC::numeric>(e)) {
    const GiNaC::numeric& n = GiNaC::ex_to<GiNaC::numeric>(e);
    if (!n.is_crational()) return 64;
    return std::max({n.real().numer().int_length(), n.real().denom().int_length(),
                     n.imag().numer().int_length(), n.imag().denom().int_length()});
  }
  if (GiNaC::is_a<GiNaC::power>(e)) return max_bits(e.op(0));
  int bits = 0;
  for (std::size_t i = 0; i < e.nops(); ++i) bits = std::max(bits, max_bits(e.op(i)));
  return bits;
}

// Throws unless GiNaC may evaluate base^exponent: a zero base with an exponent of non-positive
// real part is a division by zero; an exact power whose numbers would exceed kMaxPowerBits is
// refused (their length is at most |numerator of the exponent| times that of the base's).
inline void check_power(const GiNaC::ex& base, const GiNaC::ex& exponent, const GiNaC::ex& node) {
  if (!GiNaC::is_a<GiNaC::numeric>(exponent)) return;
  const GiNaC::numeric& n = GiNaC::ex_to<GiNaC::numeric>(exponent);
  if (base.is_zero()) {
    if (!n.is_zero() && !n.real().is_positive()) throw EvaluationError(node, "division by zero");
    return;
  }
  const int base_bits = max_bits(base);
  if (base_bits <= 1 || !n.is_crational()) return;  // only 0, 1, -1: no growth
  const int exponent_bits = std::max(n.real().numer().int_length(), n.imag().numer().int_length());
  if (exponent_bits > 40 ||
      (std::uint64_t{1} << exponent_bits) * static_cast<std::uint64_t>(base_bits) > kMaxPowerBits)
    throw EvaluationError(node, "a power too large to evaluate exactly (its numbers would exceed "
                                "2^20 binary digits)");
}

}  // namespace checked_subs_impl

/// e.subs(values) (symbols to values, no patterns), evaluated bottom-up. Throws EvaluationError
/// for a division by zero, a power too large to evaluate exactly, or any error of GiNaC's
/// evaluation (its message), naming the subexpression of `e` at fault.
inline GiNaC::ex checked_subs(const GiNaC::ex& e, const GiNaC::exmap& values) {
  if (GiNaC::is_a<GiNaC::symbol>(e)) {
    const auto it = values.find(e);
    return it == values.end() ? e : it->second;
  }
  if (e.nops() == 0) return e;  // numbers, constants
  const bool known = GiNaC::is_a<GiNaC::power>(e) || GiNaC::is_a<GiNaC::add>(e) ||
                     GiNaC::is_a<GiNaC::mul>(e) || GiNaC::is_a<GiNaC::function>(e);
  if (!known) return e.subs(values, GiNaC::subs_options::no_pattern);  // not built by the reader
  GiNaC::exvector ops;
  ops.reserve(e.nops());
  for (std::size_t i = 0; i < e.nops(); ++i) ops.push_back(checked_subs(e.op(i), values));
  try {
    // Built on the stack, evaluated when converted to ex: an exception leaves nothing behind.
    if (GiNaC::is_a<GiNaC::power>(e)) {
      checked_subs_impl::check_power(ops[0], ops[1], e);
      return GiNaC::power(ops[0], ops[1]);
    }
    if (GiNaC::is_a<GiNaC::add>(e)) return GiNaC::add(ops);
    if (GiNaC::is_a<GiNaC::mul>(e)) return GiNaC::mul(ops);
    return GiNaC::function(GiNaC::ex_to<GiNaC::function>(e).get_serial(), ops);
  } catch (const EvaluationError&) {
    throw;
  } catch (const std::exception& err) {
    throw EvaluationError(e, err.what());
  }
}

}  // namespace mbsgen::detail
