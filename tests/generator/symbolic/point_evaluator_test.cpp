// The program evaluated at a point in 50-digit floating point (generator/src/symbolic/point_evaluator.hpp:
// the numerical screen of the structural zeros and the symmetry tests) against GiNaC's own
// evaluation of the written-out expressions, and the compiled program shared by several points
// against a fresh one per point.
#include "mbsgen/generator/linear/linearize.hpp"
#include "mbsgen/generator/model/parametric_chains.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include "linear/sample_points.hpp"
#include "symbolic/point_evaluator.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace mbsgen {
namespace {

using GiNaC::ex;
using GiNaC::numeric;

const std::string kSourceDir = MBSGEN_SOURCE_DIR;

// Digits set for the evaluation, restored after.
struct Digits {
  long saved = GiNaC::Digits;
  Digits() { GiNaC::Digits = detail::PointEvaluator::kDigits; }
  ~Digits() { GiNaC::Digits = saved; }
};

std::vector<ex> entries_of(const Equations& eq, const LinearEquations& lin) {
  std::vector<ex> entries;
  for (const ExMatrix* A : {&lin.M, &lin.K, &lin.Q, &lin.B})
    for (const auto& row : *A) entries.insert(entries.end(), row.begin(), row.end());
  entries.insert(entries.end(), eq.residual.begin(), eq.residual.end());
  return entries;
}

TEST(PointEvaluator, EqualsGiNaCsEvaluationOfTheWrittenOutExpressions) {
  for (const std::string file : {"/models/robots/puma560.yaml", "/models/textbook/sleeping_top.yaml"}) {
    const Model model = read_model_file(kSourceDir + file);
    Equations eq = derive(model);
    LinearEquations lin = linearize(eq);
    std::uint64_t state = detail::kSampleSeed;
    const GiNaC::exmap point = detail::sample_point(eq, lin, state, false);
    const std::vector<ex> entries = entries_of(eq, lin);
    const Digits digits;
    const std::vector<numeric> v = detail::PointEvaluator(eq.program, point).evaluate(entries);
    ASSERT_EQ(v.size(), entries.size());
    // GiNaC evaluates the written-out trees in its own order and roundings: agreement to 1e-40
    // of the largest entry leaves ten digits for the rounding of sums of 50-digit terms.
    numeric scale = 0;
    for (const numeric& x : v) scale = std::max(scale, GiNaC::abs(x));
    ASSERT_GT(scale, 0);
    for (std::size_t k = 0; k < entries.size(); ++k) {
      const ex reference = GiNaC::evalf(eq.program.inline_all(entries[k]).subs(point, GiNaC::subs_options::no_pattern));
      ASSERT_TRUE(GiNaC::is_a<numeric>(reference)) << file << " entry " << k;
      EXPECT_LE(GiNaC::abs(v[k] - GiNaC::ex_to<numeric>(reference)), scale * numeric(1, 10).power(40))
          << file << " entry " << k;
    }
  }
}

TEST(PointEvaluator, ProgramCompiledOnceForSeveralPointsGivesTheSameBits) {
  Model model = spatial_chain(3);
  Equations eq = derive(model);
  LinearEquations lin = linearize(eq);
  const std::vector<ex> entries = entries_of(eq, lin);
  const Digits digits;
  auto tape = std::make_shared<detail::ProgramTape>(eq.program);
  std::uint64_t state = detail::kSampleSeed;
  for (int point = 0; point < 3; ++point) {
    const GiNaC::exmap values = detail::sample_point(eq, lin, state, point == 2);
    detail::PointEvaluator shared(tape, values), fresh(eq.program, values);
    // In two calls (the second reads definitions the first computed) against one.
    const std::vector<ex> first(entries.begin(), entries.begin() + static_cast<long>(entries.size() / 2));
    std::vector<numeric> a = shared.evaluate(first);
    const std::vector<numeric> rest = shared.evaluate(std::vector<ex>(entries.begin() + static_cast<long>(first.size()), entries.end()));
    a.insert(a.end(), rest.begin(), rest.end());
    const std::vector<numeric> b = fresh.evaluate(entries);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k) EXPECT_TRUE(a[k].to_cl_N() == b[k].to_cl_N()) << "point " << point << " entry " << k;
  }
}

