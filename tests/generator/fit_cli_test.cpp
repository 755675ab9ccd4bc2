// The command `fit` (issue 42) as a user runs it: `mbsgen run MODEL -- fit …` answers from the
// tape through mbsgen-fit; data made by `mbsgen run … frf` with known parameters are fitted back;
// files are all-or-nothing and never overwrite a file mbsgen did not write; bad input gets a
// message with its file, line and column; a compiled solver says where fit runs.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>

#include "run_process.hpp"

namespace {

const fs::path kChain = fs::path(MBSGEN_SOURCE_DIR) / "models/textbook/chain3_sympy.yaml";

struct FitDir {
  fs::path dir = temporary_directory();
  std::map<std::string, std::string> env{{"MBSGEN_CACHE_DIR", (dir / "cache").string()}};
  ~FitDir() { fs::remove_all(dir); }
};

// The chain's response F → end_x with k1..k3 = 12, 18, 33 as a data file (frequency_hz,re,im).
fs::path make_data(const FitDir& d) {
  const Result r = run({MBSGEN_TOOL, "run", kChain.string(), "--", "frf", "--input", "F", "--output", "end_x", "--from", "0.2",
                        "--to", "10", "--points", "30", "--format", "csv", "--set", "k1=12", "--set", "k2=18", "--set", "k3=33"},
                       d.dir, d.env);
  EXPECT_EQ(r.status, 0) << r.output;
  std::istringstream in(r.output);
  std::string line;
  std::ostringstream out;
  out << "# the chain with k1, k2, k3 = 12, 18, 33\nfrequency_hz,re,im\n";
  std::getline(in, line);  // the header
  while (std::getline(in, line)) {
    std::istringstream f(line);
    std::string hz, re, im;
    std::getline(f, hz, ',');
    std::getline(f, re, ',');
    std::getline(f, im, ',');
    out << hz << "," << re << "," << im << "\n";
  }
  const fs::path p = d.dir / "data.csv";
  std::ofstream(p) << out.str();
  return p;
}

std::vector<std::string> fit_args(const fs::path& data) {
  return {MBSGEN_TOOL, "run", kChain.string(), "--", "fit", "--data", data.string(), "--input", "F", "--output", "end_x",
          "--parameter", "k1=1:100", "--parameter", "k2=1:100", "--parameter", "k3=1:100"};
}

// The estimate of `name` in the table: the third column of its row.
double estimate(const std::string& table, const std::string& name) {
  const std::regex row("\\n *" + name + " +[-+.e0-9]+ +([-+.e0-9]+) ");
  std::smatch m;
  if (!std::regex_search(table, m, row)) return NAN;
  return std::stod(m[1]);
}

TEST(FitCommand, RecoversTheParametersOfItsData) {
  FitDir d;
  const fs::path data = make_data(d);
  const Result r = run(fit_args(data), d.dir, d.env);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("3 parameters, converged"), std::string::npos) << r.output;
  // Noise-free data (unit weights): the truth to the solver's tolerance, printed to 7 digits.
  EXPECT_NEAR(estimate(r.output, "k1"), 12.0, 1e-5) << r.output;
  EXPECT_NEAR(estimate(r.output, "k2"), 18.0, 1e-5) << r.output;
  EXPECT_NEAR(estimate(r.output, "k3"), 33.0, 1e-5) << r.output;
  EXPECT_NE(r.output.find("estimated from the residuals"), std::string::npos);
}

TEST(FitCommand, WritesItsFilesAllOrNothingAndNeverAForeignOne) {
  FitDir d;
  const fs::path data = make_data(d), out = d.dir / "out";
  fs::create_directory(out);
  std::vector<std::string> args = fit_args(data);
  for (const char* a : {"--out", "OUT", "--profile", "k1", "--plot", "PLOT", "--format", "json"}) args.push_back(a);
  args[args.size() - 7] = out.string();
  args[args.size() - 3] = (d.dir / "fit.svg").string();
  Result r = run(args, d.dir, d.env);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output.rfind("{\"generator\": \"mbsgen fit\"", 0), 0u) << r.output;
  for (const char* f : {"fit.json", "fit_points.csv", "fit_estimates.csv", "fit_profile_k1.csv"})
    EXPECT_TRUE(fs::is_regular_file(out / f)) << f;
  EXPECT_NE(slurp(out / "fit_estimates.csv").find("\n\"k1\",log,10,"), std::string::npos) << slurp(out / "fit_estimates.csv");
  EXPECT_NE(slurp(out / "fit_points.csv").find("data.csv\","), std::string::npos);
  EXPECT_NE(slurp(d.dir / "fit.svg").find("<svg"), std::string::npos);
  r = run(args, d.dir, d.env);  // its own files: replaced
  EXPECT_EQ(r.status, 0) << r.output;
  fs::remove(out / "fit_points.csv");
  std::ofstream(out / "fit.json") << "mine\n";
  r = run(args, d.dir, d.env);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("refusing to overwrite"), std::string::npos) << r.output;
  EXPECT_EQ(slurp(out / "fit.json"), "mine\n");
  EXPECT_FALSE(fs::exists(out / "fit_points.csv"));  // nothing written
}

TEST(FitCommand, BadInputIsNamed) {
  FitDir d;
  const fs::path data = make_data(d);
  std::ofstream(d.dir / "bad.csv") << "frequency_hz,re,im\n1,0.5,0.1\n2,0.4,x\n";
  std::vector<std::string> args = fit_args(d.dir / "bad.csv");
  Result r = run(args, d.dir, d.env);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("bad.csv:3:7: im: 'x' is not a number"), std::string::npos) << r.output;
  args = fit_args(data);
  args.push_back("--parameter");
  args.push_back("k7=1:2");
  r = run(args, d.dir, d.env);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("unknown parameter 'k7'"), std::string::npos) << r.output;
  args = fit_args(data);
  args[args.size() - 1] = "k3=50:100";  // the model's k3 = 30 is outside
  r = run(args, d.dir, d.env);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("starts at 30, outside its bounds [50, 100]"), std::string::npos) << r.output;
  args = fit_args(data);
  args[10] = "nowhere";  // --output
  r = run(args, d.dir, d.env);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("data.csv:3: unknown output 'nowhere'"), std::string::npos) << r.output;
}

TEST(FitCommand, NotConvergedIsSaidAndExitsThree) {
  FitDir d;
  std::vector<std::string> args = fit_args(make_data(d));
  args.push_back("--max-iterations");
  args.push_back("1");
  const Result r = run(args, d.dir, d.env);
  EXPECT_EQ(r.status, 3) << r.output;
  EXPECT_NE(r.output.find("NOT CONVERGED"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the fit did not converge"), std::string::npos) << r.output;
}

TEST(FitCommand, ACompiledSolverSaysWhereFitRuns) {
  FitDir d;
  const fs::path oscillator = fs::path(MBSGEN_SOURCE_DIR) / "models/textbook/base_excited_oscillator.yaml";
  const Result r = run({MBSGEN_TOOL, "run", oscillator.string(), "--compiled", "--", "fit", "--data", "x.csv"}, d.dir, d.env);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("fit runs on the model's tape"), std::string::npos) << r.output;
}

}  // namespace
