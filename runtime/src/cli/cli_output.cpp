#include "cli/cli_output.hpp"

#include <cmath>
#include <cstdio>

namespace mbsgen::cli {

namespace {
constexpr double kPi = 3.14159265358979323846;

/// One line on what a verdict of QuadraticEigenSolver::stability() means.
const char* stability_reason(Stability s) {
  switch (s) {
    case Stability::stable: return "every eigenvalue has Re lambda < -error_bound";
    case Stability::unstable: return "an eigenvalue has Re lambda > error_bound";
    case Stability::marginal:
      return "none unstable; eigenvalues exactly on the imaginary axis (zero, or Re lambda = 0)";
    case Stability::undecided: break;
  }
  return "none unstable; an eigenvalue is zero within its error bound or has "
         "|Re lambda| <= error_bound";
}
}  // namespace

// NaN marks a quantity that is undefined (the damping ratio of λ = 0): null in JSON, an empty
// field in CSV, "-" in tables; never the string "nan".
std::string num(double v, bool json) {
  if (!std::isfinite(v)) {
    if (json) return "null";
    if (std::isnan(v)) return "";
    return v > 0 ? "inf" : "-inf";
  }
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string short_num(double v) {
  if (std::isnan(v)) return "-";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6e", v);
  return buf;
}

std::string fixed(double v, const char* format) {
  if (std::isnan(v)) return "-";
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

std::string sweep_problem(double from_hz, double to_hz, long points, bool log_spacing) {
  const std::string range = "--from " + num(from_hz, false) + " --to " + num(to_hz, false);
  if (log_spacing && (from_hz <= 0 || to_hz <= 0))
    return "--spacing log needs --from and --to > 0 (got " + range + ")";
  if (to_hz < from_hz || (points > 1 && to_hz == from_hz))
    return "empty range " + range + " (--from must be below --to, or equal to it with --points 1)";
  return "";
}

Eigen::VectorXd sweep_hz(double from_hz, double to_hz, long points, bool log_spacing) {
  Eigen::VectorXd hz(points);
  for (long k = 0; k < points; ++k) {
    const double t = points == 1 ? 0.0 : static_cast<double>(k) / static_cast<double>(points - 1);
    hz[k] = log_spacing ? from_hz * std::pow(to_hz / from_hz, t) : from_hz + (to_hz - from_hz) * t;
  }
  if (points > 0) hz[points - 1] = to_hz;
  return hz;
}

std::string pad(const std::string& s, std::size_t w) {
  return s.size() >= w ? s : std::string(w - s.size(), ' ') + s;
}

std::string csv_field(const std::string& s) {
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' || c == '\r' ? ' ' : c);
  return q + "\"";
}

std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      o += '\\';
      o += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", c);
      o += b;
    } else {
      o += c;
    }
  }
  return o + "\"";
}

void write_modes(std::ostream& out, const QuadraticEigenSolver& solver, Eigen::Index size,
                 const ModesFormat& f) {
  std::ostringstream method;
  method << "# method " << solver.method() << ", rank M " << solver.rank_M() << "/" << size << ", rank K "
         << solver.rank_K() << "/" << size << "\n";
  write_modes(out, solver.modes(), solver.stability(), size, f, method.str());
}

