// Eigenvalues against a parameter (parameter_sweep.hpp, the solvers' `sweep`): the Jeffcott
// rotor's threshold speed against its closed form Ω_th = √(k/m) (1 + c_n/c_r) = 300 rad/s
// (models/textbook/jeffcott_rotor.yaml, docs/test-references.md §7).
#include "jeffcott_rotor_model.hpp"

#include "mbsgen/runtime/cli/solver_cli.hpp"
#include "mbsgen/runtime/spectral/parameter_sweep.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace {

using mbsgen::GeneratedModel;

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
  // 1e-10 relative, the bar: Re λ crosses zero with slope ≈ c_r/(2m)/√(k/m)·... ≈ 0.01 per
  // rad/s and is computed to ~1e-14, so the crossing is known to ~1e-12 rad/s.
  EXPECT_NEAR(b.value, 300, 300 * 1e-10);
  EXPECT_LE(b.tolerance, 300 * 1e-13);
  EXPECT_NEAR(std::abs(b.eigenvalue.imag()), 200, 1e-6);  // the whirl at √(k/m)
  EXPECT_EQ(model.parameters()[4], 250);  // Omega restored
}

TEST(Sweep, DescendingSweepFindsTheSameBoundary) {
  GeneratedModel model(jeffcott_rotor::kernels());
  const mbsgen::SweepResult r = mbsgen::sweep_parameter(model, "Omega", 450, 120, 7);
  ASSERT_EQ(r.boundaries.size(), 1u);
  EXPECT_TRUE(r.boundaries[0].becomes_unstable);  // in the direction of increasing Omega
  EXPECT_NEAR(r.boundaries[0].value, 300, 300 * 1e-10);
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

}  // namespace
