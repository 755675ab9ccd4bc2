// Model solvers (issue 4): the typed API of a generated model against the closed form, the
// solver's exit codes, and every example of docs/cli.md "Model solvers", run as documented.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "../common/doc_examples.hpp"
#include "double_pendulum_model.hpp"
#include "mbsgen/runtime/cli/solver_cli.hpp"
#include "mbsgen/runtime/model/matrix_market.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <stdexcept>

namespace {

// Double pendulum, point masses, absolute angles (docs/test-references.md §2):
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

// A negative mass is refused before any analysis by the model file's condition on the body
// (ParameterError, exit 2); behind it, an indefinite M is still an error naming the mass matrix,
// not eigenvalues that look like results (M of the double pendulum with m1 = −3, m2 = 1:
// [[−2, 1], [1, 1]], eigenvalues −2.30 and 1.30), for an operating point taken before the change.
TEST(GeneratedModel, IndefiniteMassMatrixIsAnError) {
  mbsgen::GeneratedModel m(double_pendulum::kernels());
  const mbsgen::OperatingPoint op = m.operating_point();
  m.set("m1=-3");
  try {
    (void)m.linear_model();
    FAIL() << "a negative mass was accepted";
  } catch (const mbsgen::ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("(m1 = -3) body 'rod1' has mass -3 kg; a mass must be >= 0"), std::string::npos)
        << e.what();
  }
  try {
    (void)m.linear_model(op);
    FAIL() << "an indefinite M was accepted";
  } catch (const mbsgen::Error& e) {
    EXPECT_NE(std::string(e.what()).find("not positive semi-definite"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("-2.3 to 1.3"), std::string::npos) << e.what();
  }
  m.set("m1=0");  // semi-definite (a massless first rod end): allowed, infinite eigenvalues follow
  EXPECT_NO_THROW((void)m.linear_model());
  std::string err;
  EXPECT_EQ(solve({"modes", "--set", "m1=-3"}, nullptr, &err), 2);
  EXPECT_NE(err.find("body 'rod1' has mass -3 kg"), std::string::npos) << err;
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
  EXPECT_EQ(solve({"modes", "--set", "g=nan"}, nullptr, &err), 2);  // non-finite: a usage error
  EXPECT_NE(err.find("--set 'g=nan': 'nan' is not a finite number"), std::string::npos) << err;
  EXPECT_EQ(solve({"modes", "--set", "g=1e999"}, nullptr, &err), 2);  // beyond double
  EXPECT_NE(err.find("outside the range of double"), std::string::npos) << err;
  EXPECT_EQ(solve({"frf", "--input", "X", "--output", "x2"}, nullptr, &err), 2);
  EXPECT_NE(err.find("unknown input 'X'"), std::string::npos) << err;
  EXPECT_EQ(solve({"frf", "--input", "F", "--output", "x2", "--from", "10", "--to", "1"}), 2);
  EXPECT_EQ(solve({"frf", "--input", "F", "--output", "x2", "--points", "0"}), 2);
  EXPECT_EQ(solve({"frf", "--input", "F"}), 2);                    // --output missing
  EXPECT_EQ(solve({"frf", "--input", "F", "--output", "tip_x", "--plot", "/tmp/x.txt"}), 1);  // not .svg/.png
  EXPECT_EQ(solve({"modes", "--help"}, &out), 0);
  EXPECT_NE(out.find("--shapes"), std::string::npos);
}

// A private temporary directory, removed at the end of the test.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    std::string name = (std::filesystem::temp_directory_path() / "mbsgen-solver-test-XXXXXX").string();
    if (!::mkdtemp(name.data())) throw std::runtime_error("mkdtemp failed");
    path = name;
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  std::vector<std::string> entries() const {
    std::vector<std::string> v;
    for (const auto& e : std::filesystem::directory_iterator(path)) v.push_back(e.path().filename().string());
    std::sort(v.begin(), v.end());
    return v;
  }
};

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// `matrices --format mtx --out DIR` writes the six files or none, and replaces only files it
// wrote (their first comment line says "Generated by mbsgen"); what it writes reads back exactly.
TEST(SolverCli, MatricesNeverOverwriteAUserFile) {
  TempDir dir;
  const std::string out = dir.path.string();
  std::string err;
  ASSERT_EQ(solve({"matrices", "--format", "mtx", "--out", out}, nullptr, &err), 0) << err;
  const std::vector<std::string> six = {"B.mtx", "C_v.mtx", "C_y.mtx", "K.mtx", "M.mtx", "Q.mtx"};
  EXPECT_EQ(dir.entries(), six);
  const mbsgen::LinearModel lin = mbsgen::GeneratedModel(double_pendulum::kernels()).linear_model();
  const Eigen::MatrixXd M = mbsgen::read_matrix_market((dir.path / "M.mtx").string());
  EXPECT_TRUE((M.array() == lin.M().array()).all()) << M;  // 17 digits: exact round trip
  EXPECT_EQ(read_text(dir.path / "K.mtx").rfind("%%MatrixMarket matrix array real general\n% Generated by mbsgen ", 0), 0u);
  // Its own files are replaced (here with other values).
  ASSERT_EQ(solve({"matrices", "--format", "mtx", "--out", out, "--set", "g=1.62"}, nullptr, &err), 0) << err;
  EXPECT_EQ(mbsgen::read_matrix_market((dir.path / "K.mtx").string())(1, 1), 1.0 * 1.62 * 1.0);  // m2 g l2
  // A user's M.mtx is not: exit 1, nothing written, no temporary file left.
  const std::string mine = "%%MatrixMarket matrix array real general\n% my own mass matrix\n1 1\n5\n";
  std::ofstream(dir.path / "M.mtx") << mine;
  const std::string k_before = read_text(dir.path / "K.mtx");
  EXPECT_EQ(solve({"matrices", "--format", "mtx", "--out", out}, nullptr, &err), 1);
  EXPECT_EQ(err, "double_pendulum-solve: error: matrices --out: refusing to overwrite " + out +
                     "/M.mtx: it exists and was not written by mbsgen (move it, or choose another "
                     "directory); nothing was written\n");
  EXPECT_EQ(read_text(dir.path / "M.mtx"), mine);
  EXPECT_EQ(read_text(dir.path / "K.mtx"), k_before);  // still g = 1.62: not rewritten
  EXPECT_EQ(dir.entries(), six);
}

