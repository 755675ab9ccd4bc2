#include "mbsgen/generator/model/yaml_reader.hpp"

#include "mbsgen/generator/model/escape.hpp"
#include "mbsgen/generator/model/urdf_import.hpp"

#include "model/expression_sites.hpp"
#include "symbolic/checked_subs.hpp"

#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace mbsgen {

namespace detail {

std::size_t edit_distance(const std::string& a, const std::string& b) {
  // Optimal string alignment distance: Levenshtein plus transposition of adjacent characters.
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1, 0));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i)
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[n][m];
}

std::string suggestion(const std::string& word, const std::vector<std::string>& candidates) {
  const std::size_t limit = word.size() <= 3 ? 1 : word.size() <= 6 ? 2 : 3;
  std::size_t best = limit + 1;
  std::string best_name;
  for (const auto& c : candidates) {
    const std::size_t d = detail::edit_distance(word, c);
    if (d < best && d < word.size() && d < c.size()) {  // keep at least one letter in common
      best = d;
      best_name = c;
    }
  }
  return best_name.empty() ? std::string() : " (did you mean '" + best_name + "'?)";
}

}  // namespace detail

namespace {

using detail::suggestion;

std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out;
}

// ---------------------------------------------------------------------------------------------
// Expressions: a small lexer and recursive-descent checker that mirrors GiNaC's grammar and knows
// where each token is, so that errors point at a character; the checked text, with decimal
// literals rewritten as exact rationals, is then parsed by GiNaC::parser (strict).

using detail::ExpressionError;

// What an expression may depend on.
// `kinematics`: a body's translation and rotation (positions and motion inputs);
// `world_marker`: a marker on the world (parameters and motion inputs).
enum class Scope { constants, parameters, world_marker, positions, kinematics, no_inputs, any };

enum class SymbolKind { parameter, coordinate, rate, input, motion, motion_rate };

const char* kind_name(SymbolKind k) {
  switch (k) {
    case SymbolKind::parameter: return "a parameter";
    case SymbolKind::coordinate: return "a coordinate";
    case SymbolKind::rate: return "a coordinate rate";
    case SymbolKind::input: return "an input";
    case SymbolKind::motion: return "a motion input";
    case SymbolKind::motion_rate: return "the rate of a motion input";
  }
  return "a symbol";
}

bool in_scope(SymbolKind k, Scope s) {
  switch (s) {
    case Scope::constants: return false;
    case Scope::parameters: return k == SymbolKind::parameter;
    case Scope::world_marker: return k == SymbolKind::parameter || k == SymbolKind::motion;
    case Scope::positions: return k == SymbolKind::parameter || k == SymbolKind::coordinate;
    case Scope::kinematics:
      return k == SymbolKind::parameter || k == SymbolKind::coordinate || k == SymbolKind::motion;
    case Scope::no_inputs:
      return k != SymbolKind::input && k != SymbolKind::motion && k != SymbolKind::motion_rate;
    case Scope::any: return true;
  }
  return false;
}

const char* scope_phrase(Scope s) {
  switch (s) {
    case Scope::constants: return "must be a constant (numbers, Pi and functions only)";
    case Scope::parameters: return "may depend on parameters only";
    case Scope::world_marker: return "may depend on parameters and motion inputs only";
    case Scope::positions: return "may depend on parameters and coordinates only (no rates or inputs)";
    case Scope::kinematics:
      return "may depend on parameters, coordinates and motion inputs only (no rates or force inputs)";
    case Scope::no_inputs: return "may not depend on inputs";
    case Scope::any: return "";
  }
  return "";
}

const std::vector<std::string>& known_functions() {
  static const std::vector<std::string> names = {
      "abs",  "acos", "acosh", "asin", "asinh", "atan", "atan2", "atanh", "cos",
      "cosh", "exp",  "log",   "pow",  "sin",   "sinh", "sqrt",  "tan",   "tanh"};
  return names;
}

struct Token {
  enum class Kind { number, identifier, op, end };
  Kind kind;
  std::string text;
  std::size_t pos;
};

bool is_ident_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool is_ident_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }
bool is_digit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }

std::vector<Token> lex(const std::string& s) {
  std::vector<Token> out;
  std::size_t i = 0;
  while (i < s.size()) {
    const char c = s[i];
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
      ++i;
    } else if (is_ident_start(c)) {
      std::size_t j = i + 1;
      while (j < s.size() && is_ident_char(s[j])) ++j;
      out.push_back({Token::Kind::identifier, s.substr(i, j - i), i});
      i = j;
    } else if (is_digit(c) || c == '.') {
      std::size_t j = i, digits = 0;
      while (j < s.size() && is_digit(s[j])) ++j, ++digits;
      if (j < s.size() && s[j] == '.') {
        ++j;
        while (j < s.size() && is_digit(s[j])) ++j, ++digits;
      }
      bool ok = digits > 0;
      if (ok && j < s.size() && (s[j] == 'e' || s[j] == 'E')) {
        std::size_t k = j + 1;
        if (k < s.size() && (s[k] == '+' || s[k] == '-')) ++k;
        std::size_t exp_digits = 0;
        while (k < s.size() && is_digit(s[k])) ++k, ++exp_digits;
        ok = exp_digits > 0;
        j = k;
      }
      if (ok && j < s.size() && (s[j] == '.' || is_ident_char(s[j]))) {
        // "1.2.3", "2x", "1e5x": a number glued to something else.
        while (j < s.size() && (s[j] == '.' || is_ident_char(s[j]))) ++j;
        ok = false;
      }
      if (!ok) throw ExpressionError(i, "malformed number '" + s.substr(i, j - i) + "'");
      out.push_back({Token::Kind::number, s.substr(i, j - i), i});
      i = j;
    } else if (std::string("+-*/^(),").find(c) != std::string::npos) {
      out.push_back({Token::Kind::op, std::string(1, c), i});
      ++i;
    } else {
      std::string shown(1, c);
      if (static_cast<unsigned char>(c) >= 0x80) shown = "non-ASCII character";
      throw ExpressionError(i, "unexpected character '" + shown + "' in an expression");
    }
  }
  out.push_back({Token::Kind::end, "", s.size()});
  return out;
}

// A decimal literal as an exact integer or rational ("0.25" → 1/4, "1e-6" → 1/1000000).
GiNaC::numeric exact_value(const Token& t) {
  const std::string& s = t.text;
  std::size_t epos = s.find_first_of("eE");
  const std::string mantissa = s.substr(0, epos);
  long exponent = 0;
  if (epos != std::string::npos) {
    std::string e = s.substr(epos + 1);
    bool negative = false;
    if (!e.empty() && (e[0] == '+' || e[0] == '-')) {
      negative = e[0] == '-';
      e.erase(0, 1);
    }
    e.erase(0, std::min(e.find_first_not_of('0'), e.size()));
    if (e.size() > 4) throw ExpressionError(t.pos, "exponent out of range in '" + s + "'");
    exponent = e.empty() ? 0 : std::stol(e);
    if (negative) exponent = -exponent;
  }
  std::string digits = mantissa;
  const std::size_t dot = digits.find('.');
  if (dot != std::string::npos) {
    exponent -= static_cast<long>(digits.size() - dot - 1);
    digits.erase(dot, 1);
  }
  digits.erase(0, std::min(digits.find_first_not_of('0'), digits.size()));
  if (digits.empty()) return 0;
  const GiNaC::numeric significand(digits.c_str());
  const GiNaC::numeric scale = GiNaC::numeric(10).power(exponent < 0 ? -exponent : exponent);
  return exponent >= 0 ? significand * scale : significand / scale;
}

// Checks the token stream against GiNaC's expression grammar:
//   expr := unary (('+'|'-'|'*'|'/'|'^') unary)*     unary := ('+'|'-')* primary
//   primary := number | name | function '(' [expr (',' expr)*] ')' | '(' expr ')'
// and bounds the nesting: GiNaC's parser, the expression trees and their destructors recurse once
// per parenthesis, function call and sign (a sign takes the rest of its expression as operand),
// so deeper nesting would overflow the stack.
class ExpressionChecker {
 public:
  using SymbolCheck = std::function<void(const Token&)>;
  ExpressionChecker(const std::vector<Token>& tokens, SymbolCheck check)
      : t_(tokens), check_(std::move(check)) {}

  void run() {
    if (t_.front().kind == Token::Kind::end) throw ExpressionError(0, "empty expression");
    expr();
    const Token& tok = t_[i_];
    if (tok.kind == Token::Kind::end) return;
    if (tok.text == ")") throw ExpressionError(tok.pos, "unmatched ')'");
    if (tok.text == ",") throw ExpressionError(tok.pos, "unexpected ','");
    throw ExpressionError(tok.pos, "expected an operator before '" + tok.text +
                                       "' (multiplication is written '*')");
  }

 private:
  bool is_op(const char* ops) const {
    const Token& tok = t_[i_];
    return tok.kind == Token::Kind::op && std::string(ops).find(tok.text[0]) != std::string::npos;
  }

  static constexpr std::size_t kMaxNesting = 100;

  void nest(const Token& tok) {
    if (++depth_ > kMaxNesting)
      throw ExpressionError(tok.pos, "expression nested too deeply (more than " +
                                         std::to_string(kMaxNesting) +
                                         " levels of parentheses, function calls and signs)");
  }

  void expr() {
    const std::size_t outer = depth_;
    unary();
    while (is_op("+-*/^")) {
      ++i_;
      unary();
    }
    depth_ = outer;
  }

  void unary() {
    while (is_op("+-")) nest(t_[i_++]);
    primary();
  }

