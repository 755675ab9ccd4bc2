// Evaluating program expressions at one point in CLN floating point (internal to the generator:
// linearize.cpp decides structural zeros with it, check.cpp checks the operating point).
#pragma once

#include "checked_subs.hpp"
#include "type_test.hpp"
#include "mbsgen/generator/ex_table.hpp"
#include "mbsgen/generator/linearize.hpp"
#include "mbsgen/generator/program.hpp"

#include <algorithm>
#include <cstdint>

#include <stdexcept>
#include <vector>

namespace mbsgen::detail {


using GiNaC::ex;

// Values of program expressions at one point of the variables, in floating point of kDigits
// decimal digits (CLN). Reads the program's definitions only (defines nothing).
class PointEvaluator {
 public:
  static constexpr long kDigits = 50;

  /// point: a value for every variable that the expressions use.
  PointEvaluator(const Program& program, const GiNaC::exmap& point) : prog_(program) {
    for (const auto& [x, v] : point) values_.emplace(x, float_of(v));
  }

  std::vector<GiNaC::numeric> evaluate(const std::vector<ex>& entries) {
    const auto& defs = prog_.definitions();
    std::vector<char> needed(defs.size(), 0);
    std::vector<ex> stack(entries);
    while (!stack.empty()) {
      ex e = stack.back();
      stack.pop_back();
      if (isa<GiNaC::symbol>(e)) {
        const long i = prog_.index_of(e);
        if (i >= 0 && !needed[static_cast<std::size_t>(i)] && !values_.find(e)) {
          needed[static_cast<std::size_t>(i)] = 1;
          stack.push_back(defs[static_cast<std::size_t>(i)].value);
        }
        continue;
      }
      for (std::size_t i = 0; i < e.nops(); ++i) stack.push_back(e.op(i));
    }
    // A definition refers to earlier ones only.
    for (std::size_t i = 0; i < defs.size(); ++i)
      if (needed[i]) values_.emplace(defs[i].symbol, number(defs[i].value));
    std::vector<GiNaC::numeric> out;
    out.reserve(entries.size());
    for (const ex& e : entries) out.push_back(number(e));
    return out;
  }

 private:
  static GiNaC::numeric float_of(const ex& e) {
    const ex v = GiNaC::evalf(e);
    if (!isa<GiNaC::numeric>(v)) throw std::runtime_error("not a number");
    return GiNaC::ex_to<GiNaC::numeric>(v);
  }

  GiNaC::numeric number(const ex& e) const {
    if (isa<GiNaC::numeric>(e)) return GiNaC::ex_to<GiNaC::numeric>(e);
    if (isa<GiNaC::symbol>(e)) {
      const GiNaC::numeric* v = values_.find(e);
      if (!v) throw std::runtime_error("unbound symbol");
      return *v;
    }
    if (isa<GiNaC::add>(e)) {
      GiNaC::numeric sum = 0;
      for (std::size_t i = 0; i < e.nops(); ++i) sum += number(e.op(i));
      return sum;
    }
    if (isa<GiNaC::mul>(e)) {
      GiNaC::numeric product = 1;
      for (std::size_t i = 0; i < e.nops(); ++i) product *= number(e.op(i));
      return product;
    }
    if (isa<GiNaC::power>(e)) {
      const GiNaC::numeric base = number(e.op(0)), exponent = number(e.op(1));
      if (exponent.is_integer()) return base.power(exponent);
      return GiNaC::ex_to<GiNaC::numeric>(base.evalf()).power(exponent);
    }
    if (isa<GiNaC::function>(e)) {
      GiNaC::exvector args;
      for (std::size_t i = 0; i < e.nops(); ++i) args.push_back(number(e.op(i)));
      const auto& f = GiNaC::ex_to<GiNaC::function>(e);
      // CLN's exp(1e9999) = 1 and sin(1e50) = 0: refused (EvaluationError), as in checked_evalf.
      if (const auto fixed = checked_subs_impl::check_function(f.get_name(), args, e)) return float_of(*fixed);
      return float_of(GiNaC::function(f.get_serial(), args));
    }
    return float_of(e);  // constants such as Pi
  }

  const Program& prog_;
  ExTable<GiNaC::numeric> values_;  // looked up once per symbol of every definition evaluated
};

/// A pseudo-random point for the structure tests of the linear matrices (linearize.cpp,
/// structural_zeros.cpp): every coordinate, rate, input and parameter uniform in [0.5, 2.5)
/// (exact rationals from the xorshift64 sequence in `state`, advanced); with at_operating_point,
/// the rates, and for a `given` operating point the coordinates, at the operating point of those
/// parameters (an equilibrium's coordinates stay free: they are known only numerically; so do
/// those of a model with closed loops, whose dependent coordinates the kernels refine).
inline GiNaC::exmap sample_point(const Equations& eq, const LinearEquations& lin, std::uint64_t& state,
                                 bool at_operating_point) {
  GiNaC::exmap values;
  for (const auto* group : {&eq.y, &eq.yd, &eq.u, &eq.p})
    for (const auto& x : *group) {
      state ^= state << 13, state ^= state >> 7, state ^= state << 17;  // xorshift64
      values[x] = GiNaC::numeric(static_cast<long>(state % 2000000) + 500000, 1000000);
    }
  if (at_operating_point) {
    GiNaC::exmap p;
    for (const auto& x : eq.p) p[x] = values[x];
    for (std::size_t k = 0; k < eq.y.size(); ++k) {
      // The loops' dependent coordinates stay free: the kernels close them by Newton's method, so
      // a zero at the operating point must hold for any of their values.
      const bool dependent = std::binary_search(eq.loops.dependent.begin(), eq.loops.dependent.end(), k);
      if (!lin.equilibrium && !dependent) values[eq.y[k]] = GiNaC::evalf(lin.y0[k].subs(p, GiNaC::subs_options::no_pattern));
      values[eq.yd[k]] = GiNaC::evalf(lin.yd0[k].subs(p, GiNaC::subs_options::no_pattern));
    }
  }
  return values;
}

}  // namespace mbsgen::detail
