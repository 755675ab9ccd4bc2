#include "mbsgen/generator/mechanics/loop_closure.hpp"

#include "mbsgen/generator/mechanics/dynamics.hpp"

#include "mechanics/pivoting.hpp"
#include "symbolic/point_evaluator.hpp"
#include "symbolic/zero_proof.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

namespace mbsgen {

using GiNaC::ex;

namespace {

using Eigen::MatrixXd;

std::string format(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

Vec3 column(const Mat3& A, int c) { return {A[0][c], A[1][c], A[2][c]}; }

// ---------------------------------------------------------------------------------------------
// The equations of one constraint (model.hpp, ConstraintKind), each with the squared size of
// the positions it compares (for the residual check of the operating point).
struct RawEquation {
  ConstraintEquation equation;
  ex size2;  // |r_a|² + |r_b|² (+ L²) for positional equations, 1 otherwise
};

std::vector<RawEquation> equations_of(const Model& model, Program& prog, const Kinematics& kin, const Constraint& c) {
  std::vector<RawEquation> out;
  ex size2 = 1;
  auto add = [&](const char* component, const ex& phi, bool positional) {
    out.push_back({{c.name, component, prog.define(phi), 1}, positional ? size2 : ex(1)});
  };
  if (c.kind == ConstraintKind::expression) {
    add("", c.expression, false);
    return out;
  }
  if (c.kind == ConstraintKind::rolling) {  // the wheel touches the ground (nonholonomic.hpp)
    const RollingGeometry g = rolling_geometry(model, prog, kin, c);
    size2 = prog.define(dot(g.centre, g.centre) + c.length * c.length);
    add("height", g.height, true);
    return out;
  }
  const Vec3 ra = kin.marker_position(model, prog, c.marker_a), rb = kin.marker_position(model, prog, c.marker_b);
  const Mat3 Sa = kin.marker_frame(model, prog, c.marker_a), Sb = kin.marker_frame(model, prog, c.marker_b);
  const Vec3 d = sub(rb, ra);
  const Vec3 xa = column(Sa, 0), ya = column(Sa, 1), za = column(Sa, 2);
  const Vec3 xb = column(Sb, 0), yb = column(Sb, 1), zb = column(Sb, 2);
  size2 = prog.define(dot(ra, ra) + dot(rb, rb) +
                      (c.kind == ConstraintKind::distance ? c.length * c.length : ex(0)));
  // With R = S_aᵀ S_b ≈ E + [θ]×, the relative rotation about a's axes is θ_x = z_a·y_b,
  // θ_y = x_a·z_b, θ_z = y_a·x_b (and −y_a·z_b = θ_x to first order).
  switch (c.kind) {
    case ConstraintKind::spherical:
    case ConstraintKind::revolute:
      add("x", d[0], true), add("y", d[1], true), add("z", d[2], true);
      if (c.kind == ConstraintKind::revolute) add("rx", -dot(ya, zb), false), add("ry", dot(xa, zb), false);
      break;
    case ConstraintKind::prismatic:
      add("x", dot(d, xa), true), add("y", dot(d, ya), true);
      add("rx", dot(za, yb), false), add("ry", dot(xa, zb), false), add("rz", dot(ya, xb), false);
      break;
    case ConstraintKind::planar:
      add("z", dot(d, za), true), add("rx", -dot(ya, zb), false), add("ry", dot(xa, zb), false);
      break;
    case ConstraintKind::distance:
      add("length", (dot(d, d) - c.length * c.length) / (2 * c.length), true);
      break;
    case ConstraintKind::expression:
    case ConstraintKind::rolling:
      break;
  }
  return out;
}

std::string describe(const ConstraintEquation& e) {
  return "'" + e.constraint + "'" + (e.component.empty() ? "" : " (" + e.component + ")");
}

const Constraint& constraint_named(const Model& model, const std::string& name) {
  for (const auto& c : model.constraints())
    if (c.name == name) return c;
  throw std::logic_error("close_loops: unknown constraint " + name);
}

// ---------------------------------------------------------------------------------------------
// Numbers at a point: the equations, their sizes and the Jacobian, in 50 digits.
struct Numbers {
  std::vector<double> phi, size;
  MatrixXd J;
};

Numbers evaluate(Equations& eq, const std::vector<RawEquation>& raw, const ExMatrix& Phi_y,
                 const GiNaC::exmap& point) {
  const std::size_t m = raw.size(), n = eq.y.size();
  std::vector<ex> entries;
  for (const auto& r : raw) entries.push_back(r.equation.phi);
  for (const auto& r : raw) entries.push_back(r.size2);
  for (std::size_t k = 0; k < m; ++k)
    for (std::size_t j = 0; j < n; ++j) entries.push_back(Phi_y[k][j]);
  const long digits = GiNaC::Digits;
  GiNaC::Digits = detail::PointEvaluator::kDigits;
  std::vector<GiNaC::numeric> v;
  try {
    v = detail::PointEvaluator(eq.program, point).evaluate(entries);
  } catch (...) {
    GiNaC::Digits = digits;
    throw;
  }
  GiNaC::Digits = digits;
  auto real = [](const GiNaC::numeric& x) {
    if (!x.is_real()) throw std::runtime_error("a complex value");
    const double d = x.to_double();
    if (!std::isfinite(d)) throw std::runtime_error("a value beyond the range of double");
    return d;
  };
  Numbers out;
  out.J.resize(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(n));
  for (std::size_t k = 0; k < m; ++k) {
    out.phi.push_back(real(v[k]));
    out.size.push_back(std::sqrt(std::abs(real(v[m + k]))));
    for (std::size_t j = 0; j < n; ++j)
      out.J(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j)) = real(v[2 * m + k * n + j]);
  }
  return out;
}

// The operating point with the default parameter values (a `given` point, or an equilibrium's
// initial guess).
GiNaC::exmap operating_point_values(const Model& model, const Equations& eq) {
  GiNaC::exmap p, values;
  for (std::size_t k = 0; k < eq.p.size(); ++k) p[eq.p[k]] = GiNaC::numeric(model.parameters()[k].value);
  values = p;
  const LinearizationPoint& op = model.operating_point();
  for (std::size_t k = 0; k < eq.y.size(); ++k) {
    auto it = op.position.find(model.coordinates()[k].name);
    values[eq.y[k]] = it == op.position.end() ? ex(0) : GiNaC::evalf(it->second.subs(p, GiNaC::subs_options::no_pattern));
  }
  return values;
}

// ---------------------------------------------------------------------------------------------
// Rank: a pivot below 1e-10 of the largest is zero. Equations are well scaled (lengths, unit
// vectors), so 1e-10 is far above rounding (1e-16) and far below a real mechanism's pivots.
constexpr double kRankTolerance = 1e-10;

Eigen::Index rank_of(const MatrixXd& J) {
  if (J.size() == 0) return 0;
  Eigen::ColPivHouseholderQR<MatrixXd> qr(J);
  qr.setThreshold(kRankTolerance);
  return qr.rank();
}

// The equations (rows of J) involved in a dependency (a left null vector of J), and the
// coordinates they depend on.
std::string dependency(const Model& model, Equations& eq, const std::vector<RawEquation>& raw, const MatrixXd& J) {
  Eigen::FullPivLU<MatrixXd> lu(J.transpose());
  lu.setThreshold(kRankTolerance);
  const MatrixXd W = lu.kernel();
  const double wmax = W.cwiseAbs().maxCoeff();
  std::string eqs, coords;
  std::set<std::size_t> columns;
  for (Eigen::Index k = 0; k < J.rows(); ++k) {
    if (W.row(k).cwiseAbs().maxCoeff() <= 1e-8 * wmax) continue;
    const ConstraintEquation& e = raw[static_cast<std::size_t>(k)].equation;
    eqs += (eqs.empty() ? "" : ", ") + describe(e);
    for (std::size_t j = 0; j < eq.y.size(); ++j)
      if (eq.program.depends_on(e.phi, eq.y[j])) columns.insert(j);
  }
  for (std::size_t j : columns) coords += (coords.empty() ? "" : ", ") + model.coordinates()[j].name;
  return "the gradients of the equations " + eqs + " (in the coordinates " + coords +
         ") are linearly dependent (or zero)";
}

// A double as an exact rational (so that it does not lower the precision of 50-digit floats).
GiNaC::numeric exact(double x) {
  int e = 0;
  const double m = std::frexp(x, &e);
  const auto mantissa = static_cast<long long>(std::ldexp(m, 53));
  return GiNaC::numeric(mantissa) * GiNaC::numeric(2).power(e - 53);
}

// A dependent equation may be dropped only where it holds: within this fraction of its size (a
// length, or 1), the tolerance of a `given` operating point's closure (check_closure). Where the
// equations kept hold to rounding (1e-15 of their size, after the projection below), a truly
// redundant equation holds to rounding too; a contradiction (a pin and a rod of nonzero length)
// leaves a residual of the mechanism's own size.
constexpr double kConsistencyTolerance = 1e-8;

// Moves `point` onto the equations kept (keep[k]) by minimum-norm Gauss–Newton steps in all the
// coordinates (evaluations in 50 digits, steps in double); true when they close to 1e-12 of
// their sizes, with the values there in `at`. False when it does not converge (a pseudo-random
// start far from the constraint manifold) or the equations cannot be evaluated on the way.
bool project(Equations& eq, const std::vector<RawEquation>& raw, const ExMatrix& Phi_y, const std::vector<char>& keep,
             GiNaC::exmap& point, Numbers& at) {
  std::vector<Eigen::Index> rows;
  for (std::size_t k = 0; k < raw.size(); ++k)
    if (keep[k]) rows.push_back(static_cast<Eigen::Index>(k));
  try {
    for (int iteration = 0; iteration < 30; ++iteration) {
      at = evaluate(eq, raw, Phi_y, point);
      MatrixXd J(static_cast<Eigen::Index>(rows.size()), at.J.cols());
      Eigen::VectorXd phi(static_cast<Eigen::Index>(rows.size()));
      bool closed = true;
      for (std::size_t i = 0; i < rows.size(); ++i) {
        const auto k = static_cast<std::size_t>(rows[i]);
        J.row(static_cast<Eigen::Index>(i)) = at.J.row(rows[i]);
        phi(static_cast<Eigen::Index>(i)) = at.phi[k];
        closed = closed && std::abs(at.phi[k]) <= 1e-12 * std::max(at.size[k], 1e-300);
      }
      if (closed) return true;
      const Eigen::VectorXd dy = J.completeOrthogonalDecomposition().solve(phi);
      if (!dy.allFinite()) return false;
      for (std::size_t j = 0; j < eq.y.size(); ++j)
        point[eq.y[j]] = point[eq.y[j]] - exact(dy(static_cast<Eigen::Index>(j)));
    }
  } catch (const std::runtime_error&) {
    return false;
  }
  return false;
}

// The kept equations that dropped equation k depends on: the rows of a least-squares
// combination of the kept gradients that gives k's gradient at the point of J (pseudo-random:
// at a closed point a contradicting rod's gradient vanishes).
std::string partners(const std::vector<RawEquation>& raw, const std::vector<char>& keep, const MatrixXd& J, std::size_t k) {
  std::vector<Eigen::Index> rows;
  for (std::size_t i = 0; i < raw.size(); ++i)
    if (keep[i]) rows.push_back(static_cast<Eigen::Index>(i));
  MatrixXd A(J.cols(), static_cast<Eigen::Index>(rows.size()));
  for (std::size_t i = 0; i < rows.size(); ++i) A.col(static_cast<Eigen::Index>(i)) = J.row(rows[i]).transpose();
  const Eigen::VectorXd c = A.completeOrthogonalDecomposition().solve(J.row(static_cast<Eigen::Index>(k)).transpose());
  const double cmax = c.size() ? c.cwiseAbs().maxCoeff() : 0.0;
  std::string out;
  for (std::size_t i = 0; i < rows.size(); ++i)
    if (cmax > 0 && std::abs(c(static_cast<Eigen::Index>(i))) > 1e-8 * cmax)
      out += (out.empty() ? "" : ", ") + describe(raw[static_cast<std::size_t>(rows[i])].equation);
  return out;
}

// Throws unless each dropped equation holds at `at` (a point where the kept ones hold).
void check_consistent(const Model& model, const std::vector<RawEquation>& raw, const std::vector<char>& keep,
                      const MatrixXd& J_random, const Numbers& at, const std::string& where_text) {
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const double tol = kConsistencyTolerance * at.size[k];
    if (keep[k] || std::abs(at.phi[k]) <= tol) continue;
    const bool positional = raw[k].size2 != 1;
    const Constraint& c = constraint_named(model, raw[k].equation.constraint);
    const std::string with = partners(raw, keep, J_random, k);
    throw ModelError(c.where, "constraint " + describe(raw[k].equation) +
                                  (with.empty() ? " cannot hold: its gradient vanishes in every configuration"
                                                : " contradicts " + with + ": its gradient depends on theirs in every "
                                                  "configuration, but where they hold it does not") +
                                  " (residual " + format(at.phi[k]) + (positional ? " m" : "") + " " + where_text +
                                  ", tolerance " + format(tol) + (positional ? " m" : "") +
                                  "); the constraints cannot hold together: remove or correct one");
  }
}

// Drops equations that are redundant for every configuration (the rank is deficient at a
// pseudo-random point as well) and hold where the others do (at the operating point closed onto
// the equations kept, and at two pseudo-random points, parameters included, closed the same
// way); a dependent equation that does not hold there is an error naming the constraints and the
// residual. A rank deficiency at the operating point only is a singular position, an error. An
// equation whose gradient is identically zero is dropped as identically satisfied (its reaction
// is zero, unique); the others make the reaction forces not unique.
void drop_redundant(const Model& model, Equations& eq, std::vector<RawEquation>& raw, ExMatrix& Phi_y,
                    const Numbers& at_op, LoopClosure& loops) {
  const Eigen::Index rank = rank_of(at_op.J);
  if (rank == static_cast<Eigen::Index>(raw.size())) return;
  std::uint64_t state = 0x5851f42d4c957f2dULL;
  GiNaC::exmap random = detail::random_point({&eq.y, &eq.yd, &eq.u, &eq.p}, state);
  const Numbers elsewhere = evaluate(eq, raw, Phi_y, random);
  const std::string what = dependency(model, eq, raw, at_op.J);
  const Constraint& first = constraint_named(model, raw.front().equation.constraint);
  if (rank_of(elsewhere.J) > rank)
    throw ModelError(model.operating_point().where.line ? model.operating_point().where : first.where,
                     "the constraint Jacobian is singular at the operating point: " + what +
                         " there. This is a singular position (a dead point or a locked "
                         "mechanism), or constraints redundant on the motion; the dependent coordinates "
                         "cannot be found from independent ones there, and the reaction forces would not "
                         "be unique");
  // Keep a maximal independent set of rows: the pivot columns of Jᵀ.
  Eigen::ColPivHouseholderQR<MatrixXd> qr(at_op.J.transpose());
  qr.setThreshold(kRankTolerance);
  std::vector<char> keep(raw.size(), 0);
  for (Eigen::Index i = 0; i < rank; ++i) keep[static_cast<std::size_t>(qr.colsPermutation().indices()(i))] = 1;
  // The dropped equations must hold where the kept ones do.
  GiNaC::exmap point = operating_point_values(model, eq);
  Numbers at;
  if (!project(eq, raw, Phi_y, keep, point, at))
    throw ModelError(model.operating_point().where.line ? model.operating_point().where : first.where,
                     "the constraints cannot be closed near the operating point with the default parameter values "
                     "(Newton's method on " + what + " does not converge)");
  check_consistent(model, raw, keep, elsewhere.J, at, "at the operating point closed onto the others");
  for (int sample = 0; sample < 2; ++sample) {
    GiNaC::exmap p = sample == 0 ? random : detail::random_point({&eq.y, &eq.yd, &eq.u, &eq.p}, state);
    if (project(eq, raw, Phi_y, keep, p, at))
      check_consistent(model, raw, keep, elsewhere.J, at,
                       "at a pseudo-random configuration and pseudo-random parameter values: with the defaults "
                       "they hold together, with others they do not");
  }
  std::vector<RawEquation> kept;
  ExMatrix kept_J;
  for (std::size_t k = 0; k < raw.size(); ++k) {
    if (keep[k]) {
      kept.push_back(raw[k]);
      kept_J.push_back(Phi_y[k]);
      continue;
    }
    const bool constant = all_proved_zero(eq.program, Phi_y[k].size(), [&](std::size_t j) { return Phi_y[k][j]; });
    if (constant) {
      loops.dropped.push_back({raw[k].equation, "identically satisfied (its gradient is zero and it holds at the "
                                                "operating point and at pseudo-random parameter values)"});
    } else {
      loops.dropped.push_back({raw[k].equation, "redundant in every configuration (" + what +
                                                    "); the reaction forces are not unique"});
      loops.redundant = true;
    }
  }
  raw = std::move(kept);
  Phi_y = std::move(kept_J);
}

// ---------------------------------------------------------------------------------------------
// The residual of a `given` operating point: each equation within 1e-8 of its size (a length, or
// 1 for directions and expressions), so that coordinates written with 9 digits close the loop;
// the kernels then refine the dependent coordinates to full precision by Newton's method.
void check_closure(const Model& model, const std::vector<RawEquation>& raw, const Numbers& at_op) {
  if (model.operating_point().kind != LinearizationPoint::Kind::given) return;
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const double tol = 1e-8 * at_op.size[k];
    if (std::abs(at_op.phi[k]) <= tol) continue;
    const bool positional = raw[k].size2 != 1;
    const Constraint& c = constraint_named(model, raw[k].equation.constraint);
    const SourceLocation& where = model.operating_point().where.line ? model.operating_point().where : c.where;
    throw ModelError(where, "the operating point does not close constraint " + describe(raw[k].equation) +
                                " (at " + c.where.str() + "): its residual is " + format(at_op.phi[k]) +
                                (positional ? " m" : "") + " with the default parameter values (tolerance " +
                                format(tol) + (positional ? " m" : "") +
                                "); give coordinates that satisfy the constraints (about 9 digits suffice: "
                                "the dependent coordinates are refined at run time)");
  }
}

