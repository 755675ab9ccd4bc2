// Reading and evaluating tapes (tape.hpp). The text format is in docs/generated-abi.md, "Tapes".
//
// A kernel becomes a list of register instructions over one array of doubles, laid out as
// [the inputs, copied in | locals: temporaries, operating point values and output values |
// scratch: a statement's partial results | constants]. Each statement is parsed by recursive
// descent with C++'s grammar for the subset the generator prints (+ - * / with their precedence
// and left associativity, unary minus, parentheses, std:: functions, numbers, a[i], names), so the
// instructions do the compiled kernel's operations in its order.
#include "mbsgen/runtime/model/tape.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <unordered_map>
#include <string_view>
#include <utility>

namespace mbsgen {

namespace {

enum Op : std::uint32_t {
  kMov, kNeg, kAdd, kSub, kMul, kDiv, kSqrt, kSin, kCos, kTan, kExp, kLog, kFabs, kAsin, kAcos, kAtan,
  kSinh, kCosh, kTanh, kAsinh, kAcosh, kAtanh, kAtan2, kPow
};

struct Instruction {
  std::uint32_t op, dst, a, b;
};

// The kernels ModelKernels has a field for, with their number of arguments.
enum KernelId {
  kOperatingPoint, kLinear, kResidual, kMassMatrix, kOutputTerms, kOutputs, kDescriptor, kReduced, kReducedParts,
  kDynamics, kDynamicsJacobian, kOutputsGeneral, kExcitation, kSensitivity, kOperatingPointSensitivity, kPhysical,
  kKernelCount
};
constexpr std::array<const char*, kKernelCount> kKernelNames = {
    "operating_point", "linear",          "residual",   "mass_matrix",     "output_terms",
    "outputs",         "descriptor",      "reduced",    "reduced_parts",   "dynamics",
    "dynamics_jacobian", "outputs_general", "excitation", "sensitivity", "operating_point_sensitivity",
    "physical"};
constexpr std::array<std::size_t, kKernelCount> kArity = {3, 9, 5, 3, 5, 4, 7, 7, 3, 6, 7, 6, 6, 16, 5, 2};

// Tags of operands whose slot is known only when the kernel is complete.
constexpr std::uint32_t kScratchTag = 1u << 30, kConstantTag = 1u << 31, kIndexMask = kScratchTag - 1;

}  // namespace

struct TapeKernel {
  TapeKernelInfo info;
  std::vector<std::size_t> input_offset;
  std::vector<char> fill;  // per output: zeroed first
  std::vector<Instruction> code;
  std::vector<std::array<std::uint32_t, 3>> copies;   // output, index, slot
  std::vector<std::pair<std::uint32_t, std::uint32_t>> at_op;  // argument slot, operating point slot
  std::vector<std::pair<std::uint32_t, std::uint32_t>> zeros;  // output, index
  std::vector<double> initial;  // the workspace: zeros, and the constants at the end
  mutable std::mutex mutex;
  mutable std::vector<std::unique_ptr<double[]>> spare;

  int run(void* const* argv) const;
  /// Forward mode (issue 40 §2): the derivatives of the outputs along s directions. inputs: the
  /// inputs' values; seeds[i]: the directions of input i, s blocks of its length one after the
  /// other (null: zero); tangents[o]: the same for output o (null: not wanted). Exact zeros at
  /// the operating point have zero derivatives (they are zero there for every parameter value).
  /// Returns 1 when a value or derivative is not finite.
  int derivatives(const double* const* inputs, const double* const* seeds, std::size_t s,
                  double* const* tangents) const;

 private:
  std::unique_ptr<double[]> workspace() const;
  void give_back(std::unique_ptr<double[]> w) const;
  bool at_operating_point(const double* v) const;
};

// One instruction's value, op(a, b) (b unused by unary ops): the kernel's C++ operation.
inline double apply(std::uint32_t op, double a, double b) {
  switch (op) {
    case kMov: return a;
    case kNeg: return -a;
    case kAdd: return a + b;
    case kSub: return a - b;
    case kMul: return a * b;
    case kDiv: return a / b;
    case kSqrt: return std::sqrt(a);
    case kSin: return std::sin(a);
    case kCos: return std::cos(a);
    case kTan: return std::tan(a);
    case kExp: return std::exp(a);
    case kLog: return std::log(a);
    case kFabs: return std::fabs(a);
    case kAsin: return std::asin(a);
    case kAcos: return std::acos(a);
    case kAtan: return std::atan(a);
    case kSinh: return std::sinh(a);
    case kCosh: return std::cosh(a);
    case kTanh: return std::tanh(a);
    case kAsinh: return std::asinh(a);
    case kAcosh: return std::acosh(a);
    case kAtanh: return std::atanh(a);
    case kAtan2: return std::atan2(a, b);
    case kPow: return std::pow(a, b);
  }
  return 0;
}

// One instruction's value and derivatives, d ← op(a, b): the value from va, vb, the derivatives
// along s directions from ta, tb (tb unused by unary ops; td may alias ta or tb, element by
// element).
inline double tangent_step(std::uint32_t op, double va, double vb, const double* ta, const double* tb, double* td,
                           std::size_t s) {
  const double vd = apply(op, va, vb);
  double da = 0, db = 0;  // td = da ta + db tb
  switch (op) {
    case kMov: da = 1; break;
    case kNeg: da = -1; break;
    case kAdd: da = 1, db = 1; break;
    case kSub: da = 1, db = -1; break;
    case kMul: da = vb, db = va; break;
    case kDiv: da = 1 / vb, db = -vd / vb; break;
    case kSqrt: da = 0.5 / vd; break;
    case kSin: da = std::cos(va); break;
    case kCos: da = -std::sin(va); break;
    case kTan: da = 1 + vd * vd; break;
    case kExp: da = vd; break;
    case kLog: da = 1 / va; break;
    case kFabs: da = va > 0 ? 1 : va < 0 ? -1 : 0; break;
    case kAsin: da = 1 / std::sqrt(1 - va * va); break;
    case kAcos: da = -1 / std::sqrt(1 - va * va); break;
    case kAtan: da = 1 / (1 + va * va); break;
    case kSinh: da = std::cosh(va); break;
    case kCosh: da = std::sinh(va); break;
    case kTanh: da = 1 - vd * vd; break;
    case kAsinh: da = 1 / std::sqrt(va * va + 1); break;
    case kAcosh: da = 1 / std::sqrt(va * va - 1); break;
    case kAtanh: da = 1 / (1 - va * va); break;
    case kAtan2: {
      const double r2 = va * va + vb * vb;
      da = vb / r2, db = -va / r2;
      break;
    }
    case kPow:
      da = vb * std::pow(va, vb - 1);
      db = va > 0 ? vd * std::log(va) : 0;  // (the generator's exponents are numbers: tb is 0)
      break;
  }
  if (db == 0) {
    for (std::size_t k = 0; k < s; ++k) td[k] = da * ta[k];
  } else {
    for (std::size_t k = 0; k < s; ++k) td[k] = da * ta[k] + db * tb[k];
  }
  return vd;
}

std::unique_ptr<double[]> TapeKernel::workspace() const {
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (!spare.empty()) {
      std::unique_ptr<double[]> w = std::move(spare.back());
      spare.pop_back();
      return w;
    }
  }
  std::unique_ptr<double[]> w(new double[initial.size()]);
  std::copy(initial.begin(), initial.end(), w.get());
  return w;
}