// A FIFO as an output: refused at once (opening it would block until a reader comes), nothing
// written. The test would hang if the FIFO were opened.
TEST(SolverCli, SpecialFilesAreRefused) {
  TempDir dir;
  const std::string fifo = (dir.path / "K.mtx").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string err;
  EXPECT_EQ(solve({"matrices", "--format", "mtx", "--out", dir.path.string()}, nullptr, &err), 1);
  EXPECT_EQ(err, "double_pendulum-solve: error: matrices --out: refusing to write " + fifo +
                     ": it is a FIFO, not a regular file\n");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"K.mtx"});
  const std::string plot = (dir.path / "bode.svg").string();
  ASSERT_EQ(::mkfifo(plot.c_str(), 0600), 0);
  EXPECT_EQ(solve({"frf", "--input", "F", "--output", "tip_x", "--points", "3", "--plot", plot}, nullptr, &err), 1);
  EXPECT_EQ(err, "double_pendulum-solve: error: --plot: refusing to write " + plot +
                     ": it is a FIFO, not a regular file\n");
  EXPECT_EQ(solve({"frf", "--input", "F", "--output", "tip_x", "--points", "3", "--plot", "/dev/null"}, nullptr, &err), 1);
  EXPECT_EQ(err, "double_pendulum-solve: error: --plot: refusing to write /dev/null: it is a device, not a "
                 "regular file\n");
}

