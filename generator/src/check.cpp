#include "mbsgen/generator/check.hpp"

#include "point_evaluator.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

namespace mbsgen {

namespace {

std::string format(double v) {
  std::ostringstream os;
  os.precision(4);
  os << v;
  return os.str();
}

// Where to report: the operating point's node, or else the first coordinate (an implicit
// operating point is all coordinates zero at rest).
SourceLocation where_of(const Model& model) {
  const SourceLocation& op = model.operating_point().where;
  if (op.line > 0 || model.coordinates().empty()) return op;
  return model.coordinates().front().where;
}

// "'a', 'b' and 'c'"
std::string name_list(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i)
    s += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + ("'" + names[i] + "'");
  return s;
}

}  // namespace

void check_operating_point(const Equations& eq, const LinearEquations& lin) {
  const Model& model = *eq.model;
  if (lin.equilibrium) return;
  const std::size_t f = eq.y.size();
  const SourceLocation where = where_of(model);

  GiNaC::exmap values, p;
  for (std::size_t k = 0; k < eq.p.size(); ++k)
    p[eq.p[k]] = GiNaC::numeric(model.parameters()[k].value);
  values = p;
  for (std::size_t k = 0; k < f; ++k) {
    values[eq.y[k]] = lin.y0[k].subs(p, GiNaC::subs_options::no_pattern);
    values[eq.yd[k]] = lin.yd0[k].subs(p, GiNaC::subs_options::no_pattern);
  }
  for (const auto& u : eq.u) values[u] = 0;

  std::vector<GiNaC::ex> entries;
  for (const ExMatrix* A : {&eq.M, &lin.K, &lin.Q})
    for (std::size_t i = 0; i < f; ++i)
      for (std::size_t j = 0; j < f; ++j) entries.push_back((*A)[i][j]);
  for (const auto& r : eq.residual) entries.push_back(r);

  std::vector<double> v(entries.size());
  const long digits = GiNaC::Digits;
  GiNaC::Digits = detail::PointEvaluator::kDigits;
  try {
    const std::vector<GiNaC::numeric> n = detail::PointEvaluator(eq.program, values).evaluate(entries);
    for (std::size_t i = 0; i < n.size(); ++i) {
      if (!n[i].is_real()) throw std::runtime_error("a complex value");
      v[i] = n[i].to_double();
      if (!std::isfinite(v[i])) throw std::runtime_error("a value beyond the range of double");
    }
  } catch (const std::exception& e) {
    GiNaC::Digits = digits;
    throw ModelError(where, std::string("the equations cannot be evaluated at the operating point "
                                        "with the default parameter values (") +
                                e.what() + ")");
  }
  GiNaC::Digits = digits;

  using Eigen::MatrixXd;
  using Eigen::VectorXd;
  auto matrix = [&](std::size_t which) {
    MatrixXd A(f, f);
    for (std::size_t i = 0; i < f; ++i)
      for (std::size_t j = 0; j < f; ++j)
        A(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = v[which * f * f + i * f + j];
    return A;
  };
  const MatrixXd M = matrix(0), K = matrix(1), Q = matrix(2);
  VectorXd r(f), y0(f), yd0(f);
  for (std::size_t i = 0; i < f; ++i) r(static_cast<Eigen::Index>(i)) = v[3 * f * f + i];
  const auto& coords = model.coordinates();
  auto coordinate = [&](Eigen::Index i) { return coords[static_cast<std::size_t>(i)].name; };

  // M(y0): a zero diagonal entry is a coordinate that moves no mass; otherwise the eigenvalues of
  // the equilibrated matrix (unit diagonal, so between 0 and f) show a singular combination.
  std::vector<std::string> massless;
  SourceLocation first_massless;
  for (Eigen::Index i = 0; i < M.rows(); ++i)
    if (!(M(i, i) > 0)) {
      if (massless.empty()) first_massless = coords[static_cast<std::size_t>(i)].where;
      massless.push_back(coordinate(i));
    }
  if (!massless.empty())
    throw ModelError(first_massless, "the mass matrix is singular at the operating point: coordinate" +
                                std::string(massless.size() > 1 ? "s " : " ") + name_list(massless) +
                                (massless.size() > 1 ? " move" : " moves") +
                                " no mass (give the bodies it moves a mass or inertia)");
  const VectorXd d = M.diagonal().cwiseSqrt().cwiseInverse();
  const MatrixXd S = d.asDiagonal() * M * d.asDiagonal();
  Eigen::SelfAdjointEigenSolver<MatrixXd> es(S);
  if (es.info() == Eigen::Success && es.eigenvalues()(0) < 1e-10) {
    const VectorXd null = es.eigenvectors().col(0);
    const double big = null.cwiseAbs().maxCoeff();
    std::vector<std::string> involved;
    for (Eigen::Index i = 0; i < null.size(); ++i)
      if (std::abs(null(i)) > 0.1 * big) involved.push_back(coordinate(i));
    throw ModelError(where, "the mass matrix is singular at the operating point (a kinematic "
                            "singularity such as gimbal lock): the rates of coordinates " +
                                name_list(involved) +
                                " move the bodies alike (the equilibrated mass matrix has an "
                                "eigenvalue below 1e-10); choose other coordinates or another "
                                "operating point");
  }

  // k − q at the operating point, against the scale of the forces the linear model contains.
  for (std::size_t k = 0; k < f; ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    y0(i) = GiNaC::ex_to<GiNaC::numeric>(GiNaC::evalf(values[eq.y[k]])).to_double();
    yd0(i) = GiNaC::ex_to<GiNaC::numeric>(GiNaC::evalf(values[eq.yd[k]])).to_double();
  }
  const double scale = K.cwiseAbs().maxCoeff() * std::max(1.0, y0.cwiseAbs().maxCoeff()) +
                       Q.cwiseAbs().maxCoeff() * std::max(1.0, yd0.cwiseAbs().maxCoeff());
  const double tol = 1e-9 * scale;
  if (r.cwiseAbs().maxCoeff() > tol) {
    std::vector<Eigen::Index> order(f);
    std::iota(order.begin(), order.end(), Eigen::Index{0});
    std::stable_sort(order.begin(), order.end(),
                     [&](Eigen::Index a, Eigen::Index b) { return std::abs(r(a)) > std::abs(r(b)); });
    std::string list;
    for (std::size_t k = 0; k < std::min<std::size_t>(3, f) && std::abs(r(order[k])) > tol; ++k)
      list += (k ? ", " : "") + coordinate(order[k]) + ": " + format(r(order[k]));
    throw ModelError(where, std::string("the operating point is not ") +
                                (yd0.isZero() ? "an equilibrium" : "a steady motion") +
                                ": the residual k - q is " + list +
                                " with u = 0 and the default parameter values (tolerance " +
                                format(tol) +
                                "); give the equilibrium, or write 'type: equilibrium' to have "
                                "the solver find it");
  }
}

}  // namespace mbsgen