void TapeKernel::give_back(std::unique_ptr<double[]> w) const {
  std::lock_guard<std::mutex> lock(mutex);
  spare.push_back(std::move(w));
}

// The compiled kernel's test (emit.cpp): every argument within 8 units in the last place of the
// operating point's value.
bool TapeKernel::at_operating_point(const double* v) const {
  bool at = !at_op.empty();
  for (const auto& [a, op] : at_op) {
    const double x = v[a], value = v[op];
    at = at && (x == value || std::fabs(x - value) <= 8 * 2.220446049250313e-16 * std::fabs(value));
  }
  return at;
}

int TapeKernel::run(void* const* argv) const {
  std::unique_ptr<double[]> w = workspace();
  double* const v = w.get();
  for (std::size_t i = 0; i < info.inputs.size(); ++i)
    if (info.inputs[i].second)
      std::memcpy(v + input_offset[i], argv[i], sizeof(double) * info.inputs[i].second);
  for (const Instruction& c : code) v[c.dst] = apply(c.op, v[c.a], v[c.b]);
  const std::size_t ni = info.inputs.size();
  for (std::size_t o = 0; o < info.outputs.size(); ++o)
    if (fill[o] && info.outputs[o].second)
      std::memset(argv[ni + o], 0, sizeof(double) * info.outputs[o].second);
  for (const auto& [o, i, slot] : copies) static_cast<double*>(argv[ni + o])[i] = v[slot];
  if (at_operating_point(v))
    for (const auto& [o, i] : zeros) static_cast<double*>(argv[ni + o])[i] = 0.0;
  int status = 0;
  for (std::size_t o = 0; o < info.outputs.size(); ++o) {
    const double* b = static_cast<const double*>(argv[ni + o]);
    for (std::size_t i = 0; i < info.outputs[o].second; ++i)
      if (!std::isfinite(b[i])) status = 1;
  }
  give_back(std::move(w));
  return status;
}

int TapeKernel::derivatives(const double* const* inputs, const double* const* seeds, std::size_t s,
                            double* const* tangents) const {
  constexpr std::size_t kBatch = 8;  // directions per pass: the derivatives of every slot fit in cache
  const std::size_t n = initial.size();
  std::vector<double> v(initial), t(n * kBatch);
  int status = 0;
  for (std::size_t k0 = 0; k0 < s; k0 += kBatch) {
    const std::size_t b = std::min(kBatch, s - k0);
    std::fill(t.begin(), t.end(), 0.0);
    for (std::size_t i = 0; i < info.inputs.size(); ++i)
      for (std::size_t e = 0; e < info.inputs[i].second; ++e) {
        v[input_offset[i] + e] = inputs[i][e];
        if (seeds[i])
          for (std::size_t k = 0; k < b; ++k)
            t[(input_offset[i] + e) * kBatch + k] = seeds[i][(k0 + k) * info.inputs[i].second + e];
      }
    for (const Instruction& c : code)
      v[c.dst] = tangent_step(c.op, v[c.a], v[c.b], &t[c.a * kBatch], &t[c.b * kBatch], &t[c.dst * kBatch], b);
    const bool at = at_operating_point(v.data());
    for (std::size_t o = 0; o < info.outputs.size(); ++o) {
      double* const out = tangents[o];
      const std::size_t len = info.outputs[o].second;
      if (!out) continue;
      for (std::size_t k = 0; k < b; ++k) std::fill(out + (k0 + k) * len, out + (k0 + k + 1) * len, 0.0);
      for (const auto& [oo, i, slot] : copies)
        if (oo == o)
          for (std::size_t k = 0; k < b; ++k) out[(k0 + k) * len + i] = t[slot * kBatch + k];
      if (at)
        for (const auto& [oo, i] : zeros)
          if (oo == o)
            for (std::size_t k = 0; k < b; ++k) out[(k0 + k) * len + i] = 0.0;
      for (std::size_t e = k0 * len; e < (k0 + b) * len; ++e)
        if (!std::isfinite(out[e])) status = 1;
    }
  }
  return status;
}

