// Checks of a model at its operating point, run by Model::validate() (internal to model.cpp;
// issue 14 §7): every call and power of a state-dependent expression has the derivatives the
// linear model needs there, and no spring or damper joins two coincident points. Without them
// the derivation divides by zero somewhere inside GiNaC ("power::eval(): division by zero")
// with no place to show.
#pragma once

#include "mbsgen/generator/model/model.hpp"

#include "symbolic/checked_subs.hpp"

#include <ginac/ginac.h>

#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace mbsgen::detail {

/// The values of the operating point: parameters (exact), coordinates (unless the operating
/// point is only a guess for an equilibrium), rates, and inputs 0.
inline GiNaC::exmap operating_point_values(const Model& model, const GiNaC::exmap& parameters) {
  GiNaC::exmap values = parameters;
  const LinearizationPoint& op = model.operating_point();
  const bool given = op.kind == LinearizationPoint::Kind::given;
  for (const auto& c : model.coordinates()) {
    const auto p = op.position.find(c.name);
    const auto v = op.velocity.find(c.name);
    try {
      if (given) values[c.position] = p == op.position.end() ? GiNaC::ex(0) : checked_subs(p->second, parameters);
      values[c.velocity] = v == op.velocity.end() ? GiNaC::ex(0) : checked_subs(v->second, parameters);
    } catch (const EvaluationError&) {
      // an operating point that cannot be evaluated: check_operating_point reports it
    }
  }
  for (const auto& u : model.input_symbols()) values[u] = 0;
  for (const auto& i : model.inputs())
    if (i.motion) values[i.rate] = 0;  // a support at rest in its reference place
  return values;
}

inline std::string printed(const GiNaC::ex& e) {
  std::ostringstream os;
  os << e;
  return os.str();
}

/// Whether `e` has a symbol that `values` does not give (a coordinate at an equilibrium guess).
inline bool has_free_symbol(const GiNaC::ex& e, const GiNaC::exmap& values) {
  for (GiNaC::const_preorder_iterator i = e.preorder_begin(); i != e.preorder_end(); ++i)
    if (GiNaC::is_a<GiNaC::symbol>(*i) && !values.count(*i)) return true;
  return false;
}

/// For a call or power `node` whose operands depend on the state, "" when its value and its
/// derivatives up to `order` with respect to each operand exist at `values`, else why not.
inline std::string derivative_problem(const GiNaC::ex& node, int order, const GiNaC::exmap& values,
                                      const std::vector<GiNaC::ex>& state) {
  GiNaC::exvector ops, args;
  GiNaC::exmap at;
  std::vector<GiNaC::symbol> t;
  std::string where;
  for (std::size_t i = 0; i < node.nops(); ++i) {
    const GiNaC::ex op = node.op(i);
    bool depends = false;
    for (const auto& s : state) depends = depends || op.has(s);
    if (!depends) {
      ops.push_back(op);
      continue;
    }
    if (has_free_symbol(op, values)) return "";  // not known here (an equilibrium's guess)
    GiNaC::ex v;
    try {
      v = checked_subs(op, values);
    } catch (const EvaluationError&) {
      return "";  // the operand itself is at fault: its own check reports it
    }
    t.emplace_back();
    ops.push_back(t.back());
    at[t.back()] = v;
    GiNaC::ex shown = v;
    try {
      shown = checked_evalf(v);
    } catch (const EvaluationError&) {
    }
    where += std::string(where.empty() ? "" : " and ") + printed(op) + " = " +
             (GiNaC::is_a<GiNaC::numeric>(shown) ? checked_subs_impl::describe(GiNaC::ex_to<GiNaC::numeric>(shown))
                                                  : printed(v));
  }
  if (t.empty()) return "";
  const GiNaC::ex f = GiNaC::is_a<GiNaC::power>(node)
                          ? GiNaC::ex(GiNaC::power(ops[0], ops[1]))
                          : GiNaC::ex(GiNaC::function(GiNaC::ex_to<GiNaC::function>(node).get_serial(), ops));
  // f and its partial derivatives up to `order` (mixed ones included), at the operating point.
  std::vector<GiNaC::ex> layer{f};
  for (int k = 0; k <= order; ++k) {
    std::vector<GiNaC::ex> next;
    for (const GiNaC::ex& g : layer) {
      try {
        const GiNaC::ex v = checked_evalf(checked_subs(g, at));
        if (!GiNaC::is_a<GiNaC::numeric>(v) || !GiNaC::ex_to<GiNaC::numeric>(v).is_real())
          throw EvaluationError(g, "not a real number");
      } catch (const EvaluationError&) {
        return std::string(k == 0 ? " is not defined" : " is not differentiable") +
               " at the operating point, where " + where;
      }
      if (k < order)
        for (const auto& s : t) next.push_back(g.diff(s));
    }
    layer = std::move(next);
  }
  return "";
}

