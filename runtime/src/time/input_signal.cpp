// Inputs as functions of time for simulate() (simulation.hpp).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>

#include "mbsgen/runtime/time/simulation.hpp"
#include "model/text_file.hpp"

namespace mbsgen {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

double number_in(const std::string& text, const std::string& spec) {
  return finite_number(text, "input signal '" + spec + "'");
}

std::vector<double> numbers_in(const std::string& list, const std::string& spec) {
  std::vector<double> v;
  std::size_t start = 0;
  while (true) {  // every field, the empty ones too ("1,,2" and "1,2," are refused)
    const std::size_t comma = list.find(',', start);
    v.push_back(number_in(list.substr(start, comma == std::string::npos ? std::string::npos : comma - start), spec));
    if (comma == std::string::npos) return v;
    start = comma + 1;
  }
}

// A header: a first field that does not start like a number (sign, digit or point).
bool header_line(const std::string& line) {
  const auto first = line.find_first_not_of(" \t");
  if (first == std::string::npos) return false;
  const char c = line[first];
  return !(std::isdigit(static_cast<unsigned char>(c)) || c == '+' || c == '-' || c == '.');
}

// Shortest text that reads back as x.
std::string number_text(double x) {
  std::ostringstream o;
  o.precision(17);
  o << x;
  return o.str();
}

// Reads a CSV table of t,value lines (a first line that is not numbers is a header).
InputSignal table_from_file(const std::string& path, const std::string& spec) {
  // A regular file of at most 256 MiB (a FIFO or a device is refused at once, never read).
  std::istringstream in(detail::read_regular_file<NameError>(path, std::size_t{1} << 28));
  std::vector<double> t, v;
  std::string line;
  for (long number = 1; std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (number == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // a UTF-8 byte order mark
    if (line.empty() || line[0] == '#') continue;
    if (number == 1 && header_line(line)) continue;
    const auto comma = line.find(',');
    const std::string where = path + ":" + std::to_string(number);
    if (comma == std::string::npos) throw NameError(where + ": expected 't,value'");
    try {
      t.push_back(number_in(line.substr(0, comma), spec));
      v.push_back(number_in(line.substr(comma + 1), spec));
    } catch (const NameError&) {
      throw NameError(where + ": expected 't,value' with finite numbers, got '" + line + "'");
    }
    // Checked here, with the file's line number (InputSignal::table only knows point indices).
    if (t.size() >= 2 && !(t.back() > t[t.size() - 2]))
      throw NameError(where + ": the times must increase strictly (" + line.substr(0, comma) +
                      " follows " + number_text(t[t.size() - 2]) + ")");
  }
  if (t.empty()) throw NameError(path + ": no 't,value' lines (a table needs at least one point)");
  return InputSignal::table(std::move(t), std::move(v));
}

}  // namespace

double finite_number(const std::string& text, const std::string& what) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v))
    throw NameError(what + ": '" + text + "' is not a finite number");
  return v;
}

InputSignal InputSignal::constant(double value) {
  InputSignal s;
  s.a_ = value;
  return s;
}

InputSignal InputSignal::sine(double amplitude, double frequency_hz, double phase_rad, double offset) {
  InputSignal s;
  s.kind_ = Kind::sine;
  s.a_ = amplitude, s.b_ = frequency_hz, s.c_ = phase_rad, s.d_ = offset;
  return s;
}

InputSignal InputSignal::step(double amplitude, double time, double before) {
  InputSignal s;
  s.kind_ = Kind::step;
  s.a_ = amplitude, s.b_ = time, s.c_ = before;
  s.breakpoints_ = {time};
  return s;
}

InputSignal InputSignal::chirp(double amplitude, double f0_hz, double f1_hz, double duration) {
  if (!(duration > 0)) throw Error("InputSignal::chirp: the duration must be > 0, got " + std::to_string(duration));
  InputSignal s;
  s.kind_ = Kind::chirp;
  s.a_ = amplitude, s.b_ = f0_hz, s.c_ = f1_hz, s.d_ = duration;
  return s;
}

InputSignal InputSignal::table(std::vector<double> times, std::vector<double> values) {
  if (times.size() != values.size())
    throw DimensionError("InputSignal::table: " + std::to_string(times.size()) + " times but " +
                         std::to_string(values.size()) + " values");
  if (times.empty()) throw Error("InputSignal::table: no points");
  for (std::size_t i = 0; i < times.size(); ++i) {
    if (!std::isfinite(times[i]) || !std::isfinite(values[i]))
      throw NonFiniteError("InputSignal::table: point " + std::to_string(i + 1) + " is not finite");
    if (i > 0 && !(times[i] > times[i - 1]))
      throw Error("InputSignal::table: the times must increase strictly (point " + std::to_string(i + 1) + ")");
  }
  InputSignal s;
  s.kind_ = Kind::table;
  s.t_ = std::move(times);
  s.v_ = std::move(values);
  return s;
}

InputSignal InputSignal::parse(const std::string& spec, double duration) {
  const auto colon = spec.find(':');
  if (colon == std::string::npos) return constant(number_in(spec, spec));
  const std::string kind = spec.substr(0, colon), rest = spec.substr(colon + 1);
  if (kind == "table") return table_from_file(rest, spec);
  const std::vector<double> a = numbers_in(rest, spec);
  auto need = [&](std::size_t low, std::size_t high, const char* form) {
    if (a.size() < low || a.size() > high)
      throw NameError("input signal '" + spec + "': expected " + kind + ":" + form);
  };
  if (kind == "sine") {
    need(2, 4, "AMPLITUDE,HZ[,PHASE_DEG[,OFFSET]]");
    return sine(a[0], a[1], a.size() > 2 ? a[2] * kTwoPi / 360 : 0, a.size() > 3 ? a[3] : 0);
  }
  if (kind == "step") {
    need(1, 3, "AMPLITUDE[,TIME[,BEFORE]]");
    return step(a[0], a.size() > 1 ? a[1] : 0, a.size() > 2 ? a[2] : 0);
  }
  if (kind == "chirp") {
    need(3, 4, "AMPLITUDE,F0_HZ,F1_HZ[,DURATION]");
    const double d = a.size() > 3 ? a[3] : duration;
    if (!(d > 0)) throw NameError("input signal '" + spec + "': the chirp's duration must be > 0");
    return chirp(a[0], a[1], a[2], d);
  }
  throw NameError("input signal '" + spec + "': unknown kind '" + kind +
                  "' (known: a number, sine:, step:, chirp:, table:)");
}

double InputSignal::operator()(double t) const {
  switch (kind_) {
    case Kind::constant:
      return a_;
    case Kind::sine:
      return d_ + a_ * std::sin(kTwoPi * b_ * t + c_);
    case Kind::step:
      return t > b_ ? c_ + a_ : c_;
    case Kind::chirp: {
      // phase 2π (f0 t + (f1 − f0) t² / (2 T)) up to T, then at f1
      const double T = d_, tc = std::min(t, T);
      const double phase = b_ * tc + (c_ - b_) * tc * tc / (2 * T) + c_ * (t - tc);
      return a_ * std::sin(kTwoPi * phase);
    }
    case Kind::table: {
      if (t <= t_.front()) return v_.front();
      if (t >= t_.back()) return v_.back();
      const auto i = static_cast<std::size_t>(std::upper_bound(t_.begin(), t_.end(), t) - t_.begin());
      const double w = (t - t_[i - 1]) / (t_[i] - t_[i - 1]);
      return v_[i - 1] + w * (v_[i] - v_[i - 1]);
    }
  }
  return 0;
}

}  // namespace mbsgen
