// Model solvers (issue 4): the typed API of a generated model against the closed form, the
// solver's exit codes, and every example of docs/cli.md "Model solvers", run as documented.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "../common/doc_examples.hpp"
#include "double_pendulum_model.hpp"
#include "mbsgen/runtime/solver_cli.hpp"

namespace {

// Double pendulum, point masses, absolute angles (closed-forms.md §2):
// M = [[(m1+m2) l1², m2 l1 l2], [m2 l1 l2, m2 l2²]], K = diag((m1+m2) g l1, m2 g l2), Q = 0.
TEST(TypedApi, DoublePendulumMatchesClosedForm) {
  double_pendulum::Parameters p;
  EXPECT_EQ(p.g, 9.81);  // the model file's default
  p.m1 = 2.0;
  p.l2 = 0.5;
  const mbsgen::LinearModel lin = double_pendulum::linear_model(p);
  ASSERT_EQ(lin.size(), 2);
  const double M[2][2] = {{(p.m1 + p.m2) * p.l1 * p.l1, p.m2 * p.l1 * p.l2}, {p.m2 * p.l1 * p.l2, p.m2 * p.l2 * p.l2}};
  const double K[2][2] = {{(p.m1 + p.m2) * p.g * p.l1, 0}, {0, p.m2 * p.g * p.l2}};
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      // The kernels evaluate a few products and sums of the same numbers: a few ulps.
      EXPECT_NEAR(lin.M()(i, j), M[i][j], 4e-16 * 10) << i << "," << j;
      EXPECT_NEAR(lin.K()(i, j), K[i][j], 4e-15 * 10) << i << "," << j;
      EXPECT_EQ(lin.Q()(i, j), 0.0);
    }
  EXPECT_EQ(lin.coordinate_names()[static_cast<int>(double_pendulum::Coordinate::phi2)], "phi2");
  EXPECT_EQ(lin.input_names()[static_cast<int>(double_pendulum::Input::F)], "F");
  EXPECT_EQ(lin.coordinate_units()[0], "rad");
}

int solve(std::vector<std::string> args, std::string* out_text = nullptr, std::string* err_text = nullptr);

