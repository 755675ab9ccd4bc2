#include "mbsgen/generator/codegen/emit.hpp"

#include <sched.h>
#include <unistd.h>

#include "mbsgen/generator/codegen/cse.hpp"
#include "mbsgen/generator/codegen/output_files.hpp"
#include "mbsgen/generator/linear/sensitivity.hpp"
#include "mbsgen/generator/model/escape.hpp"
#include "mbsgen/generator/symbolic/canonical.hpp"

#include "codegen/child_task.hpp"
#include "codegen/emit_chunks.hpp"
#include "symbolic/type_test.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace mbsgen {

using GiNaC::ex;
using GiNaC::ex_to;

std::string identifier(const std::string& name) {
  std::string id;
  for (char c : name) id += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  if (id.empty() || std::isdigit(static_cast<unsigned char>(id[0]))) id = "m_" + id;
  return id;
}

std::string id_problem(const std::string& id) {
  if (identifier(id) != id)
    return "is not a C identifier (letters, digits and _, not starting with a digit)";
  if (reserved_identifier(id))
    return "is a C++ keyword or a name C++ reserves (such as int, std, linux, _X, __x): the "
           "generated code could not use it";
  return "";
}

std::string format_double(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  std::string s = buf;
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

std::vector<std::string> sensitivity_parameter_names(const Model& model) {
  std::vector<std::string> names = model.selection().sensitivity_parameters;
  if (names.empty())
    for (const auto& q : model.parameters()) names.push_back(q.name);
  return names;
}

namespace {

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// Prints GiNaC expressions as C++ in canonical form (see canonical.hpp) and counts the
// operations it writes. A symbol's C++ variable holds its canonical value, so a symbol whose
// sign is −1 prints as a negated term.
class CppPrinter {
 public:
  explicit CppPrinter(CanonicalOrder& order) : order_(order) {}

  std::unordered_map<ex, std::string, std::hash<GiNaC::ex>, GiNaC::ex_is_equal> names;
  std::size_t operations = 0;

  std::string print(const ex& e) {
    bool negative = false;
    std::string s = term(e, negative);
    if (negative) {
      ++operations;
      return "-" + (is_sum(e) ? "(" + s + ")" : s);
    }
    return s;
  }

  // Prints e without its sign; sets negative when e is minus the printed text.
  std::string term(const ex& e, bool& negative) {
    negative = false;
    if (auto it = names.find(e); it != names.end()) {
      negative = order_.sign(e) < 0;
      return it->second;
    }
    if (isa<GiNaC::numeric>(e)) {
      GiNaC::numeric n = ex_to<GiNaC::numeric>(e);
      if (n.is_negative()) {
        negative = true;
        n = -n;
      }
      return number(n);
    }
    if (isa<GiNaC::constant>(e)) return number(ex_to<GiNaC::numeric>(GiNaC::evalf(e)));
    if (isa<GiNaC::symbol>(e))
      throw std::runtime_error("mbsgen: unbound symbol in generated code: " +
                               ex_to<GiNaC::symbol>(e).get_name());
    if (isa<GiNaC::add>(e)) {
      const std::vector<ex> ops = order_.operands(e);
      std::vector<std::pair<std::string, bool>> terms;
      for (const ex& op : ops) {
        bool neg = false;
        std::string t = term(op, neg);
        if (is_sum(op)) t = "(" + t + ")";
        terms.push_back({t, neg});
      }
      // The canonical form starts with a positive term; the sum's sign goes to the caller.
      negative = !terms.empty() && terms.front().second;
      std::string s;
      for (std::size_t i = 0; i < terms.size(); ++i) {
        const bool neg = terms[i].second != negative;
        if (i) ++operations;
        s += i == 0 ? terms[i].first : (neg ? " - " : " + ") + terms[i].first;
      }
      return s;
    }
    if (isa<GiNaC::mul>(e)) {
      std::vector<std::string> num, den;
      for (const ex& f : order_.operands(e)) {
        bool neg = false;
        if (isa<GiNaC::power>(f) && isa<GiNaC::numeric>(f.op(1)) &&
            ex_to<GiNaC::numeric>(f.op(1)).is_integer() && ex_to<GiNaC::numeric>(f.op(1)).is_negative()) {
          den.push_back(factor(GiNaC::pow(f.op(0), -f.op(1)), neg));
        } else if (isa<GiNaC::numeric>(f)) {
          std::string n = term(f, neg);
          if (!f.is_equal(1) && !f.is_equal(-1)) num.push_back(n);
        } else {
          num.push_back(factor(f, neg));
        }
        if (neg) negative = !negative;
      }
      std::string s;
      for (std::size_t i = 0; i < num.size(); ++i) {
        if (i) ++operations;
        s += (i ? "*" : "") + num[i];
      }
      if (num.empty()) s = "1.0";
      for (const auto& d : den) {
        ++operations;
        s += "/" + d;
      }
      return s;
    }
    if (isa<GiNaC::power>(e)) {
      const ex& b = e.op(0);
      const ex& x = e.op(1);
      if (isa<GiNaC::numeric>(x)) {
        GiNaC::numeric n = ex_to<GiNaC::numeric>(x);
        if (n.is_integer()) {
          long k = n.to_long();
          bool neg = false;
          std::string base = factor(b, neg);
          negative = neg && (k % 2 != 0);
          std::string s = base;
          for (long i = 1; i < std::labs(k); ++i) {
            ++operations;
            s += "*" + base;
          }
          if (std::labs(k) > 1) s = "(" + s + ")";
          if (k < 0) {
            ++operations;
            s = "1.0/" + s;
          }
          return s;
        }
        if (n == GiNaC::numeric(1, 2)) {
          ++operations;
          return "std::sqrt(" + print(b) + ")";
        }
        if (n == GiNaC::numeric(-1, 2)) {
          operations += 2;
          return "(1.0/std::sqrt(" + print(b) + "))";
        }
      }
      ++operations;
      return "std::pow(" + print(b) + ", " + print(x) + ")";
    }
    if (isa<GiNaC::function>(e)) {
      static const std::map<std::string, std::string> known = {
          {"sin", "std::sin"},   {"cos", "std::cos"},   {"tan", "std::tan"},   {"exp", "std::exp"},
          {"log", "std::log"},   {"abs", "std::fabs"},  {"asin", "std::asin"}, {"acos", "std::acos"},
          {"atan", "std::atan"}, {"atan2", "std::atan2"}, {"sinh", "std::sinh"}, {"cosh", "std::cosh"},
          {"tanh", "std::tanh"}, {"asinh", "std::asinh"}, {"acosh", "std::acosh"},
          {"atanh", "std::atanh"}};
      std::string fname = ex_to<GiNaC::function>(e).get_name();
      auto it = known.find(fname);
      if (it == known.end())
        throw std::runtime_error("mbsgen: function '" + fname + "' cannot be emitted as C++");
      ++operations;
      if (e.nops() == 1 && (odd_function(fname) || even_function(fname))) {
        // f(−x) = ∓f(x): the argument is printed in canonical form, its sign moved outside.
        bool neg = false;
        std::string arg = term(e.op(0), neg);
        negative = neg && odd_function(fname);
        return it->second + "(" + arg + ")";
      }
      std::string s = it->second + "(";
      for (std::size_t i = 0; i < e.nops(); ++i) s += (i ? ", " : "") + print(e.op(i));
      return s + ")";
    }
    throw std::runtime_error("mbsgen: cannot emit expression of this kind");
  }

 private:
  CanonicalOrder& order_;
  static bool is_sum(const ex& e) { return isa<GiNaC::add>(e); }
  std::string number(const GiNaC::numeric& n) {
    if (!n.is_real()) throw std::runtime_error("mbsgen: complex number in generated code");
    return format_double(n.to_double());
  }

  // A factor of a product without its sign: parenthesised when it is a sum.
  std::string factor(const ex& e, bool& negative) {
    std::string s = term(e, negative);
    return is_sum(e) ? "(" + s + ")" : s;
  }
};

struct Argument {
  std::string name;
  std::vector<ex> symbols;  // bound to name[i]
};
struct Buffer {
  std::string name;
  std::vector<ex> values;  // name[i] = values[i]
  std::string doc;
  std::vector<char> zero_at_op = {};  // name[i] is exactly 0 at the operating point
  /// Set to zero as a whole first (memset), with statements for the nonzero entries only: for
  /// the mostly zero derivatives of the sensitivity kernel (the middle ear's: 188,442 outputs, of
  /// which 23,246 have statements).
  bool zero_fill = false;
};
// A kernel's test whether it is called at the model's operating point: arguments[i] == values[i]
// (structural_zeros.hpp); the entries marked zero_at_op are then set to exact zeros.
struct OperatingPointTest {
  std::vector<std::string> arguments;
  std::vector<ex> values;
};
struct Kernel {
  std::string name, doc;
  std::vector<Argument> inputs;
  std::vector<Buffer> outputs;
  OperatingPointTest at_op = {};
  /// A model with closed loops: the kernel is emitted as the internal `<name>_full` of all the
  /// tree's coordinates, and `<name>` takes the independent ones and closes the loops first
  /// (loop_kernels below).
  bool wrapped = false;
  /// A wrapped kernel whose `<name>_full` is public too (declared in the header): a simulation
  /// keeps the tree's coordinates itself and closes the loops from the last ones (assemble_from).
  bool full_public = false;
  /// Emitted as a static function (not declared in the header).
  bool internal = false;
  /// Code that computes the outputs instead of their expressions (whose values are then only
  /// placeholders giving the sizes), setting `int computed_status` (a status > 1 is returned as
  /// it is); run before the zeros at the operating point. linear_structured: from `linear`.
  std::string computed_by = {};
  std::size_t computed_by_operations = 0;
};

std::vector<ex> column_major(const ExMatrix& A, std::size_t rows, std::size_t cols) {
  std::vector<ex> v;
  v.reserve(rows * cols);
  for (std::size_t j = 0; j < cols; ++j)
    for (std::size_t i = 0; i < rows; ++i) v.push_back(A[i][j]);
  return v;
}

std::string json_string(const std::string& s) { return json_string_literal(s); }

// Whether the code has the sensitivity kernel (its parameters' names go to the header and source).
bool has_kernel(const GeneratedCode& out, const std::string& name) {
  return std::any_of(out.kernels.begin(), out.kernels.end(), [&](const KernelInfo& k) { return k.name == name; });
}

bool has_sensitivity_kernel(const GeneratedCode& out) {
  return std::any_of(out.kernels.begin(), out.kernels.end(), [](const KernelInfo& k) { return k.name == "sensitivity"; });
}



struct EmittedKernel {
  std::string code;
  KernelInfo info;
  /// The kernel as tape text (emit_tape.hpp): its arguments, statements as printed, and exact
  /// zeros; empty for a kernel whose outputs come from code (computed_by) or that closes loops.
  std::string tape;
  /// The kernel's body cut into functions (emit_chunks.hpp): empty definitions when it is short.
  detail::ChunkedBody chunks;
};

// Sets the entries that are exact zeros at the operating point when the kernel is called
// there (its arguments equal the operating point's values bit for bit; elsewhere the entries
// keep their general expressions).
std::string zeros_at_operating_point(const Kernel& k) {
  std::ostringstream zeros;
  for (const auto& b : k.outputs)
    for (std::size_t i = 0; i < b.zero_at_op.size(); ++i)
      if (b.zero_at_op[i]) zeros << "    " << b.name << "[" << i << "] = 0.0;\n";
  if (zeros.str().empty()) return "";
  std::ostringstream code;
  code << "  // Exact zeros at the operating point (zero there for every parameter value).\n  if (";
  for (std::size_t i = 0; i < k.at_op.arguments.size(); ++i)
    code << (i ? " && " : "") << "at_operating_point(" << k.at_op.arguments[i] << ", op" << i << ")";
  code << ") {\n" << zeros.str() << "  }\n";
  return code.str();
}

// The statements of a kernel: the intermediates its outputs need (in definition order), the
// outputs, and the operating point's values for its test (`const double op<i>`); then CSE.
// Which of the program's definitions the kernel's outputs and operating point test need.
std::vector<char> needed_definitions(const Kernel& k, const Program& prog) {
  std::vector<char> needed(prog.definitions().size(), 0);
  std::vector<ex> stack;
  for (const auto& b : k.outputs)
    for (const auto& v : b.values) stack.push_back(v);
  for (const auto& v : k.at_op.values) stack.push_back(v);
  while (!stack.empty()) {
    ex e = stack.back();
    stack.pop_back();
    if (isa<GiNaC::symbol>(e)) {
      long i = prog.index_of(e);
      if (i >= 0 && !needed[static_cast<std::size_t>(i)]) {
        needed[static_cast<std::size_t>(i)] = 1;
        stack.push_back(prog.definitions()[static_cast<std::size_t>(i)].value);
      }
      continue;
    }
    for (std::size_t i = 0; i < e.nops(); ++i) stack.push_back(e.op(i));
  }
  return needed;
}

std::vector<Statement> kernel_statements(const Kernel& k, Program& prog, bool cse) {
  const std::vector<char> needed = needed_definitions(k, prog);
  std::vector<Statement> statements;
  for (std::size_t i = 0; i < needed.size(); ++i)
    if (needed[i]) {
      const auto& d = prog.definitions()[i];
      statements.push_back({d.symbol.get_name(), d.value, true, d.symbol});
    }
  if (k.computed_by.empty())  // otherwise the outputs come from computed_by
    for (const auto& b : k.outputs)
      for (std::size_t i = 0; i < b.values.size(); ++i)
        if (!(b.zero_fill && b.values[i].is_zero()))
          statements.push_back({b.name + "[" + std::to_string(i) + "]", b.values[i], false, GiNaC::ex()});
  for (std::size_t i = 0; i < k.at_op.values.size(); ++i)
    statements.push_back({"const double op" + std::to_string(i), k.at_op.values[i], false, GiNaC::ex()});
  if (cse) statements = eliminate_common_subexpressions(statements, prog.order());
  return statements;
}

// The statements as C++, each with its operation count and the local it defines.
std::vector<detail::PrintedStatement> print_statements(const Kernel& k, const std::vector<Statement>& statements,
                                                       CanonicalOrder& order, std::size_t& operations) {
  CppPrinter printer(order);
  for (const auto& a : k.inputs)
    for (std::size_t i = 0; i < a.symbols.size(); ++i)
      printer.names[a.symbols[i]] = a.name + "[" + std::to_string(i) + "]";
  std::vector<detail::PrintedStatement> out;
  out.reserve(statements.size());
  for (const auto& s : statements) {
    const std::size_t before = printer.operations;
    bool negative = false;
    std::string rhs = printer.term(s.value, negative);
    // A temporary holds its canonical value (the sign its symbol carries); an output its value.
    if (s.temporary && order.sign(s.symbol) < 0) negative = !negative;
    if (negative) {
      ++printer.operations;
      rhs = isa<GiNaC::add>(s.value) ? "-(" + rhs + ")" : "-" + rhs;
    }
    detail::PrintedStatement p{"", printer.operations - before, "", {}};
    if (s.temporary) {
      p.code = "  const double " + s.target + " = " + rhs + ";\n";
      p.defines = s.target;
      printer.names[s.symbol] = s.target;
    } else {
      p.code = "  " + s.target + " = " + rhs + ";\n";
      if (s.target.rfind("const double ", 0) == 0) {  // an operating point value, read after the body
        p.defines = s.target.substr(13);
        p.needed_after = true;
      }
    }
    out.push_back(std::move(p));
  }
  operations = printer.operations;
  return out;
}

// Which earlier statements each statement reads (for chunk_body).
void find_reads(const std::vector<Statement>& statements, std::vector<detail::PrintedStatement>& printed) {
  std::unordered_map<ex, std::size_t, std::hash<GiNaC::ex>, GiNaC::ex_is_equal> defined;
  for (std::size_t j = 0; j < statements.size(); ++j) {
    std::vector<ex> stack{statements[j].value};
    while (!stack.empty()) {
      const ex e = stack.back();
      stack.pop_back();
      if (isa<GiNaC::symbol>(e)) {
        if (auto it = defined.find(e); it != defined.end()) printed[j].reads.push_back(it->second);
        continue;
      }
      for (std::size_t i = 0; i < e.nops(); ++i) stack.push_back(e.op(i));
    }
    // In definition order, once each: the walk met them in GiNaC's operand order, which
    // follows hashes that differ from run to run (and the parts' order must not).
    auto& r = printed[j].reads;
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
    if (statements[j].temporary) defined.emplace(statements[j].symbol, j);
  }
}

// A whole kernel's body: the locals in their order, each output entry (and op value) right after
// the last local it reads, when its value is final, rather than all at the end. A value is then
// stored as soon as it is known instead of held to the end: on the 12-link chain's mass matrix
// (576 entries, 4,271 operations, -O2) that took 1.36 µs, stored at the end, and 1.22 µs stored
// early; a depth-first order per output (as in the parts) took 1.42 µs and every local just
// before its first reader 1.29 µs: both shorten the chains the processor overlaps. The order of
// statements does not change a single value.
std::string whole_body(const std::vector<Statement>& statements, std::vector<detail::PrintedStatement>& printed) {
  find_reads(statements, printed);
  std::vector<std::vector<std::size_t>> after(printed.size() + 1);  // after[j + 1]: right after j
  for (std::size_t j = 0; j < printed.size(); ++j)
    if (!statements[j].temporary) after[printed[j].reads.empty() ? 0 : printed[j].reads.back() + 1].push_back(j);
  std::string body;
  for (std::size_t j : after[0]) body += printed[j].code;
  for (std::size_t j = 0; j < printed.size(); ++j) {
    if (!statements[j].temporary) continue;
    body += printed[j].code;
    for (std::size_t o : after[j + 1]) body += printed[o].code;
  }
  return body;
}

// A kernel as tape text (docs/generated-abi.md, "Tapes"): its arguments in the C signature's
// order, then every statement exactly as printed for the compiler (so that the runtime, parsing
// it with C++'s precedence and associativity, does the same operations in the same order), the
// operating point test and the exact zeros there. Empty for a kernel the tape cannot hold.
std::string tape_kernel(const Kernel& k, const std::vector<detail::PrintedStatement>& printed, std::size_t operations) {
  if (!k.computed_by.empty() || k.wrapped || k.internal) return "";
  std::ostringstream t;
  t << "kernel " << k.name << " " << operations << "\n";
  for (const auto& a : k.inputs) t << "in " << a.name << " " << a.symbols.size() << "\n";
  for (const auto& b : k.outputs) t << "out " << b.name << " " << b.values.size() << (b.zero_fill ? " fill" : "") << "\n";
  for (const auto& p : printed) {
    std::string line = p.code;
    std::size_t from = line.find_first_not_of(' ');
    if (line.compare(from, 13, "const double ") == 0) from += 13;
    std::size_t to = line.find_last_not_of(";\n");
    t << "= " << line.substr(from, to + 1 - from) << "\n";
  }
  for (std::size_t i = 0; i < k.at_op.arguments.size(); ++i) t << "at " << k.at_op.arguments[i] << " op" << i << "\n";
  for (const auto& b : k.outputs)
    for (std::size_t i = 0; i < b.zero_at_op.size(); ++i)
      if (b.zero_at_op[i]) t << "zero " << b.name << " " << i << "\n";
  t << "end\n";
  return t.str();
}

EmittedKernel emit_kernel(const std::string& id, const Kernel& k, Program& prog, bool cse, std::size_t chunk_operations) {
  const std::vector<Statement> statements = kernel_statements(k, prog, cse);
  std::size_t operations = 0;
  std::vector<detail::PrintedStatement> printed = print_statements(k, statements, prog.order(), operations);

  const std::string fn = id + "_" + k.name + (k.wrapped ? "_full" : "");
  std::string parameters, arguments;
  for (const auto& a : k.inputs) {
    parameters += (parameters.empty() ? "" : ", ") + std::string("const double* ") + a.name;
    arguments += (arguments.empty() ? "" : ", ") + a.name;
  }
  for (const auto& b : k.outputs) {
    parameters += (parameters.empty() ? "" : ", ") + std::string("double* ") + b.name;
    arguments += (arguments.empty() ? "" : ", ") + b.name;
  }
  const std::string sig = "int " + fn + "(" + parameters + ")";

  EmittedKernel out;
  std::string body;
  if (chunk_operations > 0 && operations > EmitOptions::kCutFactor * chunk_operations && k.computed_by.empty()) {
    find_reads(statements, printed);
    out.chunks = detail::chunk_body(id + "_kernel_parts::", k.name, parameters, arguments, printed, chunk_operations);
    body = out.chunks.calls;
  } else {
    body = whole_body(statements, printed);
  }
  if (!k.computed_by.empty()) {
    body += k.computed_by;
    operations += k.computed_by_operations;
  }

  std::ostringstream code;
  code << "// " << k.doc << "\n// operations: " << operations << "\n";
  code << ((k.wrapped && !k.full_public) || k.internal ? "static " : "extern \"C\" ") << sig << " {\n";
  for (const auto& a : k.inputs) code << "  (void)" << a.name << ";\n";
  for (const auto& b : k.outputs)
    if (b.zero_fill && !b.values.empty())
      code << "  std::memset(" << b.name << ", 0, sizeof(double) * " << b.values.size() << ");\n";
  code << body << zeros_at_operating_point(k);
  code << "  int status = 0;\n";
  if (!k.computed_by.empty()) code << "  if (computed_status > 1) return computed_status;\n";
  for (const auto& b : k.outputs)
    if (!b.values.empty())
      code << "  if (!all_finite(" << b.name << ", " << b.values.size() << ")) status = 1;\n";
  code << "  return status;\n}\n\n";
  out.code = code.str();
  out.info = {k.name, sig, operations, out.code.size()};
  for (const auto& d : out.chunks.definitions) out.info.bytes += d.size();
  out.tape = tape_kernel(k, printed, operations);
  return out;
}

// linear_structured from linear (issue 17 §1: one derivation compiled once, not two): Q into
// D's buffer and K into Ks's, split in place by split_symmetric. Entries zero for every
// parameter value (lin's exact zeros) are set to 0; those zero at the operating point are set by
// the kernel's test as in every linear kernel. (X + Xᵀ)/2 computed numerically is exactly
// symmetric, which the symbolic entries evaluated one by one were only to rounding.
std::string structured_from_linear(const std::string& id, const Kernel& k, const LinearEquations& lin,
                                   std::size_t& operations) {
  const std::size_t f = lin.M.size(), m = lin.B.empty() ? 0 : lin.B[0].size(), r = lin.Cy.size();
  auto pattern = [&](const ExMatrix& A) {
    std::string s;
    for (std::size_t j = 0; j < f; ++j)
      for (std::size_t i = 0; i < f; ++i) s += A[i][j].is_zero() ? '0' : 'x';
    return s;
  };
  auto count = [&](const std::string& sym, const std::string& skew) {
    std::size_t n = 0;
    for (std::size_t j = 0; j < f; ++j)
      for (std::size_t i = 0; i < j; ++i) n += (sym[i + f * j] != '0') * 2 + (skew[i + f * j] != '0') * 3;
    return n;
  };
  const std::string D = pattern(lin.D), G = pattern(lin.G), Ks = pattern(lin.Ks), N = pattern(lin.N);
  operations = count(D, G) + count(Ks, N);
  std::ostringstream c;
  c << "  double B_linear[" << std::max<std::size_t>(f * m, 1) << "], Cy_linear[" << std::max<std::size_t>(r * f, 1)
    << "], Cv_linear[" << std::max<std::size_t>(r * f, 1) << "];\n";
  c << "  const int computed_status = " << id << "_linear" << (k.wrapped ? "_full" : "")
    << "(y0, yd0, p, M, D, Ks, B_linear, Cy_linear, Cv_linear);\n";
  c << "  split_symmetric(D, G, " << f << ", \"" << D << "\", \"" << G << "\");\n";
  c << "  split_symmetric(Ks, N, " << f << ", \"" << Ks << "\", \"" << N << "\");\n";
  return c.str();
}

// The generated file's finiteness check of a kernel's outputs, branch-free so that the compiler
// vectorizes it (GCC -O2 does: two lanes of 64 bits), with integer operations only so that it
// raises no floating-point exception (x·0, the first form, raised FE_INVALID for an infinity).
// The std::isfinite loop it replaces took 210 of the 1,200 ns of the 12-link chain's mass matrix
// (576 entries); with this one the kernel takes 1.13 instead of 1.21 µs (throwaway driver,
// 2026-11-27).
const char* const kAllFinite = R"(// Whether x[0..n) are all finite: an exponent field of all ones (infinity, NaN) is the one that
// carries into the sign bit when 1 is added to it. Integer operations only, no branch.
bool all_finite(const double* x, int n) {
  const unsigned long long exponent = 0x7ff0000000000000ull, one = 0x0010000000000000ull;
  unsigned long long carries[4] = {0, 0, 0, 0};
  int i = 0;
  for (; i + 4 <= n; i += 4)
    for (int k = 0; k < 4; ++k) {
      unsigned long long b;
      std::memcpy(&b, x + i + k, sizeof b);
      carries[k] |= (b & exponent) + one;
    }
  for (; i < n; ++i) {
    unsigned long long b;
    std::memcpy(&b, x + i, sizeof b);
    carries[0] |= (b & exponent) + one;
  }
  return ((carries[0] | carries[1] | carries[2] | carries[3]) >> 63) == 0;
}
)";

// The generated file's helper for structured_from_linear.
const char* const kSplitSymmetric = R"(// Splits X (n×n, column-major) in place into its symmetric part (X + Xᵀ)/2, left in X, and its
// skew part (X − Xᵀ)/2 in A; an entry marked '0' in sym or skew (column-major) is an exact zero.
void split_symmetric(double* X, double* A, int n, const char* sym, const char* skew) {
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < j; ++i) {
      const int ij = i + n * j, ji = j + n * i;
      const double x = X[ij], y = X[ji];
      X[ij] = X[ji] = sym[ij] == '0' ? 0.0 : 0.5 * (x + y);
      A[ij] = skew[ij] == '0' ? 0.0 : 0.5 * (x - y);
      A[ji] = skew[ij] == '0' ? 0.0 : 0.5 * (y - x);
    }
    if (sym[j + n * j] == '0') X[j + n * j] = 0.0;
    A[j + n * j] = 0.0;
  }
}
)";

