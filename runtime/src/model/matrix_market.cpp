#include "mbsgen/runtime/model/matrix_market.hpp"

#include "model/text_file.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
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

std::vector<std::string> tokens(const std::string& line) {
  std::vector<std::string> t;
  std::istringstream ss(line);
  for (std::string w; ss >> w;) t.push_back(w);
  return t;
}

bool blank(const std::string& l) {
  return std::all_of(l.begin(), l.end(), [](unsigned char c) { return std::isspace(c); });
}

// Lines of a Matrix Market stream, bounded: no line longer than kMatrixMarketMaxLine, no NUL
// byte, at most kMatrixMarketMaxBlankLines blank or comment lines. Errors carry name:line.
class Lines {
 public:
  Lines(std::istream& in, std::string name) : in_(*in.rdbuf()), name_(std::move(name)) {}

  long number() const { return number_; }
  const std::string& name() const { return name_; }

  [[noreturn]] void fail(const std::string& why) const { fail_at(number_, why); }
  [[noreturn]] void fail_at(long line, const std::string& why) const {
    throw ParseError(name_ + ":" + std::to_string(line) + ": " + why);
  }

  // The next line (without its end of line, CR LF or LF); false at the end of the input.
  bool next(std::string& line) {
    line.clear();
    ++number_;
    for (;;) {
      const int c = in_.sbumpc();
      if (c == std::char_traits<char>::eof()) return !line.empty();
      if (c == '\n') break;
      if (c == '\0') fail("a NUL byte: this is not a text file");
      if (line.size() == kMatrixMarketMaxLine)
        fail("line longer than " + std::to_string(kMatrixMarketMaxLine) +
             " characters (the format's limit)");
      line.push_back(static_cast<char>(c));
    }
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  }

  // The next line that is not blank and, in the header (`header`), not a '%' comment; false at
  // the end. Among the entries a comment is an error: the format has comments in its header only.
  bool next_content(std::string& line, bool header) {
    while (next(line)) {
      const bool comment = !line.empty() && line[0] == '%';
      if (comment && !header)
        fail("a comment among the entries (comments belong between the banner and the size line)");
      if (!blank(line) && !comment) return true;
      if (++skipped_ > kMatrixMarketMaxBlankLines)
        fail("more than " + std::to_string(kMatrixMarketMaxBlankLines) + " blank or comment lines");
    }
    return false;
  }

 private:
  std::streambuf& in_;
  std::string name_;
  long number_ = 0;
  long skipped_ = 0;
};

enum class Symmetry { general, symmetric, skew };

struct Header {
  bool coordinate = false, integer = false;
  Symmetry symmetry = Symmetry::general;
  long long rows = 0, cols = 0, entries = 0;  // entries: stored (declared, or implied by array)
};

std::string symmetry_name(Symmetry s) {
  return s == Symmetry::general ? "general" : (s == Symmetry::symmetric ? "symmetric" : "skew-symmetric");
}

void read_banner(Lines& lines, Header& h) {
  std::string line;
  if (!lines.next(line)) lines.fail("empty file (expected a %%MatrixMarket header)");
  const auto t = tokens(line);
  if (t.empty() || t[0] != "%%MatrixMarket")
    lines.fail("missing '%%MatrixMarket' banner (a Matrix Market file begins with it)");
  if (t.size() != 5)
    lines.fail("the banner has " + std::to_string(t.size()) +
               " words; expected '%%MatrixMarket matrix FORMAT FIELD SYMMETRY'");
  const std::string object = lower(t[1]), format = lower(t[2]), field = lower(t[3]),
                    symmetry = lower(t[4]);
  if (object != "matrix") lines.fail("object '" + t[1] + "' is not 'matrix'");
  if (format != "array" && format != "coordinate")
    lines.fail("format '" + t[2] + "' is neither 'array' nor 'coordinate'");
  if (field == "pattern")
    lines.fail("field 'pattern' has no values; mbsgen reads real or integer matrices");
  if (field != "real" && field != "integer" && field != "double")
    lines.fail("field '" + t[3] + "' not supported (real or integer only)");
  if (symmetry == "general") {
    h.symmetry = Symmetry::general;
  } else if (symmetry == "symmetric") {
    h.symmetry = Symmetry::symmetric;
  } else if (symmetry == "skew-symmetric") {
    h.symmetry = Symmetry::skew;
  } else {
    lines.fail("symmetry '" + t[4] + "' not supported (general, symmetric or skew-symmetric)");
  }
  h.coordinate = format == "coordinate";
  h.integer = field == "integer";
}