  void primary() {
    const Token& tok = t_[i_];
    switch (tok.kind) {
      case Token::Kind::number: ++i_; return;
      case Token::Kind::identifier:
        ++i_;
        if (is_op("(")) {
          call(tok);
        } else {
          check_(tok);
        }
        return;
      case Token::Kind::op:
        if (tok.text == "(") {
          nest(tok);
          ++i_;
          expr();
          if (!is_op(")")) throw ExpressionError(t_[i_].pos, "expected ')'");
          ++i_;
          --depth_;
          return;
        }
        if (tok.text == "*" && i_ > 0 && t_[i_ - 1].text == "*")
          throw ExpressionError(tok.pos, "unexpected '*' (powers are written '^')");
        throw ExpressionError(tok.pos, "expected an operand, got '" + tok.text + "'");
      case Token::Kind::end: break;
    }
    throw ExpressionError(tok.pos, "unexpected end of expression");
  }

  void call(const Token& name) {
    const auto& fns = known_functions();
    static const std::vector<std::string> steps = {"heaviside", "sgn", "sign", "signum", "step"};
    if (std::binary_search(steps.begin(), steps.end(), name.text))
      throw ExpressionError(name.pos, "unknown function '" + name.text + "': a step or sign has "
                                      "no derivative at 0, and the linear model needs one; write a "
                                      "law that is smooth at the operating point");
    if (!std::binary_search(fns.begin(), fns.end(), name.text))
      throw ExpressionError(name.pos, "unknown function '" + name.text + "'" +
                                          suggestion(name.text, fns));
    nest(name);
    ++i_;  // '('
    std::size_t args = 0;
    if (!is_op(")")) {
      while (true) {
        expr();
        ++args;
        if (is_op(")")) break;
        if (!is_op(","))
          throw ExpressionError(t_[i_].pos, "expected ',' or ')' in the arguments of '" +
                                                name.text + "'");
        ++i_;
      }
    }
    ++i_;  // ')'
    --depth_;
    // GiNaC's prototype table matches 0 arguments as a wildcard (and its reader then reads a
    // missing argument): every function here takes one or two.
    const auto& table = GiNaC::get_default_reader();
    if (args == 0 || table.find(GiNaC::prototype(name.text, args)) == table.end()) {
      const std::size_t want = name.text == "atan2" || name.text == "pow" ? 2 : 1;
      throw ExpressionError(name.pos, "function '" + name.text + "' takes " +
                                          std::to_string(want) + " argument" +
                                          (want == 1 ? "" : "s") + ", got " +
                                          std::to_string(args));
    }
  }

  const std::vector<Token>& t_;
  SymbolCheck check_;
  std::size_t i_ = 0;
  std::size_t depth_ = 0;
};

// The numbers and names of a checked expression, as placeholder symbols: their values and where
// they are written.
struct Leaves {
  GiNaC::exmap values;
  std::map<GiNaC::ex, std::size_t, GiNaC::ex_is_less> offsets;
};

// Puts the values into a tree of placeholders (checked_subs: each power is checked before GiNaC
// evaluates it, see checked_subs.hpp); a refusal or an error of GiNaC (log(0), tan(Pi/2)) becomes
// an ExpressionError at the first character of the offending subexpression.
class Rebuild {
 public:
  explicit Rebuild(const Leaves& leaves) : leaves_(leaves) {}

  GiNaC::ex operator()(const GiNaC::ex& tree) const {
    try {
      return detail::checked_subs(tree, leaves_.values);
    } catch (const detail::EvaluationError& e) {
      throw ExpressionError(offset(e.where()), std::string("bad expression: ") + e.what());
    }
  }

 private:
  // Where the subexpression `e` of the placeholder tree starts (its first number or name).
  std::size_t offset(const GiNaC::ex& e) const {
    const std::size_t first = first_leaf(e);
    return first == std::string::npos ? 0 : first;
  }

  std::size_t first_leaf(const GiNaC::ex& e) const {
    if (GiNaC::is_a<GiNaC::symbol>(e)) {
      auto it = leaves_.offsets.find(e);
      return it == leaves_.offsets.end() ? std::string::npos : it->second;
    }
    std::size_t first = std::string::npos;
    for (std::size_t i = 0; i < e.nops(); ++i) first = std::min(first, first_leaf(e.op(i)));
    return first;
  }

  const Leaves& leaves_;
};

// What parse_checked also does, beyond parsing (expression_sites.hpp): refuse inputs that do not
// enter linearly, and return the calls and powers that depend on symbols, with their places.
struct ParseExtras {
  bool linear_inputs = false;
  std::vector<detail::ExpressionSite> sites;
};

// The function calls of a checked token stream, with the placeholders of their arguments
// (placeholders are numbered in the order of their tokens).
std::vector<detail::Call> calls_of(const std::vector<Token>& tokens) {
  std::vector<detail::Call> calls;
  std::vector<long> open;  // index into calls, or -1 for a parenthesis
  std::size_t leaves = 0;
  for (std::size_t k = 0; k + 1 < tokens.size(); ++k) {
    const Token& tok = tokens[k];
    const bool call = tok.kind == Token::Kind::identifier && tokens[k + 1].text == "(" &&
                      tokens[k + 1].kind == Token::Kind::op;
    if (call) {
      open.push_back(static_cast<long>(calls.size()));
      calls.push_back({tok.text, tok.pos, 0, leaves, 0, open.size() - 1, false});
      ++k;  // its '('
    } else if (tok.kind == Token::Kind::op && tok.text == "(") {
      open.push_back(-1);
    } else if (tok.kind == Token::Kind::op && tok.text == ")") {
      if (!open.empty() && open.back() >= 0) {
        detail::Call& c = calls[static_cast<std::size_t>(open.back())];
        c.end = tok.pos + 1;
        c.last_leaf = leaves == 0 ? 0 : leaves - 1;
      }
      if (!open.empty()) open.pop_back();
    } else if (tok.kind != Token::Kind::op) {
      ++leaves;
    }
  }
  return calls;
}

GiNaC::ex parse_checked(const Model& model, const std::string& text,
                        const ExpressionChecker::SymbolCheck& check_known,
                        ParseExtras* extras = nullptr) {
  const std::vector<Token> tokens = lex(text);
  auto check = [&](const Token& tok) {
    if (tok.text == "Pi" || tok.text == "Euler" || tok.text == "Catalan") return;
    if (tok.text == "I")
      throw ExpressionError(tok.pos, "the imaginary unit 'I' is not allowed in a model");
    const GiNaC::symtab& table = model.symbol_table();
    if (table.find(tok.text) == table.end()) {
      std::vector<std::string> names;
      for (const auto& [name, sym] : table) names.push_back(name);
      throw ExpressionError(tok.pos, "unknown symbol '" + tok.text + "'" +
                                         suggestion(tok.text, names));
    }
    if (check_known) check_known(tok);
  };
  ExpressionChecker(tokens, check).run();

  // GiNaC's parser builds the tree with a distinct placeholder symbol for each occurrence of a
  // number or name, so that parsing evaluates nothing that can fail or grow (x - x is not yet 0,
  // 10^10^6 not yet a number); Rebuild then puts in the values, checking each power.
  GiNaC::symtab placeholders;
  Leaves leaves;
  std::map<GiNaC::ex, detail::Leaf, GiNaC::ex_is_less> spans;
  std::string rewritten;
  for (std::size_t k = 0; k + 1 < tokens.size(); ++k) {
    const Token& tok = tokens[k];
    const bool call = tok.kind == Token::Kind::identifier && tokens[k + 1].text == "(" &&
                      tokens[k + 1].kind == Token::Kind::op;
    if (tok.kind == Token::Kind::op || call) {
      rewritten += tok.text + ' ';
      continue;
    }
    const std::string name = "v" + std::to_string(placeholders.size());
    const GiNaC::symbol placeholder(name);
    placeholders[name] = placeholder;
    leaves.offsets[placeholder] = tok.pos;
    if (tok.kind == Token::Kind::number) leaves.values[placeholder] = exact_value(tok);
    else if (tok.text == "Pi") leaves.values[placeholder] = GiNaC::Pi;
    else if (tok.text == "Euler") leaves.values[placeholder] = GiNaC::Euler;
    else if (tok.text == "Catalan") leaves.values[placeholder] = GiNaC::Catalan;
    else leaves.values[placeholder] = model.symbol_table().at(tok.text);
    spans[placeholder] = {leaves.values[placeholder], tok.pos, tok.pos + tok.text.size(), spans.size()};
    rewritten += name + ' ';
  }
  GiNaC::ex tree;
  try {
    GiNaC::parser reader(placeholders);
    reader.strict = true;
    tree = reader(rewritten);
  } catch (const std::exception& e) {
    // Not expected after the checks above (but 'a^b^c'); report GiNaC's own words.
    throw ExpressionError(0, std::string("bad expression: ") + e.what());
  }
  const GiNaC::ex value = Rebuild(leaves)(tree);
  detail::SiteLocator at(text, std::move(spans), calls_of(tokens));
  try {
    detail::check_constants(at, tree, value);
    if (extras && extras->linear_inputs)
      detail::check_linear_inputs(at, tree, value, model.force_input_symbols());
    if (extras) detail::collect_sites(at, tree, extras->sites);
  } catch (const detail::SiteError& e) {
    throw ExpressionError(e.offset, e.message);
  } catch (const detail::EvaluationError& e) {  // a part whose value GiNaC refuses
    throw ExpressionError(0, std::string("bad expression: ") + e.what());
  }
  return value;
}

// ---------------------------------------------------------------------------------------------
// The YAML reader.

struct Entry {
  YAML::Node key;
  YAML::Node value;
};

std::string describe(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Null: return "nothing";
    case YAML::NodeType::Scalar: return "'" + n.Scalar() + "'";
    case YAML::NodeType::Sequence:
      return n.size() == 0 ? "an empty list"
                           : "a list of " + std::to_string(n.size()) + (n.size() == 1 ? " entry" : " entries");
    case YAML::NodeType::Map: return n.size() == 0 ? "an empty map" : "a map";
    case YAML::NodeType::Undefined: break;
  }
  return "nothing";
}