// `simulate`: the CSV and JSON layouts, the plot, and the exit codes of bad names, bad signals
// and a failed integration (nothing on standard output then).
TEST(SolverCli, Simulate) {
  std::string out, err;
  ASSERT_EQ(solve({"simulate", "--duration", "1", "--step", "0.25", "--initial", "phi1=0.2", "--input", "F=sine:0.1,2"},
                  &out, &err), 0) << err;
  EXPECT_EQ(err, "");
  std::istringstream csv(out);
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "t,phi1,phi2,phi1_dot,phi2_dot,tip_x,tip_vx,upper_angle,relative_angle");
  int rows = 0;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 5);  // t = 0, 0.25, 0.5, 0.75, 1
  ASSERT_EQ(solve({"simulate", "--duration", "0.5", "--step", "0.5", "--format", "json", "--method", "adams"}, &out, &err), 0);
  EXPECT_EQ(out.rfind("{\"model\":\"double_pendulum\",\"scene\":\"full\",\"method\":\"adams\",\"jacobian\":\"none\","
                      "\"restarts\":0,\"t\":[0,0.5],\"series\":{\"phi1\":[0,0]", 0), 0u) << out;
  ASSERT_EQ(solve({"simulate", "--duration", "0.5", "--step", "0.5", "--format", "json", "--method", "radau"}, &out, &err), 0);
  EXPECT_EQ(out.rfind("{\"model\":\"double_pendulum\",\"scene\":\"full\",\"method\":\"radau\",\"jacobian\":\"kernels\","
                      "\"restarts\":0,\"t\":[0,0.5],\"series\":{\"phi1\":[0,0]", 0), 0u) << out;
  ASSERT_EQ(solve({"simulate", "--duration", "0.5", "--step", "0.5", "--format", "json", "--method", "radau9"}, &out, &err), 0);
  EXPECT_EQ(out.rfind("{\"model\":\"double_pendulum\",\"scene\":\"full\",\"method\":\"radau9\",\"jacobian\":\"kernels\","
                      "\"restarts\":0,\"t\":[0,0.5],\"series\":{\"phi1\":[0,0]", 0), 0u) << out;
  ASSERT_EQ(solve({"simulate", "--duration", "0.5", "--step", "0.5", "--method", "radau", "--statistics"}, &out, &err), 0);
  EXPECT_EQ(err.rfind("simulate: 2 samples, radau, ", 0), 0u) << err;
  {  // radau9 is the five-stage method: fewer than half the steps of radau on 5 s of motion
    auto steps = [&](const std::string& method) {
      EXPECT_EQ(solve({"simulate", "--duration", "5", "--step", "5", "--initial", "phi1=0.5", "--rtol", "1e-8", "--method",
                       method, "--statistics"}, &out, &err), 0) << err;
      const std::string lead = "simulate: 2 samples, " + method + ", ";
      EXPECT_EQ(err.rfind(lead, 0), 0u) << err;
      return std::atol(err.c_str() + std::min(lead.size(), err.size()));
    };
    const long five = steps("radau"), nine = steps("radau9");
    EXPECT_GT(nine, 0);
    EXPECT_LT(2 * nine, five) << nine << " and " << five << " steps";
  }
  EXPECT_NE(err.find(" Jacobians (kernels)"), std::string::npos) << err;
  ASSERT_EQ(solve({"simulate", "--duration", "0.5", "--step", "0.5", "--format", "json", "--statistics"}, &out, &err), 0);
  EXPECT_NE(out.find(",\"statistics\":{\"steps\":"), std::string::npos) << out;
  EXPECT_EQ(err.rfind("simulate: 2 samples, bdf, ", 0), 0u) << err;
  TempDir dir;
  const std::string plot = (dir.path / "motion.svg").string();
  ASSERT_EQ(solve({"simulate", "--duration", "1", "--initial", "phi1=0.5", "--plot", plot, "--show", "phi1", "--show",
                   "tip_x"}, &out, &err), 0) << err;
  EXPECT_EQ(err, "wrote " + plot + "\n");
  std::ifstream svg(plot);
  std::string head((std::istreambuf_iterator<char>(svg)), std::istreambuf_iterator<char>());
  EXPECT_NE(head.find("<svg"), std::string::npos);
  EXPECT_NE(head.find("tip_x [m]"), std::string::npos);
  EXPECT_EQ(solve({"simulate", "--duration", "1", "--plot", plot, "--show", "nope"}, &out, &err), 2);
  EXPECT_EQ(err, "double_pendulum-solve: --show 'nope': no such series; known: phi1, phi2, phi1_dot, phi2_dot, tip_x, "
                 "tip_vx, upper_angle, relative_angle\n");
  EXPECT_EQ(solve({"simulate", "--duration", "1", "--input", "G=1"}, &out, &err), 2);
  EXPECT_EQ(solve({"simulate", "--duration", "1", "--input", "F=sine:1"}, &out, &err), 2);
  EXPECT_EQ(err, "double_pendulum-solve: input signal 'sine:1': expected sine:AMPLITUDE,HZ[,PHASE_DEG[,OFFSET]]\n");
  EXPECT_EQ(solve({"simulate", "--duration", "-1"}, &out, &err), 2);
  EXPECT_EQ(solve({"simulate", "--duration", "1", "--plot", "/dev/null"}, &out, &err), 1);
  EXPECT_EQ(solve({"simulate", "--duration", "1", "--initial", "phi1_dot=1e160"}, &out, &err), 1);
  EXPECT_EQ(out, "");
  EXPECT_EQ(err.rfind("double_pendulum-solve: error: simulate: the initial state fails at t = 0 s: the kernels returned "
                      "non-finite values", 0), 0u) << err;
}