// ---------------------------------------------------------------------------------------------
// The split into independent and dependent coordinates.
std::vector<std::size_t> qr_choice(const MatrixXd& J) { return pivoted_qr_columns(J); }

MatrixXd columns(const MatrixXd& J, const std::vector<std::size_t>& which) {
  MatrixXd A(J.rows(), static_cast<Eigen::Index>(which.size()));
  for (std::size_t j = 0; j < which.size(); ++j) A.col(static_cast<Eigen::Index>(j)) = J.col(static_cast<Eigen::Index>(which[j]));
  return A;
}

std::string names(const Model& model, const std::vector<std::size_t>& which) {
  std::string s;
  for (std::size_t k : which) s += (s.empty() ? "" : ", ") + model.coordinates()[k].name;
  return s;
}

void choose_coordinates(const Model& model, const MatrixXd& J, LoopClosure& loops) {
  const std::size_t n = static_cast<std::size_t>(J.cols()), m = static_cast<std::size_t>(J.rows());
  if (m >= n)
    throw ModelError(model.constraints().front().where,
                     "the constraints leave no degree of freedom: " + std::to_string(m) +
                         " independent equations in " + std::to_string(n) + " coordinates");
  const std::vector<std::size_t> suggested = qr_choice(J);
  std::vector<std::size_t> dependent = suggested;
  const auto& listed = model.independent_coordinates();
  loops.chosen = listed.empty();
  if (!listed.empty()) {
    std::set<std::size_t> indep;
    for (const auto& item : listed) indep.insert(static_cast<std::size_t>(model.coordinate_index(item.name)));
    if (indep.size() != n - m)
      throw ModelError(listed.front().where, "the constraints leave " + std::to_string(n - m) + " independent coordinate" +
                                                 (n - m == 1 ? "" : "s") + "; " + std::to_string(indep.size()) +
                                                 (indep.size() == 1 ? " is" : " are") + " listed");
    dependent.clear();
    for (std::size_t j = 0; j < n; ++j)
      if (!indep.count(j)) dependent.push_back(j);
    if (rank_of(columns(J, dependent)) < static_cast<Eigen::Index>(m)) {
      std::vector<std::size_t> suggested_indep;
      for (std::size_t j = 0; j < n; ++j)
        if (!std::binary_search(suggested.begin(), suggested.end(), j)) suggested_indep.push_back(j);
      throw ModelError(listed.front().where,
                       "the coordinates " + names(model, dependent) +
                           " cannot be found from the listed independent ones at the operating point (the "
                           "constraint Jacobian in them is singular there); independent coordinates that "
                           "work: " + names(model, suggested_indep));
    }
  }
  loops.dependent = dependent;
  for (std::size_t j = 0; j < n; ++j)
    if (!std::binary_search(dependent.begin(), dependent.end(), j)) loops.independent.push_back(j);
}

