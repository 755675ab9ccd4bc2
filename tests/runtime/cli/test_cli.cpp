// `mbsgen linear`: runs every example of docs/cli.md with the mbsgen-linear executable in
// tests/runtime/data and compares the output; plus exit-code checks through linear_main.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "../../common/doc_examples.hpp"
#include "mbsgen/runtime/cli/linear_cli.hpp"

TEST(MbsgenLinearCli, DocumentationExamples) {
  const auto examples = doc_examples::read(std::string(MBSGEN_SOURCE_DIR) + "/docs/cli.md", "## `mbsgen linear`");
  ASSERT_GE(examples.size(), 8u) << "docs/cli.md examples not found";
  const std::string prefix = "mbsgen linear ";
  for (const auto& ex : examples) {
    SCOPED_TRACE("docs/cli.md:" + std::to_string(ex.line) + ": " + ex.command);
    ASSERT_EQ(ex.command.rfind(prefix, 0), 0u);
    doc_examples::expect_output(std::string("cd '") + MBSGEN_SOURCE_DIR + "/tests/runtime/data' && '" +
                                    MBSGEN_LINEAR_EXE + "' " + ex.command.substr(prefix.size()),
                                ex);
  }
}

TEST(MbsgenLinearCli, ExitCodesInProcess) {
  const std::string data = std::string(MBSGEN_SOURCE_DIR) + "/tests/runtime/data/";
  auto run = [](std::vector<std::string> args, std::string* out_text = nullptr) {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    std::ostringstream out, err;
    const int rc = mbsgen::cli::linear_main(static_cast<int>(argv.size()), argv.data(), out, err);
    if (out_text) *out_text = out.str();
    return rc;
  };
  std::string text;
  EXPECT_EQ(run({"linear", "modes", "--M", data + "M.mtx", "--K", data + "K.mtx"}, &text), 0);
  EXPECT_NE(text.find("finite"), std::string::npos);
  EXPECT_EQ(run({"linear"}), 2);                                     // no subcommand
  EXPECT_EQ(run({"linear", "modes", "--K", data + "K.mtx"}), 2);     // --M missing
  EXPECT_EQ(run({"linear", "frf", "--M", data + "M.mtx", "--K", data + "K.mtx", "--method", "x"}), 2);
  EXPECT_EQ(run({"linear", "modes", "--M", data + "nope.mtx", "--K", data + "K.mtx"}), 1);
  EXPECT_EQ(run({"linear", "frf", "--M", data + "M.mtx", "--K", data + "K.mtx", "--input", "9"}), 2);
  EXPECT_EQ(run({"linear", "frf", "--M", data + "M.mtx", "--K", data + "K.mtx", "--method", "modal",
                 "--Q", data + "Q.mtx", "--points", "3"}),
            0);
  EXPECT_EQ(run({"linear", "--help"}), 0);
}

namespace {

struct LinearRun {
  int rc;
  std::string out, err;
};

LinearRun run_linear(std::vector<std::string> args) {
  args.insert(args.begin(), "linear");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream out, err;
  const int rc = mbsgen::cli::linear_main(static_cast<int>(argv.size()), argv.data(), out, err);
  return {rc, out.str(), err.str()};
}

}  // namespace

// docs/cli.md: a value out of range is a usage error (2), as the solvers treat it; a reversed
// range is refused with the solvers' message; --points has a documented limit.
TEST(MbsgenLinearCli, UsageErrorsAndLimits) {
  const std::string data = std::string(MBSGEN_SOURCE_DIR) + "/tests/runtime/data/";
  const std::vector<std::string> mk = {"frf", "--M", data + "M.mtx", "--K", data + "K.mtx"};
  auto with = [&mk](std::vector<std::string> more) {
    std::vector<std::string> a = mk;
    a.insert(a.end(), more.begin(), more.end());
    return run_linear(a);
  };
  LinearRun r = with({"--output", "4"});
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, "mbsgen linear: --output 4 out of range 1..3 (the rows of C)\n");
  r = with({"--input", "4"});
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, "mbsgen linear: --input 4 out of range 1..3 (the columns of B)\n");
  r = with({"--from", "10", "--to", "1"});
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, "mbsgen linear frf: empty range --from 10 --to 1 (--from must be below --to, or "
                   "equal to it with --points 1)\n");
  EXPECT_EQ(with({"--from", "5", "--to", "5"}).rc, 2);
  r = with({"--from", "5", "--to", "5", "--points", "1"});
  EXPECT_EQ(r.rc, 0) << r.err;
  r = with({"--from", "0", "--to", "5"});
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, "mbsgen linear frf: --spacing log needs --from and --to > 0 (got --from 0 --to 5)\n");
  // kMaxFrequencyPoints = 1000000: one more is a usage error, before anything is allocated.
  for (const char* points : {"1000001", "1e9", "1000000000"}) {
    r = with({"--points", points});
    EXPECT_EQ(r.rc, 2) << points;
    EXPECT_NE(r.err.find("--points"), std::string::npos) << r.err;
  }
}