// The kernels of a model with closed loops (loop_closure.hpp), in all the tree's coordinates:
// Φ(y), its Jacobian Φ_y (m×n) and the acceleration term γ(y, ẏ) of Φ_y ÿ + γ = 0, and the
// operating point of every coordinate (internal: the start of `assemble`).
std::vector<Kernel> loop_kernels(Equations& eq, const LinearEquations& lin) {
  const LoopClosure& loops = eq.loops;
  const std::size_t n = eq.y.size(), m = loops.equations.size();
  std::vector<ex> y(eq.y.begin(), eq.y.end()), yd(eq.yd.begin(), eq.yd.end()), p(eq.p.begin(), eq.p.end());
  std::vector<ex> phi, J;
  for (const auto& e : loops.equations) phi.push_back(e.phi);
  for (std::size_t j = 0; j < n; ++j)
    for (std::size_t k = 0; k < m; ++k) J.push_back(loops.Phi_y[k][j]);
  std::vector<Kernel> k;
  k.push_back({"constraints", "constraint equations Phi(y): length m (zero on the motion)",
               {{"y", y}, {"p", p}}, {{"phi", phi, ""}}});
  k.push_back({"constraint_jacobian", "constraint Jacobian dPhi/dy: m×n, column-major",
               {{"y", y}, {"p", p}}, {{"J", J, ""}}});
  k.push_back({"constraint_bias", "gamma(y, yd): length m, with J(y) ydd + gamma = 0 on the motion",
               {{"y", y}, {"yd", yd}, {"p", p}}, {{"gamma", loops.gamma, ""}}});
  Kernel op{"operating_point_full", "the operating point of every tree coordinate",
            {{"p", p}}, {{"y0", lin.y0, ""}, {"yd0", lin.yd0, ""}}};
  op.internal = true;
  k.push_back(op);
  return k;
}

