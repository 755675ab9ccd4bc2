// Evaluating program expressions at one point in CLN floating point (internal to the generator:
// linearize.cpp decides structural zeros with it, linear/operating_point_check.cpp checks the operating point).
#pragma once

#include "mbsgen/generator/symbolic/ex_table.hpp"
#include "mbsgen/generator/symbolic/program.hpp"
#include "symbolic/checked_subs.hpp"
#include "symbolic/type_test.hpp"

#include <algorithm>
#include <cstdint>
#include <initializer_list>
#include <memory>

#include <stdexcept>
#include <vector>

namespace mbsgen::detail {


using GiNaC::ex;

// The program's definitions compiled to postfix code over numbered values, once for every point
// they are evaluated at (SamplePoints evaluates the same definitions at four points). Walking the
// expression trees at each point, with a hash lookup per symbol and a GiNaC::numeric per node,
// took a sixth of a 40-link chain's generation. Compiles only (defines nothing in the program).
class ProgramTape {
 public:
  enum class Op : std::uint8_t {
    constant,    // constants[arg]
    variable,    // the point's value of variables[arg]
    definition,  // the value of the program's definition arg (computed before)
    add,         // the sum of the last arg values, left to right from 0, as GiNaC::numeric sums
    mul,         // their product, from 1
    power,       // base^exponent, the last two values
    function,    // functions[arg] (a node of that function) of its last nops() values
    other        // others[arg] in floating point (a constant such as Pi)
  };
  struct Instruction {
    Op op;
    std::uint32_t arg;
  };
  using Code = std::vector<Instruction>;

  explicit ProgramTape(const Program& program) : prog_(program) {}

  /// The code of e; the definitions it reads are compiled (definition()).
  Code compile(const ex& e) {
    Code code;
    append(e, code);
    return code;
  }
  /// The code of definition i, and the definitions it reads (compiled first).
  const Code& definition(std::size_t i) {
    if (definitions_.size() <= i) definitions_.resize(prog_.definitions().size());
    if (definitions_[i].empty()) definitions_[i] = compile(prog_.definitions()[i].value);  // never empty once compiled
    return definitions_[i];
  }

  const Program& program() const { return prog_; }
  std::vector<cln::cl_N> constants;
  std::vector<ex> variables, functions, others;

 private:
  void append(const ex& e, Code& code) {
    const auto n = [](std::size_t k) { return static_cast<std::uint32_t>(k); };
    if (isa<GiNaC::numeric>(e)) {
      code.push_back({Op::constant, n(constants.size())});
      constants.push_back(GiNaC::ex_to<GiNaC::numeric>(e).to_cl_N());
    } else if (isa<GiNaC::symbol>(e)) {
      const long i = prog_.index_of(e);
      if (i >= 0) {
        definition(static_cast<std::size_t>(i));
        code.push_back({Op::definition, n(static_cast<std::size_t>(i))});
      } else {
        std::size_t* slot = variable_slot_.find(e);
        if (!slot) {
          variable_slot_.insert(e, variables.size());
          variables.push_back(e);
          slot = variable_slot_.find(e);
        }
        code.push_back({Op::variable, n(*slot)});
      }
    } else if (isa<GiNaC::add>(e) || isa<GiNaC::mul>(e) || isa<GiNaC::power>(e) || isa<GiNaC::function>(e)) {
      for (std::size_t i = 0; i < e.nops(); ++i) append(e.op(i), code);
      if (isa<GiNaC::function>(e)) {
        code.push_back({Op::function, n(functions.size())});
        functions.push_back(e);
      } else {
        code.push_back({isa<GiNaC::add>(e) ? Op::add : isa<GiNaC::mul>(e) ? Op::mul : Op::power, n(e.nops())});
      }
    } else {
      code.push_back({Op::other, n(others.size())});
      others.push_back(e);
    }
  }

  const Program& prog_;
  std::vector<Code> definitions_;  // by definition index; empty: not compiled
  ExTable<std::size_t> variable_slot_;
};

// Values of program expressions at one point of the variables, in floating point of kDigits
// decimal digits (CLN). Reads the program's definitions only (defines nothing). The values are
// those of GiNaC::numeric arithmetic over the expression trees, bit for bit: sums and products in
// GiNaC's operand order, powers and functions through GiNaC::numeric.
class PointEvaluator {
 public:
  static constexpr long kDigits = 50;

