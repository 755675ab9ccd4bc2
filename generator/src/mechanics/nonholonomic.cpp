#include "mbsgen/generator/mechanics/nonholonomic.hpp"

#include "mbsgen/generator/mechanics/dynamics.hpp"

#include "mechanics/constraint_matrices.hpp"
#include "mechanics/pivoting.hpp"
#include "symbolic/point_evaluator.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

namespace mbsgen {

using Eigen::MatrixXd;
using GiNaC::ex;
using namespace detail;  // constraint_matrices.hpp


// ---------------------------------------------------------------------------------------------
// Rolling wheels

RollingGeometry rolling_geometry(const Model& model, Program& prog, const Kinematics& kin, const Constraint& c) {
  RollingGeometry g;
  g.centre = kin.marker_position(model, prog, c.marker_a);
  const Mat3 S = kin.marker_frame(model, prog, c.marker_a);
  for (int i = 0; i < 3; ++i) g.axle[i] = S[i][c.axis];
  g.normal = c.normal;
  const ex s = prog.define(dot(g.normal, g.axle));
  const ex w = prog.define(GiNaC::sqrt(1 - s * s));  // |n × a| = cos(lean): 1 upright
  // n·C = r |n × a| squared, so that no square root enters the holonomic condition (a model
  // whose coordinates keep the wheel on the ground then has Φ ≡ 0, proved and dropped);
  // divided by 2r to keep the size of a length (the gradient is that of n·C upright).
  const ex h = prog.define(dot(g.normal, g.centre));
  g.height = prog.define((h * h - c.length * c.length * (1 - s * s)) / (2 * c.length));
  g.offset = define(prog, scale(-c.length / w, sub(g.normal, scale(s, g.axle))));
  return g;
}

namespace {

// Two orthonormal directions of the ground plane: t1 = (e_k × n)/|e_k × n| with e_k the world
// axis least aligned with n, t2 = n × t1 (exact for a normal along a world axis).
std::pair<Vec3, Vec3> ground_tangents(const Vec3& n) {
  int k = 0;
  double least = 2;
  for (int i = 0; i < 3; ++i) {
    const double v = std::abs(GiNaC::ex_to<GiNaC::numeric>(n[i].evalf()).to_double());
    if (v < least) least = v, k = i;
  }
  Vec3 e = {0, 0, 0};
  e[k] = 1;
  const Vec3 c = cross(e, n);
  const ex norm = GiNaC::sqrt(dot(c, c).expand());
  const Vec3 t1 = {(c[0] / norm).normal(), (c[1] / norm).normal(), (c[2] / norm).normal()};
  const Vec3 t2 = cross(n, t1);
  return {t1, {t2[0].expand(), t2[1].expand(), t2[2].expand()}};
}

std::vector<VelocityEquation> velocity_equations(const Model& model, Equations& eq) {
  Program& prog = eq.program;
  const Kinematics& kin = eq.kinematics;
  std::vector<VelocityEquation> out;
  for (const auto& c : model.constraints()) {
    if (c.kind != ConstraintKind::rolling) continue;
    // The wheel's material point at the contact has v_P = v_C + ω × (P − C) = 0 along the ground.
    const RollingGeometry g = rolling_geometry(model, prog, kin, c);
    const Vec3 vP = add(kin.marker_velocity(model, prog, c.marker_a),
                        cross(kin.marker_angular_velocity(model, c.marker_a), g.offset));
    const auto [t1, t2] = ground_tangents(c.normal);
    out.push_back({c.name, "t1", prog.define(dot(t1, vP))});
    out.push_back({c.name, "t2", prog.define(dot(t2, vP))});
  }
  for (const auto& v : model.velocity_constraints()) out.push_back({v.name, "", prog.define(v.expression)});
  return out;
}

const SourceLocation& where_of(const Model& model, const std::string& name) {
  for (const auto& c : model.constraints())
    if (c.name == name) return c.where;
  for (const auto& v : model.velocity_constraints())
    if (v.name == name) return v.where;
  return model.operating_point().where;
}

// The dependent speeds (positions in the independent coordinates): listed, or chosen by pivoted
// QR of B = A T at the operating point.
std::vector<std::size_t> choose_dependent_speeds(const Model& model, const std::vector<std::size_t>& indep,
                                                 const MatrixXd& B, Nonholonomic& nh) {
  const std::size_t m = static_cast<std::size_t>(B.rows()), f = indep.size();
  Eigen::ColPivHouseholderQR<MatrixXd> qr(B);
  qr.setThreshold(1e-10);
  if (static_cast<std::size_t>(qr.rank()) < m)
    throw ModelError(where_of(model, nh.equations.front().constraint),
                     "the nonholonomic constraints are not independent at the operating point (rank " +
                         std::to_string(qr.rank()) + " of " + std::to_string(m) + " equations)");
  if (m >= f)
    throw ModelError(where_of(model, nh.equations.front().constraint),
                     "the nonholonomic constraints leave no independent speed: " + std::to_string(m) +
                         " equations in " + std::to_string(f) + " rates");
  const std::vector<std::size_t> suggested = pivoted_qr_columns(B);
  const auto& listed = model.independent_speeds();
  nh.chosen = listed.empty();
  if (nh.chosen) return suggested;
  std::vector<std::size_t> dependent;
  std::set<std::size_t> speeds;
  for (const auto& item : listed) {
    const auto k = static_cast<std::size_t>(model.coordinate_index(item.name));
    if (!std::binary_search(indep.begin(), indep.end(), k))
      throw ModelError(item.where, "independent speed '" + item.name +
                                       "' is the rate of a dependent coordinate of the loops; list independent ones");
    speeds.insert(position_in(indep, k));
  }
  if (speeds.size() != f - m)
    throw ModelError(listed.front().where, "the nonholonomic constraints leave " + std::to_string(f - m) +
                                               " independent speeds; " + std::to_string(speeds.size()) + " are listed");
  for (std::size_t j = 0; j < f; ++j)
    if (!speeds.count(j)) dependent.push_back(j);
  MatrixXd Bd(B.rows(), static_cast<Eigen::Index>(m));
  for (std::size_t d = 0; d < m; ++d) Bd.col(static_cast<Eigen::Index>(d)) = B.col(static_cast<Eigen::Index>(dependent[d]));
  Eigen::ColPivHouseholderQR<MatrixXd> qd(Bd);
  qd.setThreshold(1e-10);
  if (static_cast<std::size_t>(qd.rank()) < m) {
    std::vector<std::size_t> names_d, names_s;
    for (std::size_t j : dependent) names_d.push_back(indep[j]);
    for (std::size_t j = 0; j < f; ++j)
      if (!std::binary_search(suggested.begin(), suggested.end(), j)) names_s.push_back(indep[j]);
    throw ModelError(listed.front().where, "the rates of " + coordinate_names(model, names_d) +
                                               " cannot be found from the listed independent speeds at the operating "
                                               "point (the constraints are singular in them); independent speeds that "
                                               "work: " + coordinate_names(model, names_s));
  }
  return dependent;
}

// The operating point's rates satisfy the constraints: the dependent speeds' given rates (0 when
// not given) equal what the constraints make of the independent ones.
void check_rates(const Model& model, Equations& eq, const std::vector<std::size_t>& indep, const MatrixXd& B,
                 const Nonholonomic& nh) {
  const GiNaC::exmap at = defaults_at_operating_point(model, eq);
  const auto m = static_cast<Eigen::Index>(nh.dependent_speeds.size());
  Eigen::VectorXd rates(static_cast<Eigen::Index>(indep.size()));
  for (std::size_t j = 0; j < indep.size(); ++j)
    rates(static_cast<Eigen::Index>(j)) = GiNaC::ex_to<GiNaC::numeric>(at.at(eq.yd[indep[j]]).evalf()).to_double();
  const std::vector<double> a = at_defaults(model, eq, nh.a);
  Eigen::VectorXd rhs = -Eigen::Map<const Eigen::VectorXd>(a.data(), m);
  MatrixXd Bd(m, m);
  for (Eigen::Index d = 0; d < m; ++d) {
    const std::size_t j = position_in(indep, nh.dependent_speeds[static_cast<std::size_t>(d)]);
    Bd.col(d) = B.col(static_cast<Eigen::Index>(j));
    rates(static_cast<Eigen::Index>(j)) = 0;
  }
  rhs -= B * rates;
  const Eigen::VectorXd expected = Bd.colPivHouseholderQr().solve(rhs);
  const double size = std::max(1.0, rates.cwiseAbs().maxCoeff());
  for (Eigen::Index d = 0; d < m; ++d) {
    const std::size_t k = nh.dependent_speeds[static_cast<std::size_t>(d)];
    const double given = GiNaC::ex_to<GiNaC::numeric>(at.at(eq.yd[k]).evalf()).to_double();
    if (!(std::abs(given - expected(d)) <= 1e-9 * size))
      throw ModelError(model.operating_point().where,
                       "the operating point's rates violate the nonholonomic constraints: the rate of '" +
                           model.coordinates()[k].name + "' is " + format(given) + " but the constraints make it " +
                           format(expected(d)) + " with the default parameter values (give it as an expression in "
                           "the parameters under operating_point: velocity)");
  }
}

}  // namespace

Nonholonomic nonholonomic_constraints(const Model& model, Equations& eq) {
  Nonholonomic nh;
  if (!model.nonholonomic()) return nh;
  nh.active = true;
  Program& prog = eq.program;
  const std::size_t n = eq.y.size();
  nh.equations = velocity_equations(model, eq);
  const std::size_t m = nh.equations.size();
  GiNaC::exmap rest;
  for (const auto& s : eq.yd) rest[s] = 0;
  Program::Substitution at_rest(rest);
  nh.A = zeros(m, n);
  for (std::size_t k = 0; k < m; ++k) {
    for (std::size_t j = 0; j < n; ++j) nh.A[k][j] = prog.diff(nh.equations[k].value, eq.yd[j]);
    nh.a.push_back(prog.define(prog.substitute(nh.equations[k].value, at_rest)));
  }
  const std::vector<std::size_t> indep = independent_coordinates(eq);
  const ExMatrix B = product(prog, nh.A, tangent_map(eq));
  const MatrixXd Bn = numbers(model, eq, B);
  const std::vector<std::size_t> dependent = choose_dependent_speeds(model, indep, Bn, nh);
  for (std::size_t j = 0; j < indep.size(); ++j)
    (std::binary_search(dependent.begin(), dependent.end(), j) ? nh.dependent_speeds : nh.speeds).push_back(indep[j]);
  check_rates(model, eq, indep, Bn, nh);
  ExMatrix Bd = zeros(m, dependent.size());
  MatrixXd Bd_num(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(dependent.size()));
  for (std::size_t k = 0; k < m; ++k)
    for (std::size_t d = 0; d < dependent.size(); ++d) {
      Bd[k][d] = B[k][dependent[d]];
      Bd_num(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(d)) = Bn(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(dependent[d]));
    }
  nh.lu = SymbolicLU::factor(prog, Bd, partial_pivoting_rows(Bd_num));
  return nh;
}

}  // namespace mbsgen
