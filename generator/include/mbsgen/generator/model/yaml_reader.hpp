// Reading a model file (YAML, format in docs/model-format.md) into an mbsgen::Model.
//
// The reader is a client of the C++ model API (model.hpp): it creates parameters, coordinates
// and inputs first, then bodies, markers, forces, outputs and the operating point, and finally
// calls Model::validate(). Every problem is reported as a ModelError whose what() reads
// `FILE:LINE:COL: error: message` (1-based), located at the offending YAML node, or at the
// offending character inside an expression when the expression is written on one line.
#pragma once

#include "mbsgen/generator/model/model.hpp"

#include <string>
#include <vector>

namespace mbsgen {

/// Reads and validates the model in the YAML file `path`.
/// Throws ModelError (a syntax error, an unknown key, a missing key, a node of the wrong kind,
/// an unknown symbol or a bad expression, a vector or matrix of the wrong size, or anything
/// Model::add_* and Model::validate() reject); an unreadable file is a ModelError at `path`.
Model read_model_file(const std::string& path);

/// The text of the model file `path`, read without ever blocking: a FIFO, a device, a socket or
/// a directory is a ModelError at `path` before a byte is read, as is a file above 64 MiB.
std::string read_model_text(const std::string& path);

/// Reads and validates a model from YAML `text`; `file_name` is used in error locations only.
Model read_model_string(const std::string& text, const std::string& file_name);

namespace detail {

/// Parses one expression of a model file against `model.symbol_table()` (exposed for tests).
/// Decimal literals (`0.5`, `1e-6`, `2.5E3`) become exact rationals; only the functions sin, cos,
/// tan, asin, acos, atan, atan2, sinh, cosh, tanh, asinh, acosh, atanh, exp, log, sqrt, abs,
/// pow and the constants Pi, Euler, Catalan are known. Nesting (parentheses, calls, signs) is
/// limited to 100 levels; exact powers whose numbers would exceed 2^20 bits, divisions by zero and
/// constant function values outside double's range or CLN's accuracy (exp(1e9999), sin(1e50); see
/// docs/model-format.md) are refused. On error throws ExpressionError with the 0-based offset of
/// the offending character within `text`.
GiNaC::ex parse_expression(const Model& model, const std::string& text);

/// A bad expression: `offset` is the 0-based position within the expression text.
class ExpressionError : public std::runtime_error {
 public:
  ExpressionError(std::size_t offset, const std::string& what)
      : std::runtime_error(what), offset_(offset) {}
  std::size_t offset() const { return offset_; }

 private:
  std::size_t offset_;
};

/// Edit distance (insertions, deletions, substitutions, adjacent transpositions).
std::size_t edit_distance(const std::string& a, const std::string& b);

/// " (did you mean 'x'?)" for the candidate closest to `word` within a small edit distance
/// (1 for words up to 3 letters, 2 up to 6, else 3), or "" when there is none.
std::string suggestion(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace detail

}  // namespace mbsgen