// The dependent coordinates at the operating point with the default parameter values, closed to
// 50 digits by Newton's method (evaluations in 50 digits, steps solved in double: each step
// gains about 15 digits), for the checks of `mbsgen check` (linear/operating_point_check.cpp).
GiNaC::exmap refine(const Model& model, Equations& eq, const std::vector<RawEquation>& raw, const ExMatrix& Phi_y,
                    const std::vector<std::size_t>& dependent) {
  const long digits = GiNaC::Digits;
  GiNaC::Digits = detail::PointEvaluator::kDigits;
  GiNaC::exmap point = operating_point_values(model, eq);
  GiNaC::Digits = digits;
  for (int iteration = 0; iteration < 5; ++iteration) {
    const Numbers v = evaluate(eq, raw, Phi_y, point);
    Eigen::VectorXd phi(static_cast<Eigen::Index>(raw.size()));
    for (std::size_t k = 0; k < raw.size(); ++k) phi(static_cast<Eigen::Index>(k)) = v.phi[k];
    const Eigen::VectorXd dx = columns(v.J, dependent).colPivHouseholderQr().solve(phi);
    for (std::size_t d = 0; d < dependent.size(); ++d) {
      const ex& y = eq.y[dependent[d]];
      point[y] = point[y] - exact(dx(static_cast<Eigen::Index>(d)));
    }
  }
  GiNaC::exmap out;
  for (std::size_t d : dependent) out[eq.y[d]] = point[eq.y[d]];
  return out;
}

}  // namespace

