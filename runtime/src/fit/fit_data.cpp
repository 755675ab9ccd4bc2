// Measured data (CSV) and fitted parameters ("NAME=LO:HI[:PRIOR][:lin]") for fit(): the
// readers of fit.hpp. Every message names the file, line and column of what is wrong.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/fit/fit.hpp"
#include "mbsgen/runtime/model/generated_model.hpp"
#include "model/text_file.hpp"

namespace mbsgen {

namespace {

constexpr double kPi = 3.14159265358979323846;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

struct Cell {
  std::string text;
  int col = 1;  // 1-based column of its first character
};

std::vector<Cell> split_csv(const std::string& line) {
  std::vector<Cell> cells;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    const std::string raw = line.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const std::size_t lead = raw.find_first_not_of(" \t");
    cells.push_back({trim(raw), static_cast<int>(start + (lead == std::string::npos ? 0 : lead)) + 1});
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return cells;
}

// A printable excerpt of user text for messages (no control characters, at most 40 bytes).
std::string quoted(const std::string& s) {
  std::string o;
  for (char c : s.substr(0, 40)) o += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? '?' : c;
  return "'" + o + (s.size() > 40 ? "…'" : "'");
}

// The columns a data file may have.
const std::set<std::string> kColumns = {"frequency_hz", "re", "im", "magnitude", "magnitude_db", "phase_deg",
                                        "sigma_magnitude", "sigma_phase_deg", "input", "output", "set",
                                        "mode", "damping_ratio", "sigma_frequency", "sigma_damping"};

class CsvReader {
 public:
  CsvReader(const std::string& origin, int line) : origin_(origin), line_(line) {}
  [[noreturn]] void fail(int col, const std::string& what) const {
    throw ParseError(origin_ + ":" + std::to_string(line_) + ":" + std::to_string(col) + ": " + what);
  }
  // The number in a cell; NaN for an empty one. Refuses text, NaN and infinities.
  double number(const Cell& c, const std::string& column) const {
    if (c.text.empty()) return kNaN;
    double x = 0;
    const char* first = c.text.data();
    const char* last = first + c.text.size();
    const auto [end, ec] = std::from_chars(first, last, x);
    if (ec == std::errc::result_out_of_range) fail(c.col, column + " " + quoted(c.text) + " is outside the range of double");
    if (ec != std::errc() || end != last) fail(c.col, column + ": " + quoted(c.text) + " is not a number");
    if (!std::isfinite(x)) fail(c.col, column + ": " + quoted(c.text) + " is not finite");
    return x;
  }
  double positive(const Cell& c, const std::string& column) const {
    const double x = number(c, column);
    if (!std::isnan(x) && !(x > 0)) fail(c.col, column + " " + quoted(c.text) + " is not positive");
    return x;
  }