bool is_identifier(const std::string& s) {
  if (s.empty() || !std::isalpha(static_cast<unsigned char>(s[0]))) return false;
  return std::all_of(s.begin(), s.end(), is_ident_char);
}

Mat3 multiply(const Mat3& a, const Mat3& b) {
  Mat3 c = zero_mat3();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      GiNaC::ex s = 0;
      for (int k = 0; k < 3; ++k) s += a[i][k] * b[k][j];
      c[i][j] = s;
    }
  return c;
}

// The rotation matrix of an elementary rotation (maps components in the rotated frame to the
// frame it is applied in).
Mat3 rotation_matrix(const ElementaryRotation& r) {
  const GiNaC::ex c = GiNaC::cos(r.angle), s = GiNaC::sin(r.angle);
  Mat3 m = identity_mat3();
  int i = 0, j = 0;
  switch (r.axis) {
    case Axis::x: i = 1, j = 2; break;
    case Axis::y: i = 2, j = 0; break;
    case Axis::z: i = 0, j = 1; break;
  }
  m[i][i] = c;
  m[i][j] = -s;
  m[j][i] = s;
  m[j][j] = c;
  return m;
}

// Where the documents of a YAML text start (at most three). Not YAML::LoadAll: yaml-cpp 0.7 loops
// there forever, allocating an empty document per turn, on a token that cannot start a node such
// as a stray ',' (jbeder/yaml-cpp#1040, fixed in later releases); such a token is reported here
// as a YAML::ParserException at the token.
class DocumentMarks : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark&) override { root_seen_ = false; }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& m, YAML::anchor_t) override { root(m, true); }
  void OnAlias(const YAML::Mark& m, YAML::anchor_t a) override {
    root(m, false);
    if (anchored.count(a)) aliases[key(anchored[a])].push_back(m);
  }
  void OnScalar(const YAML::Mark& m, const std::string&, YAML::anchor_t a, const std::string&) override {
    root(m, false);
    anchor(m, a);
  }
  void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t a,
                       YAML::EmitterStyle::value) override {
    root(m, false);
    anchor(m, a);
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t a,
                  YAML::EmitterStyle::value) override {
    root(m, false);
    anchor(m, a);
  }

  using Key = std::pair<int, int>;  // line, column
  static Key key(const YAML::Mark& m) { return {m.line, m.column}; }
  /// The aliases of each anchored node (by the node's place), in document order.
  std::map<Key, std::vector<YAML::Mark>> aliases;
  void OnMapEnd() override {}

  // The mark of the current document's root node and whether it is an empty (null) node.
  YAML::Mark mark;
  bool null_root = false;

 private:
  void anchor(const YAML::Mark& m, YAML::anchor_t a) {
    if (a != 0) anchored[a] = m;
  }
  std::map<YAML::anchor_t, YAML::Mark> anchored;
  void root(const YAML::Mark& m, bool is_null) {
    if (root_seen_) return;
    root_seen_ = true;
    mark = m;
    null_root = is_null;
  }
  bool root_seen_ = false;
};

std::vector<YAML::Mark> document_marks(const std::string& text,
                                       std::map<DocumentMarks::Key, std::vector<YAML::Mark>>& aliases) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  DocumentMarks handler;
  std::vector<YAML::Mark> marks;
  bool previous_null = false;
  while (marks.size() < 3 && parser.HandleNextDocument(handler)) {
    // Two empty documents at the same place: the parser did not move (the bug above).
    if (handler.null_root && previous_null && handler.mark.pos == marks.back().pos) {
      const std::size_t pos = static_cast<std::size_t>(std::max(handler.mark.pos, 0));
      const std::string what = pos < text.size() ? "'" + text.substr(pos, 1) + "'" : "end of file";
      throw YAML::ParserException(handler.mark, "unexpected " + what);
    }
    previous_null = handler.null_root;
    marks.push_back(handler.mark);
  }
  aliases = handler.aliases;
  return marks;
}

class Reader {
 public:
  Reader(const std::string& text, const std::string& file) : text_(text), file_(file) {}

  Model read();

 private:
  YAML::Node load();
  Model read_model();
  using Fields = std::map<std::string, Entry>;

  SourceLocation loc(const YAML::Node& n) const {
    const YAML::Mark m = n.Mark();
    if (m.line < 0) return {file_, 0, 0};
    return {file_, m.line + 1, m.column + 1};
  }

  // The location of character `offset` of a scalar, when the scalar is written on one line
  // without escapes (plain or quoted); the scalar's own location otherwise.
  SourceLocation loc_in_scalar(const YAML::Node& n, std::size_t offset) const {
    SourceLocation where = loc(n);
    const YAML::Mark m = n.Mark();
    const std::string& v = n.Scalar();
    if (m.pos < 0 || where.line == 0 || v.find('\n') != std::string::npos) return where;
    const std::size_t pos = static_cast<std::size_t>(m.pos);
    if (pos >= text_.size()) return where;
    const char quote = text_[pos];
    const std::size_t shift = (quote == '\'' || quote == '"') ? 1 : 0;
    if (pos + 2 * shift + v.size() > text_.size()) return where;
    if (text_.compare(pos + shift, v.size(), v) != 0) return where;  // escapes or folded lines
    if (shift && text_[pos + shift + v.size()] != quote) return where;
    where.column += static_cast<int>(shift + offset);
    return where;
  }

  // The place of an element read from node `n`: the node's, or, when `n` is read again through
  // an alias (`- *b`), that alias's, so that a duplicate points at the alias.
  SourceLocation element_loc(const YAML::Node& n) {
    const YAML::Mark m = n.Mark();
    auto it = aliases_.find({m.line, m.column});
    const std::size_t k = reads_[{m.line, m.column}]++;
    if (it == aliases_.end() || k == 0 || k > it->second.size()) return loc(n);
    const YAML::Mark& a = it->second[k - 1];
    SourceLocation where{file_, a.line + 1, a.column + 1};
    std::string name;
    for (std::size_t p = static_cast<std::size_t>(std::max(a.pos, 0)) + 1;
         p < text_.size() && !std::isspace(static_cast<unsigned char>(text_[p])) &&
         std::string(",]}").find(text_[p]) == std::string::npos;
         ++p)
      name += text_[p];
    alias_notes_[where.str()] = " (through the alias '*" + name + "', which repeats the node at " +
                                loc(n).str() + ")";
    return where;
  }

  [[noreturn]] void fail(const YAML::Node& n, const std::string& message) const {
    throw ModelError(loc(n), message);
  }

  // A map with only `allowed` keys, each at most once.
  Fields fields(const YAML::Node& n, const std::string& what,
                const std::vector<std::string>& allowed) const {
    if (!n.IsMap()) fail(n, "expected a map for " + what + ", got " + describe(n));
    Fields out;
    for (auto it = n.begin(); it != n.end(); ++it) {
      const YAML::Node key = it->first;
      if (!key.IsScalar()) fail(key, "expected a name as a key in " + what);
      const std::string& k = key.Scalar();
      if (std::find(allowed.begin(), allowed.end(), k) == allowed.end()) {
        std::string hint = suggestion(k, allowed);
        if (hint.empty()) hint = " (allowed: " + join(allowed) + ")";
        fail(key, "unknown key '" + k + "' in " + what + hint);
      }
      auto found = out.find(k);
      if (found != out.end())
        fail(key, "duplicate key '" + k + "' in " + what + " (first at " +
                      loc(found->second.key).str() + ")");
      out.emplace(k, Entry{key, it->second});
    }
    return out;
  }

  const Entry* find(const Fields& f, const std::string& key) const {
    auto it = f.find(key);
    return it == f.end() ? nullptr : &it->second;
  }

  const Entry& require(const Fields& f, const std::string& key, const YAML::Node& map,
                       const std::string& what) const {
    auto it = f.find(key);
    if (it == f.end()) fail(map, what + " needs the key '" + key + "'");
    return it->second;
  }

  // The value of an entry, which may not be empty.
  const YAML::Node& value(const Entry& e) const {
    if (e.value.IsNull()) fail(e.key, "'" + e.key.Scalar() + "' has no value");
    return e.value;
  }

  std::string scalar(const YAML::Node& n, const std::string& what) const {
    if (!n.IsScalar()) fail(n, "expected " + what + ", got " + describe(n));
    return n.Scalar();
  }

  // A name of the model (a body, coordinate, marker, force, constraint, output, input, scene):
  // an identifier, as the names of parameters and coordinates (Model::check_new_symbol), so that
  // it is one word in every message, file name, column header and plot legend.
  std::string name(const Entry& e, const std::string& what) const {
    const YAML::Node& n = value(e);
    const std::string s = scalar(n, what);
    if (s.empty()) fail(n, what + " may not be empty");
    if (!is_identifier(s)) {
      const bool printable = std::all_of(s.begin(), s.end(), [](char c) { return c >= 0x20 && c < 0x7f; });
      const std::string shown = "'" + (printable ? s : cpp_comment_text(s)) + "'";
      const std::string kind = what.rfind("an ", 0) == 0 ? what.substr(3) : what.rfind("a ", 0) == 0 ? what.substr(2) : what;
      fail(n, shown + " is not a valid " + kind +
                  (std::isalpha(static_cast<unsigned char>(s[0])) ? " (letters, digits and _)"
                                                                  : " (a letter, then letters, digits and _)"));
    }
    return s;
  }

  // A list (an absent or empty value is an empty list).
  std::vector<YAML::Node> list(const Entry* e, const std::string& what) const {
    std::vector<YAML::Node> out;
    if (!e || e->value.IsNull()) return out;
    if (!e->value.IsSequence()) fail(e->value, "expected a list for " + what + ", got " +
                                                   describe(e->value));
    for (auto it = e->value.begin(); it != e->value.end(); ++it) out.push_back(*it);
    return out;
  }