/// Refuses a call or power of a state-dependent expression without the value or derivatives
/// the linear model needs at a given operating point (second derivatives for positions and
/// rotations, which the stiffness takes through the kinematics; first for forces and outputs).
inline void check_derivatives_at_operating_point(const Model& model, const GiNaC::exmap& parameters) {
  const GiNaC::exmap values = operating_point_values(model, parameters);
  std::vector<GiNaC::ex> state;
  for (const auto& c : model.coordinates()) state.insert(state.end(), {c.position, c.velocity});
  for (const auto& u : model.input_symbols()) state.push_back(u);
  for (const auto& i : model.inputs())
    if (i.motion) state.push_back(i.rate);
  auto check = [&](const GiNaC::ex& e, int order, const SourceLocation& element) {
    for (GiNaC::const_preorder_iterator i = e.preorder_begin(); i != e.preorder_end(); ++i) {
      const bool power = GiNaC::is_a<GiNaC::power>(*i);
      if (!power && !GiNaC::is_a<GiNaC::function>(*i)) continue;
      if (power && GiNaC::is_a<GiNaC::numeric>(i->op(1)) &&
          GiNaC::ex_to<GiNaC::numeric>(i->op(1)).is_nonneg_integer())
        continue;  // a polynomial
      const std::string why = derivative_problem(*i, order, values, state);
      if (why.empty()) continue;
      const CallSite* site = model.call_site(*i);
      throw ModelError(site ? site->where : element, (site ? site->text : printed(*i)) + why +
                                                         " (the linear model needs its derivative "
                                                         "there: use a law that is smooth at the "
                                                         "operating point, or another operating point)");
    }
  };
  for (const auto& b : model.bodies()) {
    for (const auto& x : b.translation) check(x, 2, b.where);
    for (const auto& r : b.rotations) check(r.angle, 2, b.where);
    if (b.rotation_matrix)
      for (const auto& row : *b.rotation_matrix)
        for (const auto& x : row) check(x, 2, b.where);
  }
  for (const auto& m : model.markers())  // a marker on the world may move with a motion input
    if (m.body == kWorld) {
      for (const auto& x : m.position) check(x, 2, m.where);
      for (const auto& row : m.rotation)
        for (const auto& x : row) check(x, 2, m.where);
    }
  for (const auto& g : model.generalized_forces()) check(g.value, 1, g.where);
  for (const auto& a : model.applied_forces())
    for (const Vec3* v : {&a.force, &a.torque})
      for (const auto& x : *v) check(x, 1, a.where);
  for (const auto& o : model.outputs())
    if (o.kind == OutputKind::expression) check(o.expression, 1, o.where);
}

// ---------------------------------------------------------------------------------------------
// Coincident markers

using NumVec = std::array<GiNaC::numeric, 3>;
using NumMat = std::array<NumVec, 3>;

inline std::optional<GiNaC::numeric> number_at(const GiNaC::ex& e, const GiNaC::exmap& values) {
  try {
    const GiNaC::ex v = checked_evalf(checked_subs(e, values));
    if (GiNaC::is_a<GiNaC::numeric>(v) && GiNaC::ex_to<GiNaC::numeric>(v).is_real())
      return GiNaC::ex_to<GiNaC::numeric>(v);
  } catch (const EvaluationError&) {
  }
  return std::nullopt;
}

inline std::optional<NumMat> matrix_at(const Mat3& A, const GiNaC::exmap& values) {
  NumMat m;
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j) {
      auto v = number_at(A[i][j], values);
      if (!v) return std::nullopt;
      m[i][j] = *v;
    }
  return m;
}

inline NumMat times(const NumMat& a, const NumMat& b) {
  NumMat c;
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j) c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
  return c;
}

inline NumVec apply(const NumMat& a, const NumVec& x, const NumVec& plus) {
  NumVec y;
  for (std::size_t i = 0; i < 3; ++i) y[i] = plus[i] + a[i][0] * x[0] + a[i][1] * x[1] + a[i][2] * x[2];
  return y;
}

