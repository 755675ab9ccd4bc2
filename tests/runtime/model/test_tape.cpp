// TapeModel (model/tape.hpp): the grammar against the compiler's evaluation of the same C++
// expressions, a model over a hand-written tape against its closed form, and refusals of damaged
// tapes with their line (issue 40 §1). The shipped models' tapes against their compiled kernels:
// tests/generated/tape_test.cpp.
#include "mbsgen/runtime/model/tape.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

namespace {

// A one-mass oscillator m ÿ + c ẏ + k y = F, output y; kernels written as the generator writes them.
std::string oscillator(const std::string& linear_body = "= M[0] = p[0]\n= Q[0] = p[1]\n= K[0] = p[2]\n= B[0] = 1.0\n"
                                                        "= Cy[0] = 1.0\n= Cv[0] = 0.0\n") {
  return "mbsgen-tape 1\nabi 1\ngenerator \"0.1.0\"\nid \"osc\"\nmodel \"osc\"\nscene \"full\"\n"
         "operating-point 1 0\nfrequencies 0.0 0.0 0 0\n"
         "list coordinates 1\n\"y\" \"m\"\n"
         "list parameters 3\n\"m\" \"kg\" 2.0\n\"c\" \"N s/m\" 0.0\n\"k\" \"N/m\" 8.0\n"
         "list inputs 1\n\"F\" \"N\" \"force\"\nlist outputs 1\n\"y\" \"m\"\n"
         "kernel operating_point 0\nin p 3\nout y0 1\nout yd0 1\n= y0[0] = 0.0\n= yd0[0] = 0.0\nend\n"
         "kernel linear 0\nin y0 1\nin yd0 0\nin p 3\nout M 1\nout Q 1\nout K 1\nout B 1\nout Cy 1\nout Cv 1\n" +
         linear_body + "end\n";
}

// A tape whose `physical` kernel (p → v) computes the expressions, for the grammar.
std::string expressions(const std::vector<std::string>& e, const std::string& extra = "") {
  std::string t = "mbsgen-tape 1\nabi 1\nid \"g\"\nmodel \"g\"\nscene \"full\"\nlist parameters 4\n"
                  "\"a\" \"\" 1.0\n\"b\" \"\" 1.0\n\"c\" \"\" 1.0\n\"d\" \"\" 1.0\n"
                  "list checks " + std::to_string(e.size()) + "\n";
  for (std::size_t i = 0; i < e.size(); ++i) t += "\"positive\" \"x\" \"\" \"a\"\n";
  t += "kernel physical 0\nin p 4\nout v " + std::to_string(e.size()) + "\n" + extra;
  for (std::size_t i = 0; i < e.size(); ++i) t += "= v[" + std::to_string(i) + "] = " + e[i] + "\n";
  return t + "end\n";
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(TapeModel, EvaluatesAsTheCompilerDoes) {
  // Values where the order of the operations changes the rounding.
  const double p[] = {1.0, 1e-16, -1.0, 3.0};
  const double a = p[0], b = p[1], c = p[2], d = p[3];
  const std::vector<std::pair<std::string, double>> cases = {
      {"p[0] + p[1] + p[2]", a + b + c},
      {"p[0] + (p[1] + p[2])", a + (b + c)},
      {"p[0] - p[1] - p[2] + p[3]", a - b - c + d},
      {"-p[0]*p[1] + p[2]", -a * b + c},
      {"-(p[0] + p[1])*p[3]", -(a + b) * d},
      {"p[1]/p[3]/p[3]*p[0]", b / d / d * a},
      {"p[1]/(p[3]*p[3])", b / (d * d)},
      {"(p[3]*p[3]*p[3])", (d * d * d)},
      {"1.0/(p[3]*p[3])", 1.0 / (d * d)},
      {"(1.0/std::sqrt(p[3]))", (1.0 / std::sqrt(d))},
      {"std::pow(p[3], 1.5) - 2.0*p[1]", std::pow(d, 1.5) - 2.0 * b},
      {"std::sin(p[3])*std::cos(p[3]) + std::atan2(p[1], -p[3])", std::sin(d) * std::cos(d) + std::atan2(b, -d)},
      {"std::fabs(p[2]) - std::exp(p[1])*0.10000000000000001", std::fabs(c) - std::exp(b) * 0.10000000000000001},
      {"p[3] - -p[1]", d - -b},
      {"t0*t0 + t0", (d * b - c) * (d * b - c) + (d * b - c)}};
  std::vector<std::string> texts;
  for (const auto& c0 : cases) texts.push_back(c0.first);
  auto tape = mbsgen::TapeModel::parse(expressions(texts, "= t0 = p[3]*p[1] - p[2]\n"), "grammar");
  std::vector<double> v(cases.size());
  ASSERT_EQ(tape->kernels().physical(p, v.data()), 0);
  for (std::size_t i = 0; i < cases.size(); ++i)
    EXPECT_TRUE(same_bits(v[i], cases[i].second)) << cases[i].first << ": tape " << v[i] << ", C++ " << cases[i].second;
  // Not every case is order-free: the first two differ, so the test can tell the orders apart.
  EXPECT_NE(v[0], v[1]);
  const auto& info = tape->kernel_info();
  ASSERT_EQ(info.size(), 1u);
  EXPECT_EQ(info[0].name, "physical");
  EXPECT_GT(info[0].instructions, 30u);
}

TEST(TapeModel, AModelOverATapeHasTheClosedFormModes) {
  auto tape = mbsgen::TapeModel::parse(oscillator(), "oscillator");
  const mbsgen::ModelKernels& k = tape->kernels();
  EXPECT_STREQ(k.evaluation, "tape");
  EXPECT_STREQ(k.parameter_units[1], "N s/m");
  mbsgen::GeneratedModel model(k);
  model.set("k", 18.0);
  const mbsgen::LinearModel lin = model.linear_model();
  mbsgen::QuadraticEigenSolver solver(lin.size());
  solver.compute(lin);
  // ω = √(k/m) = 3 rad/s, to rounding of the eigensolver (its bound).
  ASSERT_FALSE(solver.modes().empty());
  EXPECT_NEAR(std::abs(solver.modes()[0].lambda.imag()), 3.0, 1e-14 * 3);
  EXPECT_EQ(solver.modes()[0].lambda.real(), 0.0);
}

// A damaged or foreign tape is refused with its line, before any kernel runs.
TEST(TapeModel, RefusesDamagedTapesWithTheirLine) {
  const std::string good = oscillator();
  auto refused = [](const std::string& text, const std::string& message) {
    try {
      mbsgen::TapeModel::parse(text, "t.tape");
      ADD_FAILURE() << "accepted; expected: " << message;
    } catch (const mbsgen::ParseError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  refused("mbsgen-tape 2\n", "t.tape:1: not a tape of this runtime");
  refused("", "t.tape:0: not a tape of this runtime");
  std::string s = good;
  s.replace(s.find("abi 1"), 5, "abi 7");
  refused(s, "ABI version is 7");
  refused(oscillator("= M[0] = p[0] + q\n"), "'q' is read before it is defined");
  refused(oscillator("= M[1] = p[0]\n"), "'M[1]' is not an element of an output");
  refused(oscillator("= M[0] = p[3]\n"), "'p[…]' is not an element of an input");
  refused(oscillator("= M[0] = std::system(p[0])\n"), "'std::system' is not a function a tape knows");
  refused(oscillator("= M[0] = 1e999\n"), "a bad number");
  refused(oscillator("= M[0] = (p[0]\n"), "a ')' is missing");
  refused(oscillator("= M[0] = p[0] p[1]\n"), "unexpected 'p[1]'");
  refused(oscillator("= t1 = p[0]\n= t1 = p[1]\n"), "'t1' is defined twice");
  s = good;
  s.replace(s.find("\"kg\""), 4, "\"kg");
  refused(s, "t.tape:12: a string is not closed");
  s = good;
  s.replace(s.find("out Cv 1\n"), 9, "");
  s.replace(s.find("= Cv[0] = 0.0\n"), 14, "");
  refused(s, "kernel 'linear' has 8 arguments, not 9");
  s = good;
  s.replace(s.find("out K 1"), 7, "out K 4");
  refused(s, "kernel 'linear': 'K' has 4 values where the model's sizes give 1");
  s = good;
  s.resize(s.size() - 4);  // "end\n"
  refused(s, "the tape ends inside kernel 'linear'");
}

TEST(TapeModel, AtMostSixtyFourAtOnceAndSlotsAreReused) {
  std::vector<std::unique_ptr<mbsgen::TapeModel>> loaded;
  for (int i = 0; i < mbsgen::TapeModel::kMaxLoaded; ++i) loaded.push_back(mbsgen::TapeModel::parse(oscillator(), "o"));
  EXPECT_THROW(mbsgen::TapeModel::parse(oscillator(), "o"), mbsgen::Error);
  // Each binds its own slot: the kernels of the first and the last are different functions.
  EXPECT_NE(loaded.front()->kernels().linear, loaded.back()->kernels().linear);
  loaded.pop_back();
  auto again = mbsgen::TapeModel::parse(oscillator("= M[0] = 5.0\n= Q[0] = 0.0\n= K[0] = 5.0\n= B[0] = 1.0\n"
                                                   "= Cy[0] = 1.0\n= Cv[0] = 0.0\n"),
                                         "o");
  double y0 = 1, yd0 = 0, p[3] = {2, 0, 8}, M = 0, Q = 0, K = 0, B = 0, Cy = 0, Cv = 0;
  ASSERT_EQ(again->kernels().linear(&y0, &yd0, p, &M, &Q, &K, &B, &Cy, &Cv), 0);
  EXPECT_EQ(M, 5.0);  // the new tape's, not the freed slot's old one
  ASSERT_EQ(loaded.front()->kernels().linear(&y0, &yd0, p, &M, &Q, &K, &B, &Cy, &Cv), 0);
  EXPECT_EQ(M, 2.0);
}

}  // namespace
