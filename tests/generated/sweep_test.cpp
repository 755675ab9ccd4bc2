// Eigenvalues against a parameter (parameter_sweep.hpp, the solvers' `sweep`): the Jeffcott
// rotor's threshold speed against its closed form Ω_th = √(k/m) (1 + c_n/c_r) = 300 rad/s
// (models/textbook/jeffcott_rotor.yaml, docs/test-references.md §7); the plot's legend (issue 44
// §2) with the rotor and the Whipple bicycle (models/bicycle/whipple_benchmark.yaml).
#include "jeffcott_rotor_model.hpp"
#include "whipple_benchmark_model.hpp"

#include "mbsgen/runtime/cli/solver_cli.hpp"
#include "mbsgen/runtime/spectral/parameter_sweep.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <complex>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace {

using mbsgen::GeneratedModel;

// The text of the sweep plot `solver` writes with `extra` arguments (an SVG: gnuplot writes each
// label and legend entry as a <text> element).
std::string sweep_svg(const mbsgen::ModelKernels& kernels, std::vector<std::string> args) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("sweep_legend_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "sweep.svg").string();
  args.insert(args.begin(), {"solve", "sweep"});
  args.insert(args.end(), {"--plot", file});
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream out, err;
  EXPECT_EQ(mbsgen::cli::solver_main(kernels, static_cast<int>(argv.size()), argv.data(), out, err), 0) << err.str();
  std::ifstream in(file);
  std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::filesystem::remove_all(dir);
  return svg;
}

bool has_text(const std::string& svg, const std::string& text) {
  return svg.find("<text>" + text + "</text>") != std::string::npos;
}

TEST(Sweep, JeffcottThresholdSpeedMatchesTheClosedForm) {
  GeneratedModel model(jeffcott_rotor::kernels());
  const mbsgen::SweepResult r = mbsgen::sweep_parameter(model, "Omega", 0, 500, 11);
  ASSERT_EQ(r.points.size(), 11u);
  EXPECT_EQ(r.points[5].value, 250);
  EXPECT_EQ(r.points[5].stability, mbsgen::Stability::stable);
  EXPECT_EQ(r.points[7].stability, mbsgen::Stability::unstable);
  ASSERT_EQ(r.boundaries.size(), 1u);
  const mbsgen::StabilityBoundary& b = r.boundaries[0];
  EXPECT_TRUE(b.becomes_unstable);
  // The reported tolerance bounds the true error (issue 39 §1): the closed form 300 rad/s is exact
  // in double. And it is small: Re λ crosses zero with slope ≈ 0.01 per rad/s and its error bound
  // is ~1e-12, so the undecided band the bracket keeps is ~1e-9 relative.
  EXPECT_LE(std::abs(b.value - 300), b.tolerance);
  EXPECT_LE(b.tolerance, 300 * 1e-9);
  EXPECT_EQ(b.below, mbsgen::Stability::stable);
  EXPECT_EQ(b.above, mbsgen::Stability::unstable);
  EXPECT_NEAR(std::abs(b.eigenvalue.imag()), 200, 1e-6);  // the whirl at √(k/m)
  EXPECT_EQ(model.parameters()[4], 250);  // Omega restored
}

TEST(Sweep, DescendingSweepFindsTheSameBoundary) {
  GeneratedModel model(jeffcott_rotor::kernels());
  const mbsgen::SweepResult r = mbsgen::sweep_parameter(model, "Omega", 450, 120, 7);
  ASSERT_EQ(r.boundaries.size(), 1u);
  EXPECT_TRUE(r.boundaries[0].becomes_unstable);  // in the direction of increasing Omega
  EXPECT_LE(std::abs(r.boundaries[0].value - 300), r.boundaries[0].tolerance);
}

// Without damping every eigenvalue is on the imaginary axis at every speed: rounding of Re λ
// (±1e-16) makes no boundary, because a real part within its error bound has no sign.
TEST(Sweep, UndampedRotorHasNoSpuriousBoundary) {
  GeneratedModel model(jeffcott_rotor::kernels());
  model.set("c_n", 0.0);
  model.set("c_r", 0.0);
  const mbsgen::SweepResult r = mbsgen::sweep_parameter(model, "Omega", 0, 500, 51);
  EXPECT_TRUE(r.boundaries.empty());
}

TEST(Sweep, BadArgumentsAreErrors) {
  GeneratedModel model(jeffcott_rotor::kernels());
  EXPECT_THROW(mbsgen::sweep_parameter(model, "Omegaa", 0, 1, 3), mbsgen::NameError);
  EXPECT_THROW(mbsgen::sweep_parameter(model, "Omega", 0, 1, 1), mbsgen::Error);
  EXPECT_THROW(mbsgen::sweep_parameter(model, "Omega", 0, INFINITY, 3), mbsgen::NonFiniteError);
}