// Same rules and messages as `mbsgen linear frf` (tests/runtime/cli/test_cli.cpp), and the limit on
// --points (kMaxFrequencyPoints).
TEST(SolverCli, RangeAndPointLimits) {
  std::string err;
  EXPECT_EQ(solve({"frf", "--input", "F", "--output", "tip_x", "--from", "10", "--to", "1"}, nullptr, &err), 2);
  EXPECT_EQ(err, "double_pendulum-solve: frf: empty range --from 10 --to 1 (--from must be below --to, or "
                 "equal to it with --points 1)\n");
  for (const char* points : {"1000001", "1e9"}) {
    EXPECT_EQ(solve({"frf", "--input", "F", "--output", "tip_x", "--points", points}, nullptr, &err), 2) << points;
    EXPECT_NE(err.find("--points"), std::string::npos) << err;
  }
  EXPECT_EQ(solve({"frf", "--input", "F", "--output", "tip_x", "--points", "1000000", "--to", "1e-300",
                   "--from", "1e-300", "--spacing", "linear"}, nullptr, &err), 2);  // equal ends, many points
}

// Frequencies of a CSV sweep (first column).
std::vector<double> csv_frequencies(const std::string& csv) {
  std::vector<double> hz;
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) hz.push_back(std::stod(line.substr(0, line.find(','))));
  return hz;
}

