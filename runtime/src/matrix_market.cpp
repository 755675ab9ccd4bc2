#include "mbsgen/runtime/matrix_market.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <vector>

#include "mbsgen/runtime/error.hpp"

namespace mbsgen {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

[[noreturn]] void fail(const std::string& name, long line, const std::string& why) {
  std::ostringstream s;
  s << name << ":" << line << ": " << why;
  throw ParseError(s.str());
}

bool blank_or_comment(const std::string& l) {
  for (char c : l) {
    if (c == '%') return true;
    if (!std::isspace(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

}  // namespace

Eigen::MatrixXd read_matrix_market(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw ParseError(path + ": is a directory, not a file");
  std::ifstream in(path);
  if (!in) throw ParseError(path + ": cannot open file");
  return read_matrix_market(in, path);
}

Eigen::MatrixXd read_matrix_market(std::istream& in, const std::string& name) {
  std::string line;
  long lineno = 0;
  if (!std::getline(in, line)) fail(name, 1, "empty file (expected a %%MatrixMarket header)");
  ++lineno;
  std::istringstream hs(line);
  std::string banner, object, format, field, symmetry;
  hs >> banner >> object >> format >> field >> symmetry;
  if (banner != "%%MatrixMarket")
    fail(name, lineno, "missing '%%MatrixMarket' banner");
  object = lower(object);
  format = lower(format);
  field = lower(field);
  symmetry = lower(symmetry);
  if (object != "matrix") fail(name, lineno, "object '" + object + "' is not 'matrix'");
  if (format != "array" && format != "coordinate")
    fail(name, lineno, "format '" + format + "' is neither 'array' nor 'coordinate'");
  if (field != "real" && field != "integer" && field != "double")
    fail(name, lineno, "field '" + field + "' not supported (real or integer only)");
  if (symmetry != "general" && symmetry != "symmetric" && symmetry != "skew-symmetric")
    fail(name, lineno, "symmetry '" + symmetry + "' not supported");
  const bool sym = symmetry == "symmetric", skew = symmetry == "skew-symmetric";

  do {
    if (!std::getline(in, line)) fail(name, lineno + 1, "missing size line");
    ++lineno;
  } while (blank_or_comment(line));
  long rows = -1, cols = -1, nnz = -1;
  {
    std::istringstream ss(line);
    ss >> rows >> cols;
    if (format == "coordinate") ss >> nnz;
    std::string rest;
    if (!ss || rows < 0 || cols < 0 || (format == "coordinate" && nnz < 0) || (ss >> rest))
      fail(name, lineno, "malformed size line '" + line + "'");
  }
  if ((sym || skew) && rows != cols) fail(name, lineno, "symmetric storage of a non-square matrix");
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, cols);

  auto next_data_line = [&](long k, long total) {
    do {
      if (!std::getline(in, line)) {
        std::ostringstream s;
        s << "file ends after " << k << " of " << total << " entries";
        fail(name, lineno + 1, s.str());
      }
      ++lineno;
    } while (blank_or_comment(line));
  };
  auto parse_value = [&](std::istringstream& ss) {
    std::string tok;
    if (!(ss >> tok)) fail(name, lineno, "missing value");
    char* end = nullptr;
    const double v = std::strtod(tok.c_str(), &end);
    if (end == tok.c_str() || *end != '\0') fail(name, lineno, "bad number '" + tok + "'");
    if (!std::isfinite(v)) {
      std::ostringstream s;
      s << name << ":" << lineno << ": non-finite entry '" << tok << "'";
      throw NonFiniteError(s.str());
    }
    return v;
  };

  if (format == "array") {
    // Column-major; symmetric: lower triangle incl. diagonal; skew: strictly lower triangle.
    const long total = (sym) ? rows * (rows + 1) / 2 : (skew ? rows * (rows - 1) / 2 : rows * cols);
    long k = 0;
    for (long j = 0; j < cols; ++j) {
      const long i0 = sym ? j : (skew ? j + 1 : 0);
      for (long i = i0; i < rows; ++i, ++k) {
        next_data_line(k, total);
        std::istringstream ss(line);
        const double v = parse_value(ss);
        A(i, j) = v;
        if (sym) A(j, i) = v;
        if (skew) A(j, i) = -v;
      }
    }
  } else {
    for (long k = 0; k < nnz; ++k) {
      next_data_line(k, nnz);
      std::istringstream ss(line);
      long i = 0, j = 0;
      if (!(ss >> i >> j)) fail(name, lineno, "malformed entry '" + line + "'");
      if (i < 1 || i > rows || j < 1 || j > cols) {
        std::ostringstream s;
        s << "index (" << i << "," << j << ") outside " << rows << "x" << cols;
        fail(name, lineno, s.str());
      }
      const double v = parse_value(ss);
      A(i - 1, j - 1) += v;
      if (i != j && sym) A(j - 1, i - 1) += v;
      if (i != j && skew) A(j - 1, i - 1) -= v;
    }
  }
  while (std::getline(in, line)) {
    ++lineno;
    if (!blank_or_comment(line)) fail(name, lineno, "unexpected data after the last entry");
  }
  return A;
}

void write_matrix_market(const std::string& path, const Eigen::MatrixXd& A,
                         MatrixMarketFormat format, const std::string& comment) {
  std::ofstream out(path);
  if (!out) throw Error("write_matrix_market: cannot open '" + path + "' for writing");
  write_matrix_market(out, A, format, comment);
  if (!out) throw Error("write_matrix_market: error writing '" + path + "'");
}

void write_matrix_market(std::ostream& out, const Eigen::MatrixXd& A, MatrixMarketFormat format,
                         const std::string& comment) {
  const auto old = out.precision(std::numeric_limits<double>::max_digits10);
  out << "%%MatrixMarket matrix " << (format == MatrixMarketFormat::array ? "array" : "coordinate")
      << " real general\n";
  if (!comment.empty()) {
    std::istringstream cs(comment);
    std::string l;
    while (std::getline(cs, l)) out << "% " << l << "\n";
  }
  if (format == MatrixMarketFormat::array) {
    out << A.rows() << " " << A.cols() << "\n";
    for (Eigen::Index j = 0; j < A.cols(); ++j)
      for (Eigen::Index i = 0; i < A.rows(); ++i) out << A(i, j) << "\n";
  } else {
    const Eigen::Index nnz = (A.array() != 0.0).count();
    out << A.rows() << " " << A.cols() << " " << nnz << "\n";
    for (Eigen::Index j = 0; j < A.cols(); ++j)
      for (Eigen::Index i = 0; i < A.rows(); ++i)
        if (A(i, j) != 0.0) out << i + 1 << " " << j + 1 << " " << A(i, j) << "\n";
  }
  out.precision(old);
}

}  // namespace mbsgen
