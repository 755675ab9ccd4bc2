// Bode plots through gnuplot (Debian `gnuplot-nox`): we do not render plots ourselves.
#pragma once

#include <complex>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mbsgen/runtime/spectral/parameter_sweep.hpp"

namespace mbsgen::cli {

struct BodePlot {
  std::string title;
  std::string amplitude_label;  // e.g. "|v_stapes / P| [(m/s)/Pa]"
};

/// s as a gnuplot single-quoted string: `'` doubled; controls (newlines included) and DEL become
/// spaces, bytes that are not well-formed UTF-8 '?'. Gnuplot substitutes nothing inside single
/// quotes (no backquote commands, no macros), so the string is text and nothing else.
std::string gnuplot_string(const std::string& s);

/// Writes a Bode plot (amplitude on a log scale and phase lag in degrees over a logarithmic
/// frequency axis) of g(f) to `path` (.svg or .png). The file is written atomically (a temporary
/// file created exclusively beside it, then rename); gnuplot runs without a shell on a script in
/// a private temporary directory (mkdtemp) that names no file: data inline, the plot on its
/// standard output. Throws mbsgen::Error when gnuplot is missing or fails.
void write_bode_plot(const std::string& path, const Eigen::VectorXd& hz,
                     const Eigen::VectorXcd& g, const BodePlot& plot);

struct SweepPlot {
  std::string title;
  std::string parameter_label;  // e.g. "v [m/s]"
  std::string parameter;        // e.g. "v" (empty: the sweep's), for labels "v = 4.292 m/s"
  std::string unit;             // e.g. "m/s" ("" or "-": none)
  /// Names of the stability boundaries in order of increasing parameter (e.g. "weave",
  /// "capsize"); a boundary without one is named by what crosses there.
  std::vector<std::string> boundary_names;
};

/// Writes the eigenvalues of a parameter sweep to `path`, as write_bode_plot does: real parts
/// above, imaginary parts below, one legend for both. Real eigenvalues and complex pairs are
/// marked apart, the solver's exact zeros (SweepPoint::zeros) drawn as one grey line, each
/// stability boundary as a dashed vertical line named with its value and kind (oscillatory: a
/// complex pair crosses, with its frequency; divergence: a real eigenvalue crosses) or with
/// plot.boundary_names, the branch that crosses there (found by continuation) as a line of the
/// same colour, and the intervals where every eigenvalue but the exact zeros has Re λ < 0 shaded
/// and named "stable".
void write_sweep_plot(const std::string& path, const SweepResult& result, const SweepPlot& plot);

struct TimePlot {
  std::string title;
  std::vector<std::string> labels;  // one per series, e.g. "phi [rad]"
};
inline constexpr Eigen::Index kMaxTimePanels = 8;

/// Writes series against time (one panel each, 1 to kMaxTimePanels; values: series × samples) to
/// `path`, as write_bode_plot does. DimensionError for sizes that do not fit.
void write_time_plot(const std::string& path, const Eigen::VectorXd& t, const Eigen::MatrixXd& values,
                     const TimePlot& plot);

struct BandPlot {
  std::string title;
  std::string amplitude_label;  // e.g. "|v_stapes / P| [(m/s)/Pa]"
};

/// Writes percentile bands of an amplitude over frequency (log–log): the 5–95 % band shaded, the
/// 25–75 % band darker, the median as a line; bands rows p5, p25, p50, p75, p95 at hz. As
/// write_bode_plot does. DimensionError for sizes that do not fit.
void write_band_plot(const std::string& path, const std::vector<double>& hz,
                     const std::vector<std::vector<double>>& bands, const BandPlot& plot);

/// A fit's model response for one input/output pair (fit_cli.cpp): at the start and at the fit.
struct FitPlotCurve {
  std::string label;  // e.g. "v_stapes/P [m/s/Pa]"
  std::vector<double> hz;
  std::vector<std::complex<double>> initial, fitted;
};
/// One data set's points on a curve: data, and the weighted residuals at the fit.
struct FitPlotPoints {
  std::string label;  // e.g. "goode"
  std::size_t curve = 0;
  std::vector<double> hz;
  std::vector<std::complex<double>> data;
  std::vector<bool> has_magnitude, has_phase;
  std::vector<double> residual_magnitude, residual_phase;  // NaN: none
};
struct FitPlot {
  std::string title;
};

/// Writes a fit's plot to `path`, as write_bode_plot does: magnitude (log–log) and phase of the
/// data (points, one colour and mark per set), the start (dashed) and the fit (solid) per curve,
/// and below the weighted residuals of magnitude (filled) and phase (open) against frequency
/// with the lines ±2 named.
void write_fit_plot(const std::string& path, const std::vector<FitPlotCurve>& curves,
                    const std::vector<FitPlotPoints>& points, const FitPlot& plot);

}  // namespace mbsgen::cli
