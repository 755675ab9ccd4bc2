#include "cli/bode_plot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <system_error>
#include <utility>
#include <vector>

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
    << "set key top right box opaque noenhanced\n"  // each panel's one line named in a legend
    << "plot $bode using 1:2 with lines lw 2 lc rgb '#1f4e9c' title " << gnuplot_string("magnitude " + plot.amplitude_label)
    << "\nunset logscale y\nset format y '%g'\n"
    << "set ylabel 'phase lag [deg]'\nset xlabel 'frequency [Hz]'\n"
    << "plot $bode using 1:3 with lines lw 2 lc rgb '#1f4e9c' title 'phase lag [deg]'\n"
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
// gnuplot run without a shell in a private directory (see write_bode_plot); `size` in pixels.
void render(const std::string& path, const std::function<std::string(const std::string&)>& script_for,
            const std::string& size = "900,700") {
  const std::string ext = fs::path(path).extension().string();
  std::string terminal;
  if (ext == ".svg")
    terminal = "svg size " + size + " dynamic enhanced font 'Sans,12' background rgb 'white'";
  else if (ext == ".png")
    terminal = "pngcairo size " + size + " enhanced font 'Sans,11'";
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


// The sweep plot (issue 44 §2): every line, band and boundary named in a legend. What the sweep
// can tell is named from the data: a boundary where a complex pair crosses the imaginary axis is
// oscillatory (flutter, a Hopf point), one where a real eigenvalue crosses is a divergence; the
// branch that crosses there is found by continuation; the exact zeros the solver deflated
// (SweepPoint::zeros) are drawn as one grey line, not as a branch. Names such as "weave" come
// from the user (SweepPlot::boundary_names).

// A real eigenvalue: QZ gives Im λ exactly 0 for those; the tolerance only keeps the rounding of
// a pair that just split off the real axis from counting as real.
bool is_real(std::complex<double> l) { return std::abs(l.imag()) <= 1e-10 * std::abs(l); }

std::string format_number(double x, const char* format) {
  char b[64];
  std::snprintf(b, sizeof b, format, x);
  return b;
}

// "4.292 m/s": a parameter value with its unit (none for "" and "-").
std::string with_unit(double x, const std::string& unit) {
  return format_number(x, "%.4g") + (unit.empty() || unit == "-" ? "" : " " + unit);
}

// The branches of the nonzero eigenvalues through the sweep, by continuation: at each point the
// eigenvalues are matched to the branches' linear extrapolations, nearest pair first.
// branches[j][k]: branch j at point k, NaN where it has none. Empty when the spectrum is too
// large for the quadratic matching to be cheap (the plot then names no branch).
using Branches = std::vector<std::vector<std::complex<double>>>;
constexpr std::size_t kMaxTrackedEigenvalues = 200;

Branches track_branches(const std::vector<SweepPoint>& points) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::complex<double> none(nan, nan);
  Branches branches;
  for (std::size_t k = 0; k < points.size(); ++k) {
    std::vector<std::complex<double>> found;
    for (std::size_t i = points[k].zeros; i < points[k].eigenvalues.size(); ++i) {
      const std::complex<double> l = points[k].eigenvalues[i];
      if (std::isfinite(l.real()) && std::isfinite(l.imag())) found.push_back(l);
    }
    if (found.size() > kMaxTrackedEigenvalues) return {};
    std::vector<std::size_t> live;
    std::vector<std::complex<double>> predicted;
    for (std::size_t j = 0; j < branches.size(); ++j) {
      if (k == 0 || std::isnan(branches[j][k - 1].real())) continue;
      const std::complex<double> last = branches[j][k - 1];
      const bool two = k >= 2 && !std::isnan(branches[j][k - 2].real());
      live.push_back(j);
      predicted.push_back(two ? 2.0 * last - branches[j][k - 2] : last);
    }
    struct Match {
      double distance;
      std::size_t branch, eigenvalue;
    };
    std::vector<Match> matches;
    for (std::size_t b = 0; b < live.size(); ++b)
      for (std::size_t e = 0; e < found.size(); ++e) matches.push_back({std::abs(predicted[b] - found[e]), b, e});
    std::sort(matches.begin(), matches.end(), [](const Match& x, const Match& y) {
      return x.distance < y.distance || (x.distance == y.distance && (x.branch < y.branch ||
                                                                      (x.branch == y.branch && x.eigenvalue < y.eigenvalue)));
    });
    for (auto& b : branches) b.push_back(none);
    std::vector<bool> branch_done(live.size()), eigenvalue_done(found.size());
    for (const Match& m : matches) {
      if (branch_done[m.branch] || eigenvalue_done[m.eigenvalue]) continue;
      branches[live[m.branch]][k] = found[m.eigenvalue];
      branch_done[m.branch] = eigenvalue_done[m.eigenvalue] = true;
    }
    for (std::size_t e = 0; e < found.size(); ++e) {
      if (eigenvalue_done[e]) continue;
      branches.emplace_back(k, none);
      branches.back().push_back(found[e]);
    }
  }
  return branches;
}