  /// point: a value for every variable that the expressions use (a value given for an
  /// intermediate's symbol is used instead of its definition). tape: the program's code, shared
  /// by the evaluators at several points.
  PointEvaluator(std::shared_ptr<ProgramTape> tape, const GiNaC::exmap& point) : tape_(std::move(tape)) {
    for (const auto& [x, v] : point) {
      const GiNaC::numeric value = float_of(v);
      given_.emplace(x, value);
      const long i = tape_->program().index_of(x);
      if (i >= 0) set_definition(static_cast<std::size_t>(i), value.to_cl_N());
    }
  }
  PointEvaluator(const Program& program, const GiNaC::exmap& point)
      : PointEvaluator(std::make_shared<ProgramTape>(program), point) {}

  std::vector<GiNaC::numeric> evaluate(const std::vector<ex>& entries) {
    std::vector<ProgramTape::Code> codes;
    codes.reserve(entries.size());
    for (const ex& e : entries) codes.push_back(tape_->compile(e));
    // The definitions needed and not yet known, in index order: a definition reads earlier ones.
    std::vector<std::size_t> stack;
    auto need = [&](const ProgramTape::Code& code) {
      for (const auto& in : code)
        if (in.op == ProgramTape::Op::definition && !known(in.arg)) stack.push_back(in.arg);
    };
    for (const auto& code : codes) need(code);
    std::vector<std::size_t> needed;
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      if (known(i) || (i < marked_.size() && marked_[i])) continue;
      if (marked_.size() <= i) marked_.resize(tape_->program().definitions().size(), 0);
      marked_[i] = 1;
      needed.push_back(i);
      need(tape_->definition(i));
    }
    std::sort(needed.begin(), needed.end());
    for (std::size_t i : needed) {
      marked_[i] = 0;
      set_definition(i, run(tape_->definition(i)));
    }
    std::vector<GiNaC::numeric> out;
    out.reserve(entries.size());
    for (const auto& code : codes) out.emplace_back(run(code));
    return out;
  }

 private:
  static GiNaC::numeric float_of(const ex& e) {
    const ex v = GiNaC::evalf(e);
    if (!isa<GiNaC::numeric>(v)) throw std::runtime_error("not a number");
    return GiNaC::ex_to<GiNaC::numeric>(v);
  }

  bool known(std::size_t i) const { return i < have_.size() && have_[i]; }
  void set_definition(std::size_t i, cln::cl_N v) {
    if (values_.size() <= i) {
      const std::size_t n = std::max(i + 1, tape_->program().definitions().size());
      values_.resize(n);
      have_.resize(n, 0);
    }
    values_[i] = std::move(v);
    have_[i] = 1;
  }
  const cln::cl_N& variable(std::size_t k) {
    if (variables_.size() <= k) {
      variables_.resize(tape_->variables.size());
      have_variable_.resize(tape_->variables.size(), 0);
    }
    if (!have_variable_[k]) {
      const GiNaC::numeric* v = given_.find(tape_->variables[k]);
      if (!v) throw std::runtime_error("unbound symbol");
      variables_[k] = v->to_cl_N();
      have_variable_[k] = 1;
    }
    return variables_[k];
  }

  cln::cl_N run(const ProgramTape::Code& code);

  std::shared_ptr<ProgramTape> tape_;
  ExTable<GiNaC::numeric> given_;  // the point's values, by symbol
  std::vector<cln::cl_N> values_, variables_;  // by definition index, by the tape's variable slot
  std::vector<char> have_, have_variable_, marked_;
  std::vector<cln::cl_N> stack_;
};

/// Pseudo-random values of the symbols of `groups`, in their order: each uniform in [0.5, 2.5),
/// an exact rational from the xorshift64 sequence in `state` (advanced).
inline GiNaC::exmap random_point(std::initializer_list<const std::vector<GiNaC::symbol>*> groups, std::uint64_t& state) {
  GiNaC::exmap values;
  for (const auto* group : groups)
    for (const auto& x : *group) {
      state ^= state << 13, state ^= state >> 7, state ^= state << 17;  // xorshift64
      values[x] = GiNaC::numeric(static_cast<long>(state % 2000000) + 500000, 1000000);
    }
  return values;
}

}  // namespace mbsgen::detail