TEST(PointEvaluator, AValueGivenForAnIntermediateIsUsedAndAPoleOrAnUnboundSymbolThrows) {
  Program prog;
  const GiNaC::symbol x("x"), y("y");
  prog.add_variable(x);
  prog.add_variable(y);
  const ex t = prog.define(GiNaC::pow(x, 2) + 1);  // t = x^2 + 1
  const ex u = prog.define(t * y);                   // u = t y
  const Digits digits;
  EXPECT_EQ(detail::PointEvaluator(prog, {{x, 2}, {y, 3}}).evaluate({u})[0], 15);
  EXPECT_EQ(detail::PointEvaluator(prog, {{x, 2}, {y, 3}, {t, 7}}).evaluate({u})[0], 21);  // t given: 7 · 3
  const ex w = prog.define(GiNaC::pow(x - 2, -1));
  EXPECT_ANY_THROW(detail::PointEvaluator(prog, {{x, 2}, {y, 3}}).evaluate({w}));
  EXPECT_ANY_THROW(detail::PointEvaluator(prog, {{x, 2}}).evaluate({u}));
}

}  // namespace
}  // namespace mbsgen

namespace mbsgen {
namespace {

// Program::diff_at (the linearization's Q, B, C_y, C_v, C_a, D) against the derivative at a
// general point substituted afterwards, as linearize formed them before: both evaluated at a
// pseudo-random point with 50 digits, equal to 1e-40 of the largest (the roundings differ).
TEST(Program, DiffAtEqualsTheGeneralDerivativeSubstituted) {
  for (const std::string file : {"/models/robots/puma560.yaml", "/models/textbook/sleeping_top.yaml",
                                 "/models/middle_ear/middle_ear.yaml", "/models/textbook/jeffcott_rotor.yaml"}) {
    const Model model = read_model_file(kSourceDir + file);
    Equations eq = derive(model);
    // At rest, inputs zero; and, for a second substitution, the coordinates too.
    GiNaC::exmap rest, zero;
    for (const auto& s : eq.yd) rest[s] = zero[s] = 0;
    for (const auto& s : eq.u) rest[s] = zero[s] = 0;
    for (const auto& s : eq.y) zero[s] = 0;
    for (const GiNaC::exmap* values : {&rest, &zero}) {
      Program::Substitution at(*values), at_too(*values);
      std::vector<ex> direct, afterwards;
      for (const ex& r : eq.residual) {
        const ex ri = eq.program.define(r);
        for (const auto* group : {&eq.yd, &eq.y, &eq.u})
          for (const auto& x : *group) {
            direct.push_back(eq.program.diff_at(ri, x, at));
            afterwards.push_back(eq.program.substitute(eq.program.diff(ri, x), at_too));
          }
      }
      LinearEquations lin;  // sample_point reads only the operating point of `at_operating_point`
      std::uint64_t state = detail::kSampleSeed;
      const GiNaC::exmap point = detail::sample_point(eq, lin, state, false);
      const Digits digits;
      detail::PointEvaluator evaluator(eq.program, point);
      const std::vector<numeric> a = evaluator.evaluate(direct), b = evaluator.evaluate(afterwards);
      numeric scale = 0;
      for (const numeric& x : b) scale = std::max(scale, GiNaC::abs(x));
      ASSERT_GT(scale, 0) << file;
      std::size_t exact_zeros = 0;
      for (std::size_t k = 0; k < a.size(); ++k) {
        EXPECT_LE(GiNaC::abs(a[k] - b[k]), scale * numeric(1, 10).power(40)) << file << " entry " << k;
        exact_zeros += direct[k].is_zero();
        if (afterwards[k].is_zero()) {
          EXPECT_TRUE(direct[k].is_zero()) << file << " entry " << k << ": not an exact zero";
        }
      }
      EXPECT_GT(exact_zeros, 0u) << file;
    }
  }
}

}  // namespace
}  // namespace mbsgen