/// World positions of the markers at the operating point (50 digits), or nothing for a marker
/// whose position cannot be evaluated there.
inline std::vector<std::optional<NumVec>> marker_positions(const Model& model, const GiNaC::exmap& values) {
  const NumMat E = {NumVec{1, 0, 0}, NumVec{0, 1, 0}, NumVec{0, 0, 1}};
  std::vector<std::optional<std::pair<NumVec, NumMat>>> frames;  // r_i, S_i
  for (const auto& b : model.bodies()) {
    std::optional<std::pair<NumVec, NumMat>> parent = std::make_pair(NumVec{0, 0, 0}, E);
    if (b.parent != kWorld) parent = frames[static_cast<std::size_t>(model.body_index(b.parent))];
    std::optional<NumMat> R = E;
    if (b.rotation_matrix) R = matrix_at(*b.rotation_matrix, values);
    for (const auto& r : b.rotations) {
      const auto a = number_at(r.angle, values);
      if (!a || !R || !(GiNaC::abs(*a) < GiNaC::numeric(1000000))) { R.reset(); break; }
      const GiNaC::numeric c = GiNaC::cos(*a), s = GiNaC::sin(*a);
      NumMat m = E;
      const std::size_t i = r.axis == Axis::x ? 1 : r.axis == Axis::y ? 2 : 0, j = (i + 1) % 3;
      m[i][i] = c, m[i][j] = -s, m[j][i] = s, m[j][j] = c;
      R = times(*R, m);
    }
    NumVec t;
    bool ok = parent && R;
    for (std::size_t k = 0; k < 3 && ok; ++k)
      if (auto v = number_at(b.translation[k], values)) t[k] = *v; else ok = false;
    if (!ok) { frames.emplace_back(); continue; }
    frames.emplace_back(std::make_pair(apply(parent->second, t, parent->first), times(parent->second, *R)));
  }
  std::vector<std::optional<NumVec>> out;
  for (const auto& m : model.markers()) {
    std::optional<std::pair<NumVec, NumMat>> f = std::make_pair(NumVec{0, 0, 0}, E);
    if (m.body != kWorld) f = frames[static_cast<std::size_t>(model.body_index(m.body))];
    NumVec p;
    bool ok = f.has_value();
    for (std::size_t k = 0; k < 3 && ok; ++k)
      if (auto v = number_at(m.position[k], values)) p[k] = *v; else ok = false;
    out.push_back(ok ? std::optional<NumVec>(apply(f->second, p, f->first)) : std::nullopt);
  }
  return out;
}

/// Refuses, at a given operating point, a damper or a spring of nonzero rest length whose two
/// markers coincide (|r_B − r_A|² <= 1e-30 (|r_A|² + |r_B|²), in 50 digits): its direction is
/// undefined there (a zero-length spring, V = k L²/2, needs none).
inline void check_force_directions(const Model& model, const GiNaC::exmap& parameters) {
  if (model.operating_point().kind != LinearizationPoint::Kind::given) return;
  bool any = !model.dampers().empty();
  for (const auto& s : model.springs()) any = any || !s.rest_length.is_zero();
  if (!any) return;
  const long digits = GiNaC::Digits;
  GiNaC::Digits = 50;
  const auto r = marker_positions(model, operating_point_values(model, parameters));
  GiNaC::Digits = digits;
  auto index = [&](const std::string& name) {
    if (!model.has_marker(name)) return model.markers().size();
    return static_cast<std::size_t>(&model.marker(name) - model.markers().data());
  };
  const GiNaC::numeric tolerance = GiNaC::numeric(10).power(-30);
  auto coincide = [&](const std::string& a, const std::string& b) {
    const std::size_t i = index(a), j = index(b);
    if (i >= r.size() || j >= r.size() || !r[i] || !r[j]) return false;
    GiNaC::numeric d2 = 0, scale = 0;
    for (std::size_t k = 0; k < 3; ++k) {
      d2 += ((*r[j])[k] - (*r[i])[k]) * ((*r[j])[k] - (*r[i])[k]);
      scale += (*r[i])[k] * (*r[i])[k] + (*r[j])[k] * (*r[j])[k];
    }
    return d2 <= scale * tolerance;
  };
  for (const auto& s : model.springs())
    if (!s.rest_length.is_zero() && coincide(s.marker_a, s.marker_b))
      throw ModelError(s.where, "spring '" + s.name + "' joins markers '" + s.marker_a + "' and '" +
                                    s.marker_b + "', which coincide at the operating point: its "
                                    "direction, and so its force, is undefined there (give it rest "
                                    "length 0, or move a marker)");
  for (const auto& d : model.dampers())
    if (coincide(d.marker_a, d.marker_b))
      throw ModelError(d.where, "damper '" + d.name + "' joins markers '" + d.marker_a + "' and '" +
                                    d.marker_b + "', which coincide at the operating point: its "
                                    "direction is undefined there (move a marker)");
}

}  // namespace mbsgen::detail