// A non-negative decimal integer of at most 18 digits; -1 when `t` is not one.
long long count(const std::string& t) {
  if (t.empty() || t.size() > 18 || !std::all_of(t.begin(), t.end(), [](unsigned char c) { return std::isdigit(c); }))
    return -1;
  return std::stoll(t);
}

void read_size(Lines& lines, Header& h) {
  std::string line;
  if (!lines.next_content(line, true)) lines.fail("missing size line");
  const auto t = tokens(line);
  const std::size_t want = h.coordinate ? 3 : 2;
  const char* form = h.coordinate ? "'ROWS COLUMNS ENTRIES'" : "'ROWS COLUMNS'";
  if (t.size() != want) lines.fail("malformed size line '" + line + "' (expected " + form + ")");
  h.rows = count(t[0]);
  h.cols = count(t[1]);
  const long long declared = h.coordinate ? count(t[2]) : 0;
  if (h.rows < 0 || h.cols < 0 || declared < 0)
    lines.fail("malformed size line '" + line + "' (expected " + form +
               ", non-negative integers of at most 18 digits)");
  const long long n = h.rows;
  if (h.symmetry != Symmetry::general && h.rows != h.cols)
    lines.fail(symmetry_name(h.symmetry) + " storage of a non-square " + std::to_string(h.rows) + "x" +
               std::to_string(h.cols) + " matrix");
  // Checked before anything is allocated: the matrix is read into dense storage.
  if (h.rows > 0 && h.cols > kMatrixMarketMaxEntries / h.rows) {
    std::ostringstream s;
    s << "a " << h.rows << "x" << h.cols << " matrix has " << std::setprecision(3)
      << static_cast<double>(h.rows) * static_cast<double>(h.cols) << " entries, more than the "
      << kMatrixMarketMaxEntries << " mbsgen reads (dense storage, 8 bytes each)";
    lines.fail(s.str());
  }
  const long long capacity = h.symmetry == Symmetry::symmetric ? n * (n + 1) / 2
                             : h.symmetry == Symmetry::skew    ? n * (n - 1) / 2
                                                               : h.rows * h.cols;
  if (h.coordinate && declared > capacity)
    lines.fail("declares " + std::to_string(declared) + " entries, but a " + std::to_string(h.rows) + "x" +
               std::to_string(h.cols) + " " + symmetry_name(h.symmetry) + " matrix stores at most " +
               std::to_string(capacity));
  h.entries = h.coordinate ? declared : capacity;
}

bool is_word(std::string t, const char* const* words) {
  if (!t.empty() && (t[0] == '+' || t[0] == '-')) t.erase(0, 1);
  t = lower(t);
  for (; *words; ++words)
    if (t == *words) return true;
  return false;
}

double value(const Lines& lines, const std::string& t, bool integer) {
  static const char* const non_finite[] = {"nan", "inf", "infinity", nullptr};
  if (is_word(t, non_finite)) throw NonFiniteError(lines.name() + ":" + std::to_string(lines.number()) +
                                                   ": non-finite entry '" + t + "'");
  const bool decimal = !t.empty() && std::all_of(t.begin(), t.end(), [](unsigned char c) {
    return std::isdigit(c) || c == '+' || c == '-' || c == '.' || c == 'e' || c == 'E';
  });
  char* end = nullptr;
  errno = 0;
  const double v = decimal ? std::strtod(t.c_str(), &end) : 0.0;
  if (!decimal || end == t.c_str() || *end != '\0') lines.fail("bad number '" + t + "'");
  if (std::isinf(v))
    throw NonFiniteError(lines.name() + ":" + std::to_string(lines.number()) + ": entry '" + t +
                         "' overflows double (magnitudes above 1.8e308)");
  if (errno == ERANGE && v == 0.0)
    lines.fail("entry '" + t + "' is below the smallest double (4.9e-324) and would read as 0");
  if (integer && t.find_first_of(".eE") != std::string::npos)
    lines.fail("entry '" + t + "' is not an integer (the field is 'integer')");
  return v;
}