struct TapeModel::Impl {
  std::string id, model, scene, generator;
  int abi = 0;
  bool at_rest = false, equilibrium = false, linear_spacing = false;
  double from_hz = 0, to_hz = 0;
  int points = 0;
  std::vector<std::string> coordinates, coordinate_units, parameters, parameter_units, inputs, input_units,
      input_kinds, outputs, output_units, speeds, reduced, reduced_parts, sensitivity, check_kinds, check_labels,
      check_units, check_parameters;
  std::vector<double> defaults;
  std::vector<std::unique_ptr<TapeKernel>> kernels;
  std::array<const TapeKernel*, kKernelCount> known{};
  std::vector<TapeKernelInfo> info;
  // The C strings ModelKernels points to (each list ends with nullptr).
  std::vector<std::vector<const char*>> arrays;
  ModelKernels k{};
  int slot = -1;
  /// The sensitivity kernels by forward mode over linear, output_terms, excitation, operating_point
  /// and residual, by every parameter (a tape without the symbolic ones; issue 40 §2).
  bool forward_sensitivity = false;
  // argv as the kernels' (after count and which in the *_along forms); `directions` the
  // parameters' seeds, s × (number of directions), column-major.
  int sensitivity_by_forward_mode(void* const* argv, const std::vector<double>& directions) const;
  int operating_point_sensitivity_by_forward_mode(void* const* argv, const std::vector<double>& directions) const;
  std::vector<double> directions(int count, const int* which) const;
};

// The directions e_j of the parameters, column-major s × count: every parameter (which null, the
// identity) or the chosen ones.
std::vector<double> TapeModel::Impl::directions(int count, const int* which) const {
  const std::size_t s = parameters.size(), c = which ? static_cast<std::size_t>(count) : s;
  std::vector<double> e(s * c, 0.0);
  for (std::size_t j = 0; j < c; ++j) {
    const std::size_t i = which ? static_cast<std::size_t>(which[j]) : j;
    if (i < s) e[j * s + i] = 1;
  }
  return e;
}

// sensitivity(y0, yd0, p, dy0, dyd0, dM, dQ, dK, dB, dCy, dCv, dCa, dD, dB1, dB2, dD1): the total
// derivatives by each parameter p_j of the linear matrices, along (dy0_j, dyd0_j, e_j).
int TapeModel::Impl::sensitivity_by_forward_mode(void* const* argv, const std::vector<double>& directions) const {
  const std::size_t s = parameters.empty() ? 0 : directions.size() / parameters.size();
  auto in = [&](std::size_t i) { return static_cast<const double*>(argv[i]); };
  auto out = [&](std::size_t i) { return static_cast<double*>(argv[i]); };
  int status = 0;
  auto along = [&](const TapeKernel* kernel, std::vector<double*> derivatives) {
    const double* values[] = {in(0), in(1), in(2)};
    const double* seeds[] = {in(3), kernel->info.inputs[1].second ? in(4) : nullptr, directions.data()};
    status = std::max(status, kernel->derivatives(values, seeds, s, derivatives.data()));
  };
  along(known[kLinear], {out(5), out(6), out(7), out(8), out(9), out(10)});
  if (known[kOutputTerms]) along(known[kOutputTerms], {out(11), out(12)});
  if (known[kExcitation]) along(known[kExcitation], {out(13), out(14), out(15)});
  return status;
}

// operating_point_sensitivity(y0, yd0, p, dy0 | dr, dyd0): a given point's derivatives by the
// parameters; for a static equilibrium dr = ∂r/∂p + Q dyd0 (the caller solves K dy0 = −dr).
int TapeModel::Impl::operating_point_sensitivity_by_forward_mode(void* const* argv,
                                                                  const std::vector<double>& directions) const {
  const std::size_t s = parameters.empty() ? 0 : directions.size() / parameters.size();
  const double* p = static_cast<const double*>(argv[2]);
  double* first = static_cast<double*>(argv[3]);
  double* dyd0 = static_cast<double*>(argv[4]);
  const double* values[] = {p};
  const double* seeds[] = {directions.data()};
  double* tangents[] = {equilibrium ? nullptr : first, dyd0};
  int status = known[kOperatingPoint]->derivatives(values, seeds, s, tangents);
  if (!equilibrium) return status;
  const std::vector<double> u(inputs.size() + 1, 0.0);
  const double* r_values[] = {static_cast<const double*>(argv[0]), static_cast<const double*>(argv[1]), u.data(), p};
  const double* r_seeds[] = {nullptr, dyd0, nullptr, directions.data()};
  double* r_tangents[] = {first};
  return std::max(status, known[kResidual]->derivatives(r_values, r_seeds, s, r_tangents));
}

