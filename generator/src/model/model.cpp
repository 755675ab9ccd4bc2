#include "mbsgen/generator/model/model.hpp"

#include "mbsgen/generator/model/escape.hpp"
#include "mbsgen/generator/model/scene.hpp"

#include "model/smoothness_checks.hpp"
#include "symbolic/checked_subs.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <optional>
#include <functional>
#include <set>
#include <sstream>

namespace mbsgen {

std::string SourceLocation::str() const {
  std::ostringstream os;
  os << (file.empty() ? "<model>" : file);
  if (line > 0) {
    os << ':' << line;
    if (column > 0) os << ':' << column;
  }
  return os.str();
}

ModelError::ModelError(const SourceLocation& where, const std::string& what)
    : std::runtime_error(where.str() + ": error: " + what), where_(where), message_(what) {}

Vec3 zero_vec3() { return {GiNaC::ex(0), GiNaC::ex(0), GiNaC::ex(0)}; }

Mat3 zero_mat3() {
  Mat3 m;
  for (auto& row : m) row = zero_vec3();
  return m;
}

Mat3 identity_mat3() {
  Mat3 m = zero_mat3();
  for (int i = 0; i < 3; ++i) m[i][i] = 1;
  return m;
}

const char* to_string(Category category) {
  switch (category) {
    case Category::gravity: return "gravity";
    case Category::springs: return "springs";
    case Category::dampers: return "dampers";
    case Category::gyroscopic: return "gyroscopic";
    case Category::generalized: return "generalized";
    case Category::applied: return "applied";
  }
  return "";
}

const char* to_string(Analysis analysis) {
  switch (analysis) {
    case Analysis::modes: return "modes";
    case Analysis::frf: return "frf";
    case Analysis::statics: return "static";
    case Analysis::simulate: return "simulate";
    case Analysis::sensitivity: return "sensitivity";
  }
  return "";
}

const char* to_string(ConstraintKind kind) {
  switch (kind) {
    case ConstraintKind::spherical: return "spherical";
    case ConstraintKind::revolute: return "revolute";
    case ConstraintKind::prismatic: return "prismatic";
    case ConstraintKind::planar: return "planar";
    case ConstraintKind::distance: return "distance";
    case ConstraintKind::expression: return "expression";
    case ConstraintKind::rolling: return "rolling";
  }
  return "";
}

Model::Model(std::string name) : name_(std::move(name)) {}

void Model::check_new_symbol(const std::string& name, const SourceLocation& where) {
  static const std::set<std::string> reserved = {"sin", "cos", "tan", "exp", "log", "sqrt", "abs",
                                                 "asin", "acos", "atan", "atan2", "sinh", "cosh",
                                                 "tanh", "Pi", "I", "Euler", "Catalan", "pow",
                                                 "world"};
  // A letter first: GiNaC's lexer reads an identifier only from a letter.
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0])))
    throw ModelError(where, "'" + name + "' is not a valid name (a letter, then letters, digits and _)");
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_'))
      throw ModelError(where, "'" + name + "' is not a valid name (letters, digits and _)");
  if (reserved.count(name)) throw ModelError(where, "'" + name + "' is a reserved name");
  auto it = symbol_names_.find(name);
  if (it != symbol_names_.end())
    throw ModelError(where, "'" + name + "' is already defined at " + it->second.str());
  symbol_names_.emplace(name, where);
}

void Model::check_new_element(const std::string& name, const char* kind,
                              const SourceLocation& where) {
  if (name.empty()) throw ModelError(where, std::string("a ") + kind + " needs a name");
  // The identifier rule of parameters and coordinates (check_new_symbol): one word everywhere.
  if (!std::isalpha(static_cast<unsigned char>(name[0])) ||
      !std::all_of(name.begin(), name.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }))
    throw ModelError(where, std::string("a ") + kind + " name must be a letter, then letters, digits and _: " +
                                "'" + cpp_comment_text(name) + "' is not");
  if (name == kWorld) throw ModelError(where, "'world' is reserved for the inertial frame");
  auto it = element_names_.find(name);
  if (it != element_names_.end())
    throw ModelError(where, std::string("duplicate name '") + name + "': a " + it->second.first +
                                " of that name is defined at " + it->second.second.str());
  element_names_.emplace(name, std::make_pair(std::string(kind), where));
}

const GiNaC::symbol& Model::add_parameter(const std::string& name, double value,
                                          const std::string& unit, const std::string& source,
                                          const SourceLocation& where) {
  check_new_symbol(name, where);
  if (!std::isfinite(value))
    throw ModelError(where, "parameter '" + name + "' has a non-finite value");
  Parameter p;
  p.name = name;
  p.value = value;
  p.unit = unit;
  p.source = source;
  p.symbol = GiNaC::symbol(name);
  p.where = where;
  parameters_.push_back(p);
  symtab_[name] = parameters_.back().symbol;
  return parameters_.back().symbol;
}

