// Bode plots through gnuplot (Debian `gnuplot-nox`): we do not render plots ourselves.
#pragma once

#include <string>

#include <Eigen/Core>

namespace mbsgen::cli {

struct BodePlot {
  std::string title;
  std::string amplitude_label;  // e.g. "|v_stapes / P| [(m/s)/Pa]"
};

/// Writes a Bode plot (amplitude on a log scale and phase lag in degrees over a logarithmic
/// frequency axis) of g(f) to `path` (.svg or .png). The file is written atomically (temporary
/// file, then rename). Throws mbsgen::Error when gnuplot is missing or fails.
void write_bode_plot(const std::string& path, const Eigen::VectorXd& hz,
                     const Eigen::VectorXcd& g, const BodePlot& plot);

}  // namespace mbsgen::cli