void write_modes(std::ostream& out, const std::vector<Mode>& modes, Stability stability, Eigen::Index size,
                 const ModesFormat& f, const std::string& method_line) {
  auto coordinate = [&f](Eigen::Index i) {
    return static_cast<std::size_t>(i) < f.coordinate_names.size()
               ? f.coordinate_names[static_cast<std::size_t>(i)]
               : "y" + std::to_string(i + 1);
  };
  if (f.format == "json") {
    out << "{\"modes\":[";
    for (std::size_t k = 0; k < modes.size(); ++k) {
      const Mode& m = modes[k];
      out << (k ? ",\n" : "\n") << "{\"lambda_re\":" << num(m.lambda.real(), true)
          << ",\"lambda_im\":" << num(m.lambda.imag(), true)
          << ",\"natural_frequency_hz\":" << num(m.natural_frequency_hz, true)
          << ",\"damped_frequency_hz\":" << num(m.damped_frequency_hz, true)
          << ",\"damping_ratio\":" << num(m.damping_ratio, true)
          << ",\"backward_error\":" << num(m.backward_error, true)
          << ",\"error_bound\":" << num(m.error_bound, true) << ",\"kind\":\"" << kind_label(m)
          << "\"";
      if (f.shapes) {
        out << ",\"shape\":{";
        for (Eigen::Index i = 0; i < m.shape.size(); ++i)
          out << (i ? "," : "") << json_string(coordinate(i)) << ":[" << num(m.shape[i].real(), true)
              << "," << num(m.shape[i].imag(), true) << "]";
        out << "}";
      }
      out << "}";
    }
    out << "\n],\"stability\":\"" << to_string(stability) << "\"}\n";
  } else if (f.format == "csv") {
    out << "lambda_re,lambda_im,natural_frequency_hz,damped_frequency_hz,damping_ratio,"
           "backward_error,error_bound,kind";
    if (f.shapes)
      for (Eigen::Index i = 0; i < size; ++i) out << "," << coordinate(i) << "_re," << coordinate(i) << "_im";
    out << "\n";
    for (const Mode& m : modes) {
      out << num(m.lambda.real(), false) << "," << num(m.lambda.imag(), false) << ","
          << num(m.natural_frequency_hz, false) << "," << num(m.damped_frequency_hz, false)
          << "," << num(m.damping_ratio, false) << "," << num(m.backward_error, false) << ","
          << num(m.error_bound, false) << "," << kind_label(m);
      if (f.shapes)
        for (Eigen::Index i = 0; i < m.shape.size(); ++i)
          out << "," << num(m.shape[i].real(), false) << "," << num(m.shape[i].imag(), false);
      out << "\n";
    }
  } else {
    out << pad("#", 4) << pad("lambda_re", 15) << pad("lambda_im", 15) << pad("f_n [Hz]", 15)
        << pad("f_d [Hz]", 15) << pad("zeta", 15) << pad("backward_err", 15)
        << pad("error_bound", 15) << "  kind\n";
    int k = 1;
    for (const Mode& m : modes)
      out << pad(std::to_string(k++), 4) << pad(short_num(m.lambda.real()), 15)
          << pad(short_num(m.lambda.imag()), 15) << pad(short_num(m.natural_frequency_hz), 15)
          << pad(short_num(m.damped_frequency_hz), 15) << pad(short_num(m.damping_ratio), 15)
          << pad(short_num(m.backward_error), 15) << pad(short_num(m.error_bound), 15) << "  "
          << kind_label(m) << "\n";
    out << method_line;
    out << "# stability " << to_string(stability) << ": " << stability_reason(stability) << "\n";
    if (f.shapes) {
      out << "# mode shapes (unit 2-norm, largest entry real positive): amplitude, phase [deg]\n";
      out << pad("coordinate", 16);
      for (std::size_t j = 0; j < modes.size(); ++j) out << pad("mode " + std::to_string(j + 1), 28);
      out << "\n";
      for (Eigen::Index i = 0; i < size; ++i) {
        out << pad(coordinate(i), 16);
        for (const Mode& m : modes) {
          const std::complex<double> x = i < m.shape.size() ? m.shape[i] : 0.0;
          out << pad(short_num(std::abs(x)), 14) << pad(short_num(std::arg(x) * 180.0 / kPi), 14);
        }
        out << "\n";
      }
    }
  }
}

void write_frf(std::ostream& out, const FrfResult& r, const FrfTable& t) {
  const Eigen::VectorXd& hz = r.hz;
  const Eigen::Index n = hz.size();
  if (t.format == "json") {
    out << "{\"input\":" << t.input_json << ",\"output\":" << t.output_json << ",\"points\":[";
    for (Eigen::Index k = 0; k < n; ++k) {
      const std::complex<double> v = r.g[k];
      out << (k ? ",\n" : "\n") << "{\"frequency_hz\":" << num(hz[k], true)
          << ",\"re\":" << num(v.real(), true) << ",\"im\":" << num(v.imag(), true)
          << ",\"amplitude\":" << num(amplitude(v), true)
          << ",\"phase_lag_deg\":" << num(phase_lag(v) * 180.0 / kPi, true)
          << ",\"rcond\":" << num(r.rcond[k], true) << ",\"flag\":\""
          << to_string(r.flags[static_cast<std::size_t>(k)]) << "\"}";
    }
    out << "\n]}\n";
  } else if (t.format == "csv") {
    out << "frequency_hz,re,im,amplitude,phase_lag_deg,rcond,flag\n";
    for (Eigen::Index k = 0; k < n; ++k) {
      const std::complex<double> v = r.g[k];
      out << num(hz[k], false) << "," << num(v.real(), false) << "," << num(v.imag(), false)
          << "," << num(amplitude(v), false) << "," << num(phase_lag(v) * 180.0 / kPi, false)
          << "," << num(r.rcond[k], false) << ","
          << to_string(r.flags[static_cast<std::size_t>(k)]) << "\n";
    }
  } else {
    out << pad("f [Hz]", 15) << pad("re", 15) << pad("im", 15) << pad("amplitude", 15)
        << pad("phase_lag[deg]", 15) << pad("rcond", 15) << "  flag\n";
    for (Eigen::Index k = 0; k < n; ++k) {
      const std::complex<double> v = r.g[k];
      out << pad(short_num(hz[k]), 15) << pad(short_num(v.real()), 15)
          << pad(short_num(v.imag()), 15) << pad(short_num(amplitude(v)), 15)
          << pad(short_num(phase_lag(v) * 180.0 / kPi), 15) << pad(short_num(r.rcond[k]), 15)
          << "  " << to_string(r.flags[static_cast<std::size_t>(k)]) << "\n";
    }
    out << "# input " << t.input_label << ", output " << t.output_label << ", method "
        << to_string(r.method) << "\n";
  }
}

}  // namespace mbsgen::cli