void read_array(Lines& lines, const Header& h, Eigen::MatrixXd& A) {
  // Column-major; symmetric: lower triangle incl. diagonal; skew: strictly lower triangle.
  const bool sym = h.symmetry == Symmetry::symmetric, skew = h.symmetry == Symmetry::skew;
  std::string line;
  long long k = 0;
  for (Eigen::Index j = 0; j < A.cols(); ++j) {
    const Eigen::Index i0 = sym ? j : (skew ? j + 1 : 0);
    for (Eigen::Index i = i0; i < A.rows(); ++i, ++k) {
      if (!lines.next_content(line, false))
        lines.fail("file ends after " + std::to_string(k) + " of " + std::to_string(h.entries) + " entries");
      const auto t = tokens(line);
      if (t.size() != 1) lines.fail("expected one value per line, got '" + line + "'");
      const double v = value(lines, t[0], h.integer);
      A(i, j) = v;
      if (sym) A(j, i) = v;
      if (skew) A(j, i) = -v;
    }
  }
}

// A 1-based row or column index; fails unless it is a positive integer within n.
Eigen::Index index(const Lines& lines, const std::string& t, long long n, const std::string& line,
                   const Header& h) {
  const long long v = count(t);
  if (v < 0) lines.fail("malformed entry '" + line + "' (expected 'ROW COLUMN VALUE', 1-based)");
  if (v < 1 || v > n) {
    lines.fail("entry '" + line + "': index outside " + std::to_string(h.rows) + "x" + std::to_string(h.cols) +
               " (indices are 1-based)");
  }
  return static_cast<Eigen::Index>(v - 1);
}

void read_coordinate(Lines& lines, const Header& h, Eigen::MatrixXd& A) {
  const bool sym = h.symmetry == Symmetry::symmetric, skew = h.symmetry == Symmetry::skew;
  std::vector<bool> seen(static_cast<std::size_t>(h.rows * h.cols), false);
  std::string line;
  for (long long k = 0; k < h.entries; ++k) {
    if (!lines.next_content(line, false))
      lines.fail("file ends after " + std::to_string(k) + " of " + std::to_string(h.entries) + " entries");
    const auto t = tokens(line);
    if (t.size() < 3) lines.fail("malformed entry '" + line + "' (expected 'ROW COLUMN VALUE')");
    if (t.size() > 3) lines.fail("unexpected text '" + t[3] + "' after the entry '" + t[0] + " " + t[1] + " " + t[2] + "'");
    const Eigen::Index i = index(lines, t[0], h.rows, line, h), j = index(lines, t[1], h.cols, line, h);
    const std::string at = "(" + t[0] + "," + t[1] + ")";
    if (sym && i < j)
      lines.fail("entry " + at + " above the diagonal in a symmetric file: the format stores the lower "
                 "triangle only (row >= column)");
    if (skew && i <= j)
      lines.fail("entry " + at + (i == j ? " on the diagonal" : " above the diagonal") +
                 " in a skew-symmetric file: the format stores the strictly lower triangle only "
                 "(row > column; the diagonal is zero)");
    const std::size_t at_index = static_cast<std::size_t>(j) * static_cast<std::size_t>(h.rows) +
                                 static_cast<std::size_t>(i);
    if (seen[at_index]) lines.fail("duplicate entry " + at + " (each position may be given once)");
    seen[at_index] = true;
    const double v = value(lines, t[2], h.integer);
    A(i, j) = v;
    if (sym) A(j, i) = v;
    if (skew) A(j, i) = -v;
  }
}

}  // namespace

Eigen::MatrixXd read_matrix_market(const std::string& path) {
  // Regular files only (a FIFO or /dev/zero must not block or exhaust memory), up to 1 GiB: a
  // dense array of 5000×5000 entries in full precision is about 0.6 GiB.
  std::istringstream in(detail::read_regular_file<ParseError>(path, std::size_t{1} << 30));
  return read_matrix_market(in, path);
}

Eigen::MatrixXd read_matrix_market(std::istream& in, const std::string& name) {
  Lines lines(in, name);
  Header h;
  read_banner(lines, h);
  read_size(lines, h);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(h.rows), static_cast<Eigen::Index>(h.cols));
  if (h.coordinate) {
    read_coordinate(lines, h, A);
  } else {
    read_array(lines, h, A);
  }
  std::string line;
  if (lines.next_content(line, false))
    lines.fail("data after the last of the " + std::to_string(h.entries) + " entries: '" + line + "'");
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
