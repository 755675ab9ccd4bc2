// The projections of derive() (dynamics.hpp: Projection::composite, the default, link_frames,
// world_composite, and Projection::naive, M = Σ J̄ᵀĪJ̄ and k − q = Σ J̄ᵀf̄ body by body) give the
// same equations:
// exactly, in rational arithmetic with every intermediate written out, for the 3-link planar and
// 2-link spatial chains; to 40 digits at pseudo-random points for the tree-structured models
// (middle ear, sleeping top, rotor). bench/generation_cost.cpp compares their cost.
#include "mbsgen/generator/linear/linearize.hpp"
#include "mbsgen/generator/model/parametric_chains.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <string>
#include <utility>
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

// sin(a), cos(a) of each argument → symbols s_a, c_a.
struct TrigToSymbols : GiNaC::map_function {
  std::map<ex, std::pair<GiNaC::symbol, GiNaC::symbol>, GiNaC::ex_is_less> pairs;
  ex operator()(const ex& e) override {
    const bool s = is_ex_the_function(e, GiNaC::sin), c = is_ex_the_function(e, GiNaC::cos);
    if (!s && !c) return e.map(*this);
    auto it = pairs.find(e.op(0));
    if (it == pairs.end()) it = pairs.emplace(e.op(0), std::make_pair(GiNaC::symbol(), GiNaC::symbol())).first;
    return s ? ex(it->second.first) : ex(it->second.second);
  }
};

// x expanded with c_a² = 1 − s_a² for every argument a: zero exactly when x is zero given
// sin² + cos² = 1 (the link-frame route writes rotations link by link, the naive one in world
// axes, so equal entries can differ by multiples of sin² a + cos² a − 1).
ex reduce_trig(const ex& x) {
  TrigToSymbols trig;
  ex e = GiNaC::expand(x.map(trig));
  for (const auto& [arg, sc] : trig.pairs)
    for (int d = e.degree(sc.second); d >= 2; d = e.degree(sc.second)) {
      const ex k = e.coeff(sc.second, d);
      e = GiNaC::expand(e - k * GiNaC::pow(sc.second, d) +
                        k * GiNaC::pow(sc.second, d - 2) * (1 - GiNaC::pow(sc.first, 2)));
    }
  return e;
}

// Exact: every intermediate written out, rational values substituted, sin and cos of rationals
// kept symbolic; the difference must expand to zero with sin² + cos² = 1.
void expect_exactly_equal(const Model& model, Projection projection = Projection::composite) {
  Derived a = derive_with(model, projection);
  Derived b = derive_with(model, Projection::naive);
  const std::vector<ex> ea = entries(a), eb = entries(b);
  ASSERT_EQ(ea.size(), eb.size());
  const std::vector<numeric> p = point(a.eq.y.size() * 2 + a.eq.u.size() + a.eq.p.size(), 0x9e3779b97f4a7c15ULL);
  const GiNaC::exmap va = values_at(a.eq, p, false), vb = values_at(b.eq, p, false);
  for (std::size_t k = 0; k < ea.size(); ++k) {
    const ex x = a.eq.program.inline_all(ea[k]).subs(va).expand();
    const ex y = b.eq.program.inline_all(eb[k]).subs(vb).expand();
    EXPECT_TRUE(reduce_trig(x - y).is_zero()) << model.name() << " entry " << k << ": " << x << " vs " << y;
  }
}