// `assemble_from`: the tree's coordinates from the independent ones, the dependent ones by
// Newton's method on Φ(y) = 0 from the values y holds on entry (a simulation's last closed
// configuration, so that it follows the motion through any range). Status 2 when it fails (a
// singular Jacobian or no convergence in 50 steps): the loops cannot be closed there. `assemble`
// starts it from the operating point.
std::string assemble_code(const std::string& id, const Equations& eq) {
  const LoopClosure& loops = eq.loops;
  const std::size_t n = eq.y.size(), m = loops.equations.size(), f = loops.independent.size();
  auto list = [](const std::vector<std::size_t>& v) {
    std::string s;
    for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
    return s;
  };
  std::string scales;
  for (std::size_t k = 0; k < m; ++k) scales += (k ? ", " : "") + format_double(loops.equations[k].scale > 0 ? loops.equations[k].scale : 1.0);
  std::ostringstream c;
  c << "// Closes the loops: y (" << n << " tree coordinates) from yi (the " << f
    << " independent ones); the dependent\n// ones by Newton's method on Phi(y) = 0, starting from "
       "their values in y on entry (a nearby\n// closed configuration: Newton finds the closest solution). "
       "Returns 0, 1 (not finite) or 2 (the\n// loops cannot be closed there: a singular Jacobian, or no "
       "convergence).\n";
  c << "extern \"C\" int " << id << "_assemble_from(const double* yi, const double* p, double* y) {\n";
  c << "  static const int independent[" << f << "] = {" << list(loops.independent) << "};\n";
  c << "  static const int dependent[" << m << "] = {" << list(loops.dependent) << "};\n";
  c << "  static const double scale[" << m << "] = {" << scales << "};\n";
  c << "  double phi[" << m << "], J[" << m * n << "], A[" << m * m << "], dx[" << m << "];\n";
  c << "  for (int i = 0; i < " << f << "; ++i) y[independent[i]] = yi[i];\n";
  c << "  if (!all_finite(y, " << n << ")) return 1;\n";
  c << "  for (int iteration = 0; iteration < 50; ++iteration) {\n";
  c << "    if (" << id << "_constraints(y, p, phi) != 0 || " << id << "_constraint_jacobian(y, p, J) != 0) return 1;\n";
  c << "    // Near the solution the residual is rounding (about 1e-16 of each equation's size); one\n"
       "    // more step from below 1e-13 then leaves y at full precision (Newton converges quadratically).\n";
  c << "    bool small = true;\n";
  c << "    for (int k = 0; k < " << m << "; ++k) small = small && std::fabs(phi[k]) <= 1e-13 * scale[k];\n";
  c << "    for (int a = 0; a < " << m << "; ++a)\n      for (int b = 0; b < " << m << "; ++b) A[a + " << m
    << " * b] = J[a + " << m << " * dependent[b]];\n";
  c << "    if (!lu_solve(A, phi, dx, " << m << ")) return 2;\n";
  c << "    for (int b = 0; b < " << m << "; ++b) y[dependent[b]] -= dx[b];\n";
  c << "    if (!all_finite(y, " << n << ")) return 1;\n";
  c << "    if (small) return 0;\n  }\n  return 2;\n}\n\n";
  c << "// Closes the loops as " << id << "_assemble_from, starting from the operating point.\n";
  c << "extern \"C\" int " << id << "_assemble(const double* yi, const double* p, double* y) {\n";
  c << "  double yd0[" << n << "];\n";
  c << "  if (" << id << "_operating_point_full(p, y, yd0) != 0) return 1;\n";
  c << "  return " << id << "_assemble_from(yi, p, y);\n}\n\n";
  return c.str();
}

// The public form of a wrapped kernel: closes the loops, then calls `<name>_full`.
std::string wrapper_code(const std::string& id, const Kernel& k, const std::string& signature, std::size_t n) {
  std::ostringstream c;
  c << "// " << k.doc << "\n// in the independent coordinates; the dependent ones are found by " << id
    << "_assemble.\n";
  c << "extern \"C\" " << signature << " {\n  double full[" << n << "];\n";
  c << "  const int status = " << id << "_assemble(" << k.inputs[0].name << ", p, full);\n";
  c << "  if (status != 0) return status;\n  return " << id << "_" << k.name << "_full(full";
  for (std::size_t i = 1; i < k.inputs.size(); ++i) c << ", " << k.inputs[i].name;
  for (const auto& b : k.outputs) c << ", " << b.name;
  c << ");\n}\n\n";
  return c.str();
}

// Dense LU with partial pivoting, for `assemble` (m is small: the number of loop equations).
const char* const kLuSolve = R"(// Solves A x = b (A column-major n×n, overwritten) by LU with partial pivoting; false when A is
// singular to working precision.
bool lu_solve(double* A, const double* b, double* x, int n) {
  double amax = 0;
  for (int i = 0; i < n * n; ++i) amax = std::fmax(amax, std::fabs(A[i]));
  for (int i = 0; i < n; ++i) x[i] = b[i];
  for (int k = 0; k < n; ++k) {
    int p = k;
    for (int i = k + 1; i < n; ++i)
      if (std::fabs(A[i + n * k]) > std::fabs(A[p + n * k])) p = i;
    if (!(std::fabs(A[p + n * k]) > 1e-13 * amax)) return false;
    if (p != k) {
      for (int j = 0; j < n; ++j) std::swap(A[k + n * j], A[p + n * j]);
      std::swap(x[k], x[p]);
    }
    for (int i = k + 1; i < n; ++i) {
      const double l = A[i + n * k] / A[k + n * k];
      for (int j = k + 1; j < n; ++j) A[i + n * j] -= l * A[k + n * j];
      x[i] -= l * x[k];
    }
  }
  for (int i = n - 1; i >= 0; --i) {
    for (int j = i + 1; j < n; ++j) x[i] -= A[i + n * j] * x[j];
    x[i] /= A[i + n * i];
  }
  return true;
}
)";