// -----------------------------------------------------------------------------------------------
std::vector<ConstraintEquation> constraint_equations(const Model& model, Program& program, const Kinematics& kin) {
  std::vector<ConstraintEquation> out;
  for (const auto& c : model.constraints())
    for (const auto& r : equations_of(model, program, kin, c)) out.push_back(r.equation);
  return out;
}

std::vector<std::size_t> partial_pivoting_rows(MatrixXd A) {
  const Eigen::Index m = A.rows();
  std::vector<std::size_t> rows(static_cast<std::size_t>(m));
  for (Eigen::Index i = 0; i < m; ++i) rows[static_cast<std::size_t>(i)] = static_cast<std::size_t>(i);
  for (Eigen::Index k = 0; k < m; ++k) {
    Eigen::Index p = k;
    for (Eigen::Index i = k + 1; i < m; ++i)
      if (std::abs(A(i, k)) > std::abs(A(p, k))) p = i;
    A.row(k).swap(A.row(p));
    std::swap(rows[static_cast<std::size_t>(k)], rows[static_cast<std::size_t>(p)]);
    for (Eigen::Index i = k + 1; i < m; ++i) A.row(i) -= A(i, k) / A(k, k) * A.row(k);
  }
  return rows;
}

std::vector<std::size_t> pivoted_qr_columns(const MatrixXd& J) {
  Eigen::ColPivHouseholderQR<MatrixXd> qr(J);
  std::vector<std::size_t> picked;
  for (Eigen::Index i = 0; i < qr.rank(); ++i) picked.push_back(static_cast<std::size_t>(qr.colsPermutation().indices()(i)));
  std::sort(picked.begin(), picked.end());
  return picked;
}