// 50-digit evaluation through the programs (memoised substitution) at two points: every entry
// within 1e-40 of the largest entry of all (M, the residual and the linearized matrices).
void expect_numerically_equal(const Model& model, Projection projection = Projection::composite) {
  Derived a = derive_with(model, projection);
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
      // Intermediates that hold no variable (a fixed base's sin 0.3) are left by substitute():
      // written out, they evaluate.
      const ex x = GiNaC::evalf(a.eq.program.inline_all(a.eq.program.substitute(ea[k], sa)));
      const ex y = GiNaC::evalf(b.eq.program.inline_all(b.eq.program.substitute(eb[k], sb)));
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

// The link-frame route where composite takes the world frame (planar models, rolling), and on
// the joints it handles generally: a rotation matrix, coordinates in a translation, an angle of
// two coordinates, a body fixed to its parent, an applied force.
TEST(NaiveProjection, LinkFramesEverywhere) {
  expect_exactly_equal(planar_chain(3), Projection::link_frames);
  expect_numerically_equal(read_model_file(kSourceDir + "/models/textbook/double_pendulum_rods.yaml"),
                           Projection::link_frames);
  expect_numerically_equal(read_model_file(kSourceDir + "/models/rolling/rolling_disk.yaml"),
                           Projection::link_frames);
}

Model general_joints() {
  Model model("general_joints");
  const ex m = model.add_parameter("m", 1.3, "kg"), l = model.add_parameter("l", 0.4, "m");
  const ex g = model.add_parameter("g", 9.81, "m/s^2");
  for (const char* c : {"q1", "q2", "q3", "q4"}) model.add_coordinate(c, "rad");
  const auto q = [&](std::size_t i) { return ex(model.coordinates()[i].position); };
  Body a;
  a.name = "a";
  a.translation = {q(2), ex(0), l * GiNaC::sin(q(0))};
  const ex c = GiNaC::cos(q(0) + q(3) * q(3)), s = GiNaC::sin(q(0) + q(3) * q(3));
  const ex cb = GiNaC::cos(q(1)), sb = GiNaC::sin(q(1));
  a.rotation_matrix = Mat3{{{c, -s * cb, s * sb}, {s, c * cb, -c * sb}, {ex(0), sb, cb}}};  // R_z R_x
  a.mass = m;
  a.com = {l / 3, ex(0), -l / 2};
  a.inertia = {{{m * l * l / 10, m * l * l / 50, ex(0)}, {m * l * l / 50, m * l * l / 12, ex(0)},
                {ex(0), ex(0), m * l * l / 20}}};
  model.add_body(a);
  Body fixed;  // rigidly attached to a: shares its frame
  fixed.name = "fixed";
  fixed.parent = "a";
  fixed.mass = m / 2;
  fixed.com = {ex(0), l, ex(0)};
  model.add_body(fixed);
  Body b;
  b.name = "b";
  b.parent = "a";
  b.translation = {ex(0), ex(0), -l};
  b.rotations = {{Axis::y, q(1) - 2 * q(3)}, {Axis::z, q(3)}};
  b.mass = m;
  b.com = {ex(0), l / 4, -l / 2};
  b.inertia = {{{m * l * l / 8, ex(0), m * l * l / 40}, {ex(0), m * l * l / 9, ex(0)},
                {m * l * l / 40, ex(0), m * l * l / 30}}};
  model.add_body(b);
  Marker tip;
  tip.name = "tip";
  tip.body = "b";
  tip.position = {l / 5, ex(0), -l};
  model.add_marker(tip);
  model.add_gravity({"gravity", {ex(0), g / 3, -g}, {}});
  AppliedForce f;
  f.name = "push";
  f.marker = "tip";
  f.frame = ForceFrame::marker;
  f.force = {ex(2), ex(0), ex(1)};
  f.torque = {ex(0), ex(1) / 2, ex(0)};
  model.add_applied_force(f);
  return model;
}

// A base fixed to the world by a constant translation and tilt (steps without columns), two
// sibling branches that share a coordinate, a grandchild: the cases of the link-frame route a
// review found untested.
Model fixed_base_branches() {
  Model model("fixed_base_branches");
  const ex m = model.add_parameter("m", 0.7, "kg"), l = model.add_parameter("l", 0.3, "m");
  const ex g = model.add_parameter("g", 9.81, "m/s^2");
  for (const char* c : {"q1", "q2", "q3"}) model.add_coordinate(c, "rad");
  const auto q = [&](std::size_t i) { return ex(model.coordinates()[i].position); };
  const Mat3 inertia = {{{m * l * l / 7, m * l * l / 60, ex(0)}, {m * l * l / 60, m * l * l / 11, ex(0)},
                         {ex(0), ex(0), m * l * l / 9}}};
  auto body = [&](const char* name, const char* parent, Vec3 t, std::vector<ElementaryRotation> rotations) {
    Body b;
    b.name = name;
    if (*parent) b.parent = parent;  // else the world
    b.translation = t;
    b.rotations = std::move(rotations);
    b.mass = m;
    b.com = {l / 3, l / 5, -l / 4};
    b.inertia = inertia;
    model.add_body(b);
  };
  body("base", "", {l / 2, -l / 3, l}, {{Axis::x, ex(3) / 10}, {Axis::z, ex(-1) / 5}});
  body("left", "base", {ex(0), l, ex(0)}, {{Axis::z, q(0)}});
  body("right", "base", {ex(0), -l, ex(0)}, {{Axis::z, q(0) + q(1)}, {Axis::y, q(1)}});
  body("tip", "left", {l, ex(0), ex(0)}, {{Axis::x, q(2)}});
  model.add_gravity({"gravity", {ex(0), ex(0), -g}, {}});
  return model;
}

TEST(NaiveProjection, LinkFramesFixedBaseAndSiblingBranches) {
  expect_numerically_equal(fixed_base_branches(), Projection::link_frames);
  Model without = fixed_base_branches();  // M and gravity only: the residual's inertial part is 0
  without.set_inertial_velocity_terms(false);
  expect_numerically_equal(without, Projection::link_frames);
}

TEST(NaiveProjection, LinkFramesGeneralJoints) {
  expect_numerically_equal(general_joints(), Projection::link_frames);
  expect_numerically_equal(general_joints(), Projection::world_composite);
}

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