const Coordinate& Model::add_coordinate(const std::string& name, const std::string& unit,
                                        const SourceLocation& where) {
  check_new_symbol(name, where);
  check_new_symbol(name + "_dot", where);
  Coordinate c;
  c.name = name;
  c.unit = unit;
  c.position = GiNaC::symbol(name);
  c.velocity = GiNaC::symbol(name + "_dot");
  c.where = where;
  coordinates_.push_back(c);
  symtab_[name] = coordinates_.back().position;
  symtab_[name + "_dot"] = coordinates_.back().velocity;
  return coordinates_.back();
}

const GiNaC::symbol& Model::add_input(const std::string& name, const std::string& unit,
                                      const SourceLocation& where, bool motion) {
  check_new_symbol(name, where);
  if (motion) check_new_symbol(name + "_dot", where);
  Input input{name, unit, where, motion, GiNaC::symbol(name + "_dot")};
  inputs_.push_back(input);
  input_symbols_.push_back(GiNaC::symbol(name));
  symtab_[name] = input_symbols_.back();
  if (motion) symtab_[name + "_dot"] = inputs_.back().rate;
  return input_symbols_.back();
}

std::vector<GiNaC::symbol> Model::force_input_symbols() const {
  std::vector<GiNaC::symbol> s;
  for (std::size_t i = 0; i < inputs_.size(); ++i)
    if (!inputs_[i].motion) s.push_back(input_symbols_[i]);
  return s;
}

bool Model::has_motion_inputs() const {
  for (const auto& i : inputs_)
    if (i.motion) return true;
  return false;
}

void Model::add_body(Body body) {
  check_new_element(body.name, "body", body.where);
  body_index_[body.name] = static_cast<int>(bodies_.size());
  bodies_.push_back(std::move(body));
}

void Model::add_marker(Marker marker) {
  check_new_element(marker.name, "marker", marker.where);
  marker_index_[marker.name] = static_cast<int>(markers_.size());
  markers_.push_back(std::move(marker));
}

void Model::add_gravity(Gravity gravity) {
  check_new_element(gravity.name, "force", gravity.where);
  gravity_.push_back(std::move(gravity));
}
void Model::add_spring(Spring spring) {
  check_new_element(spring.name, "force", spring.where);
  springs_.push_back(std::move(spring));
}
void Model::add_damper(Damper damper) {
  check_new_element(damper.name, "force", damper.where);
  dampers_.push_back(std::move(damper));
}
void Model::add_bushing(Bushing bushing) {
  check_new_element(bushing.name, "force", bushing.where);
  bushings_.push_back(std::move(bushing));
}
void Model::add_generalized_force(GeneralizedForce force) {
  check_new_element(force.name, "force", force.where);
  generalized_forces_.push_back(std::move(force));
}
void Model::add_applied_force(AppliedForce force) {
  check_new_element(force.name, "force", force.where);
  applied_forces_.push_back(std::move(force));
}
void Model::add_output(Output output) {
  check_new_element(output.name, "output", output.where);
  outputs_.push_back(std::move(output));
}

void Model::add_constraint(Constraint constraint) {
  check_new_element(constraint.name, "constraint", constraint.where);
  constraints_.push_back(std::move(constraint));
}

void Model::add_velocity_constraint(VelocityConstraint constraint) {
  check_new_element(constraint.name, "nonholonomic constraint", constraint.where);
  velocity_constraints_.push_back(std::move(constraint));
}

bool Model::nonholonomic() const {
  if (!velocity_constraints_.empty()) return true;
  for (const auto& c : constraints_)
    if (c.kind == ConstraintKind::rolling) return true;
  return false;
}

void Model::add_scene(Scene scene) {
  const std::string& name = scene.name;
  bool valid = !name.empty() && std::isalpha(static_cast<unsigned char>(name[0]));
  for (char c : name) valid = valid && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
  if (!valid)
    throw ModelError(scene.where, "'" + name + "' is not a valid scene name (a letter, then letters, digits and _)");
  if (name == kFullScene)
    throw ModelError(scene.where, "'full' is the implicit scene of the whole model; choose another name");
  for (const auto& s : scenes_)
    if (s.name == name)
      throw ModelError(scene.where, "duplicate scene '" + name + "' (first at " + s.where.str() + ")");
  scenes_.push_back(std::move(scene));
}

const Scene* Model::scene(const std::string& name) const {
  for (const auto& s : scenes_)
    if (s.name == name) return &s;
  return nullptr;
}

GiNaC::ex Model::symbol(const std::string& name) const {
  auto it = symtab_.find(name);
  if (it == symtab_.end()) throw std::out_of_range("mbsgen::Model::symbol: unknown name '" + name + "'");
  return it->second;
}

int Model::body_index(const std::string& name) const {
  if (name == kWorld) return -1;
  auto it = body_index_.find(name);
  if (it == body_index_.end()) throw std::out_of_range("mbsgen::Model::body_index: unknown body '" + name + "'");
  return it->second;
}

int Model::coordinate_index(const std::string& name) const {
  for (std::size_t i = 0; i < coordinates_.size(); ++i)
    if (coordinates_[i].name == name) return static_cast<int>(i);
  return -1;
}

bool Model::has_marker(const std::string& name) const { return marker_index_.count(name) != 0; }

