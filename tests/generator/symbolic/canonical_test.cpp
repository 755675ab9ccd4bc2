// The canonical order's memo is bounded (issue 17 §1): what it forgets is computed again, equal.
#include "mbsgen/generator/symbolic/canonical.hpp"

#include "symbolic/type_test.hpp"  // generator/src: isa<T>, the fast GiNaC::is_a

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace mbsgen {
namespace {

using GiNaC::ex;

// Distinct compound expressions in a few shapes (sums, products, powers, functions), some of
// them negative, in the symbols x_0 … x_{n-1}.
std::vector<ex> expressions(const std::vector<GiNaC::symbol>& x, std::size_t count) {
  std::vector<ex> out;
  for (std::size_t i = 0; out.size() < count; ++i) {
    const ex a = x[i % x.size()], b = x[(3 * i + 1) % x.size()], c = x[(7 * i + 2) % x.size()];
    const ex k = static_cast<long>(i) + 2;
    out.push_back(k * a * b - c);
    out.push_back(-(a + k * b) * c);
    out.push_back(GiNaC::pow(a - b, 3) / k + GiNaC::sin(c - a));
  }
  out.resize(count);
  return out;
}

TEST(CanonicalOrder, MemoStaysWithinTwiceItsCapacity) {
  std::vector<GiNaC::symbol> x;
  for (int i = 0; i < 40; ++i) x.emplace_back("x" + std::to_string(i));
  const std::vector<ex> es = expressions(x, 3000);
  constexpr std::size_t kCapacity = 64;
  CanonicalOrder bounded(kCapacity);
  std::size_t largest = 0;
  for (const ex& e : es) {
    bounded.signed_key(e);
    largest = std::max(largest, bounded.memo_size());
  }
  // Two generations of at most kCapacity entries each; 3,000 expressions of about 8 compound
  // nodes each would hold some 20,000 entries unbounded.
  EXPECT_LE(largest, 2 * kCapacity);
  EXPECT_GT(largest, kCapacity);  // the bound was reached: generations were dropped
}

TEST(CanonicalOrder, KeysAndSignsDoNotDependOnWhatTheMemoForgot) {
  std::vector<GiNaC::symbol> x;
  for (int i = 0; i < 40; ++i) x.emplace_back("x" + std::to_string(i));
  const std::vector<ex> es = expressions(x, 3000);
  // A declared sign is kept however often the memo starts anew (it cannot be computed again).
  const GiNaC::symbol t("t");
  CanonicalOrder bounded(16), unbounded(1u << 20);
  bounded.set_sign(t, -1);
  unbounded.set_sign(t, -1);
  // Twice through, so that the second pass meets forgotten expressions.
  for (int pass = 0; pass < 2; ++pass)
    for (const ex& e0 : es) {
      const ex e = e0 * t;
      const CanonicalOrder::Signed b = bounded.signed_key(e), u = unbounded.signed_key(e);
      ASSERT_EQ(b.key, u.key) << e;
      ASSERT_EQ(b.sign, u.sign) << e;
      // Independently of any memo: e and −e share their key and have opposite signs.
      ASSERT_EQ(bounded.key(-e), b.key) << e;
      ASSERT_EQ(bounded.sign(-e), -b.sign) << e;
    }
  EXPECT_EQ(bounded.sign(t), -1);
  EXPECT_EQ(bounded.signed_symbols(), 1u);
  EXPECT_LE(bounded.memo_size(), 32u);
}

// isa<T> (type_test.hpp) answers as GiNaC::is_a<T> for every node class, those of its fast path
// (exact classes), their bases (basic, expairseq) and nodes it leaves to GiNaC (a subclass of
// symbol, a constant, a relational, a matrix).
template <class T>
void expect_isa_as_ginac(const std::vector<ex>& nodes) {
  for (const ex& e : nodes)
    EXPECT_EQ(isa<T>(e), GiNaC::is_a<T>(e)) << typeid(T).name() << " of " << e << " ("
                                            << GiNaC::ex_to<GiNaC::basic>(e).class_name() << ")";
}

TEST(TypeTest, IsaAnswersAsGinac) {
  const GiNaC::symbol x("x"), y("y");
  const GiNaC::realsymbol r("r");
  const GiNaC::possymbol p("p");
  const std::vector<ex> nodes = {x, r, p, ex(3), ex(GiNaC::numeric(2, 7)), x + y, x * y,
                                 GiNaC::pow(x, 3), GiNaC::sqrt(x), GiNaC::sin(x), GiNaC::Pi,
                                 x == y, GiNaC::matrix{{x, y}}, GiNaC::lst{x, y}};
  expect_isa_as_ginac<GiNaC::basic>(nodes);
  expect_isa_as_ginac<GiNaC::symbol>(nodes);
  expect_isa_as_ginac<GiNaC::realsymbol>(nodes);
  expect_isa_as_ginac<GiNaC::numeric>(nodes);
  expect_isa_as_ginac<GiNaC::add>(nodes);
  expect_isa_as_ginac<GiNaC::mul>(nodes);
  expect_isa_as_ginac<GiNaC::expairseq>(nodes);
  expect_isa_as_ginac<GiNaC::power>(nodes);
  expect_isa_as_ginac<GiNaC::function>(nodes);
  expect_isa_as_ginac<GiNaC::exprseq>(nodes);
  expect_isa_as_ginac<GiNaC::constant>(nodes);
  expect_isa_as_ginac<GiNaC::relational>(nodes);
  expect_isa_as_ginac<GiNaC::matrix>(nodes);
}

}  // namespace
}  // namespace mbsgen
