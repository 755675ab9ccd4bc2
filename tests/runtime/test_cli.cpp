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

#include "../common/doc_examples.hpp"
#include "mbsgen/runtime/linear_cli.hpp"

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
  EXPECT_EQ(run({"linear", "frf", "--M", data + "M.mtx", "--K", data + "K.mtx", "--input", "9"}), 1);
  EXPECT_EQ(run({"linear", "frf", "--M", data + "M.mtx", "--K", data + "K.mtx", "--method", "modal",
                 "--Q", data + "Q.mtx", "--points", "3"}),
            0);
  EXPECT_EQ(run({"linear", "--help"}), 0);
}