  GiNaC::ex expr(const YAML::Node& n, const std::string& what, Scope scope) const {
    if (!n.IsScalar()) fail(n, "expected an expression for " + what + ", got " + describe(n));
    auto check = [&](const Token& tok) {
      auto it = kinds_.find(tok.text);
      if (it != kinds_.end() && !in_scope(it->second, scope))
        throw ExpressionError(tok.pos, what + " " + scope_phrase(scope) + "; '" + tok.text +
                                           "' is " + kind_name(it->second));
    };
    ParseExtras extras;
    extras.linear_inputs = scope == Scope::any;
    try {
      const GiNaC::ex e = parse_checked(*model_, n.Scalar(), check, &extras);
      // Where each call and power of a state-dependent expression was written, for the checks
      // of derivatives at the operating point (Model::validate).
      if (scope != Scope::constants && scope != Scope::parameters)
        for (const auto& site : extras.sites)
          model_->add_call_site(site.node, {site.text, loc_in_scalar(n, site.offset)});
      return e;
    } catch (const ExpressionError& e) {
      throw ModelError(loc_in_scalar(n, e.offset()), e.what());
    }
  }

  GiNaC::ex expr(const Entry& e, const std::string& what, Scope scope) const {
    return expr(value(e), what, scope);
  }

  Vec3 vec3(const YAML::Node& n, const std::string& what, Scope scope) const {
    if (!n.IsSequence())
      fail(n, "expected a list of 3 expressions for " + what + ", got " + describe(n));
    if (n.size() != 3)
      fail(n, what + " needs 3 components, got " + std::to_string(n.size()));
    Vec3 v;
    for (std::size_t i = 0; i < 3; ++i) v[i] = expr(n[i], what, scope);
    return v;
  }

  Vec3 vec3(const Entry& e, const std::string& what, Scope scope) const {
    return vec3(value(e), what, scope);
  }

  Mat3 mat3(const YAML::Node& n, const std::string& what, Scope scope) const {
    if (!n.IsSequence())
      fail(n, "expected a 3x3 matrix (a list of 3 rows) for " + what + ", got " + describe(n));
    if (n.size() != 3)
      fail(n, what + " needs 3 rows, got " + std::to_string(n.size()));
    Mat3 m;
    for (std::size_t i = 0; i < 3; ++i) {
      const YAML::Node row = n[i];
      if (!row.IsSequence())
        fail(row, "row " + std::to_string(i + 1) + " of " + what +
                      " should be a list of 3 expressions, got " + describe(row));
      if (row.size() != 3)
        fail(row, "row " + std::to_string(i + 1) + " of " + what + " needs 3 entries, got " +
                      std::to_string(row.size()));
      for (std::size_t j = 0; j < 3; ++j) m[i][j] = expr(row[j], what, scope);
    }
    return m;
  }

  std::vector<ElementaryRotation> rotations(const Entry& e, const std::string& what,
                                            Scope scope) const {
    const YAML::Node& n = value(e);
    if (!n.IsSequence())
      fail(n, "expected a list of elementary rotations such as [{z: phi}, {x: psi}] for " + what +
                  ", got " + describe(n));
    std::vector<ElementaryRotation> out;
    for (auto it = n.begin(); it != n.end(); ++it) {
      const YAML::Node step = *it;
      Fields f = fields(step, "a rotation step", {"x", "y", "z"});
      if (f.size() != 1)
        fail(step, "a rotation step has exactly one key x, y or z (one elementary rotation)");
      const auto& [axis, entry] = *f.begin();
      ElementaryRotation r;
      r.axis = axis == "x" ? Axis::x : axis == "y" ? Axis::y : Axis::z;
      r.angle = expr(entry, "a rotation angle", scope);
      out.push_back(r);
    }
    return out;
  }

  std::string check_marker(const YAML::Node& n) const {
    const std::string m = scalar(n, "a marker name");
    if (!model_->has_marker(m)) {
      std::vector<std::string> names;
      for (const auto& mk : model_->markers()) names.push_back(mk.name);
      fail(n, "unknown marker '" + m + "'" + suggestion(m, names));
    }
    return m;
  }

  std::string check_coordinate(const YAML::Node& n) const {
    const std::string c = scalar(n, "a coordinate name");
    if (model_->coordinate_index(c) < 0) {
      std::vector<std::string> names;
      for (const auto& co : model_->coordinates()) names.push_back(co.name);
      fail(n, "unknown coordinate '" + c + "'" + suggestion(c, names));
    }
    return c;
  }

  void read_parameters(const Entry* e);
  void read_named_list(const Entry* e, const std::string& what, bool coordinates);
  GiNaC::exmap parameter_values() const {
    GiNaC::exmap values;
    for (const auto& p : model_->parameters()) values[p.symbol] = GiNaC::numeric(p.value);
    return values;
  }
  // evalf(e.subs(values)) for the expression written at `n`; a pole (1/(m - 1) with m = 1), a
  // floating-point exception of CLN (exp(-1e9999) underflows) or a value CLN would get wrong or
  // double cannot hold (exp(1e9999), sin(1e50), asin(2): checked_evalf) is a ModelError at `n`.
  // (Through checked_subs: GiNaC's own subs leaks the node whose evaluation throws.)
  GiNaC::ex evaluate(const YAML::Node& n, const GiNaC::ex& e, const GiNaC::exmap& values = {}) const {
    try {
      return detail::checked_evalf(values.empty() ? e : detail::checked_subs(e, values));
    } catch (const std::exception& err) {
      fail(n, "cannot evaluate '" + n.Scalar() + "'" +
                  (values.empty() ? "" : " with the default parameter values") + ": " + err.what());
    }
  }
  void read_body(const YAML::Node& n, const std::set<std::string>& later_bodies);
  std::map<std::string, std::string> declared_parents_;  ///< body → parent as written in the file
  void read_marker(const YAML::Node& n, const std::string& body, const YAML::Node* body_node);
  void read_force(const YAML::Node& n, std::map<std::string, int>& counters);
  void read_output(const YAML::Node& n);
  void read_load_output(const YAML::Node& n, const std::string& type, const Fields& f, Output& o);
  void read_constraint(const YAML::Node& n, std::map<std::string, int>& counters);
  void read_rolling(const Fields& f, const YAML::Node& n, Constraint& c);
  void read_velocity_constraints(const Entry* e);
  void read_reduced_form(const Entry& e);
  void read_operating_point(const Entry& e);
  OperatingPointOverride read_operating_point_values(const YAML::Node& n, const std::string& what);
  void read_scene(const YAML::Node& n);
  std::vector<SceneItem> items(const Entry& e, const std::string& what) const;
  void define(SymbolKind kind, const std::string& name) { kinds_[name] = kind; }

  const std::string& text_;
  std::string file_;
  Model* model_ = nullptr;
  std::map<std::string, SymbolKind> kinds_;
  std::set<std::string> used_names_;  // bodies, markers, forces, outputs
  std::map<DocumentMarks::Key, std::vector<YAML::Mark>> aliases_;  // see element_loc
  std::map<DocumentMarks::Key, std::size_t> reads_;
  std::map<std::string, std::string> alias_notes_;  // alias location → what it repeats
};

// The first tab in the indentation of line `line` (0-based) or of the line before it, which
// yaml-cpp reports in its own words ("illegal block entry", "end of map not found"); {} when
// there is none. Comment lines may be indented with tabs.
SourceLocation tab_in_indentation(const std::string& text, int line, const std::string& file) {
  std::vector<std::size_t> starts{0};
  for (std::size_t i = 0; i < text.size(); ++i)
    if (text[i] == '\n') starts.push_back(i + 1);
  for (int l = std::max(line - 1, 0); l <= line && l < static_cast<int>(starts.size()); ++l) {
    const std::size_t begin = starts[static_cast<std::size_t>(l)];
    std::size_t i = begin;
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    if (i == text.size() || text[i] == '\n' || text[i] == '\r' || text[i] == '#') continue;
    const std::size_t tab = text.find('\t', begin);
    if (tab < i) return {file, l + 1, static_cast<int>(tab - begin) + 1};
  }
  return {};
}

Model Reader::read() {
  try {
    return read_model();
  } catch (const ModelError& e) {
    const auto note = alias_notes_.find(e.where().str());
    if (note == alias_notes_.end()) throw;
    throw ModelError(e.where(), e.message() + note->second);
  }
}

YAML::Node Reader::load() {
  try {
    const std::vector<YAML::Mark> documents = document_marks(text_, aliases_);
    if (documents.size() > 1) {
      const YAML::Mark& m = documents[1];
      throw ModelError({file_, m.line + 1, m.column + 1}, "a model file holds one YAML document");
    }
    return YAML::Load(text_);
  } catch (const YAML::DeepRecursion& e) {
    throw ModelError({file_, e.mark.line + 1, e.mark.column + 1},
                     "YAML nested too deeply (" + std::to_string(e.depth()) + " levels)");
  } catch (const YAML::Exception& e) {
    const SourceLocation tab = tab_in_indentation(text_, e.mark.line, file_);
    if (tab.line > 0) throw ModelError(tab, "tab in indentation; YAML allows only spaces");
    throw ModelError({file_, e.mark.line + 1, e.mark.column + 1}, e.msg);
  }
}