// The branches that cross the imaginary axis at boundary b: among those whose real part changes
// sign between the two points around b, the one nearest b's eigenvalue and, for a complex pair,
// the one nearest its conjugate. Empty when no branch changes sign there.
std::vector<std::size_t> crossing_branches(const Branches& branches, const std::vector<SweepPoint>& points,
                                           const StabilityBoundary& b) {
  if (branches.empty() || points.size() < 2) return {};
  std::size_t k = 1;
  double best_gap = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < points.size(); ++i) {
    const double lo = std::min(points[i - 1].value, points[i].value), hi = std::max(points[i - 1].value, points[i].value);
    const double gap = b.value < lo ? lo - b.value : (b.value > hi ? b.value - hi : 0.0);
    if (gap < best_gap) {
      best_gap = gap;
      k = i;
    }
  }
  const std::size_t unstable = points[k].abscissa > 0 ? k : k - 1;
  std::vector<std::size_t> changing;
  for (std::size_t j = 0; j < branches.size(); ++j) {
    const std::complex<double> x = branches[j][k - 1], y = branches[j][k];
    if (std::isnan(x.real()) || std::isnan(y.real())) continue;
    if ((x.real() > 0) != (y.real() > 0)) changing.push_back(j);
  }
  const auto nearest = [&](std::complex<double> target, std::size_t other) {
    std::size_t best = branches.size();
    double d = std::numeric_limits<double>::infinity();
    for (const std::size_t j : changing) {
      if (j == other || !(std::abs(branches[j][unstable] - target) < d)) continue;
      d = std::abs(branches[j][unstable] - target);
      best = j;
    }
    return best;
  };
  std::vector<std::size_t> crossing;
  const std::size_t first = nearest(b.eigenvalue, branches.size());
  if (first == branches.size()) return crossing;
  crossing.push_back(first);
  if (!is_real(b.eigenvalue)) {
    const std::size_t second = nearest(std::conj(b.eigenvalue), first);
    if (second != branches.size()) crossing.push_back(second);
  }
  return crossing;
}

// The parameter intervals between the sweep's ends and its boundaries in which no point is
// unstable and some point has a decided negative spectral abscissa (the exact zeros aside).
std::vector<std::pair<double, double>> stable_intervals(const SweepResult& r) {
  std::vector<double> edges;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const SweepPoint& p : r.points) {
    lo = std::min(lo, p.value);
    hi = std::max(hi, p.value);
  }
  edges.push_back(lo);
  for (const StabilityBoundary& b : r.boundaries) edges.push_back(b.value);
  edges.push_back(hi);
  std::sort(edges.begin() + 1, edges.end() - 1);
  std::vector<std::pair<double, double>> stable;
  for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
    bool unstable = false, negative = false;
    for (const SweepPoint& p : r.points) {
      if (p.value < edges[i] || p.value > edges[i + 1]) continue;
      if (p.value != edges[i] && p.value != edges[i + 1]) unstable = unstable || p.abscissa > 0;
      negative = negative || (std::isfinite(p.abscissa) && p.abscissa < 0);
    }
    if (negative && !unstable && edges[i + 1] > edges[i]) stable.emplace_back(edges[i], edges[i + 1]);
  }
  return stable;
}