SymbolicLU SymbolicLU::factor(Program& prog, const ExMatrix& A, std::vector<std::size_t> rows) {
  const std::size_t m = A.size();
  SymbolicLU lu;
  lu.rows = std::move(rows);
  lu.L.assign(m, std::vector<ex>(m, 0));
  lu.U.assign(m, std::vector<ex>(m, 0));
  for (std::size_t i = 0; i < m; ++i) {
    lu.L[i][i] = 1;
    for (std::size_t j = 0; j < m; ++j) lu.U[i][j] = A[lu.rows[i]][j];
  }
  for (std::size_t k = 0; k < m; ++k)
    for (std::size_t i = k + 1; i < m; ++i) {
      if (lu.U[i][k].is_zero()) continue;
      const ex l = prog.define(lu.U[i][k] / lu.U[k][k]);
      lu.L[i][k] = l;
      for (std::size_t j = k + 1; j < m; ++j)
        if (!lu.U[k][j].is_zero()) lu.U[i][j] = prog.define(lu.U[i][j] - l * lu.U[k][j]);
      lu.U[i][k] = 0;
    }
  return lu;
}

std::vector<ex> SymbolicLU::solve(Program& prog, const std::vector<ex>& b) const {
  const std::size_t m = rows.size();
  std::vector<ex> z(m);
  for (std::size_t i = 0; i < m; ++i) {  // L z = P b
    ex s = b[rows[i]];
    for (std::size_t j = 0; j < i; ++j)
      if (!L[i][j].is_zero() && !z[j].is_zero()) s -= L[i][j] * z[j];
    z[i] = prog.define(s);
  }
  std::vector<ex> x(m);
  for (std::size_t i = m; i-- > 0;) {  // U x = z
    ex s = z[i];
    for (std::size_t j = i + 1; j < m; ++j)
      if (!U[i][j].is_zero() && !x[j].is_zero()) s -= U[i][j] * x[j];
    x[i] = prog.define(s / U[i][i]);
  }
  return x;
}