Model Reader::read_model() {
  const YAML::Node root = load();
  if (root.IsNull())
    throw ModelError({file_, 1, 1}, "the model file is empty (expected a map starting with "
                                    "'model: NAME')");
  const Fields top = fields(root, "the model file",
                            {"model", "parameters", "coordinates", "inputs", "bodies", "markers",
                             "forces", "constraints", "independent_coordinates", "nonholonomic",
                             "independent_speeds", "reduced_form", "outputs",
                             "operating_point", "scenes"});

  const Entry& name_entry = require(top, "model", root, "the model file");
  const std::string model_name = name(name_entry, "the model name");
  if (!is_identifier(model_name))
    fail(name_entry.value, "the model name '" + model_name +
                               "' must be an identifier (letters, digits and _)");
  if (reserved_identifier(model_name))
    fail(name_entry.value, "the model name '" + model_name +
                               "' is a C++ keyword or a name C++ reserves (such as int, class, "
                               "std, linux): the generated code names its kernels after the "
                               "model; choose another name");
  Model model(model_name);
  model_ = &model;

  read_parameters(find(top, "parameters"));
  const Entry& coords = require(top, "coordinates", root, "the model file");
  read_named_list(&coords, "coordinates", true);
  if (model.coordinates().empty()) fail(coords.key, "a model needs at least one coordinate");
  read_named_list(find(top, "inputs"), "inputs", false);

  // Names of elements, for default force names and helpful messages.
  const std::vector<YAML::Node> bodies = list(find(top, "bodies"), "bodies");
  std::set<std::string> body_names;
  for (const auto& b : bodies)
    if (b.IsMap() && b["name"] && b["name"].IsScalar()) {
      body_names.insert(b["name"].Scalar());
      if (b["parent"] && b["parent"].IsScalar()) declared_parents_[b["name"].Scalar()] = b["parent"].Scalar();
    }
  for (const auto& b : bodies) read_body(b, body_names);

  for (const auto& m : list(find(top, "markers"), "markers")) read_marker(m, "", nullptr);

  const std::vector<YAML::Node> forces = list(find(top, "forces"), "forces");
  const std::vector<YAML::Node> constraints = list(find(top, "constraints"), "constraints");
  const std::vector<YAML::Node> outputs = list(find(top, "outputs"), "outputs");
  for (const auto* group : {&forces, &constraints, &outputs})
    for (const auto& n : *group)
      if (n.IsMap() && n["name"] && n["name"].IsScalar()) used_names_.insert(n["name"].Scalar());
  std::map<std::string, int> counters;
  for (const auto& f : forces) read_force(f, counters);
  for (const auto& c : constraints) read_constraint(c, counters);
  if (const Entry* e = find(top, "independent_coordinates")) {
    std::vector<SceneItem> names = items(*e, "independent_coordinates");
    for (const auto& item : names)
      if (model.coordinate_index(item.name) < 0)
        throw ModelError(item.where, "independent coordinate '" + item.name + "' is not a coordinate");
    model.set_independent_coordinates(std::move(names));
  }
  read_velocity_constraints(find(top, "nonholonomic"));
  if (const Entry* e = find(top, "reduced_form")) read_reduced_form(*e);
  if (const Entry* e = find(top, "independent_speeds")) {
    std::vector<SceneItem> names = items(*e, "independent_speeds");
    for (const auto& item : names)
      if (model.coordinate_index(item.name) < 0)
        throw ModelError(item.where, "independent speed '" + item.name + "' is not a coordinate (name the coordinate whose rate it is)");
    model.set_independent_speeds(std::move(names));
  }
  for (const auto& o : outputs) read_output(o);

  if (const Entry* op = find(top, "operating_point")) read_operating_point(*op);
  for (const auto& sc : list(find(top, "scenes"), "scenes")) read_scene(sc);

  try {
    model.validate();
  } catch (const ModelError& e) {
    if (!e.where().file.empty()) throw;
    throw ModelError(loc(root), e.message());
  }
  model_ = nullptr;
  return model;
}

void Reader::read_parameters(const Entry* e) {
  if (!e || e->value.IsNull()) return;
  const YAML::Node& n = e->value;
  if (!n.IsMap())
    fail(n, "expected a map 'name: value' (or 'name: {value, unit, source}') for parameters, got " +
                describe(n));
  for (auto it = n.begin(); it != n.end(); ++it) {
    const YAML::Node key = it->first;
    const YAML::Node val = it->second;
    const std::string pname = scalar(key, "a parameter name");
    YAML::Node value_node = val;
    std::string unit, source;
    if (val.IsMap()) {
      const Fields f = fields(val, "parameter '" + pname + "'", {"value", "unit", "source"});
      value_node = value(require(f, "value", val, "parameter '" + pname + "'"));
      if (const Entry* u = find(f, "unit")) unit = scalar(value(*u), "a unit");
      if (const Entry* s = find(f, "source")) source = scalar(value(*s), "a source");
    } else if (val.IsNull()) {
      fail(key, "parameter '" + pname + "' has no value");
    }
    const GiNaC::ex v = evaluate(value_node, expr(value_node, "a parameter value", Scope::constants));
    if (!GiNaC::is_a<GiNaC::numeric>(v) || !GiNaC::ex_to<GiNaC::numeric>(v).is_real())
      fail(value_node, "parameter '" + pname + "' must have a real value");
    model_->add_parameter(pname, GiNaC::ex_to<GiNaC::numeric>(v).to_double(), unit, source,
                          loc(key));
    define(SymbolKind::parameter, pname);
  }
}

void Reader::read_named_list(const Entry* e, const std::string& what, bool coordinates) {
  for (const auto& n : list(e, what)) {
    std::string item_name, unit;
    bool motion = false;
    if (n.IsMap()) {
      const Fields f = coordinates ? fields(n, "an entry of " + what, {"name", "unit"})
                                   : fields(n, "an entry of " + what, {"name", "unit", "kind"});
      item_name = name(require(f, "name", n, "an entry of " + what), "a name");
      if (const Entry* u = find(f, "unit")) unit = scalar(value(*u), "a unit");
      if (const Entry* k = find(f, "kind")) {
        const std::string kind = scalar(value(*k), "an input kind");
        if (kind != "force" && kind != "motion")
          fail(value(*k), "an input's kind is 'force' (the default) or 'motion', not '" + kind + "'" +
                              suggestion(kind, {"force", "motion"}));
        motion = kind == "motion";
      }
    } else {
      item_name = scalar(n, coordinates ? "a name or {name, unit} in " + what
                                        : "a name or {name, unit, kind} in " + what);
    }
    if (coordinates) {
      model_->add_coordinate(item_name, unit, element_loc(n));
      define(SymbolKind::coordinate, item_name);
      define(SymbolKind::rate, item_name + "_dot");
    } else {
      model_->add_input(item_name, unit, element_loc(n), motion);
      define(motion ? SymbolKind::motion : SymbolKind::input, item_name);
      if (motion) define(SymbolKind::motion_rate, item_name + "_dot");
    }
  }
}

void Reader::read_body(const YAML::Node& n, const std::set<std::string>& all_bodies) {
  const Fields f = fields(n, "a body",
                          {"name", "parent", "translation", "rotation", "rotation_matrix", "mass",
                           "com", "inertia", "markers"});
  Body b;
  b.name = name(require(f, "name", n, "a body"), "a body name");
  b.where = element_loc(n);
  const std::string what = "body '" + b.name + "'";
  if (const Entry* p = find(f, "parent")) {
    const YAML::Node& pn = value(*p);
    b.parent = scalar(pn, "a body name");
    if (b.parent != kWorld) {
      bool defined = true;
      try {
        model_->body_index(b.parent);
      } catch (const std::out_of_range&) {
        defined = false;
      }
      if (!defined) {
        if (b.parent == b.name) fail(pn, what + " cannot be its own parent");
        // A parent defined later: either out of order or, when its chain of parents comes back to
        // this body, a cycle with no path to the world.
        std::string chain = "'" + b.name + "'";
        for (std::string at = b.parent; declared_parents_.count(at) && chain.size() < 4096;
             at = declared_parents_.at(at)) {
          chain += " -> '" + at + "'";
          if (at == b.name)
            fail(pn, "bodies " + chain + " form a cycle: every body needs a path to '" +
                         std::string(kWorld) + "'");
        }
        if (all_bodies.count(b.parent))
          fail(pn, "parent '" + b.parent + "' of " + what +
                       " must be defined before it (bodies are listed parents first)");
        std::vector<std::string> names(all_bodies.begin(), all_bodies.end());
        names.push_back(kWorld);
        fail(pn, "unknown parent body '" + b.parent + "'" + suggestion(b.parent, names));
      }
    }
  }
  if (const Entry* t = find(f, "translation")) b.translation = vec3(*t, "a translation", Scope::kinematics);
  const Entry* rot = find(f, "rotation");
  const Entry* rot_m = find(f, "rotation_matrix");
  if (rot && rot_m) fail(rot_m->key, what + ": give either 'rotation' or 'rotation_matrix', not both");
  if (rot) b.rotations = rotations(*rot, "a rotation", Scope::kinematics);
  if (rot_m) b.rotation_matrix = mat3(value(*rot_m), "a rotation matrix", Scope::kinematics);
  if (const Entry* m = find(f, "mass")) {
    b.mass = expr(*m, "a mass", Scope::parameters);
    const GiNaC::ex m0 = evaluate(value(*m), b.mass, parameter_values());
    if (GiNaC::is_a<GiNaC::numeric>(m0) && GiNaC::ex_to<GiNaC::numeric>(m0).is_zero())
      fail(value(*m), what + " has zero mass; omit 'mass' (and 'inertia') for a massless frame");
  }
  if (const Entry* c = find(f, "com")) b.com = vec3(*c, "a centre of mass", Scope::parameters);
  if (const Entry* i = find(f, "inertia")) {
    const YAML::Node& in = value(*i);
    if (in.IsMap()) {
      const Fields g = fields(in, "an inertia tensor", {"xx", "yy", "zz", "xy", "xz", "yz"});
      static const std::map<std::string, std::pair<int, int>> index = {
          {"xx", {0, 0}}, {"yy", {1, 1}}, {"zz", {2, 2}},
          {"xy", {0, 1}}, {"xz", {0, 2}}, {"yz", {1, 2}}};
      for (const auto& [key, entry] : g) {
        const auto [r, c] = index.at(key);
        const GiNaC::ex x = expr(entry, "an inertia tensor", Scope::parameters);
        b.inertia[r][c] = x;
        b.inertia[c][r] = x;
      }
    } else {
      b.inertia = mat3(in, "an inertia tensor", Scope::parameters);
      for (int r = 0; r < 3; ++r)
        for (int c = r + 1; c < 3; ++c)
          if (!(b.inertia[r][c] - b.inertia[c][r]).is_zero())
            fail(in, "the inertia tensor of " + what + " is not symmetric (entries " +
                         std::to_string(r + 1) + "," + std::to_string(c + 1) + " and " +
                         std::to_string(c + 1) + "," + std::to_string(r + 1) + ")");
    }
  }
  used_names_.insert(b.name);
  model_->add_body(b);
  if (const Entry* ms = find(f, "markers"))
    for (const auto& m : list(ms, "the markers of " + what)) read_marker(m, b.name, &n);
}