const Marker& Model::marker(const std::string& name) const {
  auto it = marker_index_.find(name);
  if (it == marker_index_.end()) throw std::out_of_range("mbsgen::Model::marker: unknown marker '" + name + "'");
  return markers_[static_cast<std::size_t>(it->second)];
}

namespace {

// Collects the symbols of an expression.
void collect_symbols(const GiNaC::ex& e, std::set<std::string>& out) {
  if (GiNaC::is_a<GiNaC::symbol>(e)) {
    out.insert(GiNaC::ex_to<GiNaC::symbol>(e).get_name());
    return;
  }
  for (std::size_t i = 0; i < e.nops(); ++i) collect_symbols(e.op(i), out);
}

double numeric_value(const GiNaC::ex& e, const GiNaC::exmap& defaults, bool& ok) {
  GiNaC::ex v;
  try {
    v = detail::checked_evalf(detail::checked_subs(e, defaults));  // GiNaC's subs leaks when it throws
  } catch (const std::exception&) {  // a pole (1/(m - 1) at m = 1), CLN's underflow: no value
    ok = false;
    return 0.0;
  }
  ok = GiNaC::is_a<GiNaC::numeric>(v) && GiNaC::ex_to<GiNaC::numeric>(v).is_real();
  return ok ? GiNaC::ex_to<GiNaC::numeric>(v).to_double() : 0.0;
}

// The principal moments of a symmetric 3×3 tensor in ascending order. Eigen's iterative solver,
// backward stable (each moment within a few ulps of the largest): its closed-form 3×3 solver
// loses half the digits at a double moment, so that a slender rod (0, B, B) came out with
// A + B < C by 1e-9 of C for some values of m and L.
Eigen::Vector3d principal_moments(const Mat3& I, const GiNaC::exmap& defaults, bool& ok) {
  Eigen::Matrix3d A;
  ok = true;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      bool entry_ok = false;
      A(i, j) = numeric_value(I[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)], defaults, entry_ok);
      ok = ok && entry_ok && std::isfinite(A(i, j));
    }
  if (!ok) return Eigen::Vector3d::Zero();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(A, Eigen::EigenvaluesOnly);
  return es.eigenvalues();
}

// A double as the exact rational it is.
GiNaC::numeric exact_rational(double v) {
  int e = 0;
  const double m = std::frexp(v, &e);  // v = m 2^e, 0.5 <= |m| < 1
  const long mantissa = static_cast<long>(std::ldexp(m, 53));
  return GiNaC::numeric(mantissa) * GiNaC::numeric(2).power(e - 53);
}

// The 3×3 tensor exactly, when its entries are rational at the (exact) default parameter values.
std::optional<std::array<std::array<GiNaC::numeric, 3>, 3>> exact_tensor(const Mat3& I,
                                                                         const GiNaC::exmap& exact) {
  std::array<std::array<GiNaC::numeric, 3>, 3> J;
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j) {
      GiNaC::ex v;
      try {
        v = detail::checked_subs(I[i][j], exact);
      } catch (const std::exception&) {
        return std::nullopt;
      }
      if (!GiNaC::is_a<GiNaC::numeric>(v) || !GiNaC::ex_to<GiNaC::numeric>(v).is_rational())
        return std::nullopt;
      J[i][j] = GiNaC::ex_to<GiNaC::numeric>(v);
    }
  return J;
}

// Whether a symmetric 3×3 rational matrix is positive semi-definite: all its principal minors
// (three 1×1, three 2×2 and the determinant) are >= 0, decided exactly.
bool exactly_semidefinite(const std::array<std::array<GiNaC::numeric, 3>, 3>& A) {
  for (std::size_t i = 0; i < 3; ++i)
    if (A[i][i].is_negative()) return false;
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = i + 1; j < 3; ++j)
      if ((A[i][i] * A[j][j] - A[i][j] * A[j][i]).is_negative()) return false;
  const GiNaC::numeric det = A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) -
                             A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
                             A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
  return !det.is_negative();
}

// Why R is not a rotation (RᵀR = E to 1e-6, det R = +1) at the default parameter values and two
// sample values of the coordinates, or "" (also when it has no numeric value there: the
// derivation reports that). The kinematics takes Rᵀ for R⁻¹; a matrix that is not orthogonal
// would give a mass matrix that depends on the route of the projection, with no error. 1e-6
// admits entries rounded to six decimals (CAD exports); 0.7071 for √2/2 is refused, and the
// message names the exact form.
std::string rotation_problem(const Mat3& R, GiNaC::exmap values, const std::vector<Coordinate>& coordinates) {
  for (int sample = 0; sample < 2; ++sample) {
    std::string at;  // the coordinates R holds, with their sample values
    for (std::size_t k = 0; k < coordinates.size(); ++k) {
      const double v = 0.37 + 0.61 * sample - 0.23 * static_cast<double>(k % 7);
      values[coordinates[k].position] = GiNaC::numeric(v);
      bool held = false;
      for (const auto& row : R)
        for (const auto& x : row) held = held || x.has(coordinates[k].position);
      if (held) {
        std::ostringstream s;
        s << (at.empty() ? " and " : ", ") << coordinates[k].name << " = " << v;
        at += s.str();
      }
    }
    Eigen::Matrix3d A;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        bool ok = false;
        A(i, j) = numeric_value(R[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)], values, ok);
        if (!ok) return "";
      }
    const double off = (A.transpose() * A - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    const std::string where = " (at the default parameter values" + at + ")";
    if (!(off <= 1e-6)) {
      std::ostringstream s;
      s.precision(3);
      s << "is not orthogonal: an entry of R^T R differs from the identity's by " << off << where
        << "; write exact values (sqrt(2)/2, not 0.7071)";
      return s.str();
    }
    if (!(A.determinant() > 0)) return "is a reflection (determinant -1), not a rotation" + where;
  }
  return "";
}