std::vector<ex> SymbolicLU::solve_transposed(Program& prog, const std::vector<ex>& b) const {
  const std::size_t m = rows.size();
  std::vector<ex> w(m);
  for (std::size_t i = 0; i < m; ++i) {  // Uᵀ w = b
    ex s = b[i];
    for (std::size_t j = 0; j < i; ++j)
      if (!U[j][i].is_zero() && !w[j].is_zero()) s -= U[j][i] * w[j];
    w[i] = prog.define(s / U[i][i]);
  }
  std::vector<ex> v(m);
  for (std::size_t i = m; i-- > 0;) {  // Lᵀ v = w
    ex s = w[i];
    for (std::size_t j = i + 1; j < m; ++j)
      if (!L[j][i].is_zero() && !v[j].is_zero()) s -= L[j][i] * v[j];
    v[i] = prog.define(s);
  }
  std::vector<ex> lambda(m);
  for (std::size_t i = 0; i < m; ++i) lambda[rows[i]] = v[i];  // λ = Pᵀ v
  return lambda;
}

std::vector<ex> LoopClosure::solve(Program& prog, const std::vector<ex>& b) const { return lu.solve(prog, b); }

std::vector<ex> LoopClosure::solve_transposed(Program& prog, const std::vector<ex>& b) const {
  return lu.solve_transposed(prog, b);
}