// A legend entry for each boundary and a name for the branches that cross it.
struct NamedBranch {
  std::string label;
  std::vector<std::size_t> branches;
};
struct BoundaryNames {
  std::vector<std::string> labels;    ///< per boundary, in order of the parameter
  std::vector<NamedBranch> branches;  ///< one per boundary (no branch when none was found)
  bool any_named = false;
};

// Each boundary named by the user or by what crosses there (a complex pair: oscillatory, with its
// frequency; a real eigenvalue: divergence), and the branches that cross it, each named once (at
// its first boundary).
BoundaryNames name_boundaries(const std::vector<const StabilityBoundary*>& boundaries, const Branches& branches,
                              const SweepResult& r, const SweepPlot& plot, const std::string& parameter) {
  BoundaryNames out;
  std::vector<bool> named(branches.size());
  for (std::size_t i = 0; i < boundaries.size(); ++i) {
    const StabilityBoundary& b = *boundaries[i];
    const bool oscillatory = !is_real(b.eigenvalue);
    const std::string given = i < plot.boundary_names.size() ? plot.boundary_names[i] : std::string();
    const std::string at = parameter + " = " + with_unit(b.value, plot.unit);
    std::string label = given.empty() ? (oscillatory ? "oscillatory boundary " : "divergence boundary ") : given + " boundary ";
    label += at + (oscillatory ? " (complex pair, " + format_number(std::abs(b.eigenvalue.imag()) / (2 * kPi), "%.3g") + " Hz)"
                               : " (real eigenvalue)");
    out.labels.push_back(label);
    NamedBranch n;
    n.label = given.empty() ? "branch crossing at " + at : given;
    for (const std::size_t j : crossing_branches(branches, r.points, b)) {
      if (named[j]) continue;  // it crossed at an earlier boundary too, and has that name
      named[j] = true;
      n.branches.push_back(j);
    }
    out.any_named = out.any_named || !n.branches.empty();
    out.branches.push_back(n);
  }
  return out;
}

// The named branches as data blocks $branch_<boundary>_<m>: parameter, Re λ, Im λ (a gap where
// a branch is not tracked).
void write_branches(std::ostream& s, const std::vector<NamedBranch>& named_branches, const Branches& branches,
                    const SweepResult& r) {
  for (std::size_t i = 0; i < named_branches.size(); ++i)
    for (std::size_t m = 0; m < named_branches[i].branches.size(); ++m) {
      s << "$branch_" << i << "_" << m << " << EOD\n";
      const auto& values = branches[named_branches[i].branches[m]];
      for (std::size_t k = 0; k < values.size(); ++k) {
        if (std::isnan(values[k].real())) {
          s << "\n";
          continue;
        }
        char line[128];
        std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", r.points[k].value, values[k].real(), values[k].imag());
        s << line;
      }
      s << "EOD\n";
    }
}

