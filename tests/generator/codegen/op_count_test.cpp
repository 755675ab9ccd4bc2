// Operation counts of the emitted kernels against SymPy's (issue 17 §3), and the polynomial
// simplification of cse.cpp that gets them there on short chains.
#include "mbsgen/generator/codegen/cse.hpp"
#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/model/parametric_chains.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace mbsgen {
namespace {

using GiNaC::ex;

// SymPy's operations for M, C, K of the planar chain at rest (u = 0), from
// `/usr/bin/python3 bench/peers/sympy_chain.py N` with SymPy 1.11.1 (Debian 12 python3-sympy),
// 2026-11-26: KanesMethod.kanes_equations of the same chain, M, C = −∂f/∂u, K = −∂f/∂q of
// M(q) u' = f(q, u), sympy.cse of all their entries and sympy.count_ops with the coordinates as
// plain symbols (the script's keys ops_mck_cse about any q, ops_mck_q0_cse at q = 0). The q = 0
// figures are issue 17 §3's (265 at N = 6, 989 at N = 10), which it had set against our kernel
// about any q: 371 then.
struct SympyCount {
  int links;
  std::size_t about_any_q, at_zero;
};
constexpr SympyCount kSympy[] = {{2, 31, 21}, {3, 79, 51}, {5, 303, 169}, {6, 503, 265}, {10, 2179, 989}};

std::size_t linear_operations(const Model& model, Equations& eq, const LinearEquations& lin) {
  EmitOptions options;
  options.id = "chain";
  for (const auto& k : emit(model, eq, lin, options).kernels)
    if (k.name == "linear") return k.operations;
  ADD_FAILURE() << "no linear kernel";
  return 0;
}

// Our `linear` kernel takes the operating point y0 as an argument, as SymPy's M, C, K about any q
// keep q: at most SymPy's operations at every N of docs/accuracy-vs-time.md (2, 5, 10) and the
// issue's 6. (Ours count x·x where count_ops counts x**2 as one operation, against us.)
TEST(OperationCounts, LinearKernelOfThePlanarChainAtMostSympys) {
  for (const SympyCount& s : kSympy) {
    const Model model = planar_chain(s.links);
    Equations eq = derive(model);
    const LinearEquations lin = linearize(eq);
    EXPECT_LE(linear_operations(model, eq, lin), s.about_any_q) << "N = " << s.links;
  }
}

// Like for like with the figures: our kernel specialised at y0 = 0 (each entry's
// intermediates with the coordinates replaced by 0, constants folded) against SymPy's at q = 0.
TEST(OperationCounts, LinearKernelAtZeroAtMostSympysAtZero) {
  for (const SympyCount& s : kSympy) {
    const Model model = planar_chain(s.links);
    Equations eq = derive(model);
    LinearEquations lin = linearize(eq);
    GiNaC::exmap zero;
    for (const auto& y : eq.y) zero[y] = 0;
    Program::Substitution at_zero(zero);
    for (ExMatrix* X : {&lin.M, &lin.Q, &lin.K, &lin.B, &lin.Cy, &lin.Cv})
      for (auto& row : *X)
        for (auto& e : row) e = eq.program.substitute(e, at_zero);
    EXPECT_LE(linear_operations(model, eq, lin), s.at_zero) << "N = " << s.links;
  }
}

// The double pendulum's M₂₂ is m₂ l₂², which the program computes from the world-frame position
// as (l₂ sin θ)² + (l₂ cos θ)² and more: written as a polynomial with sin² + cos² = 1 it is one
// product. Values checked at 30 digits against the input statements.
TEST(Cse, WritesPythagoreanSumsAsTheirValue) {
  const GiNaC::symbol x("x"), l("l"), m("m"), t0("t0"), t1("t1"), t2("t2"), t3("t3");
  CanonicalOrder order;
  const std::vector<std::pair<GiNaC::symbol, ex>> defs = {
      {t0, GiNaC::sin(x)}, {t1, GiNaC::cos(x)}, {t2, t0 * l}, {t3, t1 * l}};
  std::vector<Statement> in;
  for (const auto& [t, v] : defs) {
    order.set_sign(t, order.sign(v));
    in.push_back({t.get_name(), v, true, t});
  }
  in.push_back({"out[0]", m * (t2 * t2 + t3 * t3), false, ex()});
  in.push_back({"out[1]", t2 * t1 - t3 * t0, false, ex()});  // l (sin x cos x − cos x sin x) = 0
  const std::vector<Statement> out = eliminate_common_subexpressions(in, order);
  ASSERT_EQ(out.size(), 2u) << "the sine and cosine are no longer read";
  EXPECT_TRUE((out[0].value - m * l * l).expand().is_zero()) << out[0].value;
  EXPECT_TRUE(out[1].value.is_zero()) << out[1].value;
  // Independent of the rewriting: the input statements evaluated at a point.
  GiNaC::exmap at{{x, GiNaC::numeric(3, 7)}, {l, GiNaC::numeric(5, 11)}, {m, GiNaC::numeric(13, 17)}};
  for (const auto& s : in)
    if (s.temporary) at[s.symbol] = s.value.subs(at);
  const long digits = GiNaC::Digits;
  GiNaC::Digits = 30;
  const ex before = GiNaC::evalf(in[4].value.subs(at)), after = GiNaC::evalf(out[0].value.subs(at));
  GiNaC::Digits = digits;
  // 1e-25: the two differ by the rounding of sin² + cos² at 30 digits.
  EXPECT_LT(std::abs(GiNaC::ex_to<GiNaC::numeric>(before - after).to_double()), 1e-25);
}

}  // namespace
}  // namespace mbsgen