void Reader::read_marker(const YAML::Node& n, const std::string& body, const YAML::Node* on_body) {
  std::vector<std::string> keys = {"name", "position", "rotation", "rotation_matrix"};
  if (!on_body) keys.push_back("body");
  const Fields f = fields(n, "a marker", keys);
  Marker m;
  m.name = name(require(f, "name", n, "a marker"), "a marker name");
  m.where = element_loc(n);
  m.body = on_body ? body : std::string(kWorld);
  if (const Entry* b = find(f, "body")) {
    const YAML::Node& bn = value(*b);
    m.body = scalar(bn, "a body name");
    if (m.body != kWorld) {
      std::vector<std::string> names = {kWorld};
      for (const auto& bd : model_->bodies()) names.push_back(bd.name);
      if (std::find(names.begin(), names.end(), m.body) == names.end())
        fail(bn, "unknown body '" + m.body + "'" + suggestion(m.body, names));
    }
  }
  // A marker on the world may move with motion inputs (prescribed_motion.hpp).
  const Scope scope = m.body == kWorld ? Scope::world_marker : Scope::parameters;
  if (const Entry* p = find(f, "position")) m.position = vec3(*p, "a marker position", scope);
  const Entry* rot = find(f, "rotation");
  const Entry* rot_m = find(f, "rotation_matrix");
  if (rot && rot_m)
    fail(rot_m->key, "marker '" + m.name + "': give either 'rotation' or 'rotation_matrix', not both");
  if (rot)
    for (const auto& r : rotations(*rot, "a marker rotation", scope))
      m.rotation = multiply(m.rotation, rotation_matrix(r));
  if (rot_m) m.rotation = mat3(value(*rot_m), "a marker rotation matrix", scope);
  used_names_.insert(m.name);
  model_->add_marker(m);
}

void Reader::read_force(const YAML::Node& n, std::map<std::string, int>& counters) {
  static const std::vector<std::string> types = {"gravity", "spring",      "damper",
                                                 "bushing", "generalized", "applied"};
  if (!n.IsMap()) fail(n, "expected a map for a force, got " + describe(n));
  const YAML::Node type_node = n["type"];
  if (!type_node) fail(n, "a force needs the key 'type' (one of: " + join(types) + ")");
  const std::string type = scalar(type_node, "a force type");
  if (std::find(types.begin(), types.end(), type) == types.end())
    fail(type_node, "unknown force type '" + type + "'" +
                        [&] {
                          std::string s = suggestion(type, types);
                          return s.empty() ? " (one of: " + join(types) + ")" : s;
                        }());
  std::vector<std::string> keys = {"type", "name"};
  if (type == "gravity") keys.insert(keys.end(), {"g"});
  if (type == "spring") keys.insert(keys.end(), {"between", "stiffness", "rest_length"});
  if (type == "damper") keys.insert(keys.end(), {"between", "damping"});
  if (type == "bushing") keys.insert(keys.end(), {"between", "stiffness", "damping"});
  if (type == "generalized") keys.insert(keys.end(), {"coordinate", "value", "category"});
  if (type == "applied") keys.insert(keys.end(), {"marker", "frame", "force", "torque"});
  const std::string what = "a " + type + " force";
  const Fields f = fields(n, what, keys);

  std::string force_name;
  if (const Entry* e = find(f, "name")) {
    force_name = name(*e, "a force name");
  } else {
    int& k = counters[type];
    do force_name = type + std::to_string(++k);
    while (used_names_.count(force_name));
  }
  used_names_.insert(force_name);
  const SourceLocation where = element_loc(n);

  std::string marker_a, marker_b;
  if (const Entry* e = find(f, "between")) {
    const YAML::Node& bn = value(*e);
    if (!bn.IsSequence() || bn.size() != 2)
      fail(bn, "'between' needs a list of two marker names [A, B], got " +
                   (bn.IsSequence() ? std::to_string(bn.size()) + " entries" : describe(bn)));
    marker_a = check_marker(bn[0]);
    marker_b = check_marker(bn[1]);
    if (marker_a == marker_b) fail(bn[1], "a " + type + " between marker '" + marker_a + "' and itself");
  } else if (type == "spring" || type == "damper" || type == "bushing") {
    require(f, "between", n, what);
  }

  if (type == "gravity") {
    Gravity g;
    g.name = force_name;
    g.g = vec3(require(f, "g", n, what), "gravity", Scope::parameters);
    g.where = where;
    model_->add_gravity(g);
  } else if (type == "spring") {
    Spring s;
    s.name = force_name;
    s.marker_a = marker_a;
    s.marker_b = marker_b;
    s.stiffness = expr(require(f, "stiffness", n, what), "a spring stiffness", Scope::parameters);
    if (const Entry* e = find(f, "rest_length")) {
      s.rest_length = expr(*e, "a rest length", Scope::parameters);
      const GiNaC::ex L0 = evaluate(value(*e), s.rest_length, parameter_values());
      if (GiNaC::is_a<GiNaC::numeric>(L0) && GiNaC::ex_to<GiNaC::numeric>(L0).is_negative())
        fail(value(*e), "a rest length must be >= 0, got " +
                            detail::checked_subs_impl::describe(GiNaC::ex_to<GiNaC::numeric>(L0)) + " m");
    }
    s.where = where;
    model_->add_spring(s);
  } else if (type == "damper") {
    Damper d;
    d.name = force_name;
    d.marker_a = marker_a;
    d.marker_b = marker_b;
    d.damping = expr(require(f, "damping", n, what), "a damping coefficient", Scope::parameters);
    d.where = where;
    model_->add_damper(d);
  } else if (type == "bushing") {
    Bushing b;
    b.name = force_name;
    b.marker_a = marker_a;
    b.marker_b = marker_b;
    auto pair = [&](const char* key, Vec3& translation, Vec3& rotation) {
      const Entry* e = find(f, key);
      if (!e) return;
      const YAML::Node& pn = value(*e);
      const Fields g = fields(pn, std::string("the ") + key + " of a bushing", {"translation", "rotation"});
      if (const Entry* t = find(g, "translation"))
        translation = vec3(*t, std::string("a bushing ") + key, Scope::parameters);
      if (const Entry* r = find(g, "rotation"))
        rotation = vec3(*r, std::string("a bushing ") + key, Scope::parameters);
    };
    pair("stiffness", b.k_translation, b.k_rotation);
    pair("damping", b.d_translation, b.d_rotation);
    b.where = where;
    model_->add_bushing(b);
  } else if (type == "generalized") {
    GeneralizedForce g;
    g.name = force_name;
    g.coordinate = check_coordinate(value(require(f, "coordinate", n, what)));
    g.value = expr(require(f, "value", n, what), "a generalized force", Scope::any);
    if (const Entry* c = find(f, "category")) {
      const YAML::Node& cn = value(*c);
      const std::string category = scalar(cn, "a category");
      static const std::vector<std::string> allowed = {"generalized", "springs", "dampers"};
      if (category == "springs") g.category = Category::springs;
      else if (category == "dampers") g.category = Category::dampers;
      else if (category != "generalized")
        fail(cn, "unknown category '" + category + "' of a generalized force" +
                     [&] {
                       std::string h = suggestion(category, allowed);
                       return h.empty() ? " (one of: " + join(allowed) + ")" : h;
                     }());
    }
    g.where = where;
    model_->add_generalized_force(g);
  } else {  // applied
    AppliedForce a;
    a.name = force_name;
    a.marker = check_marker(value(require(f, "marker", n, what)));
    if (const Entry* e = find(f, "frame")) {
      const YAML::Node& fn = value(*e);
      const std::string frame = scalar(fn, "a frame (world or marker)");
      if (frame == "world") a.frame = ForceFrame::world;
      else if (frame == "marker") a.frame = ForceFrame::marker;
      else fail(fn, "unknown frame '" + frame + "' (world or marker)");
    }
    if (!find(f, "force") && !find(f, "torque"))
      fail(n, "an applied force needs 'force', 'torque' or both");
    if (const Entry* e = find(f, "force")) a.force = vec3(*e, "a force", Scope::any);
    if (const Entry* e = find(f, "torque")) a.torque = vec3(*e, "a torque", Scope::any);
    a.where = where;
    model_->add_applied_force(a);
  }
}

