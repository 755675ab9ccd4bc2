#include "mbsgen/generator/linear/operating_point_check.hpp"

#include "symbolic/point_evaluator.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdint>
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

// The diagonal blocks of a symmetric matrix, up to a permutation: the connected components of
// its graph of nonzero entries, each in ascending order, ordered by their first index. The
// eigenvalues of M are those of its blocks, so that a model of decoupled parts is checked block
// by block (2,000 decoupled oscillators: 2,000 blocks of one, not one dense eigenproblem of
// order 2,000).
std::vector<std::vector<Eigen::Index>> coupled_blocks(const Eigen::MatrixXd& M) {
  const Eigen::Index n = M.rows();
  std::vector<Eigen::Index> parent(static_cast<std::size_t>(n));
  std::iota(parent.begin(), parent.end(), Eigen::Index{0});
  auto root = [&](Eigen::Index i) {
    while (parent[static_cast<std::size_t>(i)] != i)
      i = parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    return i;
  };
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index i = 0; i < n; ++i)
      if (i != j && (M(i, j) != 0 || M(j, i) != 0)) {
        const Eigen::Index a = root(i), b = root(j);
        if (a != b) parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
      }
  std::vector<std::vector<Eigen::Index>> blocks;
  std::vector<std::size_t> block_of(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index r = root(i);
    if (r == i) {
      block_of[static_cast<std::size_t>(i)] = blocks.size();
      blocks.emplace_back();
    }
    blocks[block_of[static_cast<std::size_t>(r)]].push_back(i);
  }
  return blocks;
}

}  // namespace

void check_operating_point(const Equations& eq, const LinearEquations& lin) {
  const Model& model = *eq.model;
  if (lin.equilibrium) return;
  // Nonholonomic constraints: linearize_constrained checked the steady motion (the residual
  // projected on the independent speeds, the dependent accelerations, the invariance along it).
  if (lin.descriptor) return;
  // With closed loops the matrices and the residual are those of the independent coordinates
  // (f of the n tree coordinates; loop_closure.hpp).
  const std::size_t n_tree = eq.y.size(), f = eq.M.size();
  const SourceLocation where = where_of(model);

  GiNaC::exmap values, p;
  for (std::size_t k = 0; k < eq.p.size(); ++k)
    p[eq.p[k]] = GiNaC::numeric(model.parameters()[k].value);
  values = p;
  for (std::size_t k = 0; k < n_tree; ++k) {
    auto closed = eq.loops.closed_at_defaults.find(eq.y[k]);
    values[eq.y[k]] = closed != eq.loops.closed_at_defaults.end()
                          ? closed->second
                          : lin.y0[k].subs(p, GiNaC::subs_options::no_pattern);
    values[eq.yd[k]] = lin.yd0[k].subs(p, GiNaC::subs_options::no_pattern);
  }
  for (const auto& u : eq.u) values[u] = 0;

  // M, K, Q and the residual, in this order; exact zeros are not evaluated (most entries of a
  // large model's matrices).
  std::vector<GiNaC::ex> entries;
  std::vector<std::size_t> slot;  // entry k of the list above → index in `entries`
  auto add = [&](const GiNaC::ex& e) {
    slot.push_back(e.is_zero() ? SIZE_MAX : entries.size());
    if (!e.is_zero()) entries.push_back(e);
  };
  for (const ExMatrix* A : {&eq.M, &lin.K, &lin.Q})
    for (std::size_t i = 0; i < f; ++i)
      for (std::size_t j = 0; j < f; ++j) add((*A)[i][j]);
  for (const auto& r : eq.residual) add(r);

  std::vector<double> v(slot.size(), 0.0);
  const long digits = GiNaC::Digits;
  GiNaC::Digits = detail::PointEvaluator::kDigits;
  try {
    const std::vector<GiNaC::numeric> n = detail::PointEvaluator(eq.program, values).evaluate(entries);
    for (std::size_t k = 0; k < slot.size(); ++k) {
      if (slot[k] == SIZE_MAX) continue;
      const GiNaC::numeric& x = n[slot[k]];
      if (!x.is_real()) throw std::runtime_error("a complex value");
      v[k] = x.to_double();
      if (!std::isfinite(v[k])) throw std::runtime_error("a value beyond the range of double");
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
  VectorXd r(f), y0(n_tree), yd0(n_tree);
  for (std::size_t i = 0; i < f; ++i) r(static_cast<Eigen::Index>(i)) = v[3 * f * f + i];
  const auto& coords = model.coordinates();
  auto index = [&](Eigen::Index i) {
    return eq.loops.active ? eq.loops.independent[static_cast<std::size_t>(i)] : static_cast<std::size_t>(i);
  };
  auto coordinate = [&](Eigen::Index i) { return coords[index(i)].name; };

  // M(y0): a zero diagonal entry is a coordinate that moves no mass; otherwise the eigenvalues of
  // the equilibrated matrix (unit diagonal, so between 0 and f) show a singular combination.
  std::vector<std::string> massless;
  SourceLocation first_massless;
  for (Eigen::Index i = 0; i < M.rows(); ++i)
    if (!(M(i, i) > 0)) {
      if (massless.empty()) first_massless = coords[index(i)].where;
      massless.push_back(coordinate(i));
    }
  if (!massless.empty())
    throw ModelError(first_massless, "the mass matrix is singular at the operating point: coordinate" +
                                std::string(massless.size() > 1 ? "s " : " ") + name_list(massless) +
                                (massless.size() > 1 ? " move" : " moves") +
                                " no mass (give the bodies it moves a mass or inertia)");
  for (const std::vector<Eigen::Index>& block : coupled_blocks(M)) {
    if (block.size() == 1) continue;  // a positive diagonal entry (checked above)
    const auto n = static_cast<Eigen::Index>(block.size());
    MatrixXd S(n, n);  // the equilibrated block D^-1/2 M D^-1/2
    for (Eigen::Index a = 0; a < n; ++a)
      for (Eigen::Index b = 0; b < n; ++b) {
        const Eigen::Index i = block[static_cast<std::size_t>(a)], j = block[static_cast<std::size_t>(b)];
        S(a, b) = M(i, j) / std::sqrt(M(i, i) * M(j, j));
      }
    Eigen::SelfAdjointEigenSolver<MatrixXd> es(S);
    if (es.info() != Eigen::Success || !(es.eigenvalues()(0) < 1e-10)) continue;
    const VectorXd null = es.eigenvectors().col(0);
    const double big = null.cwiseAbs().maxCoeff();
    std::vector<std::string> involved;
    for (Eigen::Index a = 0; a < n; ++a)
      if (std::abs(null(a)) > 0.1 * big) involved.push_back(coordinate(block[static_cast<std::size_t>(a)]));
    throw ModelError(where, "the mass matrix is singular at the operating point (a kinematic "
                            "singularity such as gimbal lock): the rates of coordinates " +
                                name_list(involved) +
                                " move the bodies alike (the equilibrated mass matrix has an "
                                "eigenvalue below 1e-10); choose other coordinates or another "
                                "operating point");
  }

  // k − q at the operating point, against the scale of the forces the linear model contains.
  for (std::size_t k = 0; k < n_tree; ++k) {
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