// A scene's frequency_range (from, to, points, spacing) is the default sweep; each option given
// on the command line overrides its part. Kernels with a scene range: the double pendulum's with
// the fields set as a generated API sets them.
TEST(SolverCli, SceneFrequencyRangeIsTheDefaultSweep) {
  mbsgen::ModelKernels k = double_pendulum::kernels();
  k.default_from_hz = 0.5;
  k.default_to_hz = 2.0;
  k.default_points = 4;
  k.default_linear_spacing = true;
  auto sweep = [&k](std::vector<std::string> args) {
    args.insert(args.begin(), {"solve", "frf", "--input", "F", "--output", "tip_x", "--format", "csv"});
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    std::ostringstream out, err;
    EXPECT_EQ(mbsgen::cli::solver_main(k, static_cast<int>(argv.size()), argv.data(), out, err), 0) << err.str();
    return csv_frequencies(out.str());
  };
  // Linear spacing 0.5 .. 2 in 4 points: 0.5, 1, 1.5, 2 (exact in binary).
  EXPECT_EQ(sweep({}), (std::vector<double>{0.5, 1.0, 1.5, 2.0}));
  EXPECT_EQ(sweep({"--points", "3"}), (std::vector<double>{0.5, 1.25, 2.0}));
  EXPECT_EQ(sweep({"--to", "3.5"}), (std::vector<double>{0.5, 1.5, 2.5, 3.5}));
  // Logarithmic: 0.5 · 4^(i/3); the ends exact, the inner points to a few ulps (one pow).
  const std::vector<double> log = sweep({"--spacing", "log"});
  ASSERT_EQ(log.size(), 4u);
  EXPECT_EQ(log.front(), 0.5);
  EXPECT_EQ(log.back(), 2.0);
  EXPECT_NEAR(log[1], 0.5 * std::cbrt(4.0), 4e-16 * 2);
  EXPECT_NEAR(log[2], 0.5 * std::cbrt(16.0), 4e-16 * 2);
  // Without a scene range: 1 to 1000 Hz, 200 points, logarithmic.
  k.default_from_hz = k.default_to_hz = 0;
  const std::vector<double> plain = sweep({});
  ASSERT_EQ(plain.size(), 200u);
  EXPECT_EQ(plain.front(), 1.0);
  EXPECT_EQ(plain.back(), 1000.0);
}

TEST(SolverCli, Versions) {
  std::string out;
  EXPECT_EQ(solve({"--version"}, &out), 0);
  const std::string v = MBSGEN_PROJECT_VERSION;
  const std::string head =
      "double_pendulum-solve: model double_pendulum, scene full (kernels double_pendulum, ABI 1), generated by mbsgen ";
  // The typed API records the generator's version (emit_api).
  ASSERT_NE(double_pendulum::kernels().generator_version, nullptr);
  EXPECT_EQ(out, head + v + ", runtime " + v + "\n");
  // mbsgen itself.
  FILE* p = ::popen(("'" + std::string(MBSGEN_TOOL_DIR) + "/mbsgen' --version").c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string text;
  char buf[256];
  while (std::fgets(buf, sizeof buf, p)) text += buf;
  EXPECT_EQ(::pclose(p), 0);
  EXPECT_EQ(text, "mbsgen " + v + "\n");
}

// `mbsgen run --help` names every subcommand the solvers have (issue 39 §3: it listed five of
// eight). The solver's own --help is the reference.
TEST(SolverCli, RunHelpListsEverySolverSubcommand) {
  std::string help;
  {
    FILE* p = ::popen(("'" + std::string(MBSGEN_TOOL_DIR) + "/mbsgen' run --help 2>&1").c_str(), "r");
    ASSERT_NE(p, nullptr);
    char buf[4096];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) help.append(buf, n);
    ::pclose(p);
  }
  std::string out, err;
  solve({"--help"}, &out, &err);
  const std::string list = out + err;
  const auto from = list.find("Subcommands:");
  ASSERT_NE(from, std::string::npos) << list;
  std::istringstream lines(list.substr(from));
  std::string line;
  std::getline(lines, line);
  int count = 0;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string name;
    if (!(words >> name)) continue;
    ++count;
    const bool named = help.find("|" + name + "|") != std::string::npos ||
                       help.find("-- " + name + "|") != std::string::npos ||
                       help.find("|" + name + " ") != std::string::npos;
    EXPECT_TRUE(named) << "mbsgen run --help does not name '" << name << "':\n" << help;
  }
  EXPECT_GE(count, 8);
}

std::string capture(const std::string& command) {
  std::string text;
  FILE* p = ::popen(command.c_str(), "r");
  if (!p) return text;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) text.append(buf, n);
  ::pclose(p);
  return text;
}

