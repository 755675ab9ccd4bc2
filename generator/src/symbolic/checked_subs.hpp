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
//
// checked_evalf evaluates in floating point the same way, bottom-up, and refuses what CLN would
// get silently wrong or what leaves the range of double, where the generated kernels compute:
// CLN returns exp(1e9999) = 1, sin(1e50) = 0 and tanh(1e100) = 0.
#pragma once

#include <ginac/ginac.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
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

// The bounds checked_evalf applies to a function's argument x (its real part; the modulus for
// the periodic functions).
inline constexpr double kMaxPeriodicArgument = 1e15;  // beyond it the period is lost to rounding
inline constexpr double kMaxExpArgument = 709.78;     // log(DBL_MAX) = 709.7827
inline constexpr double kMinExpArgument = -745.13;    // below it exp(x) is 0 in double
inline constexpr double kMaxHyperbolicArgument = 710.47;  // asinh(DBL_MAX) = 710.4758
inline constexpr double kTanhSaturation = 60;  // 1 - tanh(60) < 1e-52: ±1 to 50 digits

// A number for a message: 6 significant digits, or its order of magnitude beyond double's range.
inline std::string describe(const GiNaC::numeric& x) {
  if (!x.is_real()) return "a complex number";
  const double d = x.to_double();
  char buf[40];
  if (std::isfinite(d) && (d == 0 || std::abs(d) > 1e-300)) {
    std::snprintf(buf, sizeof buf, "%.6g", d);
  } else {
    const double digits = GiNaC::log(GiNaC::abs(x)).to_double() / std::log(10.0);
    std::snprintf(buf, sizeof buf, "%s1e%+.0f", x.is_negative() ? "-" : "", std::floor(digits + 1e-9));
  }
  return buf;
}

// Refuses a function's float argument beyond what CLN or double can honour, or returns the value
// (tanh far out, where CLN returns 0 instead of ±1); returns nothing to let GiNaC evaluate.
inline std::optional<GiNaC::ex> check_function(const std::string& name, const GiNaC::exvector& args,
                                const GiNaC::ex& node) {
  if (args.size() != 1 || !GiNaC::is_a<GiNaC::numeric>(args[0])) return std::nullopt;
  const GiNaC::numeric& x = GiNaC::ex_to<GiNaC::numeric>(args[0]);
  const double re = x.real().to_double();  // ±inf beyond double's range
  // The message is built only when refusing: the operating-point evaluator passes every
  // function value through here.
  auto refuse = [&](const char* why) {
    throw EvaluationError(node, name + "(" + describe(x) + ")" + why);
  };
  if (name == "sin" || name == "cos" || name == "tan") {
    if (!(GiNaC::abs(x).to_double() <= kMaxPeriodicArgument))
      refuse(": an argument beyond 1e15 in magnitude, where its value is lost to rounding");
  } else if (name == "exp") {
    if (re > kMaxExpArgument) refuse(" overflows double: its argument exceeds 709.78");
    if (re < kMinExpArgument) refuse(" underflows double to 0: its argument is below -745.13");
  } else if (name == "sinh" || name == "cosh") {
    if (!(std::abs(re) <= kMaxHyperbolicArgument))
      refuse(" overflows double: its argument exceeds 710.47 in magnitude");
  } else if (name == "tanh") {
    if (x.is_real() && std::abs(re) > kTanhSaturation) return GiNaC::ex(re > 0 ? 1 : -1);
  }
  return std::nullopt;
}

inline bool all_real(const GiNaC::exvector& ops) {
  return std::all_of(ops.begin(), ops.end(), [](const GiNaC::ex& o) {
    return GiNaC::is_a<GiNaC::numeric>(o) && GiNaC::ex_to<GiNaC::numeric>(o).is_real();
  });
}

inline bool is_nonreal_number(const GiNaC::ex& v) {
  return GiNaC::is_a<GiNaC::numeric>(v) && !GiNaC::ex_to<GiNaC::numeric>(v).is_real();
}

// The function node `node` applied to `ops`, checked as check_function does and refused when real
// numbers give a value that is not real (asin(2)).
inline GiNaC::ex evaluate_function(const GiNaC::ex& node, const GiNaC::exvector& ops) {
  const auto& f = GiNaC::ex_to<GiNaC::function>(node);
  const auto fixed = check_function(f.get_name(), ops, node);
  const GiNaC::ex v = fixed ? *fixed : GiNaC::ex(GiNaC::function(f.get_serial(), ops));
  if (all_real(ops) && is_nonreal_number(v)) {
    std::string call = f.get_name() + "(";
    for (std::size_t i = 0; i < ops.size(); ++i)
      call += (i ? ", " : "") + describe(GiNaC::ex_to<GiNaC::numeric>(ops[i]));
    throw EvaluationError(node, call + ") has no real value");
  }
  return v;
}

}  // namespace checked_subs_impl

/// evalf(e) bottom-up (e holds no symbols, or keeps them as they are). Throws EvaluationError,
/// naming the subexpression at fault, where a function leaves double's range or CLN's accuracy
/// (see check_function), where real arguments give a value that is not real (asin(2),
/// (-1)^0.5), and for any error of CLN (overflow, underflow, a pole).
inline GiNaC::ex checked_evalf(const GiNaC::ex& e) {
  using GiNaC::is_a;
  const bool known = is_a<GiNaC::power>(e) || is_a<GiNaC::add>(e) || is_a<GiNaC::mul>(e) ||
                     is_a<GiNaC::function>(e);
  try {
    if (!known) return GiNaC::evalf(e);  // numbers, constants, symbols
    GiNaC::exvector ops;
    ops.reserve(e.nops());
    for (std::size_t i = 0; i < e.nops(); ++i) ops.push_back(checked_evalf(e.op(i)));
    if (is_a<GiNaC::add>(e)) return GiNaC::evalf(GiNaC::add(ops));
    if (is_a<GiNaC::mul>(e)) return GiNaC::evalf(GiNaC::mul(ops));
    if (is_a<GiNaC::function>(e)) return GiNaC::evalf(checked_subs_impl::evaluate_function(e, ops));
    const GiNaC::ex v = GiNaC::evalf(GiNaC::power(ops[0], ops[1]));
    if (checked_subs_impl::all_real(ops) && checked_subs_impl::is_nonreal_number(v))
      throw EvaluationError(e, "a negative number to a fractional power has no real value");
    return v;
  } catch (const EvaluationError&) {
    throw;
  } catch (const std::exception& err) {
    throw EvaluationError(e, err.what());
  }
}

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
    return checked_subs_impl::evaluate_function(e, ops);
  } catch (const EvaluationError&) {
    throw;
  } catch (const std::exception& err) {
    throw EvaluationError(e, err.what());
  }
}

}  // namespace mbsgen::detail