 private:
  const std::string& origin_;
  int line_;
};

using Columns = std::map<std::string, std::size_t>;

Columns read_header(const std::string& line, const std::string& origin, int number) {
  Columns cols;
  const CsvReader r(origin, number);
  const auto cells = split_csv(line);
  for (std::size_t k = 0; k < cells.size(); ++k) {
    const std::string& name = cells[k].text;
    if (!kColumns.count(name)) {
      std::string known;
      for (const auto& c : kColumns) known += (known.empty() ? "" : ", ") + c;
      r.fail(cells[k].col, "unknown column " + quoted(name) + " (known: " + known + ")");
    }
    if (cols.count(name)) r.fail(cells[k].col, "column '" + name + "' appears twice");
    cols[name] = k;
  }
  const bool modal = cols.count("mode") > 0;
  const auto need = [&](bool ok, const std::string& what) {
    if (!ok) r.fail(1, what);
  };
  need(cols.count("frequency_hz") || cols.count("damping_ratio"), "the header names no frequency_hz column");
  if (modal) {
    for (const char* c : {"re", "im", "magnitude", "magnitude_db", "phase_deg", "input", "output", "sigma_magnitude",
                          "sigma_phase_deg"})
      need(!cols.count(c), std::string("modal data (a 'mode' column) with a frequency-response column '") + c + "'");
  } else {
    need(cols.count("frequency_hz") > 0, "the header names no frequency_hz column");
    const bool reim = cols.count("re") && cols.count("im");
    const bool mag = cols.count("magnitude") || cols.count("magnitude_db");
    need(reim != mag && !(cols.count("magnitude") && cols.count("magnitude_db")) &&
             (cols.count("re") == cols.count("im")),
         "a frequency response needs either re and im, or magnitude (or magnitude_db) with optional phase_deg");
    need(!(reim && cols.count("phase_deg")), "re and im with phase_deg: give one form");
    for (const char* c : {"damping_ratio", "sigma_frequency", "sigma_damping"})
      need(!cols.count(c), std::string("a frequency response with the modal column '") + c + "'");
  }
  return cols;
}

const Cell& cell(const std::vector<Cell>& cells, const Columns& cols, const std::string& name) {
  static const Cell empty;
  const auto it = cols.find(name);
  if (it == cols.end() || it->second >= cells.size()) return empty;
  return cells[it->second];
}

}  // namespace

MeasuredData read_measured_data(const std::string& text, const std::string& origin, const std::string& default_input,
                                const std::string& default_output) {
  MeasuredData data;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  Columns cols;
  bool header = false;
  std::map<std::string, std::size_t> frf_index, modal_index;  // by set/input/output
  while (std::getline(in, line)) {
    ++number;
    if (number == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // a UTF-8 byte order mark (spreadsheets)
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    if (!header) {
      cols = read_header(line, origin, number);
      header = true;
      continue;
    }
    const CsvReader r(origin, number);
    const auto cells = split_csv(line);
    if (cells.size() != cols.size())
      r.fail(1, std::to_string(cells.size()) + " fields where the header names " + std::to_string(cols.size()));
    const std::string set = cell(cells, cols, "set").text;
    if (cols.count("mode")) {
      const Cell& mc = cell(cells, cols, "mode");
      const double m = r.number(mc, "mode");
      if (!(m >= 1 && m <= 100000 && m == std::floor(m))) r.fail(mc.col, "mode " + quoted(mc.text) + " is not a mode number 1, 2, …");
      const auto [it, added] = modal_index.emplace(set, data.modal.size());
      if (added) data.modal.push_back(ModalData{origin, set, {}, {}, {}, {}, {}, {}});
      ModalData& d = data.modal[it->second];
      const double f = r.positive(cell(cells, cols, "frequency_hz"), "frequency_hz");
      const double z = r.number(cell(cells, cols, "damping_ratio"), "damping_ratio");
      if (std::isnan(f) && std::isnan(z)) r.fail(1, "neither a frequency nor a damping ratio");
      d.mode.push_back(static_cast<int>(m));
      d.frequency_hz.push_back(f);
      d.sigma_frequency.push_back(r.positive(cell(cells, cols, "sigma_frequency"), "sigma_frequency"));
      d.damping_ratio.push_back(z);
      d.sigma_damping.push_back(r.positive(cell(cells, cols, "sigma_damping"), "sigma_damping"));
      d.line.push_back(number);
      continue;
    }
    std::string input = cell(cells, cols, "input").text, output = cell(cells, cols, "output").text;
    if (input.empty()) input = default_input;
    if (output.empty()) output = default_output;
    if (input.empty() || output.empty())
      r.fail(1, "which input and output? The file has no input/output columns and none was given (--input, --output)");
    const Cell& fc = cell(cells, cols, "frequency_hz");
    const double hz = r.positive(fc, "frequency_hz");
    if (std::isnan(hz)) r.fail(fc.col, "no frequency");
    std::complex<double> h;
    bool has_phase = true, has_magnitude = true;
    if (cols.count("re")) {
      const double re = r.number(cell(cells, cols, "re"), "re"), im = r.number(cell(cells, cols, "im"), "im");
      if (std::isnan(re) || std::isnan(im)) r.fail(1, "re or im is empty");
      if (re == 0 && im == 0) r.fail(cell(cells, cols, "re").col, "the response is zero: its logarithm is not defined");
      h = {re, im};
    } else {
      const bool db = cols.count("magnitude_db") > 0;
      const Cell& mc = cell(cells, cols, db ? "magnitude_db" : "magnitude");
      double mag = db ? r.number(mc, "magnitude_db") : r.positive(mc, "magnitude");
      const double ph = r.number(cell(cells, cols, "phase_deg"), "phase_deg");
      has_phase = !std::isnan(ph);
      has_magnitude = !std::isnan(mag);
      if (!has_magnitude && !has_phase) r.fail(mc.col, "neither a magnitude nor a phase");
      if (!has_magnitude) mag = 1.0;
      if (db && has_magnitude) mag = std::pow(10.0, mag / 20.0);
      h = std::polar(mag, has_phase ? ph * kPi / 180.0 : 0.0);
    }
    const std::string key = set + '\n' + input + '\n' + output;
    const auto [it, added] = frf_index.emplace(key, data.responses.size());
    if (added) data.responses.push_back(FrfData{origin, set, input, output, {}, {}, {}, {}, {}, {}, {}});
    FrfData& d = data.responses[it->second];
    d.hz.push_back(hz);
    d.value.push_back(h);
    d.has_phase.push_back(has_phase);
    d.has_magnitude.push_back(has_magnitude);
    d.sigma_ln_magnitude.push_back(r.positive(cell(cells, cols, "sigma_magnitude"), "sigma_magnitude"));
    const double sp = r.positive(cell(cells, cols, "sigma_phase_deg"), "sigma_phase_deg");
    d.sigma_phase_rad.push_back(std::isnan(sp) ? sp : sp * kPi / 180.0);
    d.line.push_back(number);
  }
  if (!header) throw ParseError(origin + ":1:1: no header row (e.g. frequency_hz,magnitude,phase_deg)");
  if (data.responses.empty() && data.modal.empty()) throw ParseError(origin + ":" + std::to_string(number) + ":1: no data rows");
  return data;
}

MeasuredData read_measured_data_file(const std::string& path, const std::string& default_input,
                                     const std::string& default_output) {
  return read_measured_data(detail::read_regular_file<ParseError>(path, std::size_t(64) << 20), path, default_input,
                            default_output);
}

FitParameter parse_fit_parameter(const std::string& text) {
  const auto fail = [&](const std::string& what) -> void {
    throw NameError("--parameter " + quoted(text) + ": " + what +
                " (expected NAME=LO:HI[:xF | :+-W][:lin], e.g. k=100:1e4:x2)");
  };
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0) fail("no NAME=");
  FitParameter p;
  p.name = text.substr(0, eq);
  std::vector<std::string> f;
  std::string rest = text.substr(eq + 1);
  for (std::size_t s = 0;;) {
    const auto c = rest.find(':', s);
    f.push_back(rest.substr(s, c == std::string::npos ? std::string::npos : c - s));
    if (c == std::string::npos) break;
    s = c + 1;
  }
  if (f.size() < 2 || f.size() > 4) fail("two to four fields after '='");
  const auto num = [&](const std::string& s, const char* role) {
    double x = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
    if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(x))
      fail(std::string(role) + " " + quoted(s) + " is not a finite number");
    return x;
  };
  p.lower = num(f[0], "the lower bound");
  p.upper = num(f[1], "the upper bound");
  if (!(p.lower < p.upper)) fail("the lower bound is not below the upper bound");
  p.log_space = p.lower > 0;
  bool linear = false, lognormal = false;
  for (std::size_t k = 2; k < f.size(); ++k) {
    const std::string& s = f[k];
    if (s == "lin") {
      linear = true;
    } else if (s.size() > 1 && s[0] == 'x') {
      p.prior_width = num(s.substr(1), "the prior's factor");
      if (!(p.prior_width > 1)) fail("the prior's factor F is not above 1");
      lognormal = true;
    } else if (s.rfind("+-", 0) == 0 || s.rfind("±", 0) == 0) {
      p.prior_width = num(s.substr(s[0] == '+' ? 2 : std::string("±").size()), "the prior's standard deviation");
      if (!(p.prior_width > 0)) fail("the prior's standard deviation is not positive");
      linear = true;
    } else {
      fail("unknown field " + quoted(s));
    }
  }
  if (lognormal && (linear || p.lower <= 0)) fail("a log-normal prior (xF) needs log space: LO > 0 and no 'lin' or +-W");
  if (linear) p.log_space = false;
  return p;
}

}  // namespace mbsgen