TEST(GeneratedModel, SetByNameAndErrors) {
  mbsgen::GeneratedModel m(double_pendulum::kernels());
  m.set("g=1.62");
  EXPECT_DOUBLE_EQ(m.linear_model().K()(1, 1), 1.0 * 1.62 * 1.0);  // m2 g l2
  EXPECT_THROW(m.set("G=1"), mbsgen::NameError);
  EXPECT_THROW(m.set("g="), mbsgen::NameError);
  EXPECT_THROW(m.set("g=1.5x"), mbsgen::NameError);
  EXPECT_THROW(m.set("g", std::nan("")), mbsgen::NonFiniteError);
  EXPECT_THROW(m.set("g=nan"), mbsgen::NonFiniteError);
  EXPECT_THROW(m.set("g=-inf"), mbsgen::NonFiniteError);
  // strtod says ERANGE: 1e400 would be inf, 1e-400 a silent 0.
  for (const char* out_of_range : {"g=1e400", "g=1e-400"}) {
    try {
      m.set(out_of_range);
      ADD_FAILURE() << out_of_range << " was accepted";
    } catch (const mbsgen::NonFiniteError& e) {
      EXPECT_NE(std::string(e.what()).find("outside the range of double"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_DOUBLE_EQ(m.linear_model().K()(1, 1), 1.0 * 1.62 * 1.0);  // unchanged by the refusals
  try {
    m.set("lenght=1");
    FAIL();
  } catch (const mbsgen::NameError& e) {
    EXPECT_NE(std::string(e.what()).find("known: m1, m2, l1, l2, g"), std::string::npos) << e.what();
  }
  EXPECT_THROW(m.output_index("nope"), mbsgen::NameError);
}

// A negative mass makes M indefinite: an error naming the mass matrix, not eigenvalues that look
// like results (M of the double pendulum with m1 = −3, m2 = 1: [[−2, 1], [1, 1]], eigenvalues
// −2.30 and 1.30).
TEST(GeneratedModel, IndefiniteMassMatrixIsAnError) {
  mbsgen::GeneratedModel m(double_pendulum::kernels());
  m.set("m1=-3");
  try {
    (void)m.linear_model();
    FAIL() << "an indefinite M was accepted";
  } catch (const mbsgen::Error& e) {
    EXPECT_NE(std::string(e.what()).find("not positive semi-definite"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("-2.3 to 1.3"), std::string::npos) << e.what();
  }
  m.set("m1=0");  // semi-definite (a massless first rod end): allowed, infinite eigenvalues follow
  EXPECT_NO_THROW((void)m.linear_model());
  std::string err;
  EXPECT_EQ(solve({"modes", "--set", "m1=-3"}, nullptr, &err), 1);
  EXPECT_NE(err.find("not positive semi-definite"), std::string::npos) << err;
}

int solve(std::vector<std::string> args, std::string* out_text, std::string* err_text) {
  args.insert(args.begin(), "double_pendulum-solve");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream out, err;
  const int rc = mbsgen::cli::solver_main(double_pendulum::kernels(), static_cast<int>(argv.size()),
                                          argv.data(), out, err);
  if (out_text) *out_text = out.str();
  if (err_text) *err_text = err.str();
  return rc;
}

TEST(SolverCli, ExitCodes) {
  std::string out, err;
  EXPECT_EQ(solve({"modes"}, &out), 0);
  EXPECT_NE(out.find("finite"), std::string::npos);
  EXPECT_EQ(solve({}), 2);                                         // no subcommand
  EXPECT_EQ(solve({"modes", "--set", "nope=1"}, nullptr, &err), 2);  // unknown parameter
  EXPECT_NE(err.find("unknown parameter 'nope'"), std::string::npos) << err;
  EXPECT_NE(err.find("known: m1, m2, l1, l2, g"), std::string::npos) << err;
  EXPECT_EQ(solve({"modes", "--set", "g=abc"}), 2);                // malformed number
  EXPECT_EQ(solve({"modes", "--set", "g=nan"}), 1);                // non-finite: a model error
  EXPECT_EQ(solve({"frf", "--input", "X", "--output", "x2"}, nullptr, &err), 2);
  EXPECT_NE(err.find("unknown input 'X'"), std::string::npos) << err;
  EXPECT_EQ(solve({"frf", "--input", "F", "--output", "x2", "--from", "10", "--to", "1"}), 2);
  EXPECT_EQ(solve({"frf", "--input", "F", "--output", "x2", "--points", "0"}), 2);
  EXPECT_EQ(solve({"frf", "--input", "F"}), 2);                    // --output missing
  EXPECT_EQ(solve({"frf", "--input", "F", "--output", "tip_x", "--plot", "/tmp/x.txt"}), 1);  // not .svg/.png
  EXPECT_EQ(solve({"modes", "--help"}, &out), 0);
  EXPECT_NE(out.find("--shapes"), std::string::npos);
}

// Every example of docs/cli.md "Model solvers", run in the source directory with the build's
// solvers and mbsgen on the PATH and a private solver cache.
TEST(SolverCli, DocumentationExamples) {
  const auto examples = doc_examples::read(std::string(MBSGEN_SOURCE_DIR) + "/docs/cli.md", "## Model solvers");
  ASSERT_GE(examples.size(), 6u) << "docs/cli.md \"Model solvers\" examples not found";
  const std::string tmp = std::string(MBSGEN_TEST_CACHE) + "/out";
  std::filesystem::create_directories(tmp);
  for (const auto& ex : examples) {
    SCOPED_TRACE("docs/cli.md:" + std::to_string(ex.line) + ": " + ex.command);
    doc_examples::expect_output(std::string("cd '") + MBSGEN_SOURCE_DIR + "' && PATH='" + MBSGEN_GENERATED_BIN_DIR +
                                    ":" + MBSGEN_TOOL_DIR + ":'\"$PATH\" MBSGEN_CACHE_DIR='" + MBSGEN_TEST_CACHE +
                                    "' TMPDIR='" + tmp + "' sh -c '" + ex.command + "'",
                                ex);
  }
}

}  // namespace
