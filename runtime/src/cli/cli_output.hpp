// Result formatting shared by `mbsgen linear` and the model solvers (docs/cli.md): tables for
// people, JSON and CSV for programs, full precision in the machine formats.
#pragma once

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

namespace mbsgen::cli {

/// 17 significant digits; an undefined value (NaN) is "null" in JSON and an empty field otherwise,
/// an infinite one "null" in JSON and "inf"/"-inf" otherwise.
std::string num(double v, bool json);
/// %.6e, for tables ("-" for an undefined value, "inf"/"-inf").
std::string short_num(double v);
/// v in a printf `format` with one double ("%.6g"); NaN (a statistic of no values: every
/// evaluation failed, or one value for an sd) is "-", never printed as a number.
std::string fixed(double v, const char* format);
/// The largest frequency the command lines take [Hz]: its angular frequency 2π f stays finite
/// (1e308 Hz gave "frequency 186 is inf rad/s" from the library, exit 1).
inline constexpr double kMaxFrequencyHz = 1e300;
/// A command-line frequency in Hz: a finite number in [0, 1e300], with a readable message otherwise.
inline CLI::Validator frequency_hz() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        try {
          std::size_t used = 0;
          const double v = std::stod(text, &used);
          if (used == text.size() && std::isfinite(v) && v >= 0 && v <= kMaxFrequencyHz) return "";
        } catch (const std::exception&) {
        }
        return "'" + text + "' is not a frequency in Hz (a finite number in [0, 1e300])";
      },
      "HZ", "frequency_hz");
}
/// A seed: an unsigned 64-bit integer written in decimal digits (CLI11 took "-1" as 2^64 - 1 and
/// 1e30 digits as the largest seed, silently).
inline CLI::Validator seed_value() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        static const std::string max = "18446744073709551615";
        const bool digits = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
        std::string t = text.substr(std::min(text.find_first_not_of('0'), text.size()));
        if (digits && (t.size() < max.size() || (t.size() == max.size() && t <= max))) return "";
        return "'" + text + "' is not a seed (an integer in [0, 18446744073709551615])";
      },
      "SEED", "seed_value");
}
/// A command-line number that must be finite and within [lo, hi] (lo excluded when lo_open):
/// `nan`, `inf`, 1e400 and out-of-range values are usage errors (exit 2) whose message states the
/// range as written in `range` (never DBL_MAX written out).
inline CLI::Validator finite_in(double lo, double hi, bool lo_open, const std::string& range) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        try {
          std::size_t used = 0;
          const double v = std::stod(text, &used);
          if (used == text.size() && std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi) return "";
        } catch (const std::exception&) {
        }
        return "'" + text + "' is not " + range;
      },
      "NUMBER", "finite_in");
}
/// The most frequencies a sweep may have (--points of both command lines): a sweep keeps its
/// results in memory (about 100 bytes a point) before printing them (about 100 bytes a line).
inline constexpr long kMaxFrequencyPoints = 1'000'000;
/// Checks a sweep's range as both command lines take it; "" when valid, else the reason (a usage
/// error): log spacing needs from, to > 0; from must not exceed to, and equals it only for one
/// point.
std::string sweep_problem(double from_hz, double to_hz, long points, bool log_spacing);
/// The frequencies of a valid sweep [Hz], both ends included (the last exactly to_hz).
Eigen::VectorXd sweep_hz(double from_hz, double to_hz, long points, bool log_spacing);
/// Right-aligned in a field of width w.
std::string pad(const std::string& s, std::size_t w);
/// A JSON string literal.
std::string json_string(const std::string& s);
/// s as a CSV field: quoted, quotes doubled, line breaks as spaces (a model's names and error
/// messages are data: a comma, quote or newline in them must not shift the columns or lines).
std::string csv_field(const std::string& s);

struct ModesFormat {
  std::string format = "table";                  // table | json | csv
  bool shapes = false;                           // print mode shapes
  std::vector<std::string> coordinate_names;     // for shapes
};

/// Writes the modes; the table ends with a line "# method …, rank M …, rank K …".
void write_modes(std::ostream& out, const QuadraticEigenSolver& solver, Eigen::Index size,
                 const ModesFormat& f);
/// The same for any list of modes (the first-order solver of nonholonomic models); the table's
/// footer starts with `method_line` (ending in a newline).
void write_modes(std::ostream& out, const std::vector<Mode>& modes, Stability stability, Eigen::Index size,
                 const ModesFormat& f, const std::string& method_line);

struct FrfTable {
  std::string format = "table";
  std::string input_json, output_json;    // JSON values of "input" and "output"
  std::string input_label, output_label;  // for the table's last line
};

/// One output's response to one input at the frequencies hz, as computed.
struct FrfResult {
  Eigen::VectorXd hz;
  Eigen::VectorXcd g;
  Eigen::VectorXd rcond;
  std::vector<FrfFlag> flags;
  FrfMethod method = FrfMethod::automatic;
};

/// Writes the response of one output to one input at the frequencies hz.
void write_frf(std::ostream& out, const FrfResult& r, const FrfTable& t);

}  // namespace mbsgen::cli
