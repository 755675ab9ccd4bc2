// The two projections of derive() (dynamics.hpp: Projection::composite, the default, and
// Projection::naive, M = Σ J̄ᵀĪJ̄ and k − q = Σ J̄ᵀf̄ body by body) give the same equations:
// exactly, in rational arithmetic with every intermediate written out, for the 3-link planar and
// 2-link spatial chains; to 40 digits at pseudo-random points for the tree-structured models
// (middle ear, sleeping top, rotor). bench/accuracy_bench.cpp compares their cost.
#include "mbsgen/generator/chain.hpp"
#include "mbsgen/generator/linearize.hpp"
#include "mbsgen/generator/yaml_reader.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

namespace mbsgen {
namespace {

using GiNaC::ex;
using GiNaC::numeric;

const std::string kSourceDir = MBSGEN_SOURCE_DIR;

struct Derived {
  Equations eq;
  LinearEquations lin;
};

Derived derive_with(const Model& model, Projection projection) {
  DeriveOptions options;
  options.projection = projection;
  Derived d{derive(model, options), {}};
  d.lin = linearize(d.eq);
  return d;
}

// Every expression the two routes must agree on: M(y), k − q (y, ẏ, u), and the linearization.
std::vector<ex> entries(const Derived& d) {
  std::vector<ex> v;
  for (const auto& row : d.eq.M) v.insert(v.end(), row.begin(), row.end());
  v.insert(v.end(), d.eq.residual.begin(), d.eq.residual.end());
  for (const ExMatrix* A : {&d.lin.M, &d.lin.Q, &d.lin.K, &d.lin.B})
    for (const auto& row : *A) v.insert(v.end(), row.begin(), row.end());
  return v;
}

// Values for every variable (y, ẏ, u, p) of both derivations: rationals in [0.5, 2.5).
std::vector<numeric> point(std::size_t count, std::uint64_t seed) {
  std::vector<numeric> v;
  for (std::size_t i = 0; i < count; ++i) {
    seed ^= seed << 13, seed ^= seed >> 7, seed ^= seed << 17;  // xorshift64
    v.push_back(numeric(static_cast<long>(seed % 2000000) + 500000, 1000000));
  }
  return v;
}

GiNaC::exmap values_at(const Equations& eq, const std::vector<numeric>& values, bool as_float) {
  GiNaC::exmap m;
  std::size_t i = 0;
  for (const auto* group : {&eq.y, &eq.yd, &eq.u, &eq.p})
    for (const auto& x : *group) m[x] = as_float ? ex(values[i++].evalf()) : ex(values[i++]);
  return m;
}

// Exact: every intermediate written out, rational values substituted, sin and cos of rationals
// kept symbolic; the difference must expand to zero.
void expect_exactly_equal(const Model& model) {
  Derived a = derive_with(model, Projection::composite);
  Derived b = derive_with(model, Projection::naive);
  const std::vector<ex> ea = entries(a), eb = entries(b);
  ASSERT_EQ(ea.size(), eb.size());
  const std::vector<numeric> p = point(a.eq.y.size() * 2 + a.eq.u.size() + a.eq.p.size(), 0x9e3779b97f4a7c15ULL);
  const GiNaC::exmap va = values_at(a.eq, p, false), vb = values_at(b.eq, p, false);
  for (std::size_t k = 0; k < ea.size(); ++k) {
    const ex x = a.eq.program.inline_all(ea[k]).subs(va).expand();
    const ex y = b.eq.program.inline_all(eb[k]).subs(vb).expand();
    EXPECT_TRUE((x - y).expand().is_zero()) << model.name() << " entry " << k << ": " << x << " vs " << y;
  }
}

// 50-digit evaluation through the programs (memoised substitution) at two points: every entry
// within 1e-40 of the largest entry of its group.
void expect_numerically_equal(const Model& model) {
  Derived a = derive_with(model, Projection::composite);
  Derived b = derive_with(model, Projection::naive);
  const std::vector<ex> ea = entries(a), eb = entries(b);
  ASSERT_EQ(ea.size(), eb.size());
  const long digits = GiNaC::Digits;
  GiNaC::Digits = 50;
  for (std::uint64_t seed : {0x2545f4914f6cdd1dULL, 0x9e3779b97f4a7c15ULL}) {
    const std::vector<numeric> p = point(a.eq.y.size() * 2 + a.eq.u.size() + a.eq.p.size(), seed);
    Program::Substitution sa(values_at(a.eq, p, true)), sb(values_at(b.eq, p, true));
    std::vector<numeric> xa, xb;
    numeric scale = 0;
    for (std::size_t k = 0; k < ea.size(); ++k) {
      const ex x = GiNaC::evalf(a.eq.program.substitute(ea[k], sa));
      const ex y = GiNaC::evalf(b.eq.program.substitute(eb[k], sb));
      ASSERT_TRUE(GiNaC::is_a<numeric>(x) && GiNaC::is_a<numeric>(y)) << x << ", " << y;
      xa.push_back(GiNaC::ex_to<numeric>(x));
      xb.push_back(GiNaC::ex_to<numeric>(y));
      scale = std::max(scale, GiNaC::abs(xa.back()));
    }
    const numeric tol = scale * numeric(10).power(-40);
    for (std::size_t k = 0; k < ea.size(); ++k)
      EXPECT_LE(GiNaC::abs(xa[k] - xb[k]), tol) << model.name() << " entry " << k << ": " << xa[k] << " vs " << xb[k];
  }
  GiNaC::Digits = digits;
}

TEST(NaiveProjection, PlanarChainExactlyEqual) { expect_exactly_equal(planar_chain(3)); }

TEST(NaiveProjection, SpatialChainExactlyEqual) { expect_exactly_equal(spatial_chain(2)); }

TEST(NaiveProjection, TreeModelsEqualTo40Digits) {
  for (const char* file : {"models/middle_ear/middle_ear.yaml", "models/textbook/sleeping_top.yaml",
                           "models/textbook/rotor_disk.yaml", "models/textbook/double_pendulum_rods.yaml"}) {
    SCOPED_TRACE(file);
    expect_numerically_equal(read_model_file(kSourceDir + "/" + file));
  }
  expect_numerically_equal(spatial_chain(5));
}

}  // namespace
}  // namespace mbsgen