bool inertia_is_zero(const Mat3& I, const GiNaC::exmap& defaults) {
  bool ok = false;
  return principal_moments(I, defaults, ok).cwiseAbs().maxCoeff() == 0 && ok;
}

// A tensor J about the centre of mass has principal moments A = ∫(y²+z²) dm, … so that
// A, B, C >= 0 and A + B >= C (equality for a flat body): J = tr(Σ) E − Σ with the second moment
// Σ = ∫ r rᵀ dm, and the conditions hold exactly when Σ = (tr J / 2) E − J is positive
// semi-definite (its eigenvalues are (A + B − C)/2, …). Point masses (all zero) and slender rods
// (one zero) are allowed idealizations. Where the entries are rational at the default parameter
// values (decimal literals and parameter values are exact rationals) this is decided exactly, by
// principal minors; otherwise from the eigenvalues d of J computed in double by a backward-stable
// solver, within 32 ε max|d| (the entries' rounding, a few ulps, plus the solver's, a few ulps
// times the dimension 3).
std::string inertia_problem(const Mat3& I, const GiNaC::exmap& defaults, const GiNaC::exmap& exact) {
  bool ok = false;
  const Eigen::Vector3d d = principal_moments(I, defaults, ok);
  if (!ok) return "an inertia tensor that is not numeric (or not finite) with the default parameter values";
  bool semidefinite = false, triangle = false;
  if (const auto J = exact_tensor(I, exact)) {
    semidefinite = exactly_semidefinite(*J);
    auto S = *J;
    const GiNaC::numeric half_trace = ((*J)[0][0] + (*J)[1][1] + (*J)[2][2]) / 2;
    for (std::size_t i = 0; i < 3; ++i)
      for (std::size_t j = 0; j < 3; ++j) S[i][j] = (i == j ? half_trace : GiNaC::numeric(0)) - (*J)[i][j];
    triangle = exactly_semidefinite(S);
  } else {
    const double tol = 32 * std::numeric_limits<double>::epsilon() * d.cwiseAbs().maxCoeff();
    semidefinite = d(0) >= -tol;
    triangle = d(0) + d(1) - d(2) >= -2 * tol;
  }
  std::ostringstream moments;
  moments.precision(6);
  moments << d(0) << ", " << d(1) << ", " << d(2);
  if (!semidefinite)
    return "an inertia tensor that is not positive semi-definite (principal moments " + moments.str() +
           " kg m^2)";
  if (!triangle)
    return "an inertia tensor that violates the triangle inequality: its principal moments " +
           moments.str() + " kg m^2 have A + B < C, which no mass distribution gives";
  return {};
}

// A ModelError at `where` when e uses a symbol outside `allowed` (Model::check_symbols).
void check_expr(const GiNaC::ex& e, const SourceLocation& where, const std::string& what,
                const std::set<std::string>& allowed) {
  std::set<std::string> syms;
  collect_symbols(e, syms);
  for (const auto& s : syms)
    if (!allowed.count(s)) throw ModelError(where, what + " may not depend on '" + s + "'");
}

}  // namespace

// The names of the parameters, and with `coordinates` also of the coordinates.
std::set<std::string> Model::symbol_names(bool coordinates) const {
  std::set<std::string> names;
  for (const auto& p : parameters_) names.insert(p.name);
  if (coordinates)
    for (const auto& c : coordinates_) names.insert(c.name);
  return names;
}

// A ModelError at `where` when e uses a symbol outside `allowed`.
void Model::check_symbols(const GiNaC::ex& e, const SourceLocation& where, const std::string& what,
                          const std::set<std::string>& allowed) {
  check_expr(e, where, what, allowed);
}

// A force output names force elements that transmit a force between two markers.
void Model::validate_force_output(const Output& o) const {
  if (o.elements.empty())
    throw ModelError(o.where, "output '" + o.name + "' of type force names no force element");
  std::set<std::string> seen;
  for (const auto& e : o.elements) {
    if (!seen.insert(e).second)
      throw ModelError(o.where, "output '" + o.name + "' names force element '" + e + "' twice");
    bool found = false;
    for (const auto& s : springs_) found = found || s.name == e;
    for (const auto& d : dampers_) found = found || d.name == e;
    for (const auto& b : bushings_) found = found || b.name == e;
    if (!found)
      throw ModelError(o.where, "output '" + o.name + "' names '" + e +
                                    "', which is not a spring, damper or bushing of this model");
  }
}