namespace {

std::atomic<const TapeModel::Impl*> g_slots[TapeModel::kMaxLoaded];
std::mutex g_slot_mutex;

template <int S, int K, class... A>
int call(A... a) {
  void* argv[] = {const_cast<void*>(static_cast<const void*>(a))...};
  return g_slots[S].load(std::memory_order_acquire)->known[K]->run(argv);
}

template <int S, int K, class... A>
int by_forward_mode(A... a) {
  void* argv[] = {const_cast<void*>(static_cast<const void*>(a))...};
  const TapeModel::Impl* t = g_slots[S].load(std::memory_order_acquire);
  const std::vector<double> e = t->directions(0, nullptr);
  return K == kSensitivity ? t->sensitivity_by_forward_mode(argv, e) : t->operating_point_sensitivity_by_forward_mode(argv, e);
}

template <int S, int K, class... A>
int along_forward_mode(int count, const int* which, A... a) {
  void* argv[] = {const_cast<void*>(static_cast<const void*>(a))...};
  const TapeModel::Impl* t = g_slots[S].load(std::memory_order_acquire);
  for (int j = 0; j < count; ++j)
    if (which[j] < 0 || static_cast<std::size_t>(which[j]) >= t->parameters.size()) return 1;  // no such parameter
  const std::vector<double> e = t->directions(count, which);
  return K == kSensitivity ? t->sensitivity_by_forward_mode(argv, e) : t->operating_point_sensitivity_by_forward_mode(argv, e);
}

template <int S>
void bind(ModelKernels& m, const TapeModel::Impl& t) {
  if (t.forward_sensitivity) {
    m.sensitivity = &by_forward_mode<S, kSensitivity>;
    m.operating_point_sensitivity = &by_forward_mode<S, kOperatingPointSensitivity>;
    m.sensitivity_along = &along_forward_mode<S, kSensitivity>;
    m.operating_point_sensitivity_along = &along_forward_mode<S, kOperatingPointSensitivity>;
  }
  const auto& k = t.known;
  if (k[kOperatingPoint]) m.operating_point = &call<S, kOperatingPoint>;
  if (k[kLinear]) m.linear = &call<S, kLinear>;
  if (k[kResidual]) m.residual = &call<S, kResidual>;
  if (k[kMassMatrix]) m.mass_matrix = &call<S, kMassMatrix>;
  if (k[kOutputTerms]) m.output_terms = &call<S, kOutputTerms>;
  if (k[kOutputs]) m.outputs = &call<S, kOutputs>;
  if (k[kDescriptor]) m.descriptor = &call<S, kDescriptor>;
  if (k[kReduced]) m.reduced = &call<S, kReduced>;
  if (k[kReducedParts]) m.reduced_parts = &call<S, kReducedParts>;
  if (k[kDynamics]) m.dynamics = &call<S, kDynamics>;
  if (k[kDynamicsJacobian]) m.dynamics_jacobian = &call<S, kDynamicsJacobian>;
  if (k[kOutputsGeneral]) m.outputs_general = &call<S, kOutputsGeneral>;
  if (k[kExcitation]) m.excitation = &call<S, kExcitation>;
  if (k[kSensitivity]) m.sensitivity = &call<S, kSensitivity>;
  if (k[kOperatingPointSensitivity]) m.operating_point_sensitivity = &call<S, kOperatingPointSensitivity>;
  if (k[kPhysical]) m.physical = &call<S, kPhysical>;
}

using Binder = void (*)(ModelKernels&, const TapeModel::Impl&);
template <std::size_t... S>
constexpr std::array<Binder, sizeof...(S)> binders(std::index_sequence<S...>) {
  return {&bind<static_cast<int>(S)>...};
}
constexpr auto kBinders = binders(std::make_index_sequence<TapeModel::kMaxLoaded>{});

// ---------------------------------------------------------------------------------------------
// The parser.

class Reader {
 public:
  Reader(const std::string& text, std::string origin) : text_(text), origin_(std::move(origin)) {}

  bool next_line() {
    if (at_ >= text_.size()) return false;
    std::size_t end = text_.find('\n', at_);
    if (end == std::string::npos) end = text_.size();
    line_ = std::string_view(text_).substr(at_, end - at_);
    at_ = end + 1;
    ++number_;
    pos_ = 0;
    return true;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw ParseError(origin_ + ":" + std::to_string(number_) + ": " + what);
  }
  std::string_view line() const { return line_; }
  const std::string& origin() const { return origin_; }
  bool done() const { return skip(), pos_ >= line_.size(); }
  void expect_end() const {
    if (!done()) fail("unexpected '" + std::string(line_.substr(pos_)) + "'");
  }
  // A word up to the next blank.
  std::string_view word() const {
    skip();
    const std::size_t from = pos_;
    while (pos_ < line_.size() && line_[pos_] != ' ') ++pos_;
    if (from == pos_) fail("a field is missing");
    return line_.substr(from, pos_ - from);
  }
  std::size_t count(std::size_t limit = std::size_t{1} << 28) const {
    const std::string_view w = word();
    std::size_t n = 0;
    const auto r = std::from_chars(w.data(), w.data() + w.size(), n);
    if (r.ec != std::errc() || r.ptr != w.data() + w.size() || n > limit) fail("'" + std::string(w) + "' is not a count");
    return n;
  }
  double number() const {
    const std::string_view w = word();
    double x = 0;
    const auto r = std::from_chars(w.data(), w.data() + w.size(), x);
    if (r.ec != std::errc() || r.ptr != w.data() + w.size() || !std::isfinite(x))
      fail("'" + std::string(w) + "' is not a finite number");
    return x;
  }
  std::string string() const;  // a JSON string literal

 private:
  void skip() const {
    while (pos_ < line_.size() && line_[pos_] == ' ') ++pos_;
  }
  const std::string& text_;
  std::string origin_;
  std::size_t at_ = 0, number_ = 0;
  std::string_view line_;
  mutable std::size_t pos_ = 0;
};

void put_utf8(std::string& s, unsigned c) {
  if (c < 0x80) {
    s += static_cast<char>(c);
  } else if (c < 0x800) {
    s += static_cast<char>(0xc0 | (c >> 6));
    s += static_cast<char>(0x80 | (c & 0x3f));
  } else {
    s += static_cast<char>(0xe0 | (c >> 12));
    s += static_cast<char>(0x80 | ((c >> 6) & 0x3f));
    s += static_cast<char>(0x80 | (c & 0x3f));
  }
}

std::string Reader::string() const {
  skip();
  if (pos_ >= line_.size() || line_[pos_] != '"') fail("a quoted string is missing");
  std::string s;
  for (++pos_; pos_ < line_.size(); ++pos_) {
    const char c = line_[pos_];
    if (c == '"') {
      ++pos_;
      return s;
    }
    if (c != '\\') {
      s += c;
      continue;
    }
    if (++pos_ >= line_.size()) break;
    switch (line_[pos_]) {
      case '"': s += '"'; break;
      case '\\': s += '\\'; break;
      case 'n': s += '\n'; break;
      case 't': s += '\t'; break;
      case 'r': s += '\r'; break;
      case 'u': {
        unsigned code = 0;
        if (pos_ + 4 >= line_.size() ||
            std::from_chars(line_.data() + pos_ + 1, line_.data() + pos_ + 5, code, 16).ptr != line_.data() + pos_ + 5)
          fail("a bad \\u escape");
        put_utf8(s, code);
        pos_ += 4;
        break;
      }
      default: fail("a bad escape in a string");
    }
  }
  fail("a string is not closed");
}

// Translates one kernel's statements into instructions.
class KernelCompiler {
 public:
  KernelCompiler(TapeKernel& k, const Reader& r) : k_(k), r_(r) {}