// The linear kernels' entries that are zero at the operating point only (column-major, as
// the buffers), and the test of the arguments against the operating point y0(p), ẏ0(p).
void mark_zeros_at_operating_point(Kernel& k, const std::vector<const ZeroPattern*>& patterns,
                                   Equations& eq, const LinearEquations& lin) {
  bool any = false;
  for (std::size_t b = 0; b < patterns.size(); ++b) {
    const ZeroPattern& z = *patterns[b];
    auto& flags = k.outputs[b].zero_at_op;
    const std::size_t rows = z.size(), cols = rows ? z[0].size() : 0;
    flags.assign(rows * cols, 0);
    for (std::size_t j = 0; j < cols; ++j)
      for (std::size_t i = 0; i < rows; ++i)
        if (z[i][j] == EntryZero::at_operating_point) flags[j * rows + i] = 1, any = true;
  }
  if (!any) return;
  // The kernel's y0 has every tree coordinate (after `assemble` with closed loops: the dependent
  // ones, refined by Newton, are not tested; the zeros hold for any of their values); its yd0 the
  // rates of the independent coordinates.
  const std::size_t n = lin.y0.size();
  const std::vector<std::size_t>& dependent = eq.loops.dependent;
  for (std::size_t i = 0; i < n; ++i) {
    if (std::binary_search(dependent.begin(), dependent.end(), i)) continue;
    k.at_op.arguments.push_back("y0[" + std::to_string(i) + "]");
    k.at_op.values.push_back(eq.program.define(lin.y0[i]));
  }
  if (lin.at_rest) return;
  std::size_t j = 0;  // position in yd0
  for (std::size_t i = 0; i < n; ++i) {
    if (std::binary_search(dependent.begin(), dependent.end(), i)) continue;
    if (std::find(lin.zero_rates.begin(), lin.zero_rates.end(), i) == lin.zero_rates.end()) {
      k.at_op.arguments.push_back("yd0[" + std::to_string(j) + "]");
      k.at_op.values.push_back(eq.program.define(lin.yd0[i]));
    }
    ++j;
  }
}

// The manifest's "constraints": the tree's coordinates, which are independent (and whether
// mbsgen chose them), the equations kept and those dropped, with why.
std::string constraints_json(const Model& model, const LoopClosure& loops) {
  auto names = [&](const std::vector<std::size_t>& v) {
    std::string s;
    for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + json_string(model.coordinates()[v[i]].name);
    return s;
  };
  auto equation = [](const ConstraintEquation& e) {
    return "{\"constraint\": " + json_string(e.constraint) + ", \"component\": " + json_string(e.component);
  };
  std::ostringstream j;
  std::vector<std::size_t> all(model.coordinates().size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = k;
  j << "{\"tree_coordinates\": [" << names(all) << "], \"independent\": [" << names(loops.independent)
    << "], \"dependent\": [" << names(loops.dependent) << "], \"independent_chosen_by\": "
    << (loops.chosen ? "\"mbsgen (column-pivoted QR of the constraint Jacobian at the operating point)\""
                     : "\"model\"")
    << ", \"reactions_unique\": " << (loops.redundant ? "false" : "true") << ",\n    \"equations\": [";
  for (std::size_t k = 0; k < loops.equations.size(); ++k) j << (k ? ", " : "") << equation(loops.equations[k]) << "}";
  j << "],\n    \"dropped\": [";
  for (std::size_t k = 0; k < loops.dropped.size(); ++k)
    j << (k ? ",\n      " : "") << equation(loops.dropped[k].first) << ", \"reason\": " << json_string(loops.dropped[k].second) << "}";
  j << "]}";
  return j.str();
}

// The manifest's "sparsity": each linear matrix's rows as strings, 'x' an entry that may be
// nonzero, '0' an exact zero, 'o' an exact zero at the operating point (general elsewhere); and
// how many zeros were proved of each kind (structural_zeros.hpp).
std::string sparsity_json(const LinearEquations& lin) {
  const StructuralZeros& z = lin.zeros;
  std::ostringstream j;
  j << "{\"legend\": \"x may be nonzero, 0 exact zero, o exact zero at the operating point\", "
    << "\"zero_everywhere\": " << z.everywhere << ", \"zero_at_operating_point\": "
    << z.at_operating_point << ", \"unproved_candidates\": " << z.unproved;
  const std::pair<const char*, const ZeroPattern*> matrices[] = {
      {"M", &z.M}, {"Q", &z.Q},   {"K", &z.K}, {"B", &z.B}, {"C_y", &z.Cy}, {"C_v", &z.Cv},
      {"D", &z.D}, {"G", &z.G}, {"K_s", &z.Ks}, {"N", &z.N}};
  const std::pair<const char*, const ZeroPattern*> descriptor[] = {{"E", &z.E}, {"A", &z.A}, {"B_x", &z.Bx}, {"C_x", &z.Cx}};
  for (const auto& [name, pattern] : lin.descriptor ? std::vector<std::pair<const char*, const ZeroPattern*>>(
                                                          std::begin(descriptor), std::end(descriptor))
                                                    : std::vector<std::pair<const char*, const ZeroPattern*>>(
                                                          std::begin(matrices), std::end(matrices))) {
    j << ",\n    \"" << name << "\": [";
    const std::vector<std::string> rows = pattern_rows(*pattern);
    for (std::size_t i = 0; i < rows.size(); ++i) j << (i ? ", " : "") << "\"" << rows[i] << "\"";
    j << "]";
  }
  j << "}";
  return j.str();
}

}  // namespace

// The manifest's "nonholonomic": the velocity constraints, the independent speeds (and whether
// mbsgen chose them) and the descriptor state x = (coordinates, speeds).
std::string nonholonomic_json(const Model& model, const Equations& eq, const LinearEquations& lin) {
  const Nonholonomic& nh = eq.nonholonomic;
  auto names = [&](const std::vector<std::size_t>& v, const char* suffix) {
    std::string s;
    for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + json_string(model.coordinates()[v[i]].name + suffix);
    return s;
  };
  std::ostringstream j;
  j << "{\"equations\": [";
  for (std::size_t k = 0; k < nh.equations.size(); ++k)
    j << (k ? ", " : "") << "{\"constraint\": " << json_string(nh.equations[k].constraint)
      << ", \"component\": " << json_string(nh.equations[k].component) << "}";
  j << "], \"independent_speeds\": [" << names(lin.speeds, "_dot") << "], \"dependent_speeds\": ["
    << names(nh.dependent_speeds, "_dot") << "], \"chosen\": " << (nh.chosen ? "true" : "false")
    << ",\n    \"state\": [" << names(lin.coordinates, "") << ", " << names(lin.speeds, "_dot") << "]"
    << ",\n    \"reduced_form\": ";
  if (lin.reduced.exists)
  {
    j << "{\"coordinates\": [" << names(lin.reduced.coordinates, "") << "], \"kernel\": \"reduced\", \"matrices\": "
      << "[\"M\", \"Q\", \"K\", \"B\"], \"parts\": [";
    const auto& parts = model.reduced_coefficients();
    for (std::size_t i = 0; i < parts.size(); ++i) {
      std::ostringstream m;
      m << parts[i].monomial;
      j << (i ? ", " : "") << "{\"name\": " << json_string(parts[i].name) << ", \"of\": \"" << parts[i].matrix
        << "\", \"per\": " << json_string(m.str()) << "}";
    }
    j << "]}";
  }
  else
    j << "null";
  j << "}";
  return j.str();
}

// The header: the preamble (banner, operation counts), the scene's macros, sizes, names and the
// kernels' declarations.
std::string header_text(const Model& model, const Equations& eq, const LinearEquations& lin, const SceneSelection& scene,
                        const GeneratedCode& out, const std::string& preamble) {
  const bool loops = eq.loops.active;
  const std::size_t f = lin.coordinates.size(), n = eq.y.size(), m = eq.u.size(), r = eq.outputs.size();
  const std::size_t nb = model.bodies().size(), np = eq.p.size();
  std::ostringstream h;
  h << preamble << "#pragma once\n\n";
  h << "#define " << out.id << "_ABI_VERSION " << kAbiVersion << "\n";
  h << "#define " << out.id << "_SCENE " << cpp_string_literal(scene.name) << "\n";
  for (const auto& k : out.kernels) h << "#define " << out.id << "_HAS_" << upper(k.name) << " 1\n";
  for (Analysis a : scene.analyses) h << "#define " << out.id << "_ANALYSIS_" << upper(to_string(a)) << " 1\n";
  if (const auto& fr = scene.frequency_range)
    h << "#define " << out.id << "_FREQUENCY_FROM_HZ " << format_double(fr->from_hz) << "\n#define "
      << out.id << "_FREQUENCY_TO_HZ " << format_double(fr->to_hz) << "\n#define " << out.id
      << "_FREQUENCY_POINTS " << fr->points << "\n#define " << out.id << "_FREQUENCY_LOG "
      << (fr->logarithmic ? 1 : 0) << "\n";
  h << "\n";
  h << "#ifdef __cplusplus\nextern \"C\" {\n#endif\n\n";
  h << "enum {\n  " << out.id << "_n_coordinates = " << f << ",\n  " << out.id
    << "_n_inputs = " << m << ",\n  " << out.id << "_n_outputs = " << r << ",\n  " << out.id
    << "_n_parameters = " << np << ",\n  " << out.id << "_n_bodies = " << nb << ",\n  "
    << out.id << "_at_rest = " << (lin.at_rest ? 1 : 0) << ",\n  " << out.id
    << "_equilibrium = " << (lin.equilibrium ? 1 : 0) << ",\n  " << out.id << "_D_zero = "
    << (lin.D_zero ? 1 : 0) << ",\n  " << out.id << "_G_zero = " << (lin.G_zero ? 1 : 0)
    << ",\n  " << out.id << "_N_zero = " << (lin.N_zero ? 1 : 0) << "\n};\n\n";
  h << "int " << out.id << "_abi_version(void);\n";
  h << "extern const char* const " << out.id << "_coordinate_names[];\n";
  h << "extern const char* const " << out.id << "_parameter_names[];\n";
  h << "extern const double " << out.id << "_parameter_defaults[];\n";
  h << "extern const char* const " << out.id << "_input_names[];\n";
  h << "// Per input \"force\" or \"motion\" (a motion input prescribes a support's motion).\n";
  h << "extern const char* const " << out.id << "_input_kinds[];\n";
  h << "extern const char* const " << out.id << "_output_names[];\n";
  if (has_sensitivity_kernel(out))
    h << "// Parameter sensitivities: the parameters of the sensitivity kernel, in its order.\nenum { " << out.id
      << "_n_sensitivity_parameters = " << sensitivity_parameter_names(model).size() << " };\nextern const char* const "
      << out.id << "_sensitivity_parameter_names[];\n";
  if (has_kernel(out, "physical"))
    h << "// The physical conditions on the parameters: per check its kind (positive, nonnegative, body),\n"
         "// what it is, the unit of its value, and the parameters it depends on (comma-separated); the\n"
         "// physical kernel gives the values.\nenum { "
      << out.id << "_n_checks = " << model.physical_checks().size() << " };\nextern const char* const " << out.id
      << "_check_kinds[];\nextern const char* const " << out.id << "_check_labels[];\nextern const char* const "
      << out.id << "_check_units[];\nextern const char* const " << out.id << "_check_parameters[];\n";
  if (loops)
    h << "// Closed loops: the kernels take the independent coordinates (coordinate_names); "
         "assemble\n// and the constraint kernels all " << n << " tree coordinates.\nenum { " << out.id
      << "_n_tree_coordinates = " << n << ", " << out.id << "_n_constraints = " << eq.loops.equations.size()
      << " };\nextern const char* const " << out.id << "_tree_coordinate_names[];\n";
  if (lin.descriptor)
    h << "// Nonholonomic constraints: the linear model is E x' = A x + B u, z = C x with x the " << f
      << " coordinates and\n// the " << lin.speeds.size() << " independent speeds (the rates of speed_names).\nenum { "
      << out.id << "_n_speeds = " << lin.speeds.size() << ", " << out.id << "_n_reduced = " << lin.reduced.coordinates.size()
      << ", " << out.id << "_n_reduced_parts = " << lin.reduced.named.size() << " };\nextern const char* const " << out.id
      << "_speed_names[];\nextern const char* const " << out.id << "_reduced_coordinate_names[];\nextern const char* const "
      << out.id << "_reduced_part_names[];\n";
  h << "\n// Kernels (docs/generator.md): matrices column-major. Output arrays must not overlap the inputs:\n"
       "// outputs are stored while inputs are still read.\n";
  for (const auto& k : out.kernels) h << k.signature << ";\n";
  h << "\n#ifdef __cplusplus\n}\n#endif\n";
  return h.str();
}

