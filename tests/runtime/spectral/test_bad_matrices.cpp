// The Matrix Market reader on bad input (issue 14 §4, §6): every file of tests/data/bad_matrices
// fails with the message its second line states (`% expect: {file}:LINE: MESSAGE`, {file} standing
// for the path read), and endless or binary inputs end in an error after a bounded read.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <streambuf>
#include <string>
#include <vector>

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/model/matrix_market.hpp"

namespace {

namespace fs = std::filesystem;

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const mbsgen::Error& e) {
    return e.what();
  }
  return "(no error)";
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
    s.replace(at, from.size(), to);
  return s;
}

TEST(BadMatrices, EveryCorpusFileFailsWithItsExpectedMessage) {
  const fs::path dir = fs::path(MBSGEN_SOURCE_DIR) / "tests/data/bad_matrices";
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".mtx") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 15u) << "the corpus is missing";
  for (const auto& path : files) {
    SCOPED_TRACE(path.filename().string());
    std::ifstream in(path, std::ios::binary);
    std::string banner, expect;
    std::getline(in, banner);
    std::getline(in, expect);
    const std::string prefix = "% expect: ";
    ASSERT_EQ(expect.rfind(prefix, 0), 0u) << "line 2 must be '" << prefix << "MESSAGE'";
    const std::string wanted = replace_all(expect.substr(prefix.size()), "{file}", path.string());
    EXPECT_EQ(message_of([&] { (void)mbsgen::read_matrix_market(path.string()); }), wanted);
  }
}

// A stream that yields `head` once, then `pattern` without end, and counts what was read.
class Endless : public std::streambuf {
 public:
  Endless(std::string head, std::string pattern) : head_(std::move(head)), pattern_(std::move(pattern)) {
    buffer_ = head_;
    setg(buffer_.data(), buffer_.data(), buffer_.data() + buffer_.size());
  }
  long long bytes() const { return bytes_ + (gptr() - eback()); }

 protected:
  int_type underflow() override {
    bytes_ += egptr() - eback();
    buffer_.clear();
    while (buffer_.size() < 4096) buffer_ += pattern_;
    setg(buffer_.data(), buffer_.data(), buffer_.data() + buffer_.size());
    return traits_type::to_int_type(buffer_[0]);
  }

 private:
  std::string head_, pattern_, buffer_;
  long long bytes_ = 0;
};

// What a read of an endless input may consume at most: every line the reader accepts is at most
// kMatrixMarketMaxLine characters plus its end of line, and it accepts the banner, the size line,
// the declared entries and kMatrixMarketMaxBlankLines blank or comment lines, plus the line it
// refuses.
long long bound(long long entries) {
  return (entries + 3 + mbsgen::kMatrixMarketMaxBlankLines) *
         static_cast<long long>(mbsgen::kMatrixMarketMaxLine + 2);
}

TEST(BadMatrices, EndlessInputsEndInAnErrorAfterABoundedRead) {
  const std::string coordinate = "%%MatrixMarket matrix coordinate real general\n";
  struct Case {
    std::string head, pattern, expected;
    long long entries;
  } cases[] = {
      {"", std::string(1, '\0'), "endless:1: a NUL byte: this is not a text file", 0},  // like /dev/zero
      {"", "1", "endless:1: line longer than 1024 characters (the format's limit)", 0},
      {coordinate, "% comment\n", "endless:10002: more than 10000 blank or comment lines", 0},
      {coordinate + "2 2 1\n1 1 1\n", "\n", "endless:10004: more than 10000 blank or comment lines", 1},
      {coordinate + "2 2 1\n", "1 1 1\n", "endless:4: data after the last of the 1 entries: '1 1 1'", 1},
      {"%%MatrixMarket matrix array real general\n1 1\n", "5", "endless:3: line longer than 1024 characters (the format's limit)", 1},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.expected);
    Endless buffer(c.head, c.pattern);
    std::istream in(&buffer);
    EXPECT_EQ(message_of([&] { (void)mbsgen::read_matrix_market(in, "endless"); }), c.expected);
    EXPECT_LE(buffer.bytes(), bound(c.entries));
  }
}

TEST(BadMatrices, DevZeroIsRefusedAtOnce) {
  if (!fs::exists("/dev/zero")) GTEST_SKIP() << "no /dev/zero";
  EXPECT_EQ(message_of([] { (void)mbsgen::read_matrix_market("/dev/zero"); }),
            "/dev/zero: is a character device, not a regular file (refused: reading it could block or never end)");
}

// The case: a symmetric file that stores both triangles used to be read with its
// off-diagonal terms doubled. The lower triangle alone reads as the matrix it stands for.
TEST(BadMatrices, SymmetricLowerTriangleReadsAsTheFullMatrix) {
  std::istringstream lower("%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 2\n2 1 -1\n2 2 2\n");
  const Eigen::MatrixXd A = mbsgen::read_matrix_market(lower, "lower");
  Eigen::MatrixXd expected(2, 2);
  expected << 2, -1, -1, 2;
  EXPECT_TRUE((A.array() == expected.array()).all()) << A;
}

}  // namespace