TEST(MbsgenLinearCli, BadMatrixFilesExitWithStatus1AndTheFileAndLine) {
  const std::string bad = std::string(MBSGEN_SOURCE_DIR) + "/tests/data/bad_matrices/";
  const std::string data = std::string(MBSGEN_SOURCE_DIR) + "/tests/runtime/data/";
  LinearRun r = run_linear({"modes", "--M", data + "M.mtx", "--K", bad + "symmetric_both_triangles.mtx"});
  EXPECT_EQ(r.rc, 1);
  EXPECT_EQ(r.err, "mbsgen linear: error: " + bad +
                       "symmetric_both_triangles.mtx:6: entry (1,2) above the diagonal in a symmetric "
                       "file: the format stores the lower triangle only (row >= column)\n");
  r = run_linear({"modes", "--M", bad + "huge_declared_1e9.mtx", "--K", data + "K.mtx"});
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("huge_declared_1e9.mtx:3: a 1000000000x1000000000 matrix has 1e+18 entries"),
            std::string::npos)
      << r.err;
  r = run_linear({"modes", "--M", "/dev/zero", "--K", data + "K.mtx"});
  EXPECT_EQ(r.rc, 1);
  EXPECT_EQ(r.err, "mbsgen linear: error: /dev/zero: is a character device, not a regular file (refused: reading it could block or never end)\n");
}

TEST(MbsgenLinearCli, VersionIsTheProjectVersion) {
  const LinearRun r = run_linear({"--version"});
  EXPECT_EQ(r.rc, 0);
  EXPECT_EQ(r.out, std::string("mbsgen linear ") + MBSGEN_PROJECT_VERSION + "\n");
}

// Out of memory is a message and exit status 1, not an abort: three 5000 x 5000 matrices (the
// reader's limit, 200 MB each, from one-entry files) under a 500 MB address-space limit. The
// same limit leaves room for a small model (the process itself maps about 190 MB, OpenBLAS's
// buffers included; OpenBLAS hangs at start when its threads cannot get theirs, hence one thread).
// AddressSanitizer reserves terabytes of address space, so under it (the ci preset) no
// allocation above 100 MB succeeds instead (its allocator returns null, as malloc does at the limit).
TEST(MbsgenLinearCli, OutOfMemoryIsAMessageAndStatus1) {
  std::string limit = "ulimit -v 500000 && ";
#if defined(__SANITIZE_ADDRESS__)
  limit = "ASAN_OPTIONS=\"$ASAN_OPTIONS:allocator_may_return_null=1:max_allocation_size_mb=100\" ";
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
  limit = "ASAN_OPTIONS=\"$ASAN_OPTIONS:allocator_may_return_null=1:max_allocation_size_mb=100\" ";
#endif
#endif
  const std::string dir = ::testing::TempDir();
  const std::string big = dir + "mbsgen_oom_5000.mtx";
  std::ofstream(big) << "%%MatrixMarket matrix coordinate real general\n5000 5000 1\n1 1 1.0\n";
  const std::string data = std::string(MBSGEN_SOURCE_DIR) + "/tests/runtime/data/";
  auto run = [&limit](const std::string& args, std::string* output) {
    const std::string command = limit + "OPENBLAS_NUM_THREADS=1 exec timeout 60 '" +
                                std::string(MBSGEN_LINEAR_EXE) + "' " + args + " 2>&1";
    FILE* p = ::popen(command.c_str(), "r");
    if (!p) return -1;
    char buf[512];
    output->clear();
    while (std::fgets(buf, sizeof buf, p)) *output += buf;
    const int status = ::pclose(p);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  };
  std::string text;
  EXPECT_EQ(run("modes --M " + data + "M.mtx --K " + data + "K.mtx", &text), 0) << text;
  EXPECT_EQ(run("modes --M " + big + " --K " + big + " --Q " + big, &text), 1) << text;
  // Under ASan its allocator says so itself ("==PID==WARNING: AddressSanitizer failed to allocate
  // 0x… bytes"), before our message: that line is dropped, any other stays.
  std::string ours;
  for (std::size_t at = 0, end; at < text.size(); at = end + 1) {
    end = text.find('\n', at);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(at, end - at);
    if (line.rfind("==", 0) != 0 || line.find("WARNING: AddressSanitizer failed to allocate 0x") == std::string::npos)
      ours += line + "\n";
  }
  EXPECT_EQ(ours, "mbsgen linear: error: out of memory\n") << text;
  std::remove(big.c_str());
}