// The JSON manifest: the scene, the names and units, the operating point, the effects, the
// structure and sparsity of the linear matrices, closed loops and the kernels with their counts.
std::string manifest_json(const Model& model, const Equations& eq, const LinearEquations& lin, const SceneSelection& scene,
                          const GeneratedCode& out) {
  const bool loops = eq.loops.active;
  const std::size_t f = lin.coordinates.size(), m = eq.u.size(), r = eq.outputs.size();
  const std::size_t nb = model.bodies().size(), np = eq.p.size();
  std::ostringstream j;
  j << "{\n  \"generator\": \"mbsgen " << kGeneratorVersion << "\",\n  \"abi_version\": " << kAbiVersion
    << ",\n  \"model\": " << json_string(model.name()) << ",\n  \"scene\": " << json_string(scene.name)
    << ",\n  \"description\": " << json_string(scene.description) << ",\n  \"id\": " << json_string(out.id)
    << ",\n  \"analyses\": [";
  for (std::size_t i = 0; i < scene.analyses.size(); ++i)
    j << (i ? ", " : "") << json_string(to_string(scene.analyses[i]));
  j << "],\n  \"frequency_range\": ";
  if (const auto& fr = scene.frequency_range)
    j << "{\"from_hz\": " << format_double(fr->from_hz) << ", \"to_hz\": " << format_double(fr->to_hz)
      << ", \"points\": " << fr->points << ", \"spacing\": " << (fr->logarithmic ? "\"log\"" : "\"linear\"")
      << "}";
  else
    j << "null";
  j << ",\n  \"coordinates\": [";
  for (std::size_t i = 0; i < f; ++i) {
    const Coordinate& q = model.coordinates()[loops ? eq.loops.independent[i] : i];
    j << (i ? ", " : "") << "{\"name\": " << json_string(q.name) << ", \"unit\": " << json_string(q.unit) << "}";
  }
  j << "]";
  if (loops) j << ",\n  \"constraints\": " << constraints_json(model, eq.loops);
  if (lin.descriptor) j << ",\n  \"nonholonomic\": " << nonholonomic_json(model, eq, lin);
  j << ",\n  \"parameters\": [";
  for (std::size_t i = 0; i < np; ++i) {
    const auto& q = model.parameters()[i];
    j << (i ? ",\n    " : "\n    ") << "{\"name\": " << json_string(q.name)
      << ", \"value\": " << format_double(q.value) << ", \"unit\": " << json_string(q.unit)
      << ", \"source\": " << json_string(q.source) << "}";
  }
  j << "],\n  \"inputs\": [";
  for (std::size_t i = 0; i < m; ++i)
    j << (i ? ", " : "") << "{\"name\": " << json_string(model.inputs()[i].name)
      << ", \"unit\": " << json_string(model.inputs()[i].unit)
      << ", \"kind\": \"" << (model.inputs()[i].motion ? "motion" : "force") << "\"}";
  j << "],\n  \"outputs\": [";
  for (std::size_t i = 0; i < r; ++i)
    j << (i ? ", " : "") << "{\"name\": " << json_string(model.outputs()[i].name)
      << ", \"unit\": " << json_string(model.outputs()[i].unit) << "}";
  j << "],\n  \"bodies\": [";
  for (std::size_t i = 0; i < nb; ++i) j << (i ? ", " : "") << json_string(model.bodies()[i].name);
  j << "],\n  \"operating_point\": {\"kind\": "
    << (lin.equilibrium ? "\"equilibrium\"" : "\"given\"") << ", \"at_rest\": "
    << (lin.at_rest ? "true" : "false") << ", \"zero_rates\": [";
  for (std::size_t i = 0; i < lin.zero_rates.size(); ++i)
    j << (i ? ", " : "") << json_string(model.coordinates()[lin.zero_rates[i]].name);
  j << "]},\n  \"effects\": [";
  for (std::size_t i = 0; i < scene.effects.size(); ++i) {
    const EffectState& e = scene.effects[i];
    j << (i ? "," : "") << "\n    {\"name\": " << json_string(e.name) << ", \"category\": "
      << json_string(e.category) << ", \"active\": " << (e.active ? "true" : "false");
    if (!e.note.empty()) j << ", \"note\": " << json_string(e.note);
    j << "}";
  }
  auto zero = [](bool z) { return z ? "\"zero\"" : "\"nonzero\""; };
  j << "\n  ],\n  \"structure\": {\"D\": " << zero(lin.D_zero) << ", \"G\": " << zero(lin.G_zero)
    << ", \"N\": " << zero(lin.N_zero) << "},\n  \"sparsity\": " << sparsity_json(lin)
    << ",\n  \"kernels\": [";
  for (std::size_t i = 0; i < out.kernels.size(); ++i)
    j << (i ? "," : "") << "\n    {\"name\": " << json_string(out.kernels[i].name)
      << ", \"operations\": " << out.kernels[i].operations << ", \"bytes\": " << out.kernels[i].bytes
      << ", \"signature\": " << json_string(out.kernels[i].signature) << "}";
  j << "\n  ]\n}\n";
  return j.str();
}

// mass_matrix, residual and (asked for) dynamics: the second-order model's kernels that need only
// the derivation (emit_ahead emits them while the caller linearizes). f: the coordinates.
void derivation_kernels(const Equations& eq, const std::vector<ex>& y, const std::vector<ex>& yd, const std::vector<ex>& p,
                        std::size_t f, bool dynamics, std::vector<Kernel>& kernels) {
  const std::vector<ex> u(eq.u.begin(), eq.u.end());
  kernels.push_back({"mass_matrix", "M(y, p): f×f mass matrix, column-major",
                     {{"y", y}, {"p", p}},
                     {{"M", column_major(eq.M, f, f), ""}}});
  // k − q in the form written for evaluation (Equations::residual_kernel), where there is one.
  const std::vector<ex>& residual = eq.residual_kernel.empty() ? eq.residual : eq.residual_kernel;
  kernels.push_back({"residual", "k(y, yd) − q(y, yd, u): length f (M(y) ydd + k − q = 0)",
                     {{"y", y}, {"yd", yd}, {"u", u}, {"p", p}},
                     {{"r", residual, ""}}});
  if (dynamics)
    kernels.push_back({"dynamics", "M(y) (f×f, column-major) and k − q (length f) in one kernel (EmitOptions::dynamics)",
                       {{"y", y}, {"yd", yd}, {"u", u}, {"p", p}},
                       {{"M", column_major(eq.M, f, f), ""}, {"r", residual, ""}}});
}

// dynamics_jacobian: the Jacobians of the equations of motion F = M(y) ÿ + k − q = 0 at any state,
// Ky = ∂F/∂y (with the term ∂(M ÿ)/∂y) and Kv = ∂F/∂ẏ, for implicit time integration (∂F/∂ÿ = M).
// Differentiated through the program from the form written for evaluation.
Kernel dynamics_jacobian_kernel(Equations& eq, const std::vector<ex>& y, const std::vector<ex>& yd,
                                const std::vector<ex>& p) {
  const std::size_t f = eq.M.size();
  Program& prog = eq.program;
  const std::vector<ex>& residual = eq.residual_kernel.empty() ? eq.residual : eq.residual_kernel;
  std::vector<ex> Ky(f * f), Kv(f * f);
  for (std::size_t j = 0; j < f; ++j)
    for (std::size_t i = 0; i < f; ++i) {
      ex dy = prog.diff(residual[i], eq.y[j]);
      for (std::size_t k = 0; k < f; ++k)
        if (!eq.M[i][k].is_zero()) dy += prog.diff(eq.M[i][k], eq.y[j]) * eq.accelerations[k];
      Ky[i + j * f] = dy;
      Kv[i + j * f] = prog.diff(residual[i], eq.yd[j]);
    }
  const std::vector<ex> ydd(eq.accelerations.begin(), eq.accelerations.end()), u(eq.u.begin(), eq.u.end());
  return {"dynamics_jacobian",
          "Ky = ∂(M ydd + k − q)/∂y and Kv = ∂(k − q)/∂yd (f×f, column-major) at any state (EmitOptions::dynamics)",
          {{"y", y}, {"yd", yd}, {"ydd", ydd}, {"u", u}, {"p", p}},
          {{"Ky", Ky, ""}, {"Kv", Kv, ""}}};
}

// mass_matrix, residual, linear and linear_structured: the second-order model's kernels (and, asked
// for, dynamics and dynamics_jacobian; not with closed loops, whose kernels take the tree's
// coordinates and the independent rates).
void second_order_kernels(Equations& eq, const LinearEquations& lin, const std::vector<ex>& y, const std::vector<ex>& yd,
                          const std::vector<ex>& p, bool dynamics, std::vector<Kernel>& kernels) {
  const std::size_t f = lin.M.size(), m = eq.u.size(), r = eq.outputs.size();
  derivation_kernels(eq, y, yd, p, f, dynamics, kernels);
  if (dynamics && !eq.loops.active && eq.accelerations.size() == f) kernels.push_back(dynamics_jacobian_kernel(eq, y, yd, p));
  std::vector<ex> none;
  kernels.push_back({"linear",
                     "linearized M, Q, K (f×f), B (f×m), C_y, C_v (r×f) at (y0, yd0), column-major",
                     {{"y0", y}, {"yd0", lin.at_rest ? none : yd}, {"p", p}},
                     {{"M", column_major(lin.M, f, f), ""},
                      {"Q", column_major(lin.Q, f, f), ""},
                      {"K", column_major(lin.K, f, f), ""},
                      {"B", column_major(lin.B, f, m), ""},
                      {"Cy", column_major(lin.Cy, r, f), ""},
                      {"Cv", column_major(lin.Cv, r, f), ""}}});
  // linear_structured splits linear's Q and K (structured_from_linear): its outputs' values are
  // placeholders of the right sizes.
  Kernel structured{"linear_structured",
                    "M, damping D = sym Q, gyroscopic G = skew Q, stiffness sym K, circulatory "
                    "N = skew K at (y0, yd0), column-major",
                    {{"y0", y}, {"yd0", lin.at_rest ? none : yd}, {"p", p}},
                    {{"M", std::vector<ex>(f * f, 0), ""},
                     {"D", std::vector<ex>(f * f, 0), ""},
                     {"G", std::vector<ex>(f * f, 0), ""},
                     {"Ks", std::vector<ex>(f * f, 0), ""},
                     {"N", std::vector<ex>(f * f, 0), ""}}};
  structured.computed_by = "linear";  // replaced by the code in emit(), which knows the id
  kernels.push_back(structured);
  mark_zeros_at_operating_point(kernels[kernels.size() - 2], {&lin.zeros.M, &lin.zeros.Q, &lin.zeros.K,
                                &lin.zeros.B, &lin.zeros.Cy, &lin.zeros.Cv}, eq, lin);
  mark_zeros_at_operating_point(kernels.back(), {&lin.zeros.M, &lin.zeros.D, &lin.zeros.G,
                                &lin.zeros.Ks, &lin.zeros.N}, eq, lin);
}

