// Parameter studies (issue 20 §2) through generated kernels: each evaluation against the closed
// form of a spring–mass, percentile bands against order statistics, Sobol' indices against their
// closed form for a product of lognormal factors, the same numbers for any split over threads and
// processes, and failures counted with their parameter values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "base_excited_oscillator_model.hpp"
#include "mbsgen/runtime/cli/solver_cli.hpp"
#include "mbsgen/runtime/model/generated_model.hpp"
#include "mbsgen/runtime/study/study.hpp"
#include "mbsgen/runtime/study/study_design.hpp"

namespace {

using mbsgen::Design;
using mbsgen::GeneratedModel;
using mbsgen::ParameterDistribution;
using mbsgen::StudyDesign;
using mbsgen::StudyQuantities;

GeneratedModel undamped_oscillator() {
  GeneratedModel model(base_excited_oscillator::kernels());
  model.set("c", 0.0);
  return model;
}

// f_n = √(k/m)/2π at every evaluation (1e-13: the eigenvalue of a 1×1 problem), and the response
// |x/F| = 1/|k − Ω²m| at 1 Hz (below every resonance here) and its level in dB.
TEST(Study, EveryEvaluationMatchesTheClosedForm) {
  const GeneratedModel model = undamped_oscillator();
  const StudyDesign design(Design::latin_hypercube,
                           {mbsgen::parse_distribution("k=uniform:200:2000"), mbsgen::parse_distribution("m=lognormal:2:1.5")},
                           101, 7);
  StudyQuantities q;
  q.modes = 1;
  q.input = "F", q.output = "x_abs";
  q.sweep_hz = {1.0};
  q.at_hz = {1.0};
  const auto r = mbsgen::evaluate(model, design, q, 0, design.size(), 2);
  ASSERT_EQ(r.scalar_names, (std::vector<std::string>{"f1_hz", "zeta1", "L_1Hz_dB"}));
  EXPECT_TRUE(r.failures.empty());
  for (std::size_t i = 0; i < design.size(); ++i) {
    const auto p = design.point(i);
    const double k = p[0], m = p[1], w = 2 * M_PI, f = std::sqrt(k / m) / (2 * M_PI), h = 1 / std::abs(k - w * w * m);
    EXPECT_NEAR(r.scalars[3 * i], f, 1e-13 * f);
    EXPECT_NEAR(r.scalars[3 * i + 1], 0.0, 1e-13);
    EXPECT_NEAR(r.sweep[i], h, 1e-13 * h);
    EXPECT_NEAR(r.scalars[3 * i + 2], 20 * std::log10(h), 1e-12);
  }
  // With 101 evaluations the 5 % and 95 % points are order statistics 5 and 95 exactly (type 7:
  // position q/100 · 100): the band is the responses of the ranked samples.
  std::vector<double> h(r.sweep.begin(), r.sweep.end());
  std::sort(h.begin(), h.end());
  const auto bands = mbsgen::percentile_bands(r, 1, {5, 50, 95});
  EXPECT_EQ(bands[0][0], h[5]);
  EXPECT_EQ(bands[1][0], h[50]);
  EXPECT_EQ(bands[2][0], h[95]);
}

// The same design split over 1 and 2 threads and over three "ranks" (consecutive ranges,
// appended) gives the same numbers bit for bit: every evaluation depends on its index only.
TEST(Study, AnySplitGivesTheSameNumbers) {
  const GeneratedModel model(base_excited_oscillator::kernels());
  const StudyDesign design(Design::saltelli,
                           {mbsgen::parse_distribution("k=lognormal:800:1.5"), mbsgen::parse_distribution("c=uniform:1:20")},
                           64, 11);
  StudyQuantities q;
  q.modes = 1;
  q.input = "xb", q.output = "x_rel";
  q.sweep_hz = {1, 3, 10};
  q.at_hz = {3};
  const auto one = mbsgen::evaluate(model, design, q, 0, design.size(), 1);
  const auto two = mbsgen::evaluate(model, design, q, 0, design.size(), 2);
  mbsgen::StudyResults parts;
  const std::size_t n = design.size(), cut[4] = {0, n / 3, 2 * n / 3, n};
  for (int r = 0; r < 3; ++r) mbsgen::append(parts, mbsgen::evaluate(model, design, q, cut[r], cut[r + 1] - cut[r], 2));
  ASSERT_EQ(parts.count, n);
  for (const mbsgen::StudyResults* other : {&two, static_cast<const mbsgen::StudyResults*>(&parts)}) {
    ASSERT_EQ(other->scalars.size(), one.scalars.size());
    for (std::size_t i = 0; i < one.scalars.size(); ++i) EXPECT_EQ(std::memcmp(&one.scalars[i], &other->scalars[i], 8), 0) << i;
    for (std::size_t i = 0; i < one.sweep.size(); ++i) EXPECT_EQ(std::memcmp(&one.sweep[i], &other->sweep[i], 8), 0) << i;
  }
}

// f_n = √(k/m)/2π with k and m lognormal is a product of independent lognormal factors
// A = e^{X_k/2}, B = e^{−X_m/2}: S_k = E[B]² Var A / V with V = E[A²]E[B²] − E[A]²E[B]², and
// ST_k = 1 − S_m. Saltelli's design with 2^13 base samples: each index within 4 bootstrap
// half-widths (about 8 σ of the estimator) plus 2e-3, and the interval covers at most 0.1.
TEST(Study, SobolIndicesOfTheNaturalFrequency) {
  const GeneratedModel model = undamped_oscillator();
  const double sk = std::log(1.6), sm = std::log(1.3);
  const StudyDesign design(Design::saltelli,
                           {mbsgen::parse_distribution("k=lognormal:800:1.6"), mbsgen::parse_distribution("m=lognormal:2:1.3")},
                           8192, 3);
  StudyQuantities q;
  q.modes = 1;
  const auto r = mbsgen::evaluate(model, design, q, 0, design.size(), 2);
  ASSERT_TRUE(r.failures.empty());
  std::vector<double> f(r.count);
  for (std::size_t i = 0; i < r.count; ++i) f[i] = r.scalars[2 * i];
  const auto sobol = mbsgen::sobol_indices(f, 8192, 2, 200, 5);
  auto moments = [](double s) {  // E[e^{sZ/2}], E[e^{sZ}] for Z ~ N(0, 1)
    return std::pair<double, double>{std::exp(s * s / 8), std::exp(s * s / 2)};
  };
  const auto [ea, ea2] = moments(sk);
  const auto [eb, eb2] = moments(sm);
  const double V = ea2 * eb2 - ea * ea * eb * eb;
  const double Sk = eb * eb * (ea2 - ea * ea) / V, Sm = ea * ea * (eb2 - eb * eb) / V;
  const double expect_first[2] = {Sk, Sm}, expect_total[2] = {1 - Sm, 1 - Sk};
  for (int j = 0; j < 2; ++j) {
    const auto& x = sobol.indices[static_cast<std::size_t>(j)];
    EXPECT_NEAR(x.first, expect_first[j], 4 * (x.first_high - x.first_low) / 2 + 2e-3) << j;
    EXPECT_NEAR(x.total, expect_total[j], 4 * (x.total_high - x.total_low) / 2 + 2e-3) << j;
    EXPECT_LT(x.first_high - x.first_low, 0.1);
    EXPECT_LT(x.total_high - x.total_low, 0.1);
  }
}

// A mass drawn negative fails (the runtime refuses a mass matrix that is not positive
// semi-definite): every such evaluation is counted, with its parameter value and the reason, and
// its quantities are NaN; the others are untouched.
TEST(Study, FailuresAreCountedWithTheirParameters) {
  const GeneratedModel model = undamped_oscillator();
  const StudyDesign design(Design::monte_carlo, {mbsgen::parse_distribution("m=uniform:-1:3")}, 400, 2);
  StudyQuantities q;
  q.modes = 1;
  const auto r = mbsgen::evaluate(model, design, q, 0, design.size(), 2);
  std::size_t negative = 0, f = 0;
  for (std::size_t i = 0; i < design.size(); ++i) {
    const double m = design.point(i)[0];
    if (m < 0) {
      ++negative;
      ASSERT_LT(f, r.failures.size());
      EXPECT_EQ(r.failures[f].index, i);
      EXPECT_EQ(r.failures[f].parameters[0], m);
      EXPECT_NE(r.failures[f].message.find("a mass must be >= 0"), std::string::npos) << r.failures[f].message;
      EXPECT_TRUE(std::isnan(r.scalars[2 * i]));
      ++f;
    } else {
      EXPECT_NEAR(r.scalars[2 * i], std::sqrt(800 / m) / (2 * M_PI), 1e-12 * std::sqrt(800 / m));
    }
  }
  EXPECT_GT(negative, 50u);
  EXPECT_EQ(r.failures.size(), negative);
}

int run(std::vector<std::string> args, std::string& out, std::string& err) {
  args.insert(args.begin(), "solve");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream o, e;
  const int rc = mbsgen::cli::solver_main(base_excited_oscillator::kernels(), static_cast<int>(argv.size()), argv.data(), o, e);
  out = o.str(), err = e.str();
  return rc;
}

std::string read(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The solver's `study`: its files (every evaluation, the bands, the Sobol' indices), and clear
// errors for what cannot be done.
TEST(Study, SolverCommandLine) {
  const std::string dir = ::testing::TempDir() + "/mbsgen_study_cli";
  std::filesystem::create_directories(dir);
  for (const char* f : {"/s.csv", "/b.json", "/sobol.csv"}) std::filesystem::remove(dir + f);
  std::string out, err;
  ASSERT_EQ(run({"study", "--parameter", "k=lognormal:800:1.5", "--parameter", "c=uniform:4:12", "--design", "saltelli",
                 "--samples", "32", "--modes", "1", "--input", "xb", "--output", "x_rel", "--from", "1", "--to", "10",
                 "--points", "5", "--at", "3", "--write-samples", dir + "/s.csv", "--bands", dir + "/b.json", "--sobol",
                 dir + "/sobol.csv", "--threads", "2"},
                out, err), 0) << err;
  EXPECT_NE(out.find("saltelli design, 128 evaluations"), std::string::npos) << out;
  EXPECT_NE(out.find("Sobol' indices"), std::string::npos) << out;
  const std::string samples = read(dir + "/s.csv");
  EXPECT_EQ(std::count(samples.begin(), samples.end(), '\n'), 2 + 128);
  EXPECT_NE(samples.find("index,\"k\",\"c\",f1_hz,zeta1,L_3Hz_dB,status"), std::string::npos) << samples.substr(0, 300);
  EXPECT_NE(read(dir + "/b.json").find("\"p95\": ["), std::string::npos);
  EXPECT_NE(read(dir + "/sobol.csv").find("f1_hz,\"k\","), std::string::npos);
  // Run again: the files are mbsgen's, so they are replaced.
  EXPECT_EQ(run({"study", "--parameter", "k=lognormal:800:1.5", "--samples", "8", "--modes", "1", "--write-samples",
                 dir + "/s.csv"}, out, err), 0) << err;
  EXPECT_EQ(run({"study", "--parameter", "kk=lognormal:800:1.5", "--samples", "8", "--modes", "1"}, out, err), 2);
  EXPECT_NE(err.find("no parameter 'kk'"), std::string::npos) << err;
  EXPECT_EQ(run({"study", "--parameter", "k=lognormal:800:0.5", "--samples", "8", "--modes", "1"}, out, err), 2);
  EXPECT_NE(err.find("k=lognormal:800:0.5"), std::string::npos) << err;
  EXPECT_EQ(run({"study", "--parameter", "k=uniform:1:2", "--samples", "8", "--design", "saltelli", "--input", "F",
                 "--output", "x_abs", "--from", "1", "--to", "2"}, out, err), 2);
  EXPECT_NE(err.find("need scalar quantities"), std::string::npos) << err;
  EXPECT_EQ(run({"study", "--parameter", "k=uniform:1:2", "--samples", "8", "--modes", "1", "--sobol", dir + "/x.csv"},
                out, err), 2);
  EXPECT_NE(err.find("--sobol needs the saltelli design"), std::string::npos) << err;
  // A file mbsgen did not write is refused before the evaluations, and left as it was.
  {
    std::ofstream(dir + "/mine.csv") << "my data\n";
  }
  EXPECT_EQ(run({"study", "--parameter", "k=uniform:1:2", "--samples", "8", "--modes", "1", "--write-samples",
                 dir + "/mine.csv"}, out, err), 1);
  EXPECT_NE(err.find("refusing to overwrite"), std::string::npos) << err;
  EXPECT_EQ(out, "");  // nothing was evaluated
  EXPECT_EQ(read(dir + "/mine.csv"), "my data\n");
  // Every evaluation failing (a negative mass): the failures are reported, no Sobol' index is
  // made up, exit status 1.
  EXPECT_EQ(run({"study", "--parameter", "m=uniform:-2:-1", "--samples", "8", "--modes", "1", "--design", "saltelli"},
                out, err), 1);
  EXPECT_NE(err.find("24 of 24 evaluations failed"), std::string::npos) << err;
  EXPECT_NE(out.find("f1_hz"), std::string::npos) << out;
}

}  // namespace
