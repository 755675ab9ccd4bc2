// Exact symbolic checks of the derivation on small models: the generator's matrices, with all
// intermediates written out and exact rational parameters, must equal exact reference matrices.
#include "mbsgen/generator/chain.hpp"
#include "mbsgen/generator/linearize.hpp"

#include <gtest/gtest.h>

namespace mbsgen {
namespace {

using GiNaC::ex;
using GiNaC::numeric;

// Three-link planar chain of ../shared/reference/sympy_chain3.md (SymPy 1.11 KanesMethod,
// exact rationals): M, C, K at q = 0 must agree exactly.
TEST(Derivation, ThreeLinkChainMatchesSymPyExactly) {
  Model model = planar_chain(3);
  Equations eq = derive(model);
  LinearEquations lin = linearize(eq);
  GiNaC::exmap values;
  const std::map<std::string, numeric> p = {
      {"g", numeric(981, 100)}, {"m1", 1},  {"m2", numeric(3, 2)}, {"m3", 2},
      {"l1", numeric(1, 2)},    {"l2", numeric(2, 5)}, {"l3", numeric(3, 10)},
      {"k1", 10}, {"k2", 20}, {"k3", 30},
      {"c1", numeric(1, 10)}, {"c2", numeric(1, 5)}, {"c3", numeric(3, 10)}};
  for (const auto& [name, v] : p) values[model.symbol(name)] = v;
  for (const auto& s : eq.y) values[s] = 0;
  auto exact = [&](const ex& e) { return eq.program.inline_all(e).subs(values).normal(); };
  const numeric M_ref[3][3] = {{numeric(869, 200), numeric(111, 50), numeric(18, 25)},
                               {numeric(111, 50), numeric(61, 50), numeric(21, 50)},
                               {numeric(18, 25), numeric(21, 50), numeric(9, 50)}};
  const numeric K_ref[3][3] = {{numeric(20677, 400), numeric(981, 50), numeric(2943, 500)},
                               {numeric(981, 50), numeric(1981, 50), numeric(2943, 500)},
                               {numeric(2943, 500), numeric(2943, 500), numeric(17943, 500)}};
  const numeric C_ref[3] = {numeric(1, 10), numeric(1, 5), numeric(3, 10)};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      EXPECT_TRUE((exact(lin.M[i][j]) - M_ref[i][j]).is_zero()) << "M" << i << j << " = " << exact(lin.M[i][j]);
      EXPECT_TRUE((exact(lin.K[i][j]) - K_ref[i][j]).is_zero()) << "K" << i << j << " = " << exact(lin.K[i][j]);
      EXPECT_TRUE((exact(lin.Q[i][j]) - (i == j ? C_ref[i] : numeric(0))).is_zero())
          << "Q" << i << j << " = " << exact(lin.Q[i][j]);
    }
}

}  // namespace
}  // namespace mbsgen