// descriptor: E, A (n×n), B (n×m), C (r×n) of E x' = A x + B u, z = C x (nonholonomic.hpp).
Kernel descriptor_kernel(Equations& eq, const LinearEquations& lin, const std::vector<ex>& y, const std::vector<ex>& yd,
                         const std::vector<ex>& p) {
  const std::size_t nx = lin.E.size(), m = eq.u.size(), r = eq.outputs.size();
  std::vector<ex> none;
  Kernel k{"descriptor",
           "descriptor model E x' = A x + B u, z = C x at (y0, yd0) with x = (coordinates, independent speeds): "
           "E, A (n×n), B (n×m), C (r×n), column-major; yd0 entries of dependent speeds are not used",
           {{"y0", y}, {"yd0", lin.at_rest ? none : yd}, {"p", p}},
           {{"E", column_major(lin.E, nx, nx), ""},
            {"A", column_major(lin.A, nx, nx), ""},
            {"B", column_major(lin.Bx, nx, m), ""},
            {"C", column_major(lin.Cx, r, nx), ""}}};
  mark_zeros_at_operating_point(k, {&lin.zeros.E, &lin.zeros.A, &lin.zeros.Bx, &lin.zeros.Cx}, eq, lin);
  return k;
}

// reduced: M, Q, K (n×n), B (n×m) of the reduced second-order form (nonholonomic.hpp).
Kernel reduced_kernel(Equations& eq, const LinearEquations& lin, const std::vector<ex>& y, const std::vector<ex>& yd,
                      const std::vector<ex>& p) {
  const ReducedForm& r = lin.reduced;
  const std::size_t n = r.M.size(), m = eq.u.size();
  std::vector<ex> none;
  return {"reduced",
          "reduced second-order form M q'' + Q q' + K q = B u of the descriptor model at (y0, yd0), q = "
          "reduced_coordinate_names: M, Q, K (n×n), B (n×m), column-major",
          {{"y0", y}, {"yd0", lin.at_rest ? none : yd}, {"p", p}},
          {{"M", column_major(r.M, n, n), ""},
           {"Q", column_major(r.Q, n, n), ""},
           {"K", column_major(r.K, n, n), ""},
           {"B", column_major(r.B, n, m), ""}}};
}

// bodies: the kinematics of each of the nb bodies (f coordinates).
Kernel bodies_kernel(const Equations& eq, std::size_t nb, const std::vector<ex>& y, const std::vector<ex>& p, std::size_t f) {
  std::vector<ex> rc, S, JT, JR, mass, Ic;
  for (std::size_t i = 0; i < nb; ++i) {
    const BodyKinematics& b = eq.kinematics.bodies[i];
    for (int a = 0; a < 3; ++a) rc.push_back(b.com[a]);
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) S.push_back(b.S[a][c]);
    mass.push_back(b.inertia.m);
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) Ic.push_back(b.I_com[a][c]);
  }
  for (std::size_t i = 0; i < nb; ++i)
    for (std::size_t j = 0; j < f; ++j)
      for (std::size_t a = 0; a < 3; ++a) {
        JT.push_back(eq.JT[3 * i + a][j]);
        JR.push_back(eq.JR[3 * i + a][j]);
      }
  return {"bodies",
          "per body: centre of mass rc (3), rotation S (3×3), Jacobians JT, JR (3×f, "
          "centre-of-mass velocity and angular velocity in the world frame), mass m and "
          "inertia Ic about the centre of mass in the world frame (3×3)",
          {{"y", y}, {"p", p}},
          {{"rc", rc, ""}, {"S", S, ""}, {"JT", JT, ""}, {"JR", JR, ""},
           {"m", mass, ""}, {"Ic", Ic, ""}}};
}

// sensitivity (sensitivity.hpp): the derivatives of the linear matrices by the scene's parameters,
// and, when the operating point moves with them, operating_point_sensitivity.
void sensitivity_kernels(const Model& model, Equations& eq, const LinearEquations& lin, const std::vector<ex>& y,
                         const std::vector<ex>& yd, const std::vector<ex>& p, std::vector<Kernel>& kernels) {
  const SceneSelection& scene = model.selection();
  if (!scene.emits("sensitivity")) return;
  if (scene.full && (eq.loops.active || eq.nonholonomic.active || lin.descriptor)) return;  // not available
  std::vector<std::size_t> chosen;
  for (const auto& name : scene.sensitivity_parameters)
    for (std::size_t j = 0; j < model.parameters().size(); ++j)
      if (model.parameters()[j].name == name) chosen.push_back(j);
  const LinearSensitivity s = linear_sensitivity(eq, lin, chosen);
  const std::vector<ex> none;
  std::vector<ex> dy0(s.dy0.begin(), s.dy0.end()), dyd0;
  if (!lin.at_rest) dyd0.assign(s.dyd0.begin(), s.dyd0.end());
  Kernel k{"sensitivity",
           "derivatives of the linear matrices by the parameters sensitivity_parameters (s of them) at (y0, yd0): "
           "for each matrix, s blocks of its size one after the other, column-major; dy0, dyd0 (f×s): the "
           "operating point's derivatives (operating_point_sensitivity; read only when the point moves)",
           {{"y0", y}, {"yd0", lin.at_rest ? none : yd}, {"p", p}, {"dy0", dy0}, {"dyd0", dyd0}},
           {}};
  static const char* const names[] = {"M", "Q", "K", "B", "Cy", "Cv", "Ca", "D", "B1", "B2", "D1"};
  std::vector<ZeroPattern> stacked;  // each matrix's zeros, repeated per parameter
  for (const char* name : names) {
    auto it = std::find_if(s.matrices.begin(), s.matrices.end(), [&](const MatrixDerivative& d) { return d.name == name; });
    k.outputs.push_back({std::string("d") + name, it == s.matrices.end() ? none : it->values, ""});
    k.outputs.back().zero_fill = true;
    ZeroPattern z;
    if (it != s.matrices.end() && it->zeros && !it->zeros->empty()) {
      z.assign(it->rows, {});
      for (std::size_t i = 0; i < it->rows; ++i)
        for (std::size_t j = 0; j < s.parameters.size(); ++j)
          z[i].insert(z[i].end(), (*it->zeros)[i].begin(), (*it->zeros)[i].end());
    }
    stacked.push_back(std::move(z));
  }
  std::vector<const ZeroPattern*> patterns;
  for (const auto& z : stacked) patterns.push_back(&z);
  mark_zeros_at_operating_point(k, patterns, eq, lin);
  kernels.push_back(std::move(k));
  if (!s.moving_point) return;
  kernels.push_back({"operating_point_sensitivity",
                     lin.equilibrium ? "the static equilibrium's sensitivity: dr = ∂r/∂p + Q dyd0 (f×s; then K dy0 = −dr) "
                                       "and dyd0 = the steady rates' derivatives (f×s), column-major"
                                     : "the given operating point's derivatives dy0, dyd0 by the sensitivity parameters "
                                       "(f×s each, column-major)",
                     {{"y0", y}, {"yd0", lin.at_rest ? none : yd}, {"p", p}},
                     {{lin.equilibrium ? "dr" : "dy0", s.op_first, ""}, {"dyd0", s.op_rates, ""}}});
}

// The kernels of docs/generator.md, in emission order. With closed loops the coordinates y are
// the tree's (n), the rates yd the independent ones, and the matrices those of the independent
// coordinates (f); such kernels are wrapped (Kernel::wrapped).
// The values of Model::physical_checks, one check after the other (the `physical` kernel).
std::vector<ex> physical_values(const Model& model) {
  std::vector<ex> v;
  for (const PhysicalCheck& c : model.physical_checks()) v.insert(v.end(), c.values.begin(), c.values.end());
  return v;
}

std::vector<Kernel> model_kernels(const Model& model, Equations& eq, const LinearEquations& lin, bool dynamics) {
  const bool loops = eq.loops.active;
  const std::size_t f = lin.M.size(), m = eq.u.size(), r = eq.outputs.size();
  const std::size_t nb = model.bodies().size();
  std::vector<ex> y(eq.y.begin(), eq.y.end()), yd, u(eq.u.begin(), eq.u.end()), p(eq.p.begin(), eq.p.end());
  std::vector<ex> y0_out, yd0_out;
  for (std::size_t k = 0; k < eq.yd.size(); ++k)
    if (!loops || std::binary_search(eq.loops.independent.begin(), eq.loops.independent.end(), k)) {
      yd.push_back(eq.yd[k]);
      y0_out.push_back(lin.y0[k]);
      yd0_out.push_back(lin.yd0[k]);
    }
  std::vector<Kernel> kernels;
  if (lin.descriptor) {
    kernels.push_back(descriptor_kernel(eq, lin, y, yd, p));
    if (lin.reduced.exists) kernels.push_back(reduced_kernel(eq, lin, y, yd, p));
    if (!lin.reduced.named.empty()) {
      std::vector<ex> parts;
      for (const ExMatrix& C : lin.reduced.named)
        for (const ex& x : column_major(C, C.size(), C.size())) parts.push_back(x);
      kernels.push_back({"reduced_parts",
                         "the model's named parts of the reduced form at the operating point (reduced_part_names), "
                         "each n×n column-major, one after the other",
                         {{"y0", y}, {"p", p}}, {{"C", parts, ""}}});
    }
  } else {
    second_order_kernels(eq, lin, y, yd, p, dynamics, kernels);
  }
  kernels.push_back({"operating_point",
                     "operating point y0 (or the initial guess of an equilibrium) and steady rates yd0",
                     {{"p", p}},
                     {{"y0", y0_out, ""}, {"yd0", yd0_out, ""}}});
  // Outputs that depend on accelerations and inputs (reactions.hpp): `outputs` gives them at
  // ydd = 0 and u = 0 (static loads), `outputs_general` at any (y, yd, ydd, u), and `output_terms`
  // the linear rows C_a and D of the frequency response.
  std::vector<ex> z = eq.outputs, ydd;
  if (!eq.ydd.empty()) {
    GiNaC::exmap rest;
    for (const auto& s : eq.u) rest[s] = 0;
    for (const auto& s : eq.ydd) rest[s] = 0;
    Program::Substitution at_rest(rest);
    for (auto& x : z) x = eq.program.substitute(x, at_rest);
    for (std::size_t k = 0; k < eq.ydd.size(); ++k)
      if (!loops || std::binary_search(eq.loops.independent.begin(), eq.loops.independent.end(), k))
        ydd.push_back(eq.ydd[k]);
  }
  kernels.push_back({"outputs", eq.ydd.empty() ? "outputs z(y, yd): length r" : "outputs z(y, yd) (at ydd = 0, u = 0): length r",
                     {{"y", y}, {"yd", yd}, {"p", p}}, {{"z", z, ""}}});
  if (!eq.ydd.empty())
    kernels.push_back({"outputs_general", "outputs z(y, yd, ydd, u): length r (reaction forces need ydd and u)",
                       {{"y", y}, {"yd", yd}, {"ydd", ydd}, {"u", u}, {"p", p}},
                       {{"z", eq.outputs, ""}}});
  if (!lin.Ca.empty())
    kernels.push_back({"output_terms", "output rows C_a (r×f) and D (r×m) of z = C_y y + C_v yd + C_a ydd + D u, column-major",
                       {{"y0", y}, {"yd0", lin.at_rest ? std::vector<ex>{} : yd}, {"p", p}},
                       {{"Ca", column_major(lin.Ca, r, f), ""}, {"D", column_major(lin.Du, r, m), ""}}});
  if (!lin.Ca.empty())
    mark_zeros_at_operating_point(kernels.back(), {&lin.zeros.Ca, &lin.zeros.Du}, eq, lin);
  if (!lin.B1.empty()) {
    kernels.push_back({"excitation", "prescribed motion: B1, B2 (f×m) of h = B u + B1 u̇ + B2 ü and D1 (r×m) of z += D1 u̇, column-major",
                       {{"y0", y}, {"yd0", lin.at_rest ? std::vector<ex>{} : yd}, {"p", p}},
                       {{"B1", column_major(lin.B1, f, m), ""}, {"B2", column_major(lin.B2, f, m), ""},
                        {"D1", column_major(lin.D1, r, m), ""}}});
    mark_zeros_at_operating_point(kernels.back(), {&lin.zeros.B1, &lin.zeros.B2, &lin.zeros.D1}, eq, lin);
  }
  sensitivity_kernels(model, eq, lin, y, yd, p, kernels);
  kernels.push_back(bodies_kernel(eq, nb, y, p, f));
  if (std::vector<ex> v = physical_values(model); !v.empty())
    kernels.push_back({"physical",
                       "the values of the model's physical conditions on the parameters (check_kinds, "
                       "check_labels): a body's mass and Ixx, Iyy, Izz, Ixy, Ixz, Iyz, or one length",
                       {{"p", p}}, {{"v", v, ""}}});

  if (loops)
    for (auto& k : kernels) {
      k.wrapped = k.name != "operating_point" && k.name != "physical";  // functions of p alone
      k.full_public = k.name == "dynamics" || k.name == "outputs" || k.name == "outputs_general";
    }
  return kernels;
}