// Issue 14 §2: a Jordan block at λ = 0 with rounding noise in K (Kjordan_noisy.mtx: QZ splits it
// into ±5.7e-7 1/s) is shown as zero within its error bound, with no damping ratio (it used to
// read as a stable and an unstable real mode, zeta ±1), and the verdict is not "unstable".
TEST(MbsgenLinearCli, NoisyJordanBlockAtZeroIsShownZeroWithinBound) {
  const std::string data = std::string(MBSGEN_SOURCE_DIR) + "/tests/runtime/data/";
  const std::vector<std::string> pencil = {"modes", "--M", data + "Mjordan.mtx", "--Q", data + "Qjordan.mtx",
                                           "--K", data + "Kjordan_noisy.mtx", "--all"};
  auto with = [&pencil](std::vector<std::string> more) {
    std::vector<std::string> a = pencil;
    a.insert(a.end(), more.begin(), more.end());
    return run_linear(a);
  };
  LinearRun r = with({});
  ASSERT_EQ(r.rc, 0) << r.err;
  std::istringstream lines(r.out);
  std::string line;
  int zero_within = 0, finite = 0;
  while (std::getline(lines, line)) {
    if (line.empty() || line[0] == '#' || line.find("lambda_re") != std::string::npos) continue;
    std::istringstream fields(line);
    std::string k, re, im, fn, fd, zeta, eta, bound, kind;
    fields >> k >> re >> im >> fn >> fd >> zeta >> eta >> bound >> kind;
    if (kind == "zero_within_bound") {
      ++zero_within;
      EXPECT_EQ(zeta, "-") << line;
      // The noise-free truth, λ = 0, lies within the bound: |λ| ≤ error_bound.
      EXPECT_LE(std::abs(std::stod(re)) + std::abs(std::stod(im)), std::stod(bound)) << line;
    } else {
      ++finite;
      EXPECT_EQ(kind, "finite") << line;
      // Relative motion μλ² + cλ + k = 0 (μ = 2/3, c = 0.5, k = 100): Re λ = −c/(2μ) = −0.375;
      // ζ = c/(2√(kμ)) = 0.0306186 (6 digits printed).
      EXPECT_EQ(re, "-3.750000e-01") << line;
      EXPECT_EQ(zeta, "3.061862e-02") << line;
    }
  }
  EXPECT_EQ(zero_within, 2);
  EXPECT_EQ(finite, 2);
  EXPECT_NE(r.out.find("\n# stability undecided: none unstable; an eigenvalue is zero within its error "
                       "bound or has |Re lambda| <= error_bound\n"),
            std::string::npos)
      << r.out;
  r = with({"--format", "json"});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("\"damping_ratio\":null,"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("\"damping_ratio\":-1"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("],\"stability\":\"undecided\"}\n"), std::string::npos) << r.out;
  r = with({"--format", "csv"});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(r.out.rfind("lambda_re,lambda_im,natural_frequency_hz,damped_frequency_hz,damping_ratio,"
                        "backward_error,error_bound,kind\n",
                        0),
            0u);
  EXPECT_NE(r.out.find(",,"), std::string::npos) << "empty damping ratio field";
}