void Reader::read_output(const YAML::Node& n) {
  static const std::vector<std::string> types = {"position", "velocity", "coordinate", "rate",
                                                 "expression", "reaction", "force"};
  if (!n.IsMap()) fail(n, "expected a map for an output, got " + describe(n));
  const YAML::Node type_node = n["type"];
  if (!type_node) fail(n, "an output needs the key 'type' (one of: " + join(types) + ")");
  const std::string type = scalar(type_node, "an output type");
  if (std::find(types.begin(), types.end(), type) == types.end()) {
    std::string hint = suggestion(type, types);
    if (hint.empty()) hint = " (one of: " + join(types) + ")";
    fail(type_node, "unknown output type '" + type + "'" + hint);
  }
  std::vector<std::string> keys = {"name", "type", "unit"};
  if (type == "position" || type == "velocity") keys.insert(keys.end(), {"marker", "direction", "relative_to"});
  if (type == "coordinate" || type == "rate") keys.insert(keys.end(), {"coordinate"});
  if (type == "expression") keys.insert(keys.end(), {"expression"});
  if (type == "reaction") keys.insert(keys.end(), {"of", "quantity", "direction", "frame"});
  if (type == "force") keys.insert(keys.end(), {"elements", "quantity", "direction", "frame"});
  const std::string what = "a " + type + " output";
  const Fields f = fields(n, what, keys);
  Output o;
  o.name = name(require(f, "name", n, what), "an output name");
  o.where = element_loc(n);
  if (const Entry* u = find(f, "unit")) o.unit = scalar(value(*u), "a unit");
  if (type == "position" || type == "velocity") {
    o.kind = type == "position" ? OutputKind::position : OutputKind::velocity;
    o.marker = check_marker(value(require(f, "marker", n, what)));
    o.direction = vec3(require(f, "direction", n, what), "an output direction", Scope::parameters);
    if (const Entry* r = find(f, "relative_to")) o.relative_to = check_marker(value(*r));
  } else if (type == "coordinate" || type == "rate") {
    o.kind = type == "coordinate" ? OutputKind::coordinate : OutputKind::rate;
    o.coordinate = check_coordinate(value(require(f, "coordinate", n, what)));
  } else if (type == "reaction" || type == "force") {
    read_load_output(n, type, f, o);
  } else {
    o.kind = OutputKind::expression;
    o.expression = expr(require(f, "expression", n, what), "an output expression", Scope::no_inputs);
  }
  model_->add_output(o);
}

// `type: reaction` (of: a body or a constraint) and `type: force` (elements: force elements),
// with quantity force|torque and a direction in the world frame or a frame (reactions.hpp).
void Reader::read_load_output(const YAML::Node& n, const std::string& type, const Fields& f, Output& o) {
  const std::string what = "a " + type + " output";
  if (const Entry* q = find(f, "quantity")) {
    const std::string quantity = scalar(value(*q), "a quantity");
    if (quantity != "force" && quantity != "torque")
      fail(value(*q), "unknown quantity '" + quantity + "' (force or torque)");
    o.quantity = quantity == "force" ? ForceQuantity::force : ForceQuantity::torque;
  }
  o.direction = vec3(require(f, "direction", n, what), "an output direction", Scope::parameters);
  const Entry* frame = find(f, "frame");
  const std::string frame_name = frame ? scalar(value(*frame), "a frame") : "world";
  if (type == "reaction") {
    o.kind = OutputKind::reaction;
    o.reaction_of = name(require(f, "of", n, what), "a body or constraint name");
    if (frame_name != "world") o.frame_marker = check_marker(value(*frame));
    return;
  }
  o.kind = OutputKind::force;
  const YAML::Node& list_node = value(require(f, "elements", n, what));
  if (!list_node.IsSequence() || list_node.size() == 0)
    fail(list_node, "'elements' needs a list of force element names, got " + describe(list_node));
  for (const auto& element : list_node) o.elements.push_back(scalar(element, "a force element name"));
  if (frame_name != "world" && frame_name != "marker")
    fail(value(*frame), "a force output's frame is 'world' or 'marker' (marker b of its first element), got '" +
                            frame_name + "'");
  o.force_frame = frame_name == "world" ? ForceFrame::world : ForceFrame::marker;
}

// A loop-closure constraint (model.hpp, Constraint): a joint between two markers, a rod of a
// length, or an expression Φ(y) = 0.
void Reader::read_constraint(const YAML::Node& n, std::map<std::string, int>& counters) {
  static const std::vector<std::string> types = {"spherical", "revolute", "prismatic", "planar", "distance",
                                                 "expression", "rolling"};
  if (!n.IsMap()) fail(n, "expected a map for a constraint, got " + describe(n));
  const YAML::Node type_node = n["type"];
  if (!type_node) fail(n, "a constraint needs the key 'type' (one of: " + join(types) + ")");
  const std::string type = scalar(type_node, "a constraint type");
  if (std::find(types.begin(), types.end(), type) == types.end()) {
    std::string hint = suggestion(type, types);
    fail(type_node, "unknown constraint type '" + type + "'" + (hint.empty() ? " (one of: " + join(types) + ")" : hint));
  }
  std::vector<std::string> keys = {"type", "name"};
  if (type == "expression") keys.push_back("expression");
  else if (type == "rolling") keys.insert(keys.end(), {"wheel", "radius", "axis", "normal"});
  else keys.push_back("between");
  if (type == "distance") keys.push_back("length");
  const std::string what = "a " + type + " constraint";
  const Fields f = fields(n, what, keys);
  Constraint c;
  if (const Entry* e = find(f, "name")) {
    c.name = name(*e, "a constraint name");
  } else {
    int& k = counters[type];
    do c.name = type + std::to_string(++k);
    while (used_names_.count(c.name));
  }
  used_names_.insert(c.name);
  c.where = element_loc(n);
  static const std::map<std::string, ConstraintKind> kinds = {
      {"spherical", ConstraintKind::spherical}, {"revolute", ConstraintKind::revolute},
      {"prismatic", ConstraintKind::prismatic}, {"planar", ConstraintKind::planar},
      {"distance", ConstraintKind::distance},   {"expression", ConstraintKind::expression},
      {"rolling", ConstraintKind::rolling}};
  c.kind = kinds.at(type);
  if (type == "rolling") {
    read_rolling(f, n, c);
  } else if (type == "expression") {
    c.expression = expr(require(f, "expression", n, what), "a constraint expression", Scope::positions);
  } else {
    const YAML::Node& bn = value(require(f, "between", n, what));
    if (!bn.IsSequence() || bn.size() != 2)
      fail(bn, "'between' needs a list of two marker names [A, B], got " +
                   (bn.IsSequence() ? std::to_string(bn.size()) + " entries" : describe(bn)));
    c.marker_a = check_marker(bn[0]);
    c.marker_b = check_marker(bn[1]);
    if (c.marker_a == c.marker_b) fail(bn[1], "a " + type + " constraint between marker '" + c.marker_a + "' and itself");
  }
  if (type == "distance") c.length = expr(require(f, "length", n, what), "a rod length", Scope::parameters);
  model_->add_constraint(c);
}

// A wheel rolling on the ground: `wheel` (a marker at its centre, on the wheel body), `radius`,
// `axis` (the marker's axis along the axle: x, y or z; default z) and the ground's unit `normal`
// (numbers, world frame; default [0, 0, 1]).
void Reader::read_rolling(const Fields& f, const YAML::Node& n, Constraint& c) {
  const std::string what = "a rolling constraint";
  c.marker_a = check_marker(value(require(f, "wheel", n, what)));
  c.length = expr(require(f, "radius", n, what), "a wheel radius", Scope::parameters);
  if (const Entry* a = find(f, "axis")) {
    const std::string axis = scalar(value(*a), "a wheel axis");
    if (axis != "x" && axis != "y" && axis != "z")
      fail(value(*a), "a wheel's axis is the wheel marker's x, y or z axis, got '" + axis + "'");
    c.axis = axis[0] - 'x';
  }
  if (const Entry* e = find(f, "normal")) c.normal = vec3(*e, "a ground normal", Scope::constants);
}

// `nonholonomic:` velocity constraints, expressions linear in the rates (model.hpp,
// VelocityConstraint): `- {name: N, expression: E}` or `- E` (named nonholonomic1, ...).
void Reader::read_velocity_constraints(const Entry* e) {
  int k = 0;
  for (const auto& n : list(e, "nonholonomic")) {
    VelocityConstraint v;
    v.where = element_loc(n);
    if (n.IsMap()) {
      const Fields f = fields(n, "a nonholonomic constraint", {"name", "expression"});
      if (const Entry* ne = find(f, "name")) v.name = name(*ne, "a constraint name");
      v.expression = expr(require(f, "expression", n, "a nonholonomic constraint"), "a nonholonomic constraint",
                          Scope::no_inputs);
    } else {
      v.expression = expr(n, "a nonholonomic constraint", Scope::no_inputs);
    }
    if (v.name.empty()) {
      do v.name = "nonholonomic" + std::to_string(++k);
      while (used_names_.count(v.name));
    }
    used_names_.insert(v.name);
    model_->add_velocity_constraint(v);
  }
}

// `reduced_form: {NAME: MATRIX, NAME: MATRIX/MONOMIAL, ...}`: named parts of the reduced
// second-order form, MATRIX one of M, Q, K and MONOMIAL a product of powers of parameters
// (C1: Q/v is the coefficient of v in Q).
void Reader::read_reduced_form(const Entry& e) {
  const YAML::Node& n = value(e);
  if (!n.IsMap()) fail(n, "expected a map NAME: MATRIX or NAME: MATRIX/MONOMIAL for the reduced form, got " + describe(n));
  std::vector<NamedCoefficient> out;
  for (auto it = n.begin(); it != n.end(); ++it) {
    NamedCoefficient c;
    c.name = scalar(it->first, "a matrix name");
    if (!is_identifier(c.name)) fail(it->first, "a reduced-form matrix name must be an identifier, got '" + c.name + "'");
    c.where = loc(it->second);
    const std::string text = scalar(it->second, "a reduced-form part");
    const std::size_t slash = text.find('/');
    const std::string matrix = text.substr(0, slash);
    if (matrix != "M" && matrix != "Q" && matrix != "K")
      fail(it->second, "a reduced-form part is M, Q or K, optionally per a monomial of parameters (K/g, Q/v), got '" +
                           text + "'");
    c.matrix = matrix[0];
    if (slash != std::string::npos) {
      // A node made from the text has no place in the file: errors are placed at the part's value.
      const YAML::Node monomial(text.substr(slash + 1));
      try {
        c.monomial = expr(monomial, "a reduced-form monomial", Scope::parameters);
      } catch (const ModelError& error) {
        fail(it->second, error.message() + " (in the reduced-form part '" + text + "')");
      }
    }
    for (const auto& other : out)
      if (other.name == c.name) fail(it->first, "reduced-form matrix '" + c.name + "' is named twice");
    out.push_back(c);
  }
  model_->set_reduced_coefficients(std::move(out));
}