// The eigenvalues against the parameter: real parts above, imaginary parts below, one legend for
// both below them. Every label a gnuplot_string, every text literal (noenhanced).
std::string sweep_script(const std::string& terminal, const SweepResult& r, const SweepPlot& plot) {
  static const char* const kBranchColors[] = {"#d95f02", "#1b9e77", "#e7298a", "#66a61e", "#a6761d", "#e6ab02"};
  constexpr std::size_t kColors = sizeof kBranchColors / sizeof kBranchColors[0];
  const std::string parameter = plot.parameter.empty() ? r.parameter : plot.parameter;
  std::ostringstream s;
  s << "set terminal " << terminal << "\nset termoption noenhanced\n";
  const auto row = [&s](double x, double y, double z) {
    char line[128];
    std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", x, y, z);
    s << line;
  };
  // The boundaries in order of the parameter, named by the user or by what crosses there, each
  // with the branches that cross.
  std::vector<const StabilityBoundary*> boundaries;
  for (const StabilityBoundary& b : r.boundaries) boundaries.push_back(&b);
  std::stable_sort(boundaries.begin(), boundaries.end(),
                   [](const StabilityBoundary* a, const StabilityBoundary* b) { return a->value < b->value; });
  const Branches branches = boundaries.empty() ? Branches{} : track_branches(r.points);
  const BoundaryNames names = name_boundaries(boundaries, branches, r, plot, parameter);
  const std::vector<std::string>& boundary_labels = names.labels;
  const std::vector<NamedBranch>& named_branches = names.branches;
  const bool any_named = names.any_named;
  // The points not on a named branch, real and complex apart; the exact zeros as a line (a gap
  // where there are none).
  std::vector<std::vector<std::complex<double>>> on_branch(r.points.size());  // per point
  for (const NamedBranch& n : named_branches)
    for (const std::size_t j : n.branches)
      for (std::size_t k = 0; k < r.points.size(); ++k) on_branch[k].push_back(branches[j][k]);
  std::size_t real_count = 0, complex_count = 0, zeros_min = 0, zeros_max = 0, zero_points = 0;
  std::ostringstream real_rows, complex_rows;
  for (std::size_t k = 0; k < r.points.size(); ++k) {
    const SweepPoint& p = r.points[k];
    std::vector<std::complex<double>> skip = on_branch[k];
    for (std::size_t i = p.zeros; i < p.eigenvalues.size(); ++i) {
      const auto l = p.eigenvalues[i];
      if (!std::isfinite(l.real()) || !std::isfinite(l.imag())) continue;
      const auto it = std::find(skip.begin(), skip.end(), l);
      if (it != skip.end()) {
        skip.erase(it);
        continue;
      }
      const bool real = is_real(l);
      std::ostringstream& rows = real ? real_rows : complex_rows;
      ++(real ? real_count : complex_count);
      char line[128];
      std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", p.value, l.real(), l.imag());
      rows << line;
    }
  }
  s << "$real << EOD\n" << real_rows.str() << "EOD\n$complex << EOD\n" << complex_rows.str() << "EOD\n$zeros << EOD\n";
  for (const SweepPoint& p : r.points) {
    if (p.zeros == 0) {
      s << "\n";
      continue;
    }
    ++zero_points;
    zeros_min = zeros_min == 0 ? p.zeros : std::min(zeros_min, p.zeros);
    zeros_max = std::max(zeros_max, p.zeros);
    row(p.value, 0, 0);
  }
  s << "EOD\n";
  write_branches(s, named_branches, branches, r);

  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const SweepPoint& p : r.points) {
    lo = std::min(lo, p.value);
    hi = std::max(hi, p.value);
  }
  s << "set multiplot title " << gnuplot_string(plot.title) << "\n"
    << "set grid xtics ytics\nunset key\nset lmargin at screen 0.1\nset rmargin at screen 0.97\n";
  if (hi > lo) s << "set xrange [" << format_number(lo, "%.17g") << ":" << format_number(hi, "%.17g") << "]\n";
  // The stable intervals shaded, the boundaries as dashed lines, in both panels.
  const std::vector<std::pair<double, double>> stable = stable_intervals(r);
  std::string stable_label;
  for (const auto& iv : stable) {
    s << "set object rectangle from " << format_number(iv.first, "%.17g") << ", graph 0 to "
      << format_number(iv.second, "%.17g") << ", graph 1 behind fillcolor rgb '#d9f0d3' fillstyle solid 1.0 noborder\n";
    stable_label += (stable_label.empty() ? "stable: " : ", ") + format_number(iv.first, "%.4g") + "–" +
                    with_unit(iv.second, plot.unit);
  }
  if (!stable_label.empty() && zeros_max > 0) stable_label += " (Re λ < 0 apart from the exact zeros)";
  const auto color = [&](std::size_t i) { return std::string(kBranchColors[i % kColors]); };
  for (std::size_t i = 0; i < boundaries.size(); ++i)
    s << "set arrow from " << format_number(boundaries[i]->value, "%.17g") << ", graph 0 to "
      << format_number(boundaries[i]->value, "%.17g") << ", graph 1 nohead front dashtype 2 linewidth 1.5 linecolor rgb '"
      << color(i) << "'\n";

  // The plot command of one panel (column 2: real parts, 3: imaginary parts); `titled`: with the
  // legend's entries (the lower panel carries the legend of both).
  const auto plot_command = [&](int column, bool titled) {
    const auto title = [&](const std::string& t) { return titled ? " title " + gnuplot_string(t) : std::string(" notitle"); };
    std::ostringstream c;
    c << "plot ";
    std::string sep;
    if (!stable_label.empty()) {
      c << "NaN with filledcurves y1=0 fillcolor rgb '#d9f0d3' fillstyle solid 1.0" << title(stable_label);
      sep = ", ";
    }
    if (zeros_max > 0) {
      const std::string count = zeros_min == zeros_max ? std::to_string(zeros_max)
                                                      : std::to_string(zeros_min) + "–" + std::to_string(zeros_max);
      c << sep << "$zeros using 1:" << column << " with lines linewidth 3 linecolor rgb '#9e9e9e'"
        << title("structural zeros λ = 0 (×" + count + ", exact)");
      sep = ", ";
    }
    if (real_count > 0) {
      c << sep << "$real using 1:" << column << " with points pointtype 7 pointsize 0.45 linecolor rgb '#1f4e9c'"
        << title(!any_named ? "real eigenvalues" : "other real eigenvalues");
      sep = ", ";
    }
    if (complex_count > 0) {
      c << sep << "$complex using 1:" << column << " with points pointtype 9 pointsize 0.6 linecolor rgb '#7b3294'"
        << title(!any_named ? "complex pairs (oscillatory)" : "other complex pairs (oscillatory)");
      sep = ", ";
    }
    for (std::size_t i = 0; i < named_branches.size(); ++i)
      for (std::size_t m = 0; m < named_branches[i].branches.size(); ++m) {
        c << sep << "$branch_" << i << "_" << m << " using 1:" << column << " with lines linewidth 3 linecolor rgb '"
          << color(i) << "'" << (m == 0 ? title(named_branches[i].label) : std::string(" notitle"));
        sep = ", ";
      }
    for (std::size_t i = 0; i < boundaries.size(); ++i) {
      c << sep << "NaN with lines dashtype 2 linewidth 1.5 linecolor rgb '" << color(i) << "'" << title(boundary_labels[i]);
      sep = ", ";
    }
    // The axis Re λ = 0 (Im λ = 0), unless the zeros' line is there at every point.
    if (zero_points < r.points.size()) c << sep << "0 with lines linewidth 1 linecolor rgb 'black' notitle";
    c << "\n";
    return c.str();
  };
  // The panels above the legend, which takes a line an entry.
  std::size_t entries = boundaries.size() + (stable_label.empty() ? 0 : 1) + (zeros_max > 0 ? 1 : 0) +
                        (real_count > 0 ? 1 : 0) + (complex_count > 0 ? 1 : 0);
  for (const NamedBranch& n : named_branches) entries += n.branches.empty() ? 0 : 1;
  const double key = std::min(0.45, 0.024 * static_cast<double>(entries) + 0.02), bottom = key + 0.09;
  const double panel = (0.94 - bottom - 0.07) / 2;
  s << "set offsets 0, 0, graph 0.05, graph 0.05\n"
    << "set tmargin at screen 0.94\nset bmargin at screen " << format_number(0.94 - panel, "%.4f") << "\n"
    << "set ylabel 'Re λ [1/s]'\n" << plot_command(2, false)
    << "set tmargin at screen " << format_number(bottom + panel, "%.4f") << "\nset bmargin at screen "
    << format_number(bottom, "%.4f") << "\nset ylabel 'Im λ [1/s]'\n"
    << "set xlabel " << gnuplot_string(plot.parameter_label) << "\n"
    << "set key at screen 0.5, " << format_number(key, "%.4f")
    << " center top vertical Left reverse samplen 2 spacing 1.1\n"
    << plot_command(3, true) << "unset multiplot\n";
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
    << "set grid xtics ytics\nset key top right box opaque noenhanced\n";
  for (Eigen::Index i = 0; i < values.rows(); ++i) {
    if (i + 1 == values.rows()) s << "set xlabel 'time [s]'\n";
    const std::string label = gnuplot_string(plot.labels[static_cast<std::size_t>(i)]);
    s << "set ylabel " << label << " noenhanced\n"
      << "plot $series using 1:" << i + 2 << " with lines lw 2 lc rgb '#1f4e9c' title " << label << "\n";
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
  render(path, [&](const std::string& terminal) { return sweep_script(terminal, r, plot); }, "900,900");
}

}  // namespace mbsgen::cli

