// Runs the ```console examples of a documentation section and compares their output
// (shared by the tests of `mbsgen linear` and of the model solvers, docs/cli.md).
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace doc_examples {

struct Example {
  std::string command;              // after "$ "
  std::vector<std::string> output;  // expected stdout+stderr lines
  int exit_code = 0;                // from a following "$ echo $?"
  int line = 0;
};

/// The examples of the section whose heading line is `section` (up to the next "## ").
inline std::vector<Example> read(const std::string& path, const std::string& section) {
  std::ifstream in(path);
  std::vector<Example> out;
  std::string line;
  bool in_section = false, in_console = false, expect_code = false;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.rfind("## ", 0) == 0) in_section = line == section;
    if (!in_section) continue;
    if (line.rfind("```", 0) == 0) {
      in_console = line == "```console";
      continue;
    }
    if (!in_console) continue;
    if (line == "$ echo $?") {
      expect_code = true;
    } else if (expect_code) {
      out.back().exit_code = std::stoi(line);
      expect_code = false;
    } else if (line.rfind("$ ", 0) == 0) {
      out.push_back({line.substr(2), {}, 0, lineno});
    } else if (!out.empty()) {
      out.back().output.push_back(line);
    }
  }
  return out;
}

inline std::vector<std::string> tokens(const std::string& s) {
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
inline bool same_token(const std::string& a, const std::string& b) {
  if (a == b) return true;
  char* ea = nullptr;
  char* eb = nullptr;
  const double x = std::strtod(a.c_str(), &ea), y = std::strtod(b.c_str(), &eb);
  if (*ea != '\0' || *eb != '\0' || ea == a.c_str() || eb == b.c_str()) return false;
  if (std::abs(x) < 1e-12 && std::abs(y) < 1e-12) return true;
  return std::abs(x - y) <= 5e-6 * std::max(std::abs(x), std::abs(y));
}

/// Runs shell_command (stdout and stderr together) and expects ex's output and exit code.
inline void expect_output(const std::string& shell_command, const Example& ex) {
  const std::string cmd = "(" + shell_command + ") 2>&1; echo \"__exit $?\"";
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
  EXPECT_EQ(code, ex.exit_code) << all;
  ASSERT_EQ(lines.size(), ex.output.size()) << all;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const auto a = tokens(lines[i]), b = tokens(ex.output[i]);
    bool same = a.size() == b.size();
    for (std::size_t k = 0; same && k < a.size(); ++k) same = same_token(a[k], b[k]);
    EXPECT_TRUE(same) << "got:      " << lines[i] << "\nexpected: " << ex.output[i];
  }
}

}  // namespace doc_examples
