// LinearModel validation and Matrix Market I/O.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "mbsgen/runtime/model/linear_model.hpp"
#include "mbsgen/runtime/model/matrix_market.hpp"

using mbsgen::LinearModel;

namespace {
std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const mbsgen::Error& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(LinearModel, ValidatesDimensionsWithAClearMessage) {
  const Eigen::MatrixXd I2 = Eigen::MatrixXd::Identity(2, 2);
  EXPECT_THROW(LinearModel(I2, I2, Eigen::MatrixXd::Identity(3, 3)), mbsgen::DimensionError);
  const std::string msg = message_of([&] { LinearModel(I2, I2, Eigen::MatrixXd::Identity(3, 3)); });
  EXPECT_NE(msg.find("LinearModel"), std::string::npos) << msg;
  EXPECT_NE(msg.find("3x3"), std::string::npos) << msg;
  EXPECT_NE(msg.find("2x2"), std::string::npos) << msg;
  EXPECT_THROW(LinearModel(Eigen::MatrixXd(2, 3), I2, I2), mbsgen::DimensionError);
  EXPECT_THROW(LinearModel(I2, I2, I2, Eigen::MatrixXd(3, 1), {}, {}), mbsgen::DimensionError);
  EXPECT_THROW(LinearModel(I2, I2, I2, Eigen::MatrixXd(2, 1), Eigen::MatrixXd(1, 3), {}),
               mbsgen::DimensionError);
  EXPECT_THROW(LinearModel(I2, I2, I2, Eigen::MatrixXd::Zero(2, 1), Eigen::MatrixXd::Zero(1, 2),
                           Eigen::MatrixXd::Zero(2, 2)),
               mbsgen::DimensionError);
  EXPECT_THROW(LinearModel(I2, I2, I2, Eigen::MatrixXd::Zero(2, 1), {}, {}, {"a"}),
               mbsgen::DimensionError);
}

TEST(LinearModel, RejectsNonFiniteEntries) {
  Eigen::MatrixXd K = Eigen::MatrixXd::Identity(2, 2);
  K(1, 0) = std::numeric_limits<double>::infinity();
  const std::string msg = message_of([&] { LinearModel(Eigen::MatrixXd::Identity(2, 2), {}, K); });
  EXPECT_NE(msg.find("K"), std::string::npos);
  EXPECT_NE(msg.find("(2,1)"), std::string::npos) << msg;
  EXPECT_THROW(LinearModel(Eigen::MatrixXd::Identity(2, 2), {}, K), mbsgen::NonFiniteError);
}

TEST(LinearModel, DefaultsAndProperties) {
  Eigen::MatrixXd K(3, 3);
  K << 2, -1, 0, -1, 2, -1, 0, -1, 1;
  const LinearModel m(Eigen::MatrixXd::Identity(3, 3), Eigen::MatrixXd(), K);
  EXPECT_EQ(m.num_inputs(), 3);
  EXPECT_EQ(m.num_outputs(), 3);
  EXPECT_TRUE(m.C_y().isIdentity());
  EXPECT_FALSE(m.has_damping());
  EXPECT_TRUE(m.is_symmetric_undamped());
  EXPECT_EQ(m.bandwidth(), 1);
  EXPECT_EQ(m.coordinate_names()[2], "y3");
  EXPECT_EQ(m.input_names()[0], "u1");
}

TEST(MatrixMarket, RoundTripIsLossless) {
  Eigen::MatrixXd A(3, 2);
  A << 0.1, -2.5e-300, 1.0 / 3.0, 0.0, 6.02214076e23, -0.0;
  for (auto fmt : {mbsgen::MatrixMarketFormat::array, mbsgen::MatrixMarketFormat::coordinate}) {
    std::stringstream ss;
    mbsgen::write_matrix_market(ss, A, fmt, "test matrix\nsecond line");
    const Eigen::MatrixXd B = mbsgen::read_matrix_market(ss, "mem");
    ASSERT_EQ(B.rows(), 3);
    ASSERT_EQ(B.cols(), 2);
    EXPECT_TRUE((A.array() == B.array()).all());  // 17 significant digits round-trip exactly
  }
}

TEST(MatrixMarket, ReadsSymmetricAndSkewAndInteger) {
  std::istringstream sym(
      "%%MatrixMarket matrix coordinate real symmetric\n% comment\n3 3 4\n1 1 4\n2 1 -1\n3 2 -2\n3 3 5\n");
  const Eigen::MatrixXd S = mbsgen::read_matrix_market(sym, "sym");
  EXPECT_EQ(S(0, 1), -1);
  EXPECT_EQ(S(1, 0), -1);
  EXPECT_EQ(S(1, 2), -2);
  EXPECT_EQ(S(2, 2), 5);
  std::istringstream arr("%%MatrixMarket matrix array integer symmetric\n2 2\n1\n2\n3\n");
  const Eigen::MatrixXd A = mbsgen::read_matrix_market(arr, "arr");
  EXPECT_EQ(A(0, 0), 1);
  EXPECT_EQ(A(1, 0), 2);
  EXPECT_EQ(A(0, 1), 2);
  EXPECT_EQ(A(1, 1), 3);
  std::istringstream skew("%%MatrixMarket matrix coordinate real skew-symmetric\n2 2 1\n2 1 7\n");
  const Eigen::MatrixXd K = mbsgen::read_matrix_market(skew, "skew");
  EXPECT_EQ(K(1, 0), 7);
  EXPECT_EQ(K(0, 1), -7);
}

TEST(MatrixMarket, ErrorsCarryFileAndLine) {
  auto msg = [](const std::string& text) {
    std::istringstream in(text);
    return message_of([&] { mbsgen::read_matrix_market(in, "f.mtx"); });
  };
  EXPECT_NE(msg("hello\n").find("f.mtx:1:"), std::string::npos);
  EXPECT_NE(msg("%%MatrixMarket matrix coordinate complex general\n1 1 1\n1 1 1 0\n").find("complex"),
            std::string::npos);
  EXPECT_NE(msg("%%MatrixMarket matrix coordinate real general\n2 2 1\n3 1 1.0\n").find("f.mtx:3:"),
            std::string::npos);
  EXPECT_NE(msg("%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n").find("ends after 3 of 4"),
            std::string::npos);
  EXPECT_NE(msg("%%MatrixMarket matrix array real general\n1 1\nabc\n").find("bad number"),
            std::string::npos);
  std::istringstream nan("%%MatrixMarket matrix array real general\n1 1\nnan\n");
  EXPECT_THROW(mbsgen::read_matrix_market(nan, "n"), mbsgen::NonFiniteError);
  EXPECT_THROW(mbsgen::read_matrix_market("/nonexistent/file.mtx"), mbsgen::ParseError);
  // A directory opens as a stream on Linux and reads as empty: named for what it is.
  const std::string dir = std::string(MBSGEN_SOURCE_DIR) + "/tests";
  try {
    mbsgen::read_matrix_market(dir);
    ADD_FAILURE() << "a directory was read as a matrix";
  } catch (const mbsgen::ParseError& e) {
    EXPECT_EQ(std::string(e.what()), dir + ": is a directory, not a regular file");
  }
}

TEST(RuntimeSources, NeverIncludeGinac) {
  // docs/design.md: the runtime never depends on GiNaC (nor CLN, which only the tests use).
  namespace fs = std::filesystem;
  int files = 0;
  for (const auto& e : fs::recursive_directory_iterator(std::string(MBSGEN_SOURCE_DIR) + "/runtime")) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path());
    std::string line;
    ++files;
    while (std::getline(in, line)) {
      std::string l = line;
      for (char& c : l) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      const bool include = l.find("#include") != std::string::npos;
      EXPECT_FALSE(include && (l.find("ginac") != std::string::npos || l.find("cln/") != std::string::npos))
          << e.path() << ": " << line;
      EXPECT_FALSE(l.find("target_link_libraries") != std::string::npos && l.find("ginac") != std::string::npos)
          << e.path() << ": " << line;
    }
  }
  EXPECT_GT(files, 10);
}