// `mbsgen run` answers a one-off analysis from the model's tape, without a compiler (issue 40
// §1), with the same text as the compiled solver's, byte for byte (the numbers are the same bit
// for bit: tape_agrees_with_compiled), and says so in `info`; --compiled builds the solver.
TEST(SolverCli, RunAnswersFromATapeAsTheCompiledSolverDoes) {
  const std::string cache = std::string(MBSGEN_TEST_CACHE) + "/tape";
  std::filesystem::remove_all(cache);
  const std::string mbsgen = "MBSGEN_CACHE_DIR='" + cache + "' '" + MBSGEN_TOOL_DIR + "/mbsgen' run ";
  const std::vector<std::pair<std::string, std::string>> runs = {
      {"textbook/double_pendulum", "modes --all --shapes"},
      {"textbook/double_pendulum", "frf --input F --output tip_x --from 0.1 --to 10 --points 40 --format csv"},
      {"textbook/double_pendulum", "static --set l1=0.5"},
      {"textbook/double_pendulum", "sweep --parameter l2 --from 0.5 --to 2 --points 7"},
      {"middle_ear/middle_ear", "frf --input P --output v_stapes --points 60"},
      {"rolling/rolling_disk", "modes --set w=1"},
      {"textbook/base_excited_oscillator", "frf --input xb --output x_rel --points 20"},
      {"textbook/rotor_disk", "modes"}};
  for (const auto& [model, command] : runs) {
    SCOPED_TRACE(model + ": " + command);
    const std::string id = std::filesystem::path(model).filename().string();
    const std::string tape = capture(mbsgen + "'" + MBSGEN_SOURCE_DIR + "/models/" + model + ".yaml' -- " + command + " 2>&1");
    const std::string compiled = capture("'" + std::string(MBSGEN_GENERATED_BIN_DIR) + "/" + id + "-solve' " + command + " 2>&1");
    EXPECT_GT(tape.size(), 20u) << tape;
    EXPECT_EQ(tape, compiled);
  }
  // A scene's tape, and an error path (the scene has no linear kernel: it once crashed the tape's
  // first host, which held the generator's and the runtime's OperatingPoint in one program).
  const std::string rotor = std::string("'") + MBSGEN_SOURCE_DIR + "/models/textbook/rotor_disk.yaml' --scene motion -- ";
  const std::string rotor_solver = std::string("'") + MBSGEN_GENERATED_BIN_DIR + "/rotor_disk_motion-solve' ";
  auto after_name = [](const std::string& text) { return text.substr(text.find(": ")); };  // (paths differ)
  for (const std::string command : {"modes", "frf --input T --output tilt_x --points 5"})
    EXPECT_EQ(after_name(capture(mbsgen + rotor + command + " 2>&1; echo status $?")),
              after_name(capture(rotor_solver + command + " 2>&1; echo status $?")))
        << command;
  const std::string model = std::string("'") + MBSGEN_SOURCE_DIR + "/models/textbook/double_pendulum.yaml'";
  EXPECT_NE(capture(mbsgen + model + " -- info").find("\nkernels: tape (evaluated without a compiler)\n"),
            std::string::npos);
  int solvers = 0, tapes = 0;
  for (const auto& e : std::filesystem::directory_iterator(cache)) {
    solvers += std::filesystem::exists(e.path() / "solve");
    tapes += std::filesystem::exists(e.path() / "tape");
    // Only the kernels a solver calls (EmitOptions::solver_only): not bodies, linear_structured.
    std::ifstream in(e.path() / "tape");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(text.find("\nkernel bodies "), std::string::npos) << e.path();
    EXPECT_EQ(text.find("\nkernel linear_structured "), std::string::npos) << e.path();
  }
  EXPECT_EQ(solvers, 0) << "a compiler ran";
  EXPECT_GE(tapes, 5);
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