// Loop-closure constraints: markers on two different bodies, a positive rod length, expressions
// in coordinates and parameters that depend on a coordinate; the independent coordinates exist
// once each; and the operating point is at rest (steady motions of closed loops are not
// linearized: see loop_closure.hpp).
void Model::validate_constraints(const GiNaC::exmap& defaults) const {
  const std::set<std::string> position_only = symbol_names(true), parameters_only = symbol_names(false);
  for (const auto& c : constraints_) {
    const std::string who = std::string(to_string(c.kind)) + " constraint '" + c.name + "'";
    if (c.kind == ConstraintKind::expression) {
      check_symbols(c.expression, c.where, "a constraint expression", position_only);
      bool depends = false;
      for (const auto& y : coordinates_) depends = depends || c.expression.has(y.position);
      if (!depends)
        throw ModelError(c.where, who + " does not depend on any coordinate");
      continue;
    }
    if (c.kind == ConstraintKind::rolling) {
      validate_rolling(c, who, defaults, parameters_only);
      continue;
    }
    for (const std::string* m : {&c.marker_a, &c.marker_b})
      if (!has_marker(*m)) throw ModelError(c.where, who + " names an unknown marker '" + *m + "'");
    if (marker(c.marker_a).body == marker(c.marker_b).body)
      throw ModelError(c.where, who + " joins two markers of the same body '" + marker(c.marker_a).body +
                                    "': a constraint closes a loop between two bodies");
    if (c.kind == ConstraintKind::distance) {
      check_symbols(c.length, c.where, "a rod length", parameters_only);
      bool ok = false;
      const double L = numeric_value(c.length, defaults, ok);
      if (!ok || !(L > 0))
        throw ModelError(c.where, who + " needs a positive length (" +
                                      (ok ? detail::checked_subs_impl::describe(GiNaC::numeric(L)) + " m"
                                          : std::string("not a number")) + " with the default parameter values)");
    }
  }
  std::set<std::string> independent;
  for (const auto& item : independent_) {
    if (constraints_.empty())
      throw ModelError(item.where, "independent coordinates are chosen only in a model with constraints");
    if (coordinate_index(item.name) < 0)
      throw ModelError(item.where, "independent coordinate '" + item.name + "' is not a coordinate");
    if (!independent.insert(item.name).second)
      throw ModelError(item.where, "independent coordinate '" + item.name + "' is listed twice");
  }
}

// A rolling wheel: its marker on a body (not the world), a positive radius, a unit ground normal.
void Model::validate_rolling(const Constraint& c, const std::string& who, const GiNaC::exmap& defaults,
                             const std::set<std::string>& parameters_only) const {
  if (!has_marker(c.marker_a)) throw ModelError(c.where, who + " names an unknown marker '" + c.marker_a + "'");
  if (marker(c.marker_a).body == kWorld)
    throw ModelError(c.where, who + ": wheel marker '" + c.marker_a + "' is on the world; it must be on the wheel body");
  check_symbols(c.length, c.where, "a wheel radius", parameters_only);
  bool ok = false;
  const double r = numeric_value(c.length, defaults, ok);
  if (!ok || !(r > 0))
    throw ModelError(c.where, who + " needs a positive radius (" +
                                  (ok ? detail::checked_subs_impl::describe(GiNaC::numeric(r)) + " m"
                                      : std::string("not a number")) + " with the default parameter values)");
  double norm2 = 0;
  for (const auto& x : c.normal) {
    check_symbols(x, c.where, "a ground normal", {});
    bool exact = false;
    const double v = numeric_value(x, defaults, exact);
    norm2 += exact ? v * v : std::nan("");
  }
  const double norm = std::sqrt(norm2);
  if (!(std::abs(norm - 1) <= 1e-12))
    throw ModelError(c.where, who + ": the ground normal must be a unit vector (its length is " +
                                  detail::checked_subs_impl::describe(GiNaC::numeric(norm)) + ")");
}

