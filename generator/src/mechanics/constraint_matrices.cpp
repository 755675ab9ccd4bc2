// Matrices of program expressions and numbers at the operating point, shared by the constraint
// stages (mechanics/nonholonomic.cpp, linear/constrained_linearization.cpp).
#include "mechanics/constraint_matrices.hpp"

#include "mbsgen/generator/mechanics/dynamics.hpp"

#include "symbolic/point_evaluator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mbsgen::detail {

using Eigen::MatrixXd;
using GiNaC::ex;

// ---------------------------------------------------------------------------------------------
// Matrices of program expressions (exact zeros skipped, each entry an intermediate).

ExMatrix zeros(std::size_t rows, std::size_t cols) { return ExMatrix(rows, std::vector<ex>(cols, 0)); }

std::size_t columns_of(const ExMatrix& A) { return A.empty() ? 0 : A[0].size(); }

ExMatrix product(Program& prog, const ExMatrix& A, const ExMatrix& B) {
  const std::size_t inner = B.size(), cols = columns_of(B);
  ExMatrix R = zeros(A.size(), cols);
  for (std::size_t i = 0; i < A.size(); ++i)
    for (std::size_t j = 0; j < cols; ++j) {
      ex s = 0;
      for (std::size_t k = 0; k < inner; ++k)
        if (!A[i][k].is_zero() && !B[k][j].is_zero()) s += A[i][k] * B[k][j];
      R[i][j] = prog.define(s);
    }
  return R;
}

ExMatrix transposed(const ExMatrix& A) {
  ExMatrix R = zeros(columns_of(A), A.size());
  for (std::size_t i = 0; i < A.size(); ++i)
    for (std::size_t j = 0; j < A[i].size(); ++j) R[j][i] = A[i][j];
  return R;
}

ExMatrix combination(Program& prog, const ExMatrix& A, const ExMatrix& B, int sign) {
  ExMatrix R = A;
  for (std::size_t i = 0; i < A.size(); ++i)
    for (std::size_t j = 0; j < A[i].size(); ++j)
      if (!B[i][j].is_zero()) R[i][j] = prog.define(A[i][j] + sign * B[i][j]);
  return R;
}

// The independent coordinates of the loops (all coordinates without loops).
std::vector<std::size_t> independent_coordinates(const Equations& eq) {
  if (eq.loops.active) return eq.loops.independent;
  std::vector<std::size_t> all(eq.y.size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = k;
  return all;
}

// T = ∂y/∂y_i (n×f): unit rows for the independent coordinates, X for the dependent ones.
ExMatrix tangent_map(const Equations& eq) {
  const std::vector<std::size_t> indep = independent_coordinates(eq);
  ExMatrix T = zeros(eq.y.size(), indep.size());
  for (std::size_t j = 0; j < indep.size(); ++j) T[indep[j]][j] = 1;
  if (eq.loops.active)
    for (std::size_t d = 0; d < eq.loops.dependent.size(); ++d) T[eq.loops.dependent[d]] = eq.loops.X[d];
  return T;
}

std::size_t position_in(const std::vector<std::size_t>& v, std::size_t k) {
  return static_cast<std::size_t>(std::lower_bound(v.begin(), v.end(), k) - v.begin());
}

std::string coordinate_names(const Model& model, const std::vector<std::size_t>& which) {
  std::string s;
  for (std::size_t k : which) s += (s.empty() ? "" : ", ") + model.coordinates()[k].name;
  return s;
}

// ---------------------------------------------------------------------------------------------
// Numbers at the operating point with the default parameter values (50 digits; the loops'
// dependent coordinates closed by close_loops).

GiNaC::exmap defaults_at_operating_point(const Model& model, const Equations& eq) {
  GiNaC::exmap p, values;
  for (std::size_t k = 0; k < eq.p.size(); ++k) p[eq.p[k]] = GiNaC::numeric(model.parameters()[k].value);
  values = p;
  const LinearizationPoint& op = model.operating_point();
  for (std::size_t k = 0; k < eq.y.size(); ++k) {
    const auto& name = model.coordinates()[k].name;
    auto closed = eq.loops.closed_at_defaults.find(eq.y[k]);
    auto given = op.position.find(name);
    values[eq.y[k]] = closed != eq.loops.closed_at_defaults.end() ? closed->second
                      : given != op.position.end()                  ? given->second.subs(p)
                                                                    : ex(0);
    auto rate = op.velocity.find(name);
    values[eq.yd[k]] = rate != op.velocity.end() ? rate->second.subs(p) : ex(0);
  }
  return values;
}

// `shift` moves coordinates away from the operating point (index → amount).
std::vector<double> at_defaults(const Model& model, Equations& eq, const std::vector<ex>& entries,
                                const std::map<std::size_t, double>& shift) {
  const long digits = GiNaC::Digits;
  GiNaC::Digits = detail::PointEvaluator::kDigits;
  std::vector<GiNaC::numeric> v;
  try {
    GiNaC::exmap point = defaults_at_operating_point(model, eq);
    for (const auto& [k, amount] : shift) point[eq.y[k]] = point[eq.y[k]] + GiNaC::numeric(amount);
    v = detail::PointEvaluator(eq.program, point).evaluate(entries);
  } catch (const std::exception& e) {
    GiNaC::Digits = digits;
    throw ModelError(model.operating_point().where, std::string("the velocity constraints cannot be evaluated at the "
                                                                "operating point with the default parameter values (") +
                                                        e.what() + ")");
  }
  GiNaC::Digits = digits;
  std::vector<double> out;
  for (const auto& x : v) out.push_back(x.is_real() ? x.to_double() : std::nan(""));
  return out;
}

MatrixXd numbers(const Model& model, Equations& eq, const ExMatrix& A) {
  std::vector<ex> entries;
  for (const auto& row : A) entries.insert(entries.end(), row.begin(), row.end());
  const std::vector<double> v = at_defaults(model, eq, entries);
  MatrixXd R(static_cast<Eigen::Index>(A.size()), static_cast<Eigen::Index>(columns_of(A)));
  for (Eigen::Index i = 0; i < R.rows(); ++i)
    for (Eigen::Index j = 0; j < R.cols(); ++j) R(i, j) = v[static_cast<std::size_t>(i * R.cols() + j)];
  return R;
}

// The largest steady rate with the default parameter values.
double rate_size(const Model& model, const Equations& eq) {
  const GiNaC::exmap at = defaults_at_operating_point(model, eq);
  double size = 0;
  for (const auto& s : eq.yd) size = std::max(size, std::abs(GiNaC::ex_to<GiNaC::numeric>(at.at(s).evalf()).to_double()));
  return size;
}

std::string format(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

}  // namespace mbsgen::detail