void Reader::read_operating_point(const Entry& e) {
  const YAML::Node& n = value(e);
  const OperatingPointOverride values = read_operating_point_values(n, "the operating point");
  LinearizationPoint op;
  op.where = values.where;
  op.kind = values.kind.value_or(LinearizationPoint::Kind::given);
  op.position = values.position;
  op.velocity = values.velocity;
  model_->set_operating_point(op);
}

OperatingPointOverride Reader::read_operating_point_values(const YAML::Node& n, const std::string& what) {
  const Fields f = fields(n, what, {"type", "position", "velocity"});
  OperatingPointOverride op;
  op.where = loc(n);
  if (const Entry* t = find(f, "type")) {
    const YAML::Node& tn = value(*t);
    const std::string type = scalar(tn, "an operating point type (given or equilibrium)");
    if (type == "given") op.kind = LinearizationPoint::Kind::given;
    else if (type == "equilibrium") op.kind = LinearizationPoint::Kind::equilibrium;
    else fail(tn, "unknown operating point type '" + type + "' (given or equilibrium)");
  }
  auto values = [&](const char* key, std::map<std::string, GiNaC::ex>& out) {
    const Entry* v = find(f, key);
    if (!v || v->value.IsNull()) return;
    const YAML::Node& vn = v->value;
    if (!vn.IsMap())
      fail(vn, std::string("expected a map 'coordinate: value' for the operating point's ") + key +
                   ", got " + describe(vn));
    std::set<std::string> seen;
    for (auto it = vn.begin(); it != vn.end(); ++it) {
      const std::string c = check_coordinate(it->first);
      if (!seen.insert(c).second) fail(it->first, "coordinate '" + c + "' is given twice");
      if (it->second.IsNull()) fail(it->first, "coordinate '" + c + "' has no value");
      out[c] = expr(it->second, "an operating point value", Scope::parameters);
    }
  };
  values("position", op.position);
  values("velocity", op.velocity);
  return op;
}

std::vector<SceneItem> Reader::items(const Entry& e, const std::string& what) const {
  std::vector<SceneItem> out;
  for (const auto& n : list(&e, what)) out.push_back({scalar(n, "a name in " + what), loc(n)});
  return out;
}

void Reader::read_scene(const YAML::Node& n) {
  const Fields f = fields(n, "a scene",
                          {"name", "description", "analyses", "effects", "without", "inputs",
                           "outputs", "operating_point", "frequency_range", "sensitivity"});
  Scene s;
  s.name = name(require(f, "name", n, "a scene"), "a scene name");
  s.where = loc(n);
  const std::string what = "scene '" + s.name + "'";
  if (const Entry* d = find(f, "description")) s.description = scalar(value(*d), "a description");
  if (const Entry* a = find(f, "analyses")) {
    static const std::vector<std::string> known = {"modes", "frf", "static", "simulate", "sensitivity"};
    s.analyses.clear();
    std::map<std::string, SourceLocation> seen;
    for (const auto& an : list(a, "the analyses of " + what)) {
      const std::string k = scalar(an, "an analysis (modes, frf, static, simulate or sensitivity)");
      if (std::find(known.begin(), known.end(), k) == known.end()) {
        std::string hint = suggestion(k, known);
        if (hint.empty()) hint = " (one of: " + join(known) + ")";
        fail(an, "unknown analysis '" + k + "' in " + what + hint);
      }
      if (auto [at, inserted] = seen.emplace(k, loc(an)); !inserted)
        fail(an, "'" + k + "' is listed twice in " + what + " (first at " + at->second.str() + ")");
      s.analyses.push_back(k == "modes"    ? Analysis::modes
                           : k == "frf"    ? Analysis::frf
                           : k == "static" ? Analysis::statics
                           : k == "simulate" ? Analysis::simulate
                                             : Analysis::sensitivity);
    }
    if (s.analyses.empty()) fail(a->key, what + " asks for no analysis (modes, frf, static, simulate, sensitivity)");
  }
  if (const Entry* e = find(f, "effects")) s.effects = items(*e, "the effects of " + what);
  if (const Entry* e = find(f, "without")) s.without = items(*e, "the effects " + what + " is without");
  if (const Entry* e = find(f, "inputs")) s.inputs = items(*e, "the inputs of " + what);
  if (const Entry* e = find(f, "outputs")) s.outputs = items(*e, "the outputs of " + what);
  if (const Entry* e = find(f, "sensitivity")) s.sensitivity = items(*e, "the sensitivity parameters of " + what);
  if (const Entry* op = find(f, "operating_point"))
    s.operating_point = read_operating_point_values(value(*op), "the operating point of " + what);
  if (const Entry* fr = find(f, "frequency_range")) {
    const YAML::Node& fn = value(*fr);
    const Fields g = fields(fn, "a frequency range", {"from", "to", "points", "spacing"});
    FrequencyRange range;
    range.where = loc(fn);
    auto hz = [&](const char* key) {
      const Entry& e = require(g, key, fn, "a frequency range");
      const GiNaC::ex v = evaluate(value(e), expr(e, std::string("a frequency (Hz)"), Scope::constants));
      if (!GiNaC::is_a<GiNaC::numeric>(v) || !GiNaC::ex_to<GiNaC::numeric>(v).is_real())
        fail(value(e), "a frequency must be a real number (Hz)");
      return GiNaC::ex_to<GiNaC::numeric>(v).to_double();
    };
    range.from_hz = hz("from");
    range.to_hz = hz("to");
    if (const Entry* p = find(g, "points")) {
      const YAML::Node& pn = value(*p);
      const std::string t = scalar(pn, "a number of points");
      std::size_t used = 0;
      long k = 0;
      try {
        k = std::stol(t, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != t.size() || k < 2 || k > 10000000)
        fail(pn, "the number of points must be an integer from 2 to 10000000, got '" + t + "'");
      range.points = static_cast<int>(k);
    }
    if (const Entry* sp = find(g, "spacing")) {
      const YAML::Node& sn = value(*sp);
      const std::string t = scalar(sn, "a spacing (log or linear)");
      if (t == "log") range.logarithmic = true;
      else if (t == "linear") range.logarithmic = false;
      else fail(sn, "unknown spacing '" + t + "' (log or linear)");
    }
    if (!(range.to_hz > range.from_hz) || range.from_hz < 0)
      fail(fn, "a frequency range needs 0 <= from < to (Hz)");
    if (range.logarithmic && !(range.from_hz > 0))
      fail(fn, "a logarithmic frequency range needs from > 0 (or spacing: linear)");
    s.frequency_range = range;
  }
  model_->add_scene(s);
}

}  // namespace

namespace detail {

GiNaC::ex parse_expression(const Model& model, const std::string& text) {
  return parse_checked(model, text, nullptr);
}

}  // namespace detail

Model read_model_string(const std::string& text, const std::string& file_name) {
  return Reader(text, file_name).read();
}

std::string read_model_text(const std::string& path) {
  // Non-blocking open and fstat on the same descriptor: a FIFO, a device (/dev/zero), a socket or
  // a directory is refused before a byte is read; 64 MiB at most (the largest model shipped is
  // 30 kB).
  constexpr std::size_t kMax = std::size_t{64} << 20;
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) throw ModelError({path, 0, 0}, std::string("cannot open the model file: ") + std::strerror(errno));
  struct stat st {};
  const bool stat_ok = ::fstat(fd, &st) == 0;
  if (!stat_ok || !S_ISREG(st.st_mode)) {
    ::close(fd);
    const char* kind = S_ISDIR(st.st_mode)    ? "a directory"
                       : S_ISFIFO(st.st_mode) ? "a FIFO (named pipe)"
                       : S_ISCHR(st.st_mode)  ? "a character device"
                       : S_ISBLK(st.st_mode)  ? "a block device"
                       : S_ISSOCK(st.st_mode) ? "a socket"
                                              : "not a regular file";
    throw ModelError({path, 0, 0}, stat_ok ? std::string("is ") + kind + ", not a model file (a regular file)"
                                           : "cannot inspect the model file");
  }
  if (static_cast<unsigned long long>(st.st_size) > kMax) {
    ::close(fd);
    throw ModelError({path, 0, 0}, "is " + std::to_string(st.st_size) + " bytes; a model file may have at most " +
                                       std::to_string(kMax) + " bytes");
  }
  std::string text;
  char buf[65536];
  for (;;) {
    const ssize_t r = ::read(fd, buf, sizeof buf);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) {
      ::close(fd);
      throw ModelError({path, 0, 0}, "cannot read the model file");
    }
    if (r == 0) break;
    text.append(buf, static_cast<std::size_t>(r));
    if (text.size() > kMax) {
      ::close(fd);
      throw ModelError({path, 0, 0}, "grew beyond " + std::to_string(kMax) + " bytes while being read");
    }
  }
  ::close(fd);
  return text;
}

Model read_model_file(const std::string& path) {
  // A URDF file is imported with the default options (urdf_import.hpp); YAML errors in what the
  // import wrote (which mbsgen import shows) are at the lines of that text.
  if (is_urdf_path(path)) {
    const std::string text = import_urdf_file(path).yaml;
    try {
      return read_model_string(text, path + " (as imported)");
    } catch (const ModelError& e) {  // at lines of a text the user has not seen: say where to see it
      throw ModelError({path, 0, 0}, "the model imported from it is refused: " + e.message() + " (at " +
                                         e.where().str() + " of the text that `mbsgen import " + path +
                                         "` prints)");
    }
  }
  return read_model_string(read_model_text(path), path);
}

}  // namespace mbsgen