// Nonholonomic constraints: expressions in coordinates, rates and parameters, linear in the
// rates and depending on one; independent speeds name coordinates once each; a steady motion or
// rest given, not an equilibrium to be found (an equilibrium search does not know the constraints).
void Model::validate_velocity_constraints() const {
  std::set<std::string> allowed = symbol_names(true);
  for (const auto& y : coordinates_) allowed.insert(y.name + "_dot");
  for (const auto& v : velocity_constraints_) {
    check_symbols(v.expression, v.where, "a nonholonomic constraint", allowed);
    bool depends = false;
    for (const auto& y : coordinates_) depends = depends || v.expression.has(y.velocity);
    if (!depends)
      throw ModelError(v.where, "nonholonomic constraint '" + v.name +
                                    "' does not depend on any rate (a constraint on positions belongs in 'constraints')");
    for (const auto& a : coordinates_)
      for (const auto& b : coordinates_)
        if (!v.expression.diff(a.velocity).diff(b.velocity).expand().is_zero())
          throw ModelError(v.where, "nonholonomic constraint '" + v.name + "' is not linear in the rates (it has a term in " +
                                        a.name + "_dot*" + b.name + "_dot)");
  }
  std::set<std::string> listed;
  for (const auto& item : independent_speeds_) {
    if (!nonholonomic())
      throw ModelError(item.where, "independent speeds are chosen only in a model with nonholonomic constraints");
    if (coordinate_index(item.name) < 0)
      throw ModelError(item.where, "independent speed '" + item.name + "' is not a coordinate (name the coordinate whose rate it is)");
    if (!listed.insert(item.name).second)
      throw ModelError(item.where, "independent speed '" + item.name + "' is listed twice");
  }
  for (const auto& o : outputs_)
    if (o.kind == OutputKind::reaction && nonholonomic())
      throw ModelError(o.where, "output '" + o.name + "': reaction outputs are not available in a model with "
                                "nonholonomic constraints (rolling wheels) yet");
  if (nonholonomic() && operating_point_.kind == LinearizationPoint::Kind::equilibrium)
    throw ModelError(operating_point_.where, "a model with nonholonomic constraints is linearized at a given operating point "
                                             "(rest or a steady motion), not at an equilibrium to be found");
}

// Prescribed motion (prescribed_motion.hpp) is derived for trees: a motion input in a model
// with loop or velocity constraints, or with reaction outputs (whose joint probes would need the
// prescribed accelerations), is refused rather than linearized wrongly.
void Model::validate_motion_inputs() const {
  for (const auto& i : inputs_) {
    if (!i.motion) continue;
    const std::string head = "motion input '" + i.name + "': prescribed motion ";
    if (!constraints_.empty())
      throw ModelError(i.where, head + "is derived for trees; this model has loop constraints (not supported yet)");
    if (!velocity_constraints_.empty())
      throw ModelError(i.where, head + "is derived for trees; this model has nonholonomic constraints (not supported yet)");
    for (const auto& o : outputs_)
      if (o.kind == OutputKind::reaction)
        throw ModelError(i.where, head + "and reaction outputs ('" + o.name +
                                      "') together are not supported yet");
  }
}