LoopClosure close_loops(const Model& model, Equations& eq) {
  LoopClosure loops;
  if (model.constraints().empty()) return loops;
  loops.active = true;
  Program& prog = eq.program;
  const std::size_t n = eq.y.size();

  std::vector<RawEquation> raw;
  for (const auto& c : model.constraints())
    for (auto& r : equations_of(model, prog, eq.kinematics, c)) {
      if (proved_zero(prog, r.equation.phi, /*bound_terms=*/false))
        loops.dropped.push_back({r.equation, "identically zero (the motion never violates it)"});
      else
        raw.push_back(std::move(r));
    }
  bool only_rolling = true;
  for (const auto& c : model.constraints()) only_rolling = only_rolling && c.kind == ConstraintKind::rolling;
  if (raw.empty() && only_rolling) {  // wheels whose contact the coordinates keep (a rolling disk)
    loops.active = false;
    return loops;
  }
  if (raw.empty())
    throw ModelError(model.constraints().front().where,
                     "every constraint equation is identically satisfied: the constraints do not restrict the motion");
  ExMatrix Phi_y(raw.size(), std::vector<ex>(n, 0));
  for (std::size_t k = 0; k < raw.size(); ++k)
    for (std::size_t j = 0; j < n; ++j) Phi_y[k][j] = prog.diff(raw[k].equation.phi, eq.y[j]);

  Numbers at_op;
  try {
    at_op = evaluate(eq, raw, Phi_y, operating_point_values(model, eq));
  } catch (const std::runtime_error& e) {
    throw ModelError(model.operating_point().where, std::string("the constraints cannot be evaluated at the "
                                                                "operating point with the default parameter values (") +
                                                        e.what() + ")");
  }
  drop_redundant(model, eq, raw, Phi_y, at_op, loops);
  if (raw.empty())
    throw ModelError(model.constraints().front().where,
                     "every constraint equation is identically satisfied: the constraints do not restrict the motion");
  // The equations kept, at the operating point again (their sizes for the kernels' checks).
  const Numbers kept = evaluate(eq, raw, Phi_y, operating_point_values(model, eq));
  check_closure(model, raw, kept);
  const MatrixXd& J = kept.J;
  for (std::size_t k = 0; k < raw.size(); ++k) {
    raw[k].equation.scale = kept.size[k];
    loops.equations.push_back(raw[k].equation);
  }
  loops.Phi_y = Phi_y;
  choose_coordinates(model, J, loops);
  loops.closed_at_defaults = refine(model, eq, raw, Phi_y, loops.dependent);
  ExMatrix Phi_yd(loops.dependent.size(), std::vector<ex>(loops.dependent.size(), 0));
  for (std::size_t k = 0; k < Phi_yd.size(); ++k)
    for (std::size_t d = 0; d < loops.dependent.size(); ++d) Phi_yd[k][d] = Phi_y[k][loops.dependent[d]];
  loops.lu = SymbolicLU::factor(prog, Phi_yd, partial_pivoting_rows(columns(J, loops.dependent)));

  // X = −Φ_yd⁻¹ Φ_yi, column by column; g_d = −Φ_yd⁻¹ γ with γ = (∂(Φ_y ẏ)/∂y) ẏ.
  const std::size_t fi = loops.independent.size(), m = loops.dependent.size();
  loops.X.assign(m, std::vector<ex>(fi, 0));
  for (std::size_t j = 0; j < fi; ++j) {
    std::vector<ex> b(m);
    for (std::size_t k = 0; k < m; ++k) b[k] = -Phi_y[k][loops.independent[j]];
    const std::vector<ex> x = loops.solve(prog, b);
    for (std::size_t d = 0; d < m; ++d) loops.X[d][j] = x[d];
  }
  std::vector<ex> minus_gamma(m);
  for (std::size_t k = 0; k < m; ++k) {
    ex v = 0;
    for (std::size_t j = 0; j < n; ++j)
      if (!Phi_y[k][j].is_zero()) v += Phi_y[k][j] * eq.yd[j];
    v = prog.define(v);
    ex gamma = 0;
    for (std::size_t l = 0; l < n; ++l) gamma += prog.diff(v, eq.y[l]) * eq.yd[l];
    loops.gamma.push_back(prog.define(gamma));
    minus_gamma[k] = prog.define(-gamma);
  }
  loops.g = loops.solve(prog, minus_gamma);
  return loops;
}

// -----------------------------------------------------------------------------------------------
namespace {

// A T (rows × f_i) and Tᵀ A (f_i × cols) with T = [E; X] in the coordinates' order.
ExMatrix times_T(Program& prog, const LoopClosure& loops, const ExMatrix& A) {
  const std::size_t fi = loops.independent.size();
  ExMatrix R(A.size(), std::vector<ex>(fi, 0));
  for (std::size_t a = 0; a < A.size(); ++a)
    for (std::size_t j = 0; j < fi; ++j) {
      ex s = A[a][loops.independent[j]];
      for (std::size_t d = 0; d < loops.dependent.size(); ++d)
        if (!A[a][loops.dependent[d]].is_zero() && !loops.X[d][j].is_zero()) s += A[a][loops.dependent[d]] * loops.X[d][j];
      R[a][j] = prog.define(s);
    }
  return R;
}

ExMatrix T_transposed_times(Program& prog, const LoopClosure& loops, const ExMatrix& A) {
  const std::size_t fi = loops.independent.size(), cols = A.empty() ? 0 : A[0].size();
  ExMatrix R(fi, std::vector<ex>(cols, 0));
  for (std::size_t i = 0; i < fi; ++i)
    for (std::size_t c = 0; c < cols; ++c) {
      ex s = A[loops.independent[i]][c];
      for (std::size_t d = 0; d < loops.dependent.size(); ++d)
        if (!A[loops.dependent[d]][c].is_zero() && !loops.X[d][i].is_zero()) s += loops.X[d][i] * A[loops.dependent[d]][c];
      R[i][c] = prog.define(s);
    }
  return R;
}

// Tᵀ A T, made exactly symmetric when A is (the mass matrix).
ExMatrix congruence(Program& prog, const LoopClosure& loops, const ExMatrix& A, bool symmetric) {
  ExMatrix R = T_transposed_times(prog, loops, times_T(prog, loops, A));
  if (symmetric)
    for (std::size_t i = 0; i < R.size(); ++i)
      for (std::size_t j = i + 1; j < R.size(); ++j) R[i][j] = R[j][i];
  return R;
}

ExMatrix column_vector(const std::vector<ex>& v) {
  ExMatrix A;
  for (const auto& x : v) A.push_back({x});
  return A;
}

}  // namespace