TEST(Sweep, SolverCommandPrintsTheBoundary) {
  std::vector<std::string> args = {"jeffcott_rotor-solve", "sweep", "--parameter", "Omega", "--from", "0",
                                   "--to", "500", "--points", "6"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream out, err;
  EXPECT_EQ(mbsgen::cli::solver_main(jeffcott_rotor::kernels(), static_cast<int>(argv.size()), argv.data(), out, err), 0)
      << err.str();
  EXPECT_NE(out.str().find("# stability boundary: Omega = 300.0000000"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("unstable above"), std::string::npos) << out.str();
}

// --plot draws the eigenvalues against the parameter with gnuplot (an SVG: text we can read).
TEST(Sweep, PlotIsWritten) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("sweep_plot_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "omega.svg").string();
  std::vector<std::string> args = {"jeffcott_rotor-solve", "sweep", "--parameter", "Omega", "--from", "0",
                                   "--to", "500", "--points", "21", "--plot", file};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream out, err;
  ASSERT_EQ(mbsgen::cli::solver_main(jeffcott_rotor::kernels(), static_cast<int>(argv.size()), argv.data(), out, err), 0)
      << err.str();
  std::ifstream in(file);
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("eigenvalues against Omega"), std::string::npos);
  EXPECT_NE(svg.find("Omega [rad/s]"), std::string::npos);
  std::filesystem::remove_all(dir);
}

// Issue 44 §2: the plot has a legend naming every line, band and boundary. Without names the
// boundary is named by what crosses there (a complex pair: oscillatory, with its frequency
// √(k/m)/2π = 31.8 Hz), the branch that crosses by its boundary, the stable interval by its ends.
TEST(Sweep, PlotLegendNamesTheBoundaryTheBranchAndTheStableInterval) {
  const std::string svg = sweep_svg(jeffcott_rotor::kernels(), {"--parameter", "Omega", "--from", "0", "--to", "500",
                                                                "--points", "21"});
  EXPECT_TRUE(has_text(svg, "oscillatory boundary Omega = 300 rad/s (complex pair, 31.8 Hz)")) << svg;
  EXPECT_TRUE(has_text(svg, "branch crossing at Omega = 300 rad/s")) << svg;
  EXPECT_TRUE(has_text(svg, "stable: 0–300 rad/s")) << svg;
  EXPECT_TRUE(has_text(svg, "other complex pairs (oscillatory)")) << svg;
  EXPECT_TRUE(has_text(svg, "Re λ [1/s]")) << svg;
  EXPECT_TRUE(has_text(svg, "Im λ [1/s]")) << svg;
  // A name given on the command line (escaped for gnuplot: a quote and backquotes stay text).
  const std::string named = sweep_svg(jeffcott_rotor::kernels(), {"--parameter", "Omega", "--from", "0", "--to", "500",
                                                                  "--points", "21", "--boundary-names", "it's `x`"});
  EXPECT_TRUE(has_text(named, "it's `x` boundary Omega = 300 rad/s (complex pair, 31.8 Hz)")) << named;
  EXPECT_TRUE(has_text(named, "it's `x`")) << named;
}

// The bicycle (reference speeds 4.292 and 6.024 m/s, docs/test-references.md): the weave pair and
// the capsize root named by the user, the kinds from the data; the six exact zeros of the
// ignorable coordinates one grey line of their own, not a branch.
TEST(Sweep, BicyclePlotNamesWeaveCapsizeAndTheStructuralZeros) {
  const std::string svg = sweep_svg(whipple_benchmark::kernels(), {"--parameter", "v", "--from", "0", "--to", "10",
                                                                   "--points", "21", "--boundary-names", "weave,capsize"});
  EXPECT_TRUE(has_text(svg, "weave boundary v = 4.292 m/s (complex pair, 0.547 Hz)")) << svg;
  EXPECT_TRUE(has_text(svg, "capsize boundary v = 6.024 m/s (real eigenvalue)")) << svg;
  EXPECT_TRUE(has_text(svg, "weave")) << svg;
  EXPECT_TRUE(has_text(svg, "capsize")) << svg;
  EXPECT_TRUE(has_text(svg, "stable: 4.292–6.024 m/s (Re λ &lt; 0 apart from the exact zeros)")) << svg;  // XML
  EXPECT_TRUE(has_text(svg, "structural zeros λ = 0 (×6, exact)")) << svg;
  EXPECT_TRUE(has_text(svg, "other real eigenvalues")) << svg;  // the castering root
  EXPECT_TRUE(has_text(svg, "v [m/s]")) << svg;
  // Without names: the kinds.
  const std::string plain = sweep_svg(whipple_benchmark::kernels(), {"--parameter", "v", "--from", "0", "--to", "10",
                                                                     "--points", "21"});
  EXPECT_TRUE(has_text(plain, "oscillatory boundary v = 4.292 m/s (complex pair, 0.547 Hz)")) << plain;
  EXPECT_TRUE(has_text(plain, "divergence boundary v = 6.024 m/s (real eigenvalue)")) << plain;
}

// The exact zeros are counted apart from the computed eigenvalues: the bicycle's six (of its
// ignorable coordinates, tests/generated/rolling_test.cpp), the rotor's none.
TEST(Sweep, ExactZerosAreCounted) {
  GeneratedModel bicycle(whipple_benchmark::kernels());
  const mbsgen::SweepResult b = mbsgen::sweep_parameter(bicycle, "v", 4, 5, 2);
  for (const mbsgen::SweepPoint& p : b.points) {
    ASSERT_EQ(p.zeros, 6u);
    for (std::size_t i = 0; i < p.zeros; ++i) EXPECT_EQ(p.eigenvalues[i], std::complex<double>(0, 0));
    EXPECT_EQ(p.eigenvalues.size(), 10u);
  }
  GeneratedModel rotor(jeffcott_rotor::kernels());
  EXPECT_EQ(mbsgen::sweep_parameter(rotor, "Omega", 0, 1, 2).points[0].zeros, 0u);
}

}  // namespace