// The kernels' parts (emit_chunks.hpp): in the main file when parts is 0, otherwise spread
// over `parts` files, the next part to the file with the fewest operations so far, so that the
// files take about the same time to compile in parallel.
void distribute_chunks(GeneratedCode& out, const std::vector<std::pair<std::string, std::size_t>>& chunks,
                       std::size_t parts, const std::string& banner, std::ostringstream& main_file) {
  const std::string open = "namespace " + out.id + "_kernel_parts {\n\n", close = "}  // namespace " + out.id + "_kernel_parts\n";
  if (parts == 0) {
    if (chunks.empty()) return;
    main_file << open;
    for (const auto& [code, ops] : chunks) main_file << code << "\n";
    main_file << close;
    return;
  }
  std::vector<std::string> files(parts);
  std::vector<std::size_t> load(parts, 0);
  for (const auto& [code, ops] : chunks) {
    const std::size_t k = static_cast<std::size_t>(std::min_element(load.begin(), load.end()) - load.begin());
    files[k] += code + "\n";
    load[k] += ops;
  }
  out.parts.clear();
  for (std::size_t k = 0; k < parts; ++k) {
    std::ostringstream f;
    f << banner << "// Part " << k + 1 << " of " << parts << " of the kernels of " << out.id << ".cpp: " << load[k]
      << " operations.\n";
    if (files[k].empty()) {
      f << "// Nothing here: the kernels are short enough to stay in " << out.id << ".cpp.\n";
    } else {
      f << "#include <cmath>\n\n" << open << files[k] << close;
    }
    out.parts.push_back(f.str());
  }
}

namespace {

// The scene's selection, with every effect of the model for the full model.
SceneSelection emitted_scene(const Model& model) {
  SceneSelection scene = model.selection();
  if (scene.full && scene.effects.empty()) scene.effects = effects_of(model);
  return scene;
}

// The kernels of a time step (dynamics, dynamics_jacobian): asked for (EmitOptions::dynamics) of
// the full model, or by a scene's `simulate`.
bool wants_dynamics(const SceneSelection& scene, const EmitOptions& options) {
  return (options.dynamics && scene.full) || scene.asks(Analysis::simulate);
}

void check_dynamics(const SceneSelection& scene, const EmitOptions& options, const LinearEquations& lin) {
  const bool simulate = scene.asks(Analysis::simulate);
  if (lin.descriptor && (options.dynamics || simulate))
    throw std::invalid_argument(
        std::string(simulate ? "scene '" + scene.name + "' asks for simulate, whose" : "the") +
        " dynamics kernel (--dynamics) needs the second-order form M(y) ydd + k - q = 0, which a model with "
        "nonholonomic constraints does not have (its kernels are the descriptor form's)");
  if (options.dynamics && !scene.full && !simulate)
    throw std::invalid_argument("the dynamics kernel (--dynamics) is for the full model or a scene that asks for "
                                "simulate: scene '" + scene.name +
                                "' does not (add simulate to its analyses; a scene without it prunes, at rest, the "
                                "velocity terms a time step needs)");
}

// The kernels' C identifier prefix (EmitOptions::id).
std::string emitted_id(const Model& model, const EmitOptions& options) {
  const SceneSelection& scene = model.selection();
  if (!options.id.empty() && !id_problem(options.id).empty())
    throw std::invalid_argument("mbsgen::emit: the id '" + options.id + "' " + id_problem(options.id));
  // A model name that C++ cannot use as a name (int, std) gets a final '_'.
  std::string id = identifier(!options.id.empty() ? options.id
                              : scene.full     ? model.name()
                                               : model.name() + "_" + scene.name);
  if (reserved_identifier(id)) id += "_";
  return id;
}

// The scene kernel each kernel comes with (SceneSelection::emits; dynamics: see wants_dynamics).
std::string scene_kernel(const std::string& name) {
  if (name == "outputs_general") return "outputs";
  if (name == "dynamics" || name == "dynamics_jacobian") return "dynamics";
  if (name == "operating_point_sensitivity") return "sensitivity";
  if (name == "output_terms" || name == "excitation" || name == "descriptor" || name == "reduced" || name == "reduced_parts") return "linear";
  return name;
}

// ---------------------------------------------------------------------------------------------
// Kernels emitted ahead (emit_ahead), in a child process: their code comes back as a string.

void put(std::string& s, std::uint64_t n) { s.append(reinterpret_cast<const char*>(&n), sizeof n); }
void put(std::string& s, const std::string& text) {
  put(s, text.size());
  s += text;
}

void put(std::string& s, const EmittedKernel& k) {
  put(s, k.code);
  put(s, k.info.name);
  put(s, k.info.signature);
  put(s, k.info.operations);
  put(s, k.info.bytes);
  put(s, k.chunks.definitions.size());
  for (const auto& d : k.chunks.definitions) put(s, d);
  for (std::size_t n : k.chunks.operations) put(s, n);
  put(s, k.chunks.declarations);
  put(s, k.chunks.calls);
  put(s, k.chunks.workspace);
  put(s, k.tape);
}

// Reads what put() wrote; ok turns false (and stays) at the first read past the end.
struct Reader {
  const std::string& s;
  std::size_t at = 0;
  bool ok = true;

  std::uint64_t number() {
    std::uint64_t n = 0;
    if (!ok || s.size() - at < sizeof n) return ok = false, 0;
    std::memcpy(&n, s.data() + at, sizeof n);
    at += sizeof n;
    return n;
  }
  std::string text() {
    const std::size_t n = number();
    if (!ok || s.size() - at < n) return ok = false, std::string();
    std::string t = s.substr(at, n);
    at += n;
    return t;
  }
  EmittedKernel kernel() {
    EmittedKernel k;
    k.code = text();
    k.info.name = text();
    k.info.signature = text();
    k.info.operations = number();
    k.info.bytes = number();
    const std::size_t chunks = number();
    for (std::size_t c = 0; ok && c < chunks; ++c) k.chunks.definitions.push_back(text());
    for (std::size_t c = 0; ok && c < chunks; ++c) k.chunks.operations.push_back(number());
    k.chunks.declarations = text();
    k.chunks.calls = text();
    k.chunks.workspace = number();
    k.tape = text();
    return k;
  }
};

std::uint64_t mix(std::uint64_t h, std::uint64_t v) {
  h ^= v + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
  return h * 0xbf58476d1ce4e5b9ULL;
}

// A hash of a kernel: its name, arguments (with their symbols' names, which the printed code's
// order follows) and outputs, and the definitions they need, with GiNaC's hashes of the
// expressions (of a symbol: its serial number; of a number: its value). A child that derived from
// the caller's state (emit_ahead) made the same symbols with the same serial numbers: a kernel
// emitted there is taken only when the caller's has the same fingerprint.
std::uint64_t fingerprint(const Kernel& k, const Program& prog) {
  const std::hash<std::string> text;
  std::uint64_t h = mix(text(k.name), text(k.doc));
  h = mix(mix(h, k.wrapped), mix(k.internal, text(k.computed_by)));
  h = mix(h, k.full_public);
  h = mix(h, k.computed_by_operations);
  for (const auto& a : k.inputs) {
    h = mix(h, text(a.name));
    for (const ex& s : a.symbols)
      h = mix(mix(h, s.gethash()), isa<GiNaC::symbol>(s) ? text(ex_to<GiNaC::symbol>(s).get_name()) : 0);
  }
  for (const std::string& a : k.at_op.arguments) h = mix(h, text(a));
  for (const auto& b : k.outputs) {
    h = mix(mix(h, text(b.name)), b.zero_at_op.size());
    for (const ex& v : b.values) h = mix(h, v.gethash());
    for (char z : b.zero_at_op) h = mix(h, static_cast<std::uint64_t>(z));
  }
  for (const ex& v : k.at_op.values) h = mix(h, v.gethash());
  const std::vector<char> needed = needed_definitions(k, prog);
  for (std::size_t i = 0; i < needed.size(); ++i)
    if (needed[i]) h = mix(mix(h, i), mix(prog.definitions()[i].symbol.gethash(), prog.definitions()[i].value.gethash()));
  return h;
}

// The kernels emit_ahead emits: those of the scene that need only the derivation; none for a
// model with closed loops (its kernels are wrapped) or rolling constraints (whose kernels are the
// linearization's descriptor form).
std::vector<Kernel> derivation_only_kernels(const Model& model, const Equations& eq, const EmitOptions& options) {
  if (eq.loops.active || eq.nonholonomic.active) return {};
  const SceneSelection scene = emitted_scene(model);
  const std::vector<ex> y(eq.y.begin(), eq.y.end()), yd(eq.yd.begin(), eq.yd.end()), p(eq.p.begin(), eq.p.end());
  std::vector<Kernel> all, kernels;
  derivation_kernels(eq, y, yd, p, eq.y.size(), wants_dynamics(scene, options), all);
  if (!options.solver_only) all.push_back(bodies_kernel(eq, model.bodies().size(), y, p, eq.y.size()));
  for (Kernel& k : all)
    if (scene.emits(scene_kernel(k.name))) kernels.push_back(std::move(k));
  return kernels;
}

}  // namespace

struct KernelsAhead::State {
  std::string id;
  EmitOptions options;
  std::unique_ptr<detail::ChildTask> task;
  std::vector<std::pair<std::uint64_t, EmittedKernel>> emitted;  // with their fingerprints
  std::size_t taken = 0;
};

KernelsAhead::KernelsAhead() = default;
KernelsAhead::KernelsAhead(KernelsAhead&&) noexcept = default;
KernelsAhead& KernelsAhead::operator=(KernelsAhead&&) noexcept = default;
KernelsAhead::~KernelsAhead() = default;
std::size_t KernelsAhead::taken() const { return state_ ? state_->taken : 0; }