void reduce_equations(Equations& eq) {
  LoopClosure& loops = eq.loops;
  if (!loops.active) return;
  Program& prog = eq.program;
  const std::size_t n = eq.y.size();
  eq.tree = {eq.M, eq.JT, eq.JR, eq.residual, eq.outputs};

  // The dependent rates follow from the independent ones: ẏ_d = X ẏ_i.
  GiNaC::exmap rates;
  for (std::size_t d = 0; d < loops.dependent.size(); ++d) {
    ex v = 0;
    for (std::size_t j = 0; j < loops.independent.size(); ++j)
      if (!loops.X[d][j].is_zero()) v += loops.X[d][j] * eq.yd[loops.independent[j]];
    rates[eq.yd[loops.dependent[d]]] = prog.define(v);
  }
  // Accelerations (for reaction outputs): ÿ_d = X ÿ_i + g_d, with g_d at ẏ_d = X ẏ_i.
  if (!eq.ydd.empty()) {
    Program::Substitution on_rates(rates);
    GiNaC::exmap accelerations = rates;
    for (std::size_t d = 0; d < loops.dependent.size(); ++d) {
      ex v = prog.substitute(loops.g[d], on_rates);
      for (std::size_t j = 0; j < loops.independent.size(); ++j)
        if (!loops.X[d][j].is_zero()) v += loops.X[d][j] * eq.ydd[loops.independent[j]];
      accelerations[eq.ydd[loops.dependent[d]]] = prog.define(v);
    }
    rates = accelerations;
  }
  Program::Substitution sub(rates);
  auto on_motion = [&](const ex& e) { return prog.define(prog.substitute(e, sub)); };

  eq.M = congruence(prog, loops, eq.tree.M, true);
  // Tᵀ (M [0; g_d] + h) at ẏ = T ẏ_i.
  std::vector<ex> w(n);
  for (std::size_t a = 0; a < n; ++a) {
    ex s = eq.tree.residual[a];
    for (std::size_t d = 0; d < loops.dependent.size(); ++d)
      if (!eq.tree.M[a][loops.dependent[d]].is_zero()) s += eq.tree.M[a][loops.dependent[d]] * loops.g[d];
    w[a] = on_motion(prog.define(s));
  }
  const ExMatrix r = T_transposed_times(prog, loops, column_vector(w));
  eq.residual.clear();
  for (const auto& row : r) eq.residual.push_back(row[0]);
  for (auto& z : eq.outputs) z = on_motion(z);
  eq.JT = times_T(prog, loops, eq.tree.JT);
  eq.JR = times_T(prog, loops, eq.tree.JR);
}

ExMatrix reduce_columns(Equations& eq, const ExMatrix& A) { return times_T(eq.program, eq.loops, A); }

void reduce_linear(Equations& eq, const std::vector<ex>& residual_at_rest, ExMatrix& M, ExMatrix& Q, ExMatrix& K,
                   ExMatrix& B, ExMatrix& Cy, ExMatrix& Cv) {
  const LoopClosure& loops = eq.loops;
  Program& prog = eq.program;
  const std::size_t n = eq.y.size(), m = loops.dependent.size();
  // λ from the dependent rows at rest, Φ_ydᵀ λ = h_d, and the geometric stiffness −Σ λ_k ∂²Φ_k/∂y².
  std::vector<ex> h_d(m);
  for (std::size_t d = 0; d < m; ++d) h_d[d] = residual_at_rest[loops.dependent[d]];
  const std::vector<ex> lambda = loops.solve_transposed(prog, h_d);
  ExMatrix K_aug = K;
  for (std::size_t k = 0; k < loops.equations.size(); ++k) {
    if (lambda[k].is_zero()) continue;
    for (std::size_t j = 0; j < n; ++j) {
      if (loops.Phi_y[k][j].is_zero()) continue;
      for (std::size_t l = 0; l < n; ++l) {
        const ex H = prog.diff(loops.Phi_y[k][j], eq.y[l]);
        if (!H.is_zero()) K_aug[j][l] = prog.define(K_aug[j][l] - lambda[k] * H);
      }
    }
  }
  M = congruence(prog, loops, M, true);
  Q = congruence(prog, loops, Q, false);
  K = congruence(prog, loops, K_aug, false);
  B = T_transposed_times(prog, loops, B);
  Cy = times_T(prog, loops, Cy);
  Cv = times_T(prog, loops, Cv);
}

}  // namespace mbsgen