  void input(const std::string& name, std::size_t n) {
    k_.input_offset.push_back(inputs_);
    arguments_[name] = {static_cast<std::uint32_t>(inputs_), n};
    inputs_ += n;
    k_.info.inputs.push_back({name, n});
  }
  void output(const std::string& name, std::size_t n, bool fill) {
    outputs_[name] = k_.info.outputs.size();
    k_.info.outputs.push_back({name, n});
    k_.fill.push_back(fill);
  }

  // "TARGET = EXPR": TARGET a new local or OUT[i].
  void statement(std::string_view s) {
    const std::size_t eq = s.find(" = ");
    if (eq == std::string_view::npos) r_.fail("a statement without ' = '");
    const std::string_view target = s.substr(0, eq);
    text_ = s.substr(eq + 3);
    pos_ = 0;
    Operand value = expression();
    skip();
    if (pos_ != text_.size()) r_.fail("unexpected '" + std::string(text_.substr(pos_)) + "' in an expression");
    const std::uint32_t slot = local(std::string(target.find('[') == std::string_view::npos ? target : std::string_view()));
    if (value.scratch && !k_.code.empty() && k_.code.back().dst == value.slot) {
      k_.code.back().dst = slot;  // the last instruction writes the target itself
    } else {
      k_.code.push_back({kMov, slot, value.slot, 0});
    }
    top_ = 0;
    if (target.find('[') != std::string_view::npos) {
      const auto [o, i] = element_of_output(target);
      k_.copies.push_back({o, i, slot});
    }
  }
  void at_operating_point(std::string_view argument, std::string_view value) {
    text_ = argument;
    pos_ = 0;
    const Operand a = primary();
    const auto it = locals_.find(std::string(value));
    if (a.scratch || it == locals_.end() || pos_ != text_.size()) r_.fail("a bad operating point test");
    k_.at_op.push_back({a.slot, it->second});
  }
  void zero(std::string_view element) { k_.zeros.push_back(element_of_output(element)); }

  void finish() {
    const std::size_t locals = locals_count_, scratch_base = inputs_ + locals;
    const std::size_t constants_base = scratch_base + max_top_;
    auto place = [&](std::uint32_t& x) {
      if (x & kConstantTag) x = static_cast<std::uint32_t>(constants_base + (x & kIndexMask));
      else if (x & kScratchTag) x = static_cast<std::uint32_t>(scratch_base + (x & kIndexMask));
      // (an input or a local is placed already)
    };
    for (Instruction& c : k_.code) {
      place(c.dst);
      place(c.a);
      place(c.b);
    }
    for (auto& c : k_.copies) place(c[2]);
    for (auto& [a, v] : k_.at_op) place(v), place(a);
    k_.initial.assign(constants_base, 0.0);
    k_.initial.insert(k_.initial.end(), constants_.begin(), constants_.end());
    if (k_.initial.size() >= kScratchTag) r_.fail("the kernel is too large for a tape");
    k_.info.instructions = k_.code.size();
    k_.info.bytes = k_.code.size() * sizeof(Instruction) + k_.initial.size() * sizeof(double);
  }

 private:
  struct Operand {
    std::uint32_t slot;
    bool scratch;
  };

  std::uint32_t local(const std::string& name) {
    if (locals_count_ + inputs_ >= kScratchTag) r_.fail("the kernel is too large for a tape");
    const auto slot = static_cast<std::uint32_t>(inputs_ + locals_count_++);
    if (!name.empty() && !locals_.emplace(name, slot).second) r_.fail("'" + name + "' is defined twice");
    return slot;
  }
  std::pair<std::uint32_t, std::uint32_t> element_of_output(std::string_view e) const {
    const std::size_t open = e.find('[');
    const auto it = outputs_.find(std::string(e.substr(0, open)));
    std::size_t i = 0;
    if (open == std::string_view::npos || e.back() != ']' || it == outputs_.end() ||
        std::from_chars(e.data() + open + 1, e.data() + e.size() - 1, i).ptr != e.data() + e.size() - 1 ||
        i >= k_.info.outputs[it->second].second)
      r_.fail("'" + std::string(e) + "' is not an element of an output");
    return {static_cast<std::uint32_t>(it->second), static_cast<std::uint32_t>(i)};
  }

  void skip() {
    while (pos_ < text_.size() && text_[pos_] == ' ') ++pos_;
  }
  bool accept(char c) {
    skip();
    if (pos_ < text_.size() && text_[pos_] == c) return ++pos_, true;
    return false;
  }
  Operand result(std::uint32_t op, Operand a, Operand b = {0, false}) {
    if (b.scratch) --top_;
    if (a.scratch) --top_;
    const std::uint32_t dst = kScratchTag | top_++;
    if (top_ > max_top_) max_top_ = top_;
    k_.code.push_back({op, dst, a.slot, b.slot});
    return {dst, true};
  }
  Operand expression() {
    Operand a = term();
    for (;;) {
      if (accept('+')) a = result(kAdd, a, term());
      else if (accept('-')) a = result(kSub, a, term());
      else return a;
    }
  }
  Operand term() {
    Operand a = unary();
    for (;;) {
      if (accept('*')) a = result(kMul, a, unary());
      else if (accept('/')) a = result(kDiv, a, unary());
      else return a;
    }
  }
  Operand unary() {
    if (accept('-')) return result(kNeg, unary());
    return primary();
  }
  Operand primary();

