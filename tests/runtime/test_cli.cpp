// `mbsgen linear`: runs every example of docs/cli.md with the mbsgen-linear executable in
// tests/runtime/data and compares the output; plus exit-code checks through linear_main.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "mbsgen/runtime/linear_cli.hpp"

namespace {

struct Example {
  std::string args;                 // after "$ mbsgen linear "
  std::vector<std::string> output;  // expected stdout+stderr lines
  int exit_code = 0;
  int line = 0;
};

std::vector<Example> read_examples(const std::string& path) {
  std::ifstream in(path);
  std::vector<Example> out;
  std::string line;
  bool in_console = false;
  int lineno = 0;
  bool expect_code = false;
  bool in_section = false;  // "## `mbsgen linear`"; other sections have their own tests
  while (std::getline(in, line)) {
    ++lineno;
    if (line.rfind("## ", 0) == 0) in_section = line == "## `mbsgen linear`";
    if (!in_section) continue;
    if (line.rfind("```", 0) == 0) {
      in_console = line == "```console";
      continue;
    }
    if (!in_console) continue;
    const std::string prefix = "$ mbsgen linear ";
    if (line.rfind(prefix, 0) == 0) {
      out.push_back({line.substr(prefix.size()), {}, 0, lineno});
    } else if (line == "$ echo $?") {
      expect_code = true;
    } else if (expect_code) {
      out.back().exit_code = std::stoi(line);
      expect_code = false;
    } else if (!out.empty()) {
      out.back().output.push_back(line);
    }
  }
  return out;
}

std::vector<std::string> tokens(const std::string& s) {
  std::vector<std::string> t;
  std::string cur;
  for (char c : s) {
    if (std::string(" ,:{}[]\"\t").find(c) != std::string::npos) {
      if (!cur.empty()) t.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) t.push_back(cur);
  return t;
}

/// Numbers equal to 6 significant digits (the table precision; JSON/CSV print 17 but LAPACK
/// kernels differ between machines in the last digits), and values below 1e-12 in magnitude
/// (rounding-level backward errors, ±0) equal to each other. Other tokens compare exactly.
bool same_token(const std::string& a, const std::string& b) {
  if (a == b) return true;
  char* ea = nullptr;
  char* eb = nullptr;
  const double x = std::strtod(a.c_str(), &ea), y = std::strtod(b.c_str(), &eb);
  if (*ea != '\0' || *eb != '\0' || ea == a.c_str() || eb == b.c_str()) return false;
  if (std::abs(x) < 1e-12 && std::abs(y) < 1e-12) return true;
  return std::abs(x - y) <= 5e-6 * std::max(std::abs(x), std::abs(y));
}

}  // namespace

TEST(MbsgenLinearCli, DocumentationExamples) {
  const auto examples = read_examples(std::string(MBSGEN_SOURCE_DIR) + "/docs/cli.md");
  ASSERT_GE(examples.size(), 8u) << "docs/cli.md examples not found";
  for (const Example& ex : examples) {
    SCOPED_TRACE("docs/cli.md:" + std::to_string(ex.line) + ": mbsgen linear " + ex.args);
    const std::string cmd = std::string("cd '") + MBSGEN_SOURCE_DIR + "/tests/runtime/data' && '" +
                            MBSGEN_LINEAR_EXE + "' " + ex.args + " 2>&1; echo \"__exit $?\"";
    FILE* p = popen(cmd.c_str(), "r");
    ASSERT_NE(p, nullptr);
    std::string all;
    std::array<char, 4096> buf{};
    while (std::fgets(buf.data(), buf.size(), p)) all += buf.data();
    pclose(p);
    std::vector<std::string> lines;
    std::istringstream ss(all);
    std::string l;
    int code = -1;
    while (std::getline(ss, l)) {
      if (l.rfind("__exit ", 0) == 0)
        code = std::stoi(l.substr(7));
      else
        lines.push_back(l);
    }
    EXPECT_EQ(code, ex.exit_code);
    ASSERT_EQ(lines.size(), ex.output.size()) << all;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const auto a = tokens(lines[i]), b = tokens(ex.output[i]);
      bool same = a.size() == b.size();
      for (std::size_t k = 0; same && k < a.size(); ++k) same = same_token(a[k], b[k]);
      EXPECT_TRUE(same) << "got:      " << lines[i] << "\nexpected: " << ex.output[i];
    }
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
  EXPECT_EQ(run({"linear", "frf", "--M", data + "M.mtx", "--K", data + "K.mtx", "--input", "9"}), 1);
  EXPECT_EQ(run({"linear", "frf", "--M", data + "M.mtx", "--K", data + "K.mtx", "--method", "modal",
                 "--Q", data + "Q.mtx", "--points", "3"}),
            0);
  EXPECT_EQ(run({"linear", "--help"}), 0);
}