namespace {

// A ModelError at `where` when `name` is not a marker of the model (naming its markers).
void check_marker(const Model& model, const std::string& name, const SourceLocation& where, const std::string& who) {
  if (!model.has_marker(name)) {
    std::string known_markers;
    for (const auto& m : model.markers()) known_markers += (known_markers.empty() ? "" : ", ") + m.name;
    throw ModelError(where, who + " names an unknown marker '" + name + "' (markers: " +
                                (known_markers.empty() ? "none" : known_markers) + ")");
  }
}

// Checks the tree and each body's symbols, mass, inertia tensor and rotation matrix.
void check_bodies(const std::vector<Body>& bodies, const std::map<std::string, int>& body_index,
                  const std::set<std::string>& kinematic, const std::set<std::string>& parameters_only,
                  const std::vector<Coordinate>& kinematic_coordinates, const GiNaC::exmap& defaults,
                  const GiNaC::exmap& exact_defaults) {
  // The tree: every parent exists and is defined before its children (so no cycles).
  std::set<std::string> seen;
  for (const auto& b : bodies) {
    if (b.parent != kWorld && !body_index.count(b.parent))
      throw ModelError(b.where, "body '" + b.name + "' has an unknown parent '" + b.parent + "'");
    if (b.parent != kWorld && !seen.count(b.parent))
      throw ModelError(b.where, "body '" + b.name + "': parent '" + b.parent +
                                    "' must be defined before its children (a cycle, or out of order)");
    seen.insert(b.name);
    for (const auto& t : b.translation) check_expr(t, b.where, "a body's translation", kinematic);
    for (const auto& r : b.rotations) check_expr(r.angle, b.where, "a rotation angle", kinematic);
    if (b.rotation_matrix)
      for (const auto& row : *b.rotation_matrix)
        for (const auto& x : row) check_expr(x, b.where, "a rotation matrix", kinematic);
    check_expr(b.mass, b.where, "a mass", parameters_only);
    for (const auto& x : b.com) check_expr(x, b.where, "a centre of mass", parameters_only);
    for (const auto& row : b.inertia)
      for (const auto& x : row) check_expr(x, b.where, "an inertia tensor", parameters_only);
    bool ok = false;
    double m = numeric_value(b.mass, defaults, ok);
    if (!ok || m < 0)
      throw ModelError(b.where, "body '" + b.name + "' has a negative or non-numeric mass");
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (!(b.inertia[i][j] - b.inertia[j][i]).is_zero())
          throw ModelError(b.where, "body '" + b.name + "': the inertia tensor is not symmetric");
    const std::string inertia_error = inertia_problem(b.inertia, defaults, exact_defaults);
    if (!inertia_error.empty()) throw ModelError(b.where, "body '" + b.name + "' has " + inertia_error);
    if (b.rotation_matrix) {
      const std::string problem = rotation_problem(*b.rotation_matrix, defaults, kinematic_coordinates);
      if (!problem.empty()) throw ModelError(b.where, "body '" + b.name + "': the rotation matrix " + problem);
    }
    if (m == 0 && !inertia_is_zero(b.inertia, defaults))
      throw ModelError(b.where, "body '" + b.name +
                                    "' has zero mass but a nonzero inertia tensor (give it a mass, "
                                    "or omit both for a massless frame)");
  }
}

// Checks each marker's body, the symbols of its position and rotation, and that the rotation is one.
void check_markers(const std::vector<Marker>& markers, const std::map<std::string, int>& body_index,
                   const std::set<std::string>& world_marker, const std::set<std::string>& parameters_only,
                   const std::vector<Coordinate>& kinematic_coordinates, const GiNaC::exmap& defaults) {
  for (const auto& m : markers) {
    if (m.body != kWorld && !body_index.count(m.body))
      throw ModelError(m.where, "marker '" + m.name + "' is on an unknown body '" + m.body + "'");
    const std::set<std::string>& marker_scope = m.body == kWorld ? world_marker : parameters_only;
    for (const auto& x : m.position) check_expr(x, m.where, "a marker position", marker_scope);
    for (const auto& row : m.rotation)
      for (const auto& x : row) check_expr(x, m.where, "a marker rotation", marker_scope);
    const std::string problem = rotation_problem(m.rotation, defaults, kinematic_coordinates);
    if (!problem.empty()) throw ModelError(m.where, "marker '" + m.name + "': the rotation " + problem);
  }
}

// Checks the force elements' markers, coordinates and symbols, and that no rest length is negative.
void check_force_elements(const Model& model, const std::set<std::string>& known,
                          const std::set<std::string>& parameters_only, const GiNaC::exmap& defaults) {
  for (const auto& s : model.springs()) {
    check_marker(model, s.marker_a, s.where, "spring '" + s.name + "'");
    check_marker(model, s.marker_b, s.where, "spring '" + s.name + "'");
    check_expr(s.stiffness, s.where, "a spring stiffness", parameters_only);
    check_expr(s.rest_length, s.where, "a rest length", parameters_only);
    bool ok = false;
    if (const double L0 = numeric_value(s.rest_length, defaults, ok); ok && L0 < 0)
      throw ModelError(s.where, "spring '" + s.name + "' has a negative rest length (" +
                                    detail::checked_subs_impl::describe(GiNaC::numeric(L0)) + " m)");
  }
  for (const auto& d : model.dampers()) {
    check_marker(model, d.marker_a, d.where, "damper '" + d.name + "'");
    check_marker(model, d.marker_b, d.where, "damper '" + d.name + "'");
    check_expr(d.damping, d.where, "a damping coefficient", parameters_only);
  }
  for (const auto& b : model.bushings()) {
    check_marker(model, b.marker_a, b.where, "bushing '" + b.name + "'");
    check_marker(model, b.marker_b, b.where, "bushing '" + b.name + "'");
    for (const Vec3* v : {&b.k_translation, &b.k_rotation, &b.d_translation, &b.d_rotation})
      for (const auto& x : *v) check_expr(x, b.where, "a bushing coefficient", parameters_only);
  }
  for (const auto& g : model.generalized_forces()) {
    if (model.coordinate_index(g.coordinate) < 0)
      throw ModelError(g.where, "generalized force '" + g.name + "' names an unknown coordinate '" +
                                    g.coordinate + "'");
    check_expr(g.value, g.where, "a generalized force", known);
  }
  for (const auto& f : model.applied_forces()) {
    check_marker(model, f.marker, f.where, "force '" + f.name + "'");
    for (const auto& x : f.force) check_expr(x, f.where, "a force", known);
    for (const auto& x : f.torque) check_expr(x, f.where, "a torque", known);
  }
  for (const auto& g : model.gravity())
    for (const auto& x : g.g) check_expr(x, g.where, "gravity", parameters_only);
}

// Checks that the operating point names coordinates and depends on parameters only.
void check_operating_point_values(const Model& model, const std::set<std::string>& parameters_only) {
  const LinearizationPoint& op = model.operating_point();
  for (const auto& [name, value] : op.position) {
    if (model.coordinate_index(name) < 0)
      throw ModelError(op.where, "operating point names an unknown coordinate '" + name + "'");
    check_expr(value, op.where, "an operating point", parameters_only);
  }
  for (const auto& [name, value] : op.velocity) {
    if (model.coordinate_index(name) < 0)
      throw ModelError(op.where, "operating point names an unknown coordinate '" + name + "'");
    check_expr(value, op.where, "an operating point", parameters_only);
  }
}

}  // namespace