KernelsAhead emit_ahead(const Model& model, const EmitOptions& options) {
  KernelsAhead ahead;
  if ((!options.id.empty() && !id_problem(options.id).empty()) ||
      (!options.scene.empty() && options.scene != model.selection().name))
    return ahead;  // emit() reports these
  // On one processor the child only takes turns with the caller.
  cpu_set_t cpus;
  CPU_ZERO(&cpus);
  if (::sched_getaffinity(0, sizeof cpus, &cpus) != 0 || CPU_COUNT(&cpus) < 2) return ahead;
  const SceneSelection scene = emitted_scene(model);
  if (!scene.emits("mass_matrix") && !scene.emits("residual") && !scene.emits("bodies")) return ahead;
  auto state = std::make_unique<KernelsAhead::State>();
  state->id = emitted_id(model, options);
  state->options = options;
  const KernelsAhead::State& st = *state;
  // The child derives the model itself: forked before the caller's derivation, it shares almost
  // no memory with it. Forked after, each process's first write to a shared page (GiNaC's
  // reference counts are in every node) copied the page, and the caller's linearization took a
  // third longer while the child ran (40-link chain: 3.0 → 4.1 s).
  state->task = detail::ChildTask::start([&model, &st] {
    // Never destroyed: the child ends with _exit, and freeing a large derivation takes time.
    Equations& eq = *new Equations(derive(model));
    const std::vector<Kernel> kernels = derivation_only_kernels(model, eq, st.options);
    std::string out;
    put(out, kernels.size());
    for (const Kernel& k : kernels) {
      put(out, fingerprint(k, eq.program));
      put(out, emit_kernel(st.id, k, eq.program, st.options.cse, st.options.chunk_operations));
    }
    return out;
  });
  if (state->task) ahead.state_ = std::move(state);
  return ahead;
}

namespace {

// Kernel k as emitted ahead, when it was, with the same options and fingerprint.
std::optional<EmittedKernel> emitted_ahead(KernelsAhead::State* ahead, const Kernel& k, const Program& prog,
                                           const std::string& id, const EmitOptions& options) {
  if (!ahead || ahead->id != id || ahead->options.cse != options.cse ||
      ahead->options.chunk_operations != options.chunk_operations)
    return std::nullopt;
  if (ahead->task) {  // the first kernel asked for: the child's result
    const std::optional<std::string> result = ahead->task->result();
    ahead->task.reset();
    if (result) {
      Reader r{*result};
      std::vector<std::pair<std::uint64_t, EmittedKernel>> emitted;
      const std::size_t n = r.number();
      for (std::size_t i = 0; r.ok && i < n; ++i) {
        const std::uint64_t f = r.number();
        emitted.emplace_back(f, r.kernel());
      }
      if (r.ok && r.at == result->size()) ahead->emitted = std::move(emitted);
    }
  }
  for (auto& [f, e] : ahead->emitted)
    if (e.info.name == k.name && f == fingerprint(k, prog)) {
      ++ahead->taken;
      return std::move(e);  // (each kernel is asked for once)
    }
  return std::nullopt;
}

}  // namespace

GeneratedCode emit(const Model& model, Equations& eq, const LinearEquations& lin, const EmitOptions& options,
                   KernelsAhead* ahead) {
  GeneratedCode out;
  const SceneSelection scene = emitted_scene(model);
  if (!options.scene.empty() && options.scene != scene.name)
    throw std::invalid_argument("mbsgen::emit: the model was pruned for scene '" + scene.name +
                                "', not '" + options.scene + "' (apply_scene)");
  out.id = emitted_id(model, options);
  const bool loops = eq.loops.active;
  const std::size_t n = eq.y.size();
  check_dynamics(scene, options, lin);
  std::vector<Kernel> kernels = model_kernels(model, eq, lin, wants_dynamics(scene, options));
  std::ostringstream kernel_code;
  std::vector<std::pair<std::string, std::size_t>> chunks;  // definitions of kernel parts, operations
  if (loops) {
    kernel_code << "namespace {\n" << kLuSolve << "}  // namespace\n\n";
    for (Kernel& k : loop_kernels(eq, lin)) {
      EmittedKernel ek = emit_kernel(out.id, k, eq.program, options.cse, options.chunk_operations);
      kernel_code << ek.code;
      if (!k.internal) out.kernels.push_back(ek.info);
    }
    kernel_code << assemble_code(out.id, eq);
    out.kernels.push_back({"assemble_from", "int " + out.id + "_assemble_from(const double* yi, const double* p, double* y)", 0});
    out.kernels.push_back({"assemble", "int " + out.id + "_assemble(const double* yi, const double* p, double* y)", 0});
  }
  bool split_needed = false;
  for (const auto& k0 : kernels) {
    if (!scene.emits(scene_kernel(k0.name))) continue;
    if (options.solver_only && (k0.name == "bodies" || k0.name == "linear_structured")) continue;
    Kernel k = k0;
    if (k.computed_by == "linear") {
      if (!scene.emits("linear"))
        throw std::logic_error("mbsgen::emit: linear_structured needs the linear kernel, which the scene prunes");
      k.computed_by = structured_from_linear(out.id, k, lin, k.computed_by_operations);
      k.computed_by_operations += out.kernels.back().operations;  // linear's, emitted just before
      split_needed = true;
    }
    std::optional<EmittedKernel> early =
        emitted_ahead(ahead ? ahead->state_.get() : nullptr, k, eq.program, out.id, options);
    EmittedKernel ek = early ? std::move(*early) : emit_kernel(out.id, k, eq.program, options.cse, options.chunk_operations);
    if (!ek.chunks.definitions.empty()) {
      kernel_code << "namespace " << out.id << "_kernel_parts {\n" << ek.chunks.declarations << "}\n\n";
      for (std::size_t c = 0; c < ek.chunks.definitions.size(); ++c)
        chunks.push_back({ek.chunks.definitions[c], ek.chunks.operations[c]});
    }
    kernel_code << ek.code;
    if (!loops) out.tape += ek.tape;  // a model with closed loops has no tape (its kernels close them)
    KernelInfo full_info = ek.info;
    if (k.wrapped) {
      const std::string full = "_" + k.name + "_full(";
      ek.info.signature.replace(ek.info.signature.find(full), full.size(), "_" + k.name + "(");
      kernel_code << wrapper_code(out.id, k, ek.info.signature, n);
    }
    out.kernels.push_back(ek.info);
    if (k.full_public) {
      full_info.name += "_full";
      out.kernels.push_back(full_info);
    }
  }
  // A child whose result was not asked for (other options) is stopped and reaped now, before a
  // caller's own waitpid could take it.
  if (ahead && ahead->state_) ahead->state_->task.reset();

  const std::string banner =
      std::string("// Generated by mbsgen ") + kGeneratorVersion + " from model '" + cpp_comment_text(model.name()) +
      "' (scene '" + cpp_comment_text(scene.name) + "')" +
      (options.source_file.empty()
           ? ""
           : ", file " + cpp_comment_text(std::filesystem::path(options.source_file).filename().string())) +
      ".\n// Generated code: do not edit. Regenerate with `mbsgen generate`.\n";
  std::ostringstream ops;
  ops << "// Operation counts (+, -, *, /, calls):";
  for (const auto& k : out.kernels) ops << " " << k.name << " " << k.operations << ";";
  ops << "\n";

  out.header = header_text(model, eq, lin, scene, out, banner + ops.str());

  auto names_array = [&](const std::string& what, const std::vector<std::string>& names) {
    std::ostringstream s;
    s << "extern \"C\" const char* const " << out.id << "_" << what << "[] = {";
    for (const auto& name : names) s << cpp_string_literal(name) << ", ";
    s << "nullptr};\n";
    return s.str();
  };
  std::vector<std::string> cn, pn, in, on, tree;
  for (const auto& c : model.coordinates()) tree.push_back(c.name);
  for (std::size_t k = 0; k < n; ++k)
    if (!loops || std::binary_search(eq.loops.independent.begin(), eq.loops.independent.end(), k))
      cn.push_back(model.coordinates()[k].name);
  for (const auto& q : model.parameters()) pn.push_back(q.name);
  for (const auto& i : model.inputs()) in.push_back(i.name);
  for (const auto& o : model.outputs()) on.push_back(o.name);

  std::ostringstream c;
  c << banner << ops.str() << "#include \"" << out.id << ".hpp\"\n\n#include <cmath>\n#include <cstring>\n\n";
  c << "namespace {\n" << kAllFinite;
  // An argument equals the operating point's value when it is within 8 units in the last place:
  // the operating_point kernel and this one compute the value by different roundings (a speed
  // v/r as v*(1/r)), and the entries zero at the operating point are of that rounding size there.
  c << "// Whether a kernel argument is the operating point's value (to 8 units in the last place).\n"
       "inline bool at_operating_point(double argument, double value) {\n"
       "  return argument == value || std::fabs(argument - value) <= 8 * 2.220446049250313e-16 * std::fabs(value);\n}\n";
  if (split_needed) c << kSplitSymmetric;
  c << "}  // namespace\n\n";
  c << "extern \"C\" int " << out.id << "_abi_version(void) { return " << kAbiVersion << "; }\n";
  c << names_array("coordinate_names", cn) << names_array("parameter_names", pn)
    << names_array("input_names", in) << names_array("output_names", on);
  std::vector<std::string> kinds;
  for (const auto& i : model.inputs()) kinds.push_back(i.motion ? "motion" : "force");
  c << names_array("input_kinds", kinds);
  if (has_sensitivity_kernel(out))
    c << names_array("sensitivity_parameter_names", sensitivity_parameter_names(model));
  if (loops) c << names_array("tree_coordinate_names", tree);
  if (has_kernel(out, "physical")) {
    std::vector<std::string> kinds_of_checks, labels, units, parameters;
    for (const PhysicalCheck& check : model.physical_checks()) {
      kinds_of_checks.push_back(to_string(check.kind));
      labels.push_back(check.label);
      units.push_back(check.unit);
      std::string names;
      for (const auto& name : check.parameters) names += (names.empty() ? "" : ",") + name;
      parameters.push_back(names);
    }
    c << names_array("check_kinds", kinds_of_checks) << names_array("check_labels", labels)
      << names_array("check_units", units) << names_array("check_parameters", parameters);
  }
  if (lin.descriptor) {
    std::vector<std::string> sn;
    for (std::size_t k : lin.speeds) sn.push_back(model.coordinates()[k].name);
    c << names_array("speed_names", sn);
    std::vector<std::string> rn;
    for (std::size_t k : lin.reduced.coordinates) rn.push_back(model.coordinates()[k].name);
    c << names_array("reduced_coordinate_names", rn);
    std::vector<std::string> parts;
    for (const auto& part : model.reduced_coefficients()) parts.push_back(part.name);
    c << names_array("reduced_part_names", parts);
  }
  c << "extern \"C\" const double " << out.id << "_parameter_defaults[] = {";
  for (const auto& q : model.parameters()) c << format_double(q.value) << ", ";
  c << "0.0};\n\n";
  c << kernel_code.str();
  distribute_chunks(out, chunks, options.parts, banner, c);
  out.source = c.str();

  out.manifest = manifest_json(model, eq, lin, scene, out);
  return out;
}

void write_atomically(const std::filesystem::path& path, const std::string& content) {
  write_files({{path, content}});
}

std::vector<OutputFile> generated_files(const GeneratedCode& code, const std::string& dir) {
  const std::filesystem::path d(dir);
  std::vector<OutputFile> files = {{d / (code.id + ".hpp"), code.header},
                                    {d / (code.id + ".cpp"), code.source},
                                    {d / (code.id + ".json"), code.manifest}};
  for (std::size_t k = 0; k < code.parts.size(); ++k)
    files.push_back({d / (code.id + "_part" + std::to_string(k + 1) + ".cpp"), code.parts[k]});
  return files;
}

void write_generated(const GeneratedCode& code, const std::string& dir) {
  write_files(generated_files(code, dir));
}

}  // namespace mbsgen
