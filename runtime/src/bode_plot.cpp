#include "bode_plot.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <system_error>

#include <unistd.h>

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/frequency_response.hpp"

namespace mbsgen::cli {

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string quoted(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o + "\"";
}

}  // namespace

void write_bode_plot(const std::string& path, const Eigen::VectorXd& hz, const Eigen::VectorXcd& g,
                     const BodePlot& plot) {
  namespace fs = std::filesystem;
  const std::string ext = fs::path(path).extension().string();
  std::string terminal;
  if (ext == ".svg")
    terminal = "svg size 900,700 dynamic enhanced font 'Sans,12' background rgb 'white'";
  else if (ext == ".png")
    terminal = "pngcairo size 900,700 enhanced font 'Sans,11'";
  else
    throw Error("--plot " + path + ": the file name must end in .svg or .png");

  std::error_code ec;
  const fs::path dir = fs::temp_directory_path(ec);
  if (ec) throw Error("--plot: no temporary directory: " + ec.message());
  const std::string stem = "mbsgen-bode-" + std::to_string(::getpid());
  const fs::path data = dir / (stem + ".dat"), script = dir / (stem + ".gp");
  const fs::path target = fs::absolute(path);
  const fs::path tmp = target.parent_path() / ("." + target.filename().string() + ".tmp");
  struct Cleanup {
    fs::path a, b, c;
    ~Cleanup() {
      std::error_code e;
      fs::remove(a, e);
      fs::remove(b, e);
      fs::remove(c, e);
    }
  } cleanup{data, script, tmp};
  {
    std::ofstream d(data);
    for (Eigen::Index k = 0; k < hz.size(); ++k) {
      const double a = std::abs(g[k]);
      if (!std::isfinite(a) || a <= 0 || !(hz[k] > 0)) continue;  // log axes
      char line[128];
      std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", hz[k], a, phase_lag(g[k]) * 180.0 / kPi);
      d << line;
    }
    if (!d) throw Error("--plot: cannot write " + data.string());
  }
  {
    std::ofstream s(script);
    s << "set terminal " << terminal << "\n"
      << "set output " << quoted(tmp.string()) << "\n"
      << "set multiplot layout 2,1 title " << quoted(plot.title) << " noenhanced\n"
      << "set xrange [" << hz.minCoeff() << ":" << hz.maxCoeff() << "]\n"
      << "set logscale x\nset grid xtics ytics mxtics\nset format x '10^{%L}'\n"
      << "set logscale y\nset format y '10^{%L}'\n"
      << "set ylabel " << quoted(plot.amplitude_label) << " noenhanced\n"
      << "unset key\n"
      << "plot " << quoted(data.string()) << " using 1:2 with lines lw 2 lc rgb '#1f4e9c'\n"
      << "unset logscale y\nset format y '%g'\n"
      << "set ylabel 'phase lag [deg]'\nset xlabel 'frequency [Hz]'\n"
      << "plot " << quoted(data.string()) << " using 1:3 with lines lw 2 lc rgb '#1f4e9c'\n"
      << "unset multiplot\n";
    if (!s) throw Error("--plot: cannot write " + script.string());
  }
  const std::string command = "gnuplot " + quoted(script.string()) + " 2>&1";
  FILE* p = popen(command.c_str(), "r");
  if (!p) throw Error("--plot: cannot run gnuplot (install Debian package gnuplot-nox)");
  std::string messages;
  char buf[256];
  while (std::fgets(buf, sizeof buf, p)) messages += buf;
  const int status = pclose(p);
  if (status != 0 || !fs::exists(tmp))
    throw Error("--plot: gnuplot failed" +
                (messages.empty() ? std::string(" (is it installed? Debian package gnuplot-nox)")
                                  : ": " + messages));
  fs::rename(tmp, target, ec);
  if (ec) throw Error("--plot: cannot write " + target.string() + ": " + ec.message());
}

}  // namespace mbsgen::cli
