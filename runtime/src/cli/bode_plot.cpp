#include "cli/bode_plot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <system_error>

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"

extern char** environ;

namespace mbsgen::cli {

namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A private directory (mkdtemp, mode 0700) under the temporary directory, removed with what it
// holds when this goes out of scope.
struct PrivateDirectory {
  fs::path path;
  PrivateDirectory() {
    std::error_code ec;
    const fs::path base = fs::temp_directory_path(ec);
    if (ec) throw Error("--plot: no temporary directory: " + ec.message());
    std::string name = (base / "mbsgen-bode-XXXXXX").string();
    if (!::mkdtemp(name.data()))
      throw Error("--plot: cannot create a directory in " + base.string() + ": " + std::strerror(errno));
    path = name;
  }
  ~PrivateDirectory() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  PrivateDirectory(const PrivateDirectory&) = delete;
  PrivateDirectory& operator=(const PrivateDirectory&) = delete;
};

// Runs gnuplot on script with its standard output going to out_fd (the plot: no file name is
// in the script) and its messages to log; returns gnuplot's exit status (-1: killed).
int run_gnuplot(const fs::path& script, int out_fd, const fs::path& log) {
  const int log_fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (log_fd < 0) throw Error("--plot: cannot create " + log.string() + ": " + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, out_fd, STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, log_fd, STDERR_FILENO);
  std::string program = "gnuplot", file = script.string();
  char* argv[] = {program.data(), file.data(), nullptr};
  pid_t pid = 0;
  const int error = ::posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(log_fd);
  if (error != 0)
    throw Error(std::string("--plot: cannot run gnuplot: ") + std::strerror(error) +
                " (install Debian package gnuplot-nox)");
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The script: data inline (a datablock), no file names, every label a gnuplot_string.
std::string bode_script(const std::string& terminal, const Eigen::VectorXd& hz, const Eigen::VectorXcd& g,
                        const BodePlot& plot) {
  std::ostringstream s;
  s << "set terminal " << terminal << "\n$bode << EOD\n";
  for (Eigen::Index k = 0; k < hz.size(); ++k) {
    const double a = std::abs(g[k]);
    if (!std::isfinite(a) || a <= 0 || !(hz[k] > 0)) continue;  // log axes
    char line[128];
    std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", hz[k], a, phase_lag(g[k]) * 180.0 / kPi);
    s << line;
  }
  s << "EOD\n"
    << "set multiplot layout 2,1 title " << gnuplot_string(plot.title) << " noenhanced\n"
    << "set xrange [" << hz.minCoeff() << ":" << hz.maxCoeff() << "]\n"
    << "set logscale x\nset grid xtics ytics mxtics\nset format x '10^{%L}'\n"
    << "set logscale y\nset format y '10^{%L}'\n"
    << "set ylabel " << gnuplot_string(plot.amplitude_label) << " noenhanced\n"
    << "unset key\n"
    << "plot $bode using 1:2 with lines lw 2 lc rgb '#1f4e9c'\n"
    << "unset logscale y\nset format y '%g'\n"
    << "set ylabel 'phase lag [deg]'\nset xlabel 'frequency [Hz]'\n"
    << "plot $bode using 1:3 with lines lw 2 lc rgb '#1f4e9c'\n"
    << "unset multiplot\n";
  return s.str();
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

std::string gnuplot_string(const std::string& s) {
  std::string o = "'";
  for (std::size_t i = 0; i < s.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if (c == '\'') {
      o += "''";
    } else if (c < 0x20 || c == 0x7F) {
      o += ' ';
    } else if (c < 0x80) {
      o += static_cast<char>(c);
    } else {
      // Well-formed UTF-8 stays; any other byte becomes '?' (the plot's text must be UTF-8).
      std::size_t n = c >= 0xF0 ? 4 : c >= 0xE0 ? 3 : c >= 0xC2 ? 2 : 0;
      bool ok = n > 0 && c <= 0xF4 && i + n <= s.size();
      for (std::size_t k = 1; ok && k < n; ++k) ok = (static_cast<unsigned char>(s[i + k]) & 0xC0) == 0x80;
      if (ok && n == 3) {
        const unsigned c1 = static_cast<unsigned char>(s[i + 1]);
        ok = !(c == 0xE0 && c1 < 0xA0) && !(c == 0xED && c1 > 0x9F);
      } else if (ok && n == 4) {
        const unsigned c1 = static_cast<unsigned char>(s[i + 1]);
        ok = !(c == 0xF0 && c1 < 0x90) && !(c == 0xF4 && c1 > 0x8F);
      }
      if (!ok) {
        o += '?';
        continue;
      }
      o.append(s, i, n);
      i += n - 1;
    }
  }
  return o + "'";
}

namespace {

// Renders the script that `script(terminal)` gives to `path` (.svg or .png), atomically, with
// gnuplot run without a shell in a private directory (see write_bode_plot).
void render(const std::string& path, const std::function<std::string(const std::string&)>& script_for) {
  const std::string ext = fs::path(path).extension().string();
  std::string terminal;
  if (ext == ".svg")
    terminal = "svg size 900,700 dynamic enhanced font 'Sans,12' background rgb 'white'";
  else if (ext == ".png")
    terminal = "pngcairo size 900,700 enhanced font 'Sans,11'";
  else
    throw Error("--plot " + path + ": the file name must end in .svg or .png");

  PrivateDirectory work;
  const fs::path script = work.path / "plot.gp", log = work.path / "gnuplot.log";
  {
    std::ofstream s(script, std::ios::binary);
    s << script_for(terminal);
    if (!s.flush()) throw Error("--plot: cannot write " + script.string());
  }
  // The plot goes to a file created exclusively beside the target, then renamed over it.
  const fs::path target = fs::absolute(path);
  std::string tmp = (target.parent_path() / ("." + target.filename().string() + ".XXXXXX.tmp")).string();
  const int out_fd = ::mkstemps(tmp.data(), 4);
  if (out_fd < 0) throw Error("--plot: cannot write in " + target.parent_path().string() + ": " + std::strerror(errno));
  struct RemoveTemporary {
    std::string path;
    ~RemoveTemporary() { ::unlink(path.c_str()); }
  } remove_tmp{tmp};
  int status = -1;
  try {
    status = run_gnuplot(script, out_fd, log);
  } catch (...) {
    ::close(out_fd);
    throw;
  }
  const bool written = ::lseek(out_fd, 0, SEEK_END) > 0;
  const mode_t mask = ::umask(0);
  ::umask(mask);
  const bool closed = ::fchmod(out_fd, 0666 & ~mask) == 0 && ::close(out_fd) == 0;
  if (status != 0 || !written || !closed) {
    const std::string messages = read_text(log);
    throw Error("--plot: gnuplot failed" + (messages.empty() ? std::string(" (exit status ") +
                                                                   std::to_string(status) + ")"
                                                             : ": " + messages));
  }
  if (::rename(tmp.c_str(), target.c_str()) != 0)
    throw Error("--plot: cannot write " + target.string() + ": " + std::strerror(errno));
  remove_tmp.path.clear();
}


// The eigenvalues against the parameter: real parts above, imaginary parts below, the
// stability boundaries as vertical lines.
std::string sweep_script(const std::string& terminal, const SweepResult& r, const SweepPlot& plot) {
  std::ostringstream s;
  s << "set terminal " << terminal << "\n$sweep << EOD\n";
  for (const SweepPoint& p : r.points)
    for (const auto& l : p.eigenvalues) {
      if (!std::isfinite(l.real()) || !std::isfinite(l.imag())) continue;
      char line[128];
      std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", p.value, l.real(), l.imag());
      s << line;
    }
  s << "EOD\n"
    << "set multiplot layout 2,1 title " << gnuplot_string(plot.title) << " noenhanced\n"
    << "set grid xtics ytics\nunset key\n";
  for (const StabilityBoundary& b : r.boundaries)
    s << "set arrow from " << b.value << ", graph 0 to " << b.value << ", graph 1 nohead dt 2 lc rgb '#b03030'\n";
  s << "set ylabel 'Re lambda [1/s]'\n"
    << "plot $sweep using 1:2 with points pt 7 ps 0.4 lc rgb '#1f4e9c', 0 with lines lc rgb 'black'\n"
    << "set ylabel 'Im lambda [1/s]'\nset xlabel " << gnuplot_string(plot.parameter_label) << " noenhanced\n"
    << "plot $sweep using 1:3 with points pt 7 ps 0.4 lc rgb '#1f4e9c'\n"
    << "unset multiplot\n";
  return s.str();
}

// Series against time, one panel each (at most kMaxPanels), every label a gnuplot_string.
std::string time_script(const std::string& terminal, const Eigen::VectorXd& t, const Eigen::MatrixXd& values,
                        const TimePlot& plot) {
  std::ostringstream s;
  s << "set terminal " << terminal << "\n$series << EOD\n";
  // At most about 20,000 points a series (more do not show, and the script is held in memory).
  const Eigen::Index stride = std::max<Eigen::Index>(1, t.size() / 20000);
  for (Eigen::Index k = 0; k < t.size(); k += stride) {
    char field[32];
    std::snprintf(field, sizeof field, "%.17g", t[k]);
    s << field;
    for (Eigen::Index i = 0; i < values.rows(); ++i) {
      std::snprintf(field, sizeof field, " %.17g", values(i, k));
      s << field;
    }
    s << "\n";
  }
  s << "EOD\n"
    << "set multiplot layout " << values.rows() << ",1 title " << gnuplot_string(plot.title) << " noenhanced\n"
    << "set grid xtics ytics\nunset key\n";
  for (Eigen::Index i = 0; i < values.rows(); ++i) {
    if (i + 1 == values.rows()) s << "set xlabel 'time [s]'\n";
    s << "set ylabel " << gnuplot_string(plot.labels[static_cast<std::size_t>(i)]) << " noenhanced\n"
      << "plot $series using 1:" << i + 2 << " with lines lw 2 lc rgb '#1f4e9c'\n";
  }
  s << "unset multiplot\n";
  return s.str();
}

// The band plot's script: data inline, as bode_script.
std::string band_script(const std::string& terminal, const std::vector<double>& hz,
                        const std::vector<std::vector<double>>& b, const BandPlot& plot) {
  std::ostringstream s;
  s << "set terminal " << terminal << "\n$band << EOD\n";
  double lo = 0, hi = 0;
  for (std::size_t k = 0; k < hz.size(); ++k) {
    bool ok = hz[k] > 0;
    for (const auto& row : b) ok = ok && std::isfinite(row[k]) && row[k] > 0;
    if (!ok) continue;  // log axes
    if (lo == 0) lo = hz[k];
    hi = hz[k];
    char line[256];
    std::snprintf(line, sizeof line, "%.17g %.17g %.17g %.17g %.17g %.17g\n", hz[k], b[0][k], b[1][k], b[2][k],
                  b[3][k], b[4][k]);
    s << line;
  }
  s << "EOD\n"
    << "set title " << gnuplot_string(plot.title) << " noenhanced\n";
  if (hi > lo) s << "set xrange [" << lo << ":" << hi << "]\n";
  s << "set logscale xy\nset grid xtics ytics mxtics\nset format x '10^{%L}'\nset format y '10^{%L}'\n"
    << "set xlabel 'frequency [Hz]'\nset ylabel " << gnuplot_string(plot.amplitude_label) << " noenhanced\n"
    << "set key top left\n"
    << "plot $band using 1:2:6 with filledcurves lc rgb '#c6d4ee' title '5-95 %', "
    << "$band using 1:3:5 with filledcurves lc rgb '#8fa9dc' title '25-75 %', "
    << "$band using 1:4 with lines lw 2 lc rgb '#1f4e9c' title 'median'\n";
  return s.str();
}

}  // namespace

void write_band_plot(const std::string& path, const std::vector<double>& hz,
                     const std::vector<std::vector<double>>& bands, const BandPlot& plot) {
  if (bands.size() != 5)
    throw DimensionError("write_band_plot: " + std::to_string(bands.size()) + " percentile rows, 5 expected");
  for (const auto& row : bands)
    if (row.size() != hz.size())
      throw DimensionError("write_band_plot: a band of " + std::to_string(row.size()) + " values for " +
                           std::to_string(hz.size()) + " frequencies");
  render(path, [&](const std::string& terminal) { return band_script(terminal, hz, bands, plot); });
}

void write_time_plot(const std::string& path, const Eigen::VectorXd& t, const Eigen::MatrixXd& values,
                     const TimePlot& plot) {
  if (values.rows() < 1 || values.rows() > kMaxTimePanels || static_cast<std::size_t>(values.rows()) != plot.labels.size() ||
      values.cols() != t.size())
    throw DimensionError("write_time_plot: " + std::to_string(values.rows()) + " series (1 to " +
                         std::to_string(kMaxTimePanels) + ", each with a label) of " + std::to_string(values.cols()) +
                         " samples at " + std::to_string(t.size()) + " times");
  render(path, [&](const std::string& terminal) { return time_script(terminal, t, values, plot); });
}

void write_bode_plot(const std::string& path, const Eigen::VectorXd& hz, const Eigen::VectorXcd& g,
                     const BodePlot& plot) {
  render(path, [&](const std::string& terminal) { return bode_script(terminal, hz, g, plot); });
}

void write_sweep_plot(const std::string& path, const SweepResult& r, const SweepPlot& plot) {
  render(path, [&](const std::string& terminal) { return sweep_script(terminal, r, plot); });
}

}  // namespace mbsgen::cli