namespace mbsgen::cli {

namespace {

// The fit plot's script: one datablock per curve ($c: hz, |start|, start phase, |fit|, fit phase,
// phases unwrapped) and per set of points ($d: hz, |data|, phase on the fitted curve's branch,
// residuals); data inline, labels gnuplot strings.
std::string fit_script(const std::string& terminal, const std::vector<FitPlotCurve>& curves,
                       const std::vector<FitPlotPoints>& points, const FitPlot& plot) {
  static const char* colours[] = {"#1f4e9c", "#c0392b", "#1e8449", "#7d3c98", "#b9770e", "#17a589"};
  static const int marks[] = {7, 5, 9, 11, 13, 15};
  std::ostringstream s;
  s << "set terminal " << terminal << "\n";
  const auto deg = [](std::complex<double> z) { return std::arg(z) * 180.0 / kPi; };
  const auto unwrap = [&](const std::vector<std::complex<double>>& z, double near) {
    std::vector<double> out;
    for (std::size_t i = 0; i < z.size(); ++i) {
      double d = deg(z[i]);
      const double ref = i == 0 ? near : out.back();
      if (std::isfinite(ref)) d += 360.0 * std::round((ref - d) / 360.0);
      out.push_back(d);
    }
    return out;
  };
  double lo = 0, hi = 0;
  std::vector<std::vector<double>> fit_phase;
  for (std::size_t k = 0; k < curves.size(); ++k) {
    const FitPlotCurve& c = curves[k];
    fit_phase.push_back(unwrap(c.fitted, NAN));
    const std::vector<double> start = unwrap(c.initial, fit_phase.back().empty() ? NAN : fit_phase.back().front());
    s << "$c" << k << " << EOD\n";
    for (std::size_t i = 0; i < c.hz.size(); ++i) {
      char line[256];
      std::snprintf(line, sizeof line, "%.17g %.17g %.17g %.17g %.17g\n", c.hz[i], std::abs(c.initial[i]), start[i],
                    std::abs(c.fitted[i]), fit_phase.back()[i]);
      s << line;
      lo = lo == 0 ? c.hz[i] : std::min(lo, c.hz[i]);
      hi = std::max(hi, c.hz[i]);
    }
    s << "EOD\n";
  }
  for (std::size_t k = 0; k < points.size(); ++k) {
    const FitPlotPoints& x = points[k];
    const FitPlotCurve& c = curves[x.curve];
    s << "$d" << k << " << EOD\n";
    for (std::size_t i = 0; i < x.hz.size(); ++i) {
      double ph = x.has_phase[i] ? deg(x.data[i]) : NAN;
      std::size_t near = 0;  // the curve's frequency nearest the point's (log scale)
      for (std::size_t j = 0; j < c.hz.size(); ++j)
        if (std::abs(std::log(c.hz[j] / x.hz[i])) < std::abs(std::log(c.hz[near] / x.hz[i]))) near = j;
      if (std::isfinite(ph) && near < fit_phase[x.curve].size()) ph += 360.0 * std::round((fit_phase[x.curve][near] - ph) / 360.0);
      char line[256];
      std::snprintf(line, sizeof line, "%.17g %.17g %.17g %.17g %.17g\n", x.hz[i], x.has_magnitude[i] ? std::abs(x.data[i]) : NAN,
                    ph, x.residual_magnitude[i], x.residual_phase[i]);
      s << line;
    }
    s << "EOD\n";
  }
  const auto any = [&](const FitPlotPoints& x, const std::vector<bool>& v) {
    return std::find(v.begin(), v.end(), true) != v.end() && !x.hz.empty();
  };
  s << "set multiplot layout 3,1 title " << gnuplot_string(plot.title) << " noenhanced\n";
  if (hi > lo) s << "set xrange [" << lo / 1.1 << ":" << hi * 1.1 << "]\n";
  s << "set logscale x\nset grid xtics ytics mxtics\nset format x '10^{%L}'\nset key outside right top box noenhanced\n"
    << "set lmargin 12\nset rmargin 36\n";
  const auto curve_lines = [&](int start_col, int fit_col) {
    std::string out;
    for (std::size_t k = 0; k < curves.size(); ++k) {
      const std::string c = std::string("lc rgb '") + colours[k % 6] + "'", n = std::to_string(k);
      out += (k ? ", " : "") + std::string("$c") + n + " using 1:" + std::to_string(start_col) + " with lines dt 2 lw 1.5 " + c +
             " title " + gnuplot_string(curves[k].label + " start") + ", $c" + n + " using 1:" + std::to_string(fit_col) +
             " with lines lw 2 " + c + " title " + gnuplot_string(curves[k].label + " fit");
    }
    return out;
  };
  const auto point_marks = [&](int col, bool magnitude, bool open, const std::string& what) {
    std::string out;
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (!any(points[k], magnitude ? points[k].has_magnitude : points[k].has_phase)) continue;
      const std::string c = std::string("lc rgb '") + colours[(k + 2) % 6] + "'";
      out += ", $d" + std::to_string(k) + " using 1:" + std::to_string(col) + " with points pt " +
             std::to_string(marks[k % 6] - (open ? 1 : 0)) + " ps 1.3 " + c + " title " + gnuplot_string(points[k].label + what);
    }
    return out;
  };
  s << "set logscale y\nset format y '10^{%L}'\nset ylabel 'magnitude [units: legend]'\n"
    << "plot " << curve_lines(2, 4) << point_marks(2, true, false, " data") << "\n"
    << "unset logscale y\nset format y '%g'\nset ylabel 'phase [deg]'\n"
    << "plot " << curve_lines(3, 5) << point_marks(3, false, false, " data") << "\n"
    << "set ylabel 'weighted residual [-]'\nset xlabel 'frequency [Hz]'\n"
    << "plot 2 with lines dt 3 lc rgb '#777777' title '+2 (2 sigma)', -2 with lines dt 3 lc rgb '#777777' title '-2', "
    << "0 with lines lc rgb '#000000' notitle" << point_marks(4, true, false, " ln|H|") << point_marks(5, false, true, " phase")
    << "\nunset multiplot\n";
  return s.str();
}

}  // namespace

void write_fit_plot(const std::string& path, const std::vector<FitPlotCurve>& curves,
                    const std::vector<FitPlotPoints>& points, const FitPlot& plot) {
  if (curves.empty()) throw DimensionError("write_fit_plot: no curve");
  for (const FitPlotCurve& c : curves)
    if (c.initial.size() != c.hz.size() || c.fitted.size() != c.hz.size() || c.hz.empty())
      throw DimensionError("write_fit_plot: curve '" + c.label + "' has vectors of different sizes");
  for (const FitPlotPoints& x : points)
    if (x.curve >= curves.size() || x.data.size() != x.hz.size() || x.has_phase.size() != x.hz.size() ||
        x.has_magnitude.size() != x.hz.size() || x.residual_magnitude.size() != x.hz.size() ||
        x.residual_phase.size() != x.hz.size())
      throw DimensionError("write_fit_plot: the points of '" + x.label + "' do not fit their sizes or curve");
  render(path, [&](const std::string& terminal) { return fit_script(terminal, curves, points, plot); }, "1100,1000");
}

}  // namespace mbsgen::cli