void Model::validate() const {
  std::set<std::string> known;
  for (const auto& [name, sym] : symtab_) known.insert(name);
  // Parameters and coordinates (no rates, no inputs); parameters only.
  const std::set<std::string> position_only = symbol_names(true), parameters_only = symbol_names(false);
  // Where motion inputs may appear: the kinematics of bodies and of markers on the world.
  std::set<std::string> kinematic = position_only, world_marker = parameters_only;
  std::vector<Coordinate> kinematic_coordinates = coordinates_;
  for (std::size_t i = 0; i < inputs_.size(); ++i)
    if (inputs_[i].motion) {
      kinematic.insert(inputs_[i].name);
      world_marker.insert(inputs_[i].name);
      kinematic_coordinates.push_back({inputs_[i].name, "", input_symbols_[i], inputs_[i].rate, inputs_[i].where});
    }

  GiNaC::exmap defaults, exact_defaults;
  for (const auto& p : parameters_) defaults[p.symbol] = GiNaC::numeric(p.value);
  for (const auto& p : parameters_) exact_defaults[p.symbol] = exact_rational(p.value);

  check_bodies(bodies_, body_index_, kinematic, parameters_only, kinematic_coordinates, defaults, exact_defaults);
  check_markers(markers_, body_index_, world_marker, parameters_only, kinematic_coordinates, defaults);
  check_force_elements(*this, known, parameters_only, defaults);
  for (const auto& o : outputs_) {
    switch (o.kind) {
      case OutputKind::position:
      case OutputKind::velocity:
        check_marker(*this, o.marker, o.where, "output '" + o.name + "'");
        if (!o.relative_to.empty()) check_marker(*this, o.relative_to, o.where, "output '" + o.name + "'");
        for (const auto& x : o.direction) check_expr(x, o.where, "an output direction", parameters_only);
        break;
      case OutputKind::coordinate:
      case OutputKind::rate:
        if (coordinate_index(o.coordinate) < 0)
          throw ModelError(o.where, "output '" + o.name + "' names an unknown coordinate '" +
                                        o.coordinate + "'");
        break;
      case OutputKind::expression: {
        std::set<std::string> allowed = known;
        for (const auto& i : inputs_) allowed.erase(i.name), allowed.erase(i.motion ? i.name + "_dot" : "");
        check_expr(o.expression, o.where, "an output expression", allowed);
        break;
      }
      case OutputKind::reaction: {
        bool joint = body_index_.count(o.reaction_of) > 0, constraint = false;
        for (const auto& c : constraints_) constraint = constraint || c.name == o.reaction_of;
        if (!joint && !constraint)
          throw ModelError(o.where, "output '" + o.name + "' names '" + o.reaction_of +
                                        "', which is neither a body (its joint) nor a constraint of this model");
        if (!o.frame_marker.empty()) check_marker(*this, o.frame_marker, o.where, "output '" + o.name + "'");
        for (const auto& x : o.direction) check_expr(x, o.where, "an output direction", parameters_only);
        break;
      }
      case OutputKind::force:
        validate_force_output(o);
        for (const auto& x : o.direction) check_expr(x, o.where, "an output direction", parameters_only);
        break;
    }
  }
  validate_constraints(defaults);
  validate_velocity_constraints();
  validate_motion_inputs();
  check_operating_point_values(*this, parameters_only);
  if (coordinates_.empty()) throw ModelError({}, "model '" + name_ + "' has no coordinates");
  for (const auto& s : scenes_) check_scene(*this, s);
  detail::check_derivatives_at_operating_point(*this, exact_defaults);
  detail::check_force_directions(*this, exact_defaults);
}

const char* to_string(PhysicalCheck::Kind kind) {
  switch (kind) {
    case PhysicalCheck::Kind::positive: return "positive";
    case PhysicalCheck::Kind::nonnegative: return "nonnegative";
    case PhysicalCheck::Kind::body: return "body";
  }
  return "";
}

std::vector<PhysicalCheck> Model::physical_checks() const {
  std::vector<PhysicalCheck> checks;
  // A check of `values` when they depend on a parameter, naming those in the model's order.
  auto add = [&](PhysicalCheck::Kind kind, std::string label, std::string unit, std::vector<GiNaC::ex> values) {
    std::set<std::string> symbols;
    for (const auto& v : values) collect_symbols(v, symbols);
    PhysicalCheck c{kind, std::move(label), std::move(unit), {}, std::move(values)};
    for (const auto& p : parameters_)
      if (symbols.count(p.name)) c.parameters.push_back(p.name);
    if (!c.parameters.empty()) checks.push_back(std::move(c));
  };
  for (const auto& b : bodies_) {
    const Mat3& I = b.inertia;
    add(PhysicalCheck::Kind::body, "body '" + b.name + "'", "",
        {b.mass, I[0][0], I[1][1], I[2][2], I[0][1], I[0][2], I[1][2]});
  }
  for (const auto& c : constraints_) {
    if (c.kind == ConstraintKind::distance)
      add(PhysicalCheck::Kind::positive, "the length of distance constraint '" + c.name + "'", "m", {c.length});
    if (c.kind == ConstraintKind::rolling)
      add(PhysicalCheck::Kind::positive, "the wheel radius of rolling constraint '" + c.name + "'", "m", {c.length});
  }
  for (const auto& s : springs_)
    add(PhysicalCheck::Kind::nonnegative, "the rest length of spring '" + s.name + "'", "m", {s.rest_length});
  return checks;
}

}  // namespace mbsgen