  TapeKernel& k_;
  const Reader& r_;
  std::size_t inputs_ = 0, locals_count_ = 0;
  std::uint32_t top_ = 0, max_top_ = 0;
  std::unordered_map<std::string, std::pair<std::uint32_t, std::size_t>> arguments_;
  std::unordered_map<std::string, std::size_t> outputs_;
  std::unordered_map<std::string, std::uint32_t> locals_;
  std::map<std::uint64_t, std::uint32_t> constant_index_;
  std::vector<double> constants_;
  std::string_view text_;
  std::size_t pos_ = 0;
};

KernelCompiler::Operand KernelCompiler::primary() {
  if (accept('(')) {
    const Operand a = expression();
    if (!accept(')')) r_.fail("a ')' is missing in an expression");
    return a;
  }
  skip();
  const std::size_t from = pos_;
  if (pos_ < text_.size() && (std::isdigit(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '.')) {
    double x = 0;
    const auto r = std::from_chars(text_.data() + pos_, text_.data() + text_.size(), x);
    if (r.ec != std::errc() || !std::isfinite(x)) r_.fail("a bad number in an expression");
    pos_ = static_cast<std::size_t>(r.ptr - text_.data());
    std::uint64_t bits;
    std::memcpy(&bits, &x, sizeof x);
    auto [it, added] = constant_index_.emplace(bits, static_cast<std::uint32_t>(constants_.size()));
    if (added) constants_.push_back(x);
    return {kConstantTag | it->second, false};
  }
  while (pos_ < text_.size() && (std::isalnum(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '_' ||
                                 text_[pos_] == ':'))
    ++pos_;
  const std::string name(text_.substr(from, pos_ - from));
  if (name.empty()) r_.fail("an operand is missing in an expression");
  if (name.rfind("std::", 0) == 0) {
    static const std::map<std::string, Op> functions = {
        {"sqrt", kSqrt}, {"sin", kSin},   {"cos", kCos},   {"tan", kTan},     {"exp", kExp},     {"log", kLog},
        {"fabs", kFabs}, {"asin", kAsin}, {"acos", kAcos}, {"atan", kAtan},   {"sinh", kSinh},   {"cosh", kCosh},
        {"tanh", kTanh}, {"asinh", kAsinh}, {"acosh", kAcosh}, {"atanh", kAtanh}, {"atan2", kAtan2}, {"pow", kPow}};
    const auto f = functions.find(name.substr(5));
    if (f == functions.end() || !accept('(')) r_.fail("'" + name + "' is not a function a tape knows");
    const Operand a = expression();
    Operand b{0, false};
    if (f->second == kAtan2 || f->second == kPow) {
      if (!accept(',')) r_.fail("'" + name + "' needs two arguments");
      b = expression();
    }
    if (!accept(')')) r_.fail("a ')' is missing after the arguments of '" + name + "'");
    return result(f->second, a, b);
  }
  if (accept('[')) {
    skip();
    std::size_t i = 0;
    const auto r = std::from_chars(text_.data() + pos_, text_.data() + text_.size(), i);
    const auto it = arguments_.find(name);
    if (r.ec != std::errc() || it == arguments_.end() || i >= it->second.second)
      r_.fail("'" + name + "[…]' is not an element of an input");
    pos_ = static_cast<std::size_t>(r.ptr - text_.data());
    if (!accept(']')) r_.fail("a ']' is missing");
    return {static_cast<std::uint32_t>(it->second.first + i), false};
  }
  const auto it = locals_.find(name);
  if (it == locals_.end()) r_.fail("'" + name + "' is read before it is defined");
  return {it->second, false};
}


}  // namespace

TapeModel::TapeModel(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

TapeModel::~TapeModel() {
  if (impl_ && impl_->slot >= 0) {
    std::lock_guard<std::mutex> lock(g_slot_mutex);
    g_slots[impl_->slot].store(nullptr, std::memory_order_release);
  }
}

const ModelKernels& TapeModel::kernels() const { return impl_->k; }
const std::vector<TapeKernelInfo>& TapeModel::kernel_info() const { return impl_->info; }

std::unique_ptr<TapeModel> TapeModel::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read the tape " + path);
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw Error("cannot read the tape " + path);
  return parse(s.str(), path);
}

namespace {

// `list NAME COUNT` and its rows: the columns of fields (strings, or a number in column
// number_column).
void read_list(Reader& r, std::size_t rows, std::vector<std::vector<std::string>*> columns,
               std::vector<double>* numbers = nullptr) {
  for (auto* c : columns) c->clear();
  for (std::size_t i = 0; i < rows; ++i) {
    if (!r.next_line()) r.fail("the tape ends inside a list");
    for (auto* c : columns) c->push_back(r.string());
    if (numbers) numbers->push_back(r.number());
    r.expect_end();
  }
}

const char* const* c_strings(TapeModel::Impl& t, const std::vector<std::string>& v) {
  std::vector<const char*> a;
  for (const auto& s : v) a.push_back(s.c_str());
  a.push_back(nullptr);
  t.arrays.push_back(std::move(a));
  return t.arrays.back().data();
}

void read_header_field(Reader& r, TapeModel::Impl& t, const std::string& key);
void read_kernel(Reader& r, TapeModel::Impl& t);
void check_sizes(const Reader& r, const TapeModel::Impl& t);
void fill_kernels(TapeModel::Impl& t);

}  // namespace

std::unique_ptr<TapeModel> TapeModel::parse(const std::string& text, const std::string& origin) {
  auto t = std::make_unique<Impl>();
  Reader r(text, origin);
  if (!r.next_line() || r.line() != "mbsgen-tape 1") r.fail("not a tape of this runtime (the first line is not 'mbsgen-tape 1')");
  while (r.next_line()) {
    if (r.done()) continue;
    const std::string key(r.word());
    if (key == "kernel") read_kernel(r, *t);
    else read_header_field(r, *t, key);
  }
  if (t->abi != kKernelAbiVersion)
    r.fail("the tape's ABI version is " + std::to_string(t->abi) + ", this runtime's " + std::to_string(kKernelAbiVersion));
  check_sizes(r, *t);
  fill_kernels(*t);
  {
    std::lock_guard<std::mutex> lock(g_slot_mutex);
    for (int s = 0; s < kMaxLoaded && t->slot < 0; ++s)
      if (!g_slots[s].load(std::memory_order_acquire)) t->slot = s;
    if (t->slot < 0)
      throw Error("TapeModel: " + std::to_string(kMaxLoaded) + " tapes are loaded already (at most that many at once)");
    kBinders[static_cast<std::size_t>(t->slot)](t->k, *t);
    g_slots[t->slot].store(t.get(), std::memory_order_release);
  }
  return std::unique_ptr<TapeModel>(new TapeModel(std::move(t)));
}

namespace {

// One line of the header (a list: with its rows).
void read_header_field(Reader& r, TapeModel::Impl& t, const std::string& key) {
  if (key == "abi") {
    t.abi = static_cast<int>(r.count(1000));
  } else if (key == "generator") {
    t.generator = r.string();
  } else if (key == "id") {
    t.id = r.string();
  } else if (key == "model") {
    t.model = r.string();
  } else if (key == "scene") {
    t.scene = r.string();
  } else if (key == "operating-point") {
    t.at_rest = r.count(1) == 1;
    t.equilibrium = r.count(1) == 1;
  } else if (key == "frequencies") {
    t.from_hz = r.number();
    t.to_hz = r.number();
    t.points = static_cast<int>(r.count(100000000));
    t.linear_spacing = r.count(1) == 1;
  } else if (key == "list") {
    const std::string what(r.word());
    const std::size_t n = r.count(10000000);
    r.expect_end();
    if (what == "coordinates") read_list(r, n, {&t.coordinates, &t.coordinate_units});
    else if (what == "parameters") read_list(r, n, {&t.parameters, &t.parameter_units}, &t.defaults);
    else if (what == "inputs") read_list(r, n, {&t.inputs, &t.input_units, &t.input_kinds});
    else if (what == "outputs") read_list(r, n, {&t.outputs, &t.output_units});
    else if (what == "speeds") read_list(r, n, {&t.speeds});
    else if (what == "reduced-coordinates") read_list(r, n, {&t.reduced});
    else if (what == "reduced-parts") read_list(r, n, {&t.reduced_parts});
    else if (what == "sensitivity-parameters") read_list(r, n, {&t.sensitivity});
    else if (what == "checks") read_list(r, n, {&t.check_kinds, &t.check_labels, &t.check_units, &t.check_parameters});
    else r.fail("an unknown list '" + what + "'");
    return;
  } else {
    r.fail("'" + key + "' is not a field of a tape's header");
  }
  r.expect_end();
}

void read_kernel(Reader& r, TapeModel::Impl& t) {
  auto k = std::make_unique<TapeKernel>();
  k->info.name = std::string(r.word());
  k->info.operations = r.count();
  r.expect_end();
  KernelCompiler c(*k, r);
  for (;;) {
    if (!r.next_line()) r.fail("the tape ends inside kernel '" + k->info.name + "'");
    const std::string_view line = r.line();
    if (line == "end") break;
    if (line.rfind("= ", 0) == 0) {
      c.statement(line.substr(2));
      continue;
    }
    const std::string key(r.word());
    if (key == "in" || key == "out") {
      const std::string name(r.word());
      const std::size_t n = r.count();
      bool fill = false;
      if (key == "out" && !r.done()) fill = r.word() == "fill" || (r.fail("a bad output"), false);
      r.expect_end();
      if (key == "in") c.input(name, n);
      else c.output(name, n, fill);
    } else if (key == "at") {
      const std::string_view argument = r.word(), value = r.word();
      r.expect_end();
      c.at_operating_point(argument, value);
    } else if (key == "zero") {
      const std::string name(r.word());
      const std::size_t i = r.count();
      r.expect_end();
      c.zero(name + "[" + std::to_string(i) + "]");
    } else {
      r.fail("'" + key + "' is not a line of a kernel");
    }
  }
  c.finish();
  for (std::size_t id = 0; id < kKernelCount; ++id)
    if (k->info.name == kKernelNames[id]) {
      if (t.known[id]) r.fail("kernel '" + k->info.name + "' appears twice");
      if (k->info.inputs.size() + k->info.outputs.size() != kArity[id])
        r.fail("kernel '" + k->info.name + "' has " + std::to_string(k->info.inputs.size() + k->info.outputs.size()) +
               " arguments, not " + std::to_string(kArity[id]));
      t.known[id] = k.get();
    }
  t.info.push_back(k->info);
  t.kernels.push_back(std::move(k));
}


// The lengths the runtime gives each argument of a kernel, in the signature's order: a tape that
// disagrees (damaged, or not of this model) is refused rather than read or written out of bounds.
// Codes: f coordinates, m inputs, r outputs, p parameters, x descriptor states, q reduced
// coordinates, P named parts, s sensitivity parameters, v check values; "0|" also allows none.
void check_sizes(const Reader& r, const TapeModel::Impl& t) {
  static const std::map<std::string, std::vector<const char*>> sizes = {
      {"operating_point", {"p", "f", "f"}},
      {"linear", {"f", "0|f", "p", "ff", "ff", "ff", "fm", "rf", "rf"}},
      {"residual", {"f", "f", "m", "p", "f"}},
      {"mass_matrix", {"f", "p", "ff"}},
      {"output_terms", {"f", "0|f", "p", "rf", "rm"}},
      {"outputs", {"f", "f", "p", "r"}},
      {"descriptor", {"f", "0|f", "p", "xx", "xx", "xm", "rx"}},
      {"reduced", {"f", "0|f", "p", "qq", "qq", "qq", "0|qm"}},
      {"reduced_parts", {"f", "p", "Pqq"}},
      {"dynamics", {"f", "f", "m", "p", "ff", "f"}},
      {"dynamics_jacobian", {"f", "f", "f", "m", "p", "ff", "ff"}},
      {"outputs_general", {"f", "f", "f", "m", "p", "r"}},
      {"excitation", {"f", "0|f", "p", "fm", "fm", "rm"}},
      {"sensitivity", {"f", "0|f", "p", "0|fs", "0|fs", "0|ffs", "0|ffs", "0|ffs", "0|fms", "0|rfs", "0|rfs", "0|rfs",
                       "0|rms", "0|fms", "0|fms", "0|rms"}},
      {"operating_point_sensitivity", {"f", "0|f", "p", "fs", "0|fs"}},
      {"physical", {"p", "v"}}};
  std::size_t values = 0;
  for (const auto& kind : t.check_kinds) values += kind == "body" ? 7 : 1;
  auto dimension = [&](char c) -> std::size_t {
    switch (c) {
      case 'f': return t.coordinates.size();
      case 'm': return t.inputs.size();
      case 'r': return t.outputs.size();
      case 'p': return t.parameters.size();
      case 'x': return t.coordinates.size() + t.speeds.size();
      case 'q': return t.reduced.size();
      case 'P': return t.reduced_parts.size();
      case 's': return t.sensitivity.size();
      default: return values;
    }
  };
  if (t.parameter_units.size() != t.parameters.size() || t.defaults.size() != t.parameters.size())
    throw ParseError(r.origin() + ": the parameters' list is damaged");
  for (const auto& k : t.kernels) {
    const auto it = sizes.find(k->info.name);
    if (it == sizes.end()) continue;  // not one of ModelKernels': never called through it
    std::vector<std::pair<std::string, std::size_t>> arguments = k->info.inputs;
    arguments.insert(arguments.end(), k->info.outputs.begin(), k->info.outputs.end());
    for (std::size_t a = 0; a < arguments.size() && a < it->second.size(); ++a) {
      std::string code = it->second[a];
      const bool none = code.rfind("0|", 0) == 0;
      if (none) code = code.substr(2);
      std::size_t n = 1;
      for (char c : code) n *= dimension(c);
      if (arguments[a].second != n && !(none && arguments[a].second == 0))
        throw ParseError(r.origin() + ": kernel '" + k->info.name + "': '" + arguments[a].first + "' has " +
                         std::to_string(arguments[a].second) + " values where the model's sizes give " +
                         std::to_string(n) + " (a damaged tape, or one of another model)");
    }
  }
}

void fill_kernels(TapeModel::Impl& t) {
  ModelKernels& k = t.k;
  k.id = t.id.c_str();
  k.model = t.model.c_str();
  k.scene = t.scene.c_str();
  k.abi_version = t.abi;
  k.n_coordinates = static_cast<int>(t.coordinates.size());
  k.n_inputs = static_cast<int>(t.inputs.size());
  k.n_outputs = static_cast<int>(t.outputs.size());
  k.n_parameters = static_cast<int>(t.parameters.size());
  k.at_rest = t.at_rest;
  k.equilibrium = t.equilibrium;
  k.default_from_hz = t.from_hz;
  k.default_to_hz = t.to_hz;
  k.coordinate_names = c_strings(t, t.coordinates);
  k.coordinate_units = c_strings(t, t.coordinate_units);
  k.parameter_names = c_strings(t, t.parameters);
  k.parameter_units = c_strings(t, t.parameter_units);
  k.parameter_defaults = t.defaults.data();
  k.input_names = c_strings(t, t.inputs);
  k.input_units = c_strings(t, t.input_units);
  k.output_names = c_strings(t, t.outputs);
  k.output_units = c_strings(t, t.output_units);
  k.default_points = t.points;
  k.default_linear_spacing = t.linear_spacing;
  k.generator_version = t.generator.c_str();
  if (!t.speeds.empty() || t.known[kDescriptor]) {
    k.n_speeds = static_cast<int>(t.speeds.size());
    k.speed_names = c_strings(t, t.speeds);
    k.n_reduced = static_cast<int>(t.reduced.size());
    k.reduced_coordinate_names = c_strings(t, t.reduced);
    k.n_reduced_parts = static_cast<int>(t.reduced_parts.size());
    k.reduced_part_names = c_strings(t, t.reduced_parts);
  }
  if (std::find(t.input_kinds.begin(), t.input_kinds.end(), "motion") != t.input_kinds.end())
    k.input_kinds = c_strings(t, t.input_kinds);
  if (t.known[kSensitivity]) {
    k.n_sensitivity_parameters = static_cast<int>(t.sensitivity.size());
    k.sensitivity_parameter_names = c_strings(t, t.sensitivity);
  } else if (t.known[kLinear] && t.known[kOperatingPoint] && (!t.equilibrium || t.known[kResidual]) &&
             !t.known[kOperatingPointSensitivity]) {
    t.forward_sensitivity = true;  // by every parameter, from the tape (bind)
    k.n_sensitivity_parameters = static_cast<int>(t.parameters.size());
    k.sensitivity_parameter_names = c_strings(t, t.parameters);
  }
  if (t.known[kPhysical]) {
    k.n_checks = static_cast<int>(t.check_kinds.size());
    k.check_kinds = c_strings(t, t.check_kinds);
    k.check_labels = c_strings(t, t.check_labels);
    k.check_units = c_strings(t, t.check_units);
    k.check_parameters = c_strings(t, t.check_parameters);
  }
  k.evaluation = "tape";
}

}  // namespace

}  // namespace mbsgen
