// Zero proofs (generator/src/symbolic/zero_proof.hpp) give the same verdict however GiNaC happened
// to write an expression: its operand order (and so the sign of a base such as x − y) follows
// hashes seeded by addresses, which change from run to run. A proof that held in one run of
// mbsgen generate and failed in the next changed the committed sensitivity kernel of the spring
// chain (2026-11-29); the cause was the visit that looks for divisions, which took a node made
// anew at a freed node's address for one already seen (DivisionsInsideOperandsThatGiNaCMakesAnew).
// The spring chain's candidate still failed in some runs after that fix: the radicals of one base
// were unrelated symbols to normal() (RadicalsAreProvedInEveryOperandOrder). Each case is zero
// (or not) by the hand calculation beside it.
#include "symbolic/zero_proof.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace mbsgen {
namespace {

using GiNaC::ex;
using GiNaC::pow;

const ex half = GiNaC::numeric(1, 2);

TEST(ZeroProof, RadicalsOfOneBaseWrittenWithEitherSign) {
  const GiNaC::symbol x("x"), y("y"), k("k");
  Program program;
  // ((x−y)²)^(−1/2) − ((y−x)²)^(−3/2)·(x−y)² = 1/r − r²/r³ = 0 with r = |x − y|.
  const ex e = k * (pow(pow(x - y, 2), -half) - pow(pow(y - x, 2), -3 * half) * pow(x - y, 2));
  EXPECT_TRUE(proved_zero(program, e));
  // The same with the two bases written alike, as GiNaC does in some runs.
  EXPECT_TRUE(proved_zero(program, k * (pow(pow(x - y, 2), -half) - pow(pow(x - y, 2), -3 * half) * pow(x - y, 2))));
}

// d/da of the last spring's stiffness in the chain fixed at both ends (wall at 6a): the partial
// derivative candidate of mbsgen generate's sensitivity screen, as written in a run where the
// proof failed. With d = x5 − 6a and r = |d|, r² = d²:
//   2d/r³ − (3d²/r⁵ − 1/r³)·d = 3d/r³ − 3d³/r⁵ = 0, so the second term vanishes, and
//   18·(1/r − d²/r³)·d/r = 0, (1/r − d²/r³) = 0.
ex spring_to_a_wall_candidate(const GiNaC::symbol& x5, const GiNaC::symbol& a, const GiNaC::symbol& k) {
  const ex d = x5 - 6 * a, d2 = pow(d, 2);
  return -18 * (pow(d2, -half) - d2 * pow(d2, -3 * half)) * d * pow(d2, -half) * k +
         6 * (GiNaC::sqrt(d2) - a) * (2 * d * pow(d2, -3 * half) + (pow(d2, -3 * half) - 3 * d2 * pow(d2, -5 * half)) * d) * k -
         (pow(d2, -half) - d2 * pow(d2, -3 * half)) * k;
}

TEST(ZeroProof, SpringToAWallCandidateOfTheSensitivityKernel) {
  const GiNaC::symbol x5("x5"), a("a"), k("k");
  Program program;
  EXPECT_TRUE(proved_zero(program, spring_to_a_wall_candidate(x5, a, k)));
}

// The same candidate with fresh symbols 200 times: GiNaC orders a sum's and a product's operands
// by hashes that follow the symbols' serial numbers, so each round writes it in another order
// (and a product B·B^(−3/2) is combined into B^(−1/2) in some and not in others). Left to
// normal(), B^(1/2), B^(3/2) and B^(5/2) were unrelated symbols and the proof failed in 2 to 8 of
// the 200 orders (and in 2 of 20 runs of the test above, 2026-11-29); with one symbol t = B^(1/2)
// per base and t² = B it holds in every order.
TEST(ZeroProof, RadicalsAreProvedInEveryOperandOrder) {
  int failed = 0;
  for (int round = 0; round < 200; ++round) {
    const GiNaC::symbol x5("x5"), a("a"), k("k");
    Program program;
    if (!proved_zero(program, spring_to_a_wall_candidate(x5, a, k))) ++failed;
  }
  EXPECT_EQ(failed, 0) << "of 200 operand orders";
}

// Powers of one base written apart, so that GiNaC cannot combine them: B = x² + 2x + 1 = (x + 1)².
TEST(ZeroProof, PowersOfOneRadicalWrittenApart) {
  const GiNaC::symbol x("x"), y("y");
  Program program;
  const ex B = pow(x, 2) + 2 * x + 1, square = pow(x + 1, 2);
  // B^(3/2) = B·B^(1/2), B^(−3/2)·B = B^(−1/2), B^(5/2)·B^(−1/2) = B²: t³ = t·t², t² = B.
  EXPECT_TRUE(proved_zero(program, pow(B, 3 * half) - square * pow(B, half)));
  EXPECT_TRUE(proved_zero(program, y * pow(B, -3 * half) * square - y * pow(B, -half)));
  EXPECT_TRUE(proved_zero(program, pow(B, 5 * half) * pow(pow(x + 1, 2), -half) - pow(square, 2)));
  // Cube roots: (B^(1/3))³ = B; B^(2/3)·B^(1/3) = B.
  EXPECT_TRUE(proved_zero(program, pow(B, GiNaC::numeric(2, 3)) * pow(square, GiNaC::numeric(1, 3)) - B));
  // But B^(3/2) is |x + 1|³, not (x + 1)³, and B^(1/2) + B^(1/2) is not 0.
  EXPECT_FALSE(proved_zero(program, pow(B, 3 * half) - pow(x + 1, 3)));
  EXPECT_FALSE(proved_zero(program, pow(B, half) + pow(square, half)));
  // A radical inside a radical's base: √(1 + √B)² = 1 + √B, with √B written two ways.
  EXPECT_TRUE(proved_zero(program, pow(1 + GiNaC::sqrt(B), 1) -
                                       pow(GiNaC::sqrt(1 + GiNaC::sqrt(square)), 2) + y - y));
  EXPECT_TRUE(proved_zero(program, GiNaC::sqrt(1 + GiNaC::sqrt(B)) * GiNaC::sqrt(1 + GiNaC::sqrt(square)) -
                                       (1 + GiNaC::sqrt(B))));
}

TEST(ZeroProof, RadicalsOfBasesEqualOnlyWhenExpanded) {
  const GiNaC::symbol x("x"), y("y");
  Program program;
  // (x(y+1))^(1/2)·(xy+x)^(3/2) = (xy + x)²: one radical, t⁴ = B².
  EXPECT_TRUE(proved_zero(program, pow(x * (y + 1), half) * pow(x * y + x, 3 * half) - pow(x * y + x, 2)));
  // (x²)^(1/3)·(x²)^(1/2) = (x²)^(5/6): Q = 6.
  EXPECT_TRUE(proved_zero(program, pow(pow(x, 2), GiNaC::numeric(1, 3)) * pow(x * x, half) -
                                       pow(pow(x, 2), GiNaC::numeric(5, 6))));
}

TEST(ZeroProof, ARadicalIsNotItsBase) {
  const GiNaC::symbol x("x"), y("y");
  Program program;
  // √(x²) = |x|, not x; √((x−y)²) − (y − x) is 2(y − x)'s negative part; (x²)^(3/2) ≠ x³.
  EXPECT_FALSE(proved_zero(program, GiNaC::sqrt(pow(x, 2)) - x));
  EXPECT_FALSE(proved_zero(program, GiNaC::sqrt(pow(x - y, 2)) - (y - x)));
  EXPECT_FALSE(proved_zero(program, pow(pow(x, 2), 3 * half) - pow(x, 3)));
  // But its square is: (√(x²))² − x² (written so that GiNaC does not combine it first).
  EXPECT_TRUE(proved_zero(program, GiNaC::sqrt(pow(x - y, 2)) * GiNaC::sqrt(pow(y - x, 2)) - pow(x - y, 2)));
}

TEST(ZeroProof, RadicalsWithSinesAndCosines) {
  const GiNaC::symbol q("q"), l("l");
  Program program;
  // √((l cos q)² + (l sin q)²) · √(l² sin² q + l² cos² q) = l² (c² + s² = 1), the two bases
  // written apart (GiNaC does not combine them) and equal once expanded.
  const ex r1 = GiNaC::sqrt(pow(l * GiNaC::cos(q), 2) + pow(l * GiNaC::sin(q), 2));
  const ex r2 = GiNaC::sqrt(pow(l, 2) * pow(GiNaC::sin(q), 2) + pow(l, 2) * pow(GiNaC::cos(q), 2));
  EXPECT_TRUE(proved_zero(program, r1 * r2 - pow(l, 2)));
  EXPECT_FALSE(proved_zero(program, r1 * r2 - l));
}

TEST(ZeroProof, DivisionsInsideOperandsThatGiNaCMakesAnew) {
  // A rational identity, 1/(z+1) + 1/(z−1) − 2z/(z²−1) = 0, inside products c_i·(a_i + 2b_i·(…)):
  // the proof must see the divisions, which op() hands out in products made anew (2b_i·(…)), at
  // addresses just freed by the products c_i·(a_i + …) visited before them. Marking nodes as
  // seen by address alone took them for visited and proved nothing (in most runs).
  const GiNaC::symbol z("z");
  const ex identity = 1 / (z + 1) + 1 / (z - 1) - 2 * z / (pow(z, 2) - 1);
  ex e = 0;
  std::vector<GiNaC::symbol> a, b, c;
  for (int i = 0; i < 32; ++i) {
    a.emplace_back("a" + std::to_string(i));
    b.emplace_back("b" + std::to_string(i));
    c.emplace_back("c" + std::to_string(i));
    e += c.back() * (a.back() + 2 * b.back() * identity) - c.back() * a.back();
  }
  Program program;
  EXPECT_TRUE(proved_zero(program, e));
  EXPECT_FALSE(proved_zero(program, e + b[0] / (z + 1)));
}

}  // namespace
}  // namespace mbsgen
