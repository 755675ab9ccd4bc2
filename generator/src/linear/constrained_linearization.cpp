// The linear model of a constrained steady motion, its reduced second-order form and the model's
// named parts of it (linear/constrained_linearization.hpp).
#include "mbsgen/generator/linear/constrained_linearization.hpp"

#include "mbsgen/generator/linear/linearize.hpp"
#include "mbsgen/generator/mechanics/dynamics.hpp"

#include "linear/sample_points.hpp"
#include "mechanics/constraint_matrices.hpp"

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
// The linear model of a constrained steady motion (constrained_linearization.hpp)

namespace {

// What the linearization works with: the tree's derivatives at the steady motion, with the rates
// of the dependent speeds and coordinates written in the independent speeds.
struct SteadyMotion {
  std::vector<std::size_t> indep, speeds;
  ExMatrix T, N, P;           // n×f, f×s, f×f
  ExMatrix M, Hy, Hv, B;      // n×n, n×n, n×n, n×m
  ExMatrix Cy, Cv;            // r×n
  ExMatrix G;                 // n×n geometric stiffness of the constraint forces
  std::vector<ex> r0;         // h at the steady motion
};

// Rates of the dependent speeds (ẏ_d = Y w + c) and of the loops' dependent coordinates
// (ẏ = X ẏ_i), as substitutions.
GiNaC::exmap dependent_rates(Equations& eq, SteadyMotion& sm) {
  Program& prog = eq.program;
  const Nonholonomic& nh = eq.nonholonomic;
  GiNaC::exmap rates;
  const std::size_t f = sm.indep.size(), s = sm.speeds.size();
  sm.N = zeros(f, s);
  for (std::size_t k = 0; k < s; ++k) sm.N[position_in(sm.indep, sm.speeds[k])][k] = 1;
  if (nh.active) {
    const ExMatrix B = product(prog, nh.A, sm.T);
    const std::size_t m = nh.dependent_speeds.size();
    for (std::size_t k = 0; k < s; ++k) {  // Y = −B_d⁻¹ B_s, column by column
      std::vector<ex> b(m);
      for (std::size_t e = 0; e < m; ++e) b[e] = -B[e][position_in(sm.indep, sm.speeds[k])];
      const std::vector<ex> y = nh.lu.solve(prog, b);
      for (std::size_t d = 0; d < m; ++d) sm.N[position_in(sm.indep, nh.dependent_speeds[d])][k] = y[d];
    }
    std::vector<ex> minus_a(m);
    for (std::size_t e = 0; e < m; ++e) minus_a[e] = -nh.a[e];
    const std::vector<ex> c = nh.lu.solve(prog, minus_a);
    for (std::size_t d = 0; d < m; ++d) {
      ex v = c[d];
      const std::size_t row = position_in(sm.indep, nh.dependent_speeds[d]);
      for (std::size_t k = 0; k < s; ++k)
        if (!sm.N[row][k].is_zero()) v += sm.N[row][k] * eq.yd[sm.speeds[k]];
      rates[eq.yd[nh.dependent_speeds[d]]] = prog.define(v);
    }
  }
  if (eq.loops.active) {
    Program::Substitution on_speeds(rates);
    for (std::size_t d = 0; d < eq.loops.dependent.size(); ++d) {
      ex v = 0;
      for (std::size_t j = 0; j < f; ++j)
        if (!eq.loops.X[d][j].is_zero()) v += eq.loops.X[d][j] * prog.substitute(eq.yd[sm.indep[j]], on_speeds);
      rates[eq.yd[eq.loops.dependent[d]]] = prog.define(v);
    }
  }
  for (const auto& u : eq.u) rates[u] = 0;
  for (const auto& a : eq.ydd) rates[a] = 0;
  return rates;
}

// H_y, H_v, B, C_y, C_v and h of the tree at the steady motion.
void tree_derivatives(Equations& eq, SteadyMotion& sm, Program::Substitution& at_motion) {
  Program& prog = eq.program;
  const bool loops = eq.loops.active;
  const std::vector<ex>& h = loops ? eq.tree.residual : eq.residual;
  const std::vector<ex>& z = loops ? eq.tree.outputs : eq.outputs;
  const std::size_t n = eq.y.size(), m = eq.u.size(), r = z.size();
  auto at = [&](const ex& e) { return prog.define(prog.substitute(e, at_motion)); };
  sm.M = loops ? eq.tree.M : eq.M;
  sm.Hy = zeros(n, n), sm.Hv = zeros(n, n), sm.B = zeros(n, m);
  for (std::size_t i = 0; i < n; ++i) {
    const ex hi = prog.define(h[i]);
    sm.r0.push_back(at(hi));
    for (std::size_t j = 0; j < n; ++j) {
      sm.Hy[i][j] = at(prog.diff(hi, eq.y[j]));
      sm.Hv[i][j] = at(prog.diff(hi, eq.yd[j]));
    }
    for (std::size_t k = 0; k < m; ++k) sm.B[i][k] = at(-prog.diff(hi, eq.u[k]));
  }
  sm.Cy = zeros(r, n), sm.Cv = zeros(r, n);
  for (std::size_t i = 0; i < r; ++i) {
    const ex zi = prog.define(z[i]);
    for (std::size_t j = 0; j < n; ++j) {
      sm.Cy[i][j] = at(prog.diff(zi, eq.y[j]));
      sm.Cv[i][j] = at(prog.diff(zi, eq.yd[j]));
    }
  }
}

// The multipliers of h(y0, ẏ0) = Φ_yᵀ λ + Aᵀ μ and the geometric stiffness G of those forces;
// with nonholonomic constraints also P = [0; −B_d⁻¹ A_q T].
void constraint_forces(Equations& eq, SteadyMotion& sm, Program::Substitution& at_motion) {
  Program& prog = eq.program;
  const Nonholonomic& nh = eq.nonholonomic;
  const LoopClosure& loops = eq.loops;
  const std::size_t n = eq.y.size(), f = sm.indep.size();
  auto at = [&](const ex& e) { return prog.define(prog.substitute(e, at_motion)); };
  sm.G = zeros(n, n);
  sm.P = zeros(f, f);
  std::vector<ex> rest = sm.r0;
  if (nh.active) {
    // (Tᵀ h)_d = B_dᵀ μ: the dependent speeds' rows of the projected residual.
    const ExMatrix Th = product(prog, transposed(sm.T), transposed(ExMatrix{sm.r0}));
    std::vector<ex> b;
    for (std::size_t k : nh.dependent_speeds) b.push_back(Th[position_in(sm.indep, k)][0]);
    const std::vector<ex> mu = nh.lu.solve_transposed(prog, b);
    const std::size_t m = nh.equations.size();
    ExMatrix Aq = zeros(m, n);
    for (std::size_t k = 0; k < m; ++k) {
      const ex value = prog.define(nh.equations[k].value);
      for (std::size_t j = 0; j < n; ++j) {
        Aq[k][j] = at(prog.diff(value, eq.y[j]));
        if (nh.A[k][j].is_zero()) continue;
        rest[j] = prog.define(rest[j] - mu[k] * at(nh.A[k][j]));
        for (std::size_t l = 0; l < n; ++l) {
          const ex dA = at(prog.diff(nh.A[k][j], eq.y[l]));
          if (!dA.is_zero()) sm.G[j][l] = prog.define(sm.G[j][l] + mu[k] * dA);
        }
      }
    }
    const ExMatrix AqT = product(prog, Aq, sm.T);
    for (std::size_t j = 0; j < f; ++j) {
      std::vector<ex> column(m);
      for (std::size_t k = 0; k < m; ++k) column[k] = -AqT[k][j];
      const std::vector<ex> x = nh.lu.solve(prog, column);
      for (std::size_t d = 0; d < nh.dependent_speeds.size(); ++d) sm.P[position_in(sm.indep, nh.dependent_speeds[d])][j] = x[d];
    }
  }
  if (loops.active) {
    std::vector<ex> h_d;
    for (std::size_t d : loops.dependent) h_d.push_back(rest[d]);
    const std::vector<ex> lambda = loops.solve_transposed(prog, h_d);
    for (std::size_t k = 0; k < loops.equations.size(); ++k) {
      if (lambda[k].is_zero()) continue;
      for (std::size_t j = 0; j < n; ++j) {
        if (loops.Phi_y[k][j].is_zero()) continue;
        for (std::size_t l = 0; l < n; ++l) {
          const ex H = at(prog.diff(loops.Phi_y[k][j], eq.y[l]));
          if (!H.is_zero()) sm.G[j][l] = prog.define(sm.G[j][l] + lambda[k] * H);
        }
      }
    }
  }
}

// The steady motion is one, with the default parameter values: the projected residual vanishes,
// the dependent speeds and the loops' dependent rates do not accelerate (P ẏ_i0 = 0, γ = 0), and
// the linear model does not change along the motion.
void check_steady_motion(const Model& model, Equations& eq, const SteadyMotion& sm, const ExMatrix& TN,
                         const std::vector<const ExMatrix*>& matrices) {
  Program& prog = eq.program;
  const ExMatrix projected = product(prog, transposed(TN), transposed(ExMatrix{sm.r0}));
  const MatrixXd res = numbers(model, eq, projected), r0 = numbers(model, eq, ExMatrix{sm.r0});
  const double size = r0.size() ? r0.cwiseAbs().maxCoeff() : 0.0;
  if (res.size() && !(res.cwiseAbs().maxCoeff() <= 1e-10 * std::max(size, 1e-300) || res.cwiseAbs().maxCoeff() <= 1e-40))
    throw ModelError(model.operating_point().where,
                     "the operating point is not a steady motion: the projected equations of motion leave a "
                     "residual of " + format(res.cwiseAbs().maxCoeff()) + " (N or N m) with the default parameter values");
  std::vector<ex> accelerations = eq.loops.active ? eq.loops.gamma : std::vector<ex>{};
  for (const auto& row : sm.P) {
    ex a = 0;
    for (std::size_t j = 0; j < row.size(); ++j)
      if (!row[j].is_zero()) a += row[j] * eq.yd[sm.indep[j]];
    accelerations.push_back(prog.define(a));
  }
  const std::vector<double> acc = at_defaults(model, eq, accelerations);
  for (double a : acc)
    if (!(std::abs(a) <= 1e-10 * std::max(1.0, rate_size(model, eq))))
      throw ModelError(model.operating_point().where,
                       "the operating point is not a steady motion: the constraints make the dependent rates change "
                       "along it (an acceleration of " + format(a) + "); give constant rates that the constraints keep "
                       "constant (a wheel rolling straight, a constant spin)");
  // Along the motion the coordinates with nonzero rates change: the linear model must not (else
  // it is periodic or drifting, such as a spinning wheel that is not axisymmetric). Compared at
  // the operating point and with those coordinates moved by 0.7 (rad or m), relative to each
  // matrix's size.
  const GiNaC::exmap at = defaults_at_operating_point(model, eq);
  std::vector<ex> entries;
  for (const ExMatrix* A : matrices)
    for (const auto& row : *A) entries.insert(entries.end(), row.begin(), row.end());
  std::vector<double> here;
  for (std::size_t k = 0; k < eq.y.size(); ++k) {
    if (GiNaC::ex_to<GiNaC::numeric>(at.at(eq.yd[k]).evalf()).to_double() == 0) continue;
    if (here.empty()) here = at_defaults(model, eq, entries);
    const std::vector<double> there = at_defaults(model, eq, entries, {{k, 0.7}});
    double scale = 0, change = 0;
    for (std::size_t i = 0; i < here.size(); ++i) {
      scale = std::max(scale, std::abs(here[i]));
      change = std::max(change, std::abs(here[i] - there[i]));
    }
    if (!(change <= 1e-12 * std::max(scale, 1e-300) || change <= 1e-40))
      throw ModelError(model.operating_point().where,
                       "the operating point is not a steady motion: the linearized equations change along it (by " +
                           format(change) + " of " + format(scale) + " when '" + model.coordinates()[k].name +
                           "', whose rate is not zero, moves by 0.7); a steady motion needs equations independent of "
                           "the coordinates that change (an axisymmetric wheel, a level ground)");
  }
}

}  // namespace

void linearize_constrained(Equations& eq, LinearEquations& lin) {
  const Model& model = *eq.model;
  Program& prog = eq.program;
  const Nonholonomic& nh = eq.nonholonomic;
  SteadyMotion sm;
  sm.indep = independent_coordinates(eq);
  sm.speeds = nh.active ? nh.speeds : sm.indep;
  sm.T = tangent_map(eq);
  Program::Substitution at_motion(dependent_rates(eq, sm));
  tree_derivatives(eq, sm, at_motion);
  constraint_forces(eq, sm, at_motion);

  const std::size_t f = sm.indep.size(), s = sm.speeds.size();
  const ExMatrix TN = product(prog, sm.T, sm.N), TNt = transposed(TN);
  const ExMatrix MT = product(prog, sm.M, sm.T);
  // W = M T P + H_v T: what δẏ_i's dependence on δy_i adds through the accelerations and rates.
  const ExMatrix W = combination(prog, product(prog, MT, sm.P), product(prog, sm.Hv, sm.T), 1);
  ExMatrix Mr = product(prog, TNt, product(prog, MT, sm.N));
  for (std::size_t i = 0; i < s; ++i)
    for (std::size_t j = i + 1; j < s; ++j) Mr[i][j] = Mr[j][i];  // exactly symmetric
  const ExMatrix Cr = product(prog, TNt, product(prog, W, sm.N));
  const ExMatrix stiff = combination(prog, product(prog, combination(prog, sm.Hy, sm.G, -1), sm.T), product(prog, W, sm.P), 1);
  const ExMatrix Kr = product(prog, TNt, stiff);
  const ExMatrix Br = product(prog, TNt, sm.B);
  const ExMatrix CyT = combination(prog, product(prog, sm.Cy, sm.T), product(prog, product(prog, sm.Cv, sm.T), sm.P), 1);
  const ExMatrix CvTN = product(prog, sm.Cv, TN);
  check_steady_motion(model, eq, sm, TN, {&Mr, &Cr, &Kr, &Br, &sm.P, &sm.N});

  lin.coordinates = sm.indep;
  lin.speeds = sm.speeds;
  if (!nh.active) {  // second order in the independent coordinates
    lin.M = Mr, lin.Q = Cr, lin.K = Kr, lin.B = Br, lin.Cy = CyT, lin.Cv = CvTN;
    return;
  }
  // x = (δy_i, δw):  E = diag(E, M_r),  A = [[P, N], [−K_r, −C_r]],  B = [0; B_r],  C = [C_y T + C_v T P, C_v T N].
  lin.descriptor = true;
  const std::size_t nx = f + s, m = eq.u.size(), r = sm.Cy.size();
  lin.E = zeros(nx, nx), lin.A = zeros(nx, nx), lin.Bx = zeros(nx, m), lin.Cx = zeros(r, nx);
  for (std::size_t i = 0; i < f; ++i) {
    lin.E[i][i] = 1;
    for (std::size_t j = 0; j < f; ++j) lin.A[i][j] = sm.P[i][j];
    for (std::size_t k = 0; k < s; ++k) lin.A[i][f + k] = sm.N[i][k];
  }
  for (std::size_t i = 0; i < s; ++i) {
    for (std::size_t k = 0; k < s; ++k) {
      lin.E[f + i][f + k] = Mr[i][k];
      lin.A[f + i][f + k] = Cr[i][k].is_zero() ? ex(0) : prog.define(-Cr[i][k]);
    }
    for (std::size_t j = 0; j < f; ++j) lin.A[f + i][j] = Kr[i][j].is_zero() ? ex(0) : prog.define(-Kr[i][j]);
    for (std::size_t k = 0; k < m; ++k) lin.Bx[f + i][k] = Br[i][k];
  }
  for (std::size_t i = 0; i < r; ++i) {
    for (std::size_t j = 0; j < f; ++j) lin.Cx[i][j] = CyT[i][j];
    for (std::size_t k = 0; k < s; ++k) lin.Cx[i][f + k] = CvTN[i][k];
  }
}

}  // namespace mbsgen

namespace mbsgen {

ReducedForm reduced_form(const LinearEquations& lin) {
  ReducedForm r;
  const std::size_t f = lin.coordinates.size(), s = lin.speeds.size();
  auto nonzero = [](const ZeroPattern& z, std::size_t i, std::size_t j) { return z[i][j] == EntryZero::nonzero; };
  // speed_of[j]: the speed whose rate is coordinate position j, or s (none).
  std::vector<std::size_t> speed_of(f, s), coordinate_of(s);
  for (std::size_t k = 0; k < s; ++k) {
    coordinate_of[k] = position_in(lin.coordinates, lin.speeds[k]);
    speed_of[coordinate_of[k]] = k;
  }
  // Start from the speeds whose coordinate has a stiffness (a nonzero column in a dynamic row),
  // then close under the couplings of their rows.
  std::vector<char> kept(s, 0);
  for (std::size_t k = 0; k < s; ++k)
    for (std::size_t i = f; i < f + s; ++i) kept[k] = kept[k] || nonzero(lin.zeros.A, i, coordinate_of[k]);
  for (bool grew = true; grew;) {
    grew = false;
    for (std::size_t k = 0; k < s; ++k) {
      if (!kept[k]) continue;
      for (std::size_t row : {coordinate_of[k], f + k})
        for (std::size_t j = 0; j < f + s; ++j) {
          if (!nonzero(lin.zeros.A, row, j) && !nonzero(lin.zeros.E, row, j)) continue;
          const std::size_t speed = j < f ? speed_of[j] : j - f;
          if (speed == s) return r;  // coupled to a coordinate that is no speed's: no reduced form
          if (!kept[speed]) kept[speed] = 1, grew = true;
        }
    }
  }
  std::vector<std::size_t> speeds;
  for (std::size_t k = 0; k < s; ++k)
    if (kept[k]) speeds.push_back(k);
  if (speeds.empty()) return r;
  r.exists = true;
  const std::size_t n = speeds.size(), m = lin.Bx.empty() ? 0 : lin.Bx[0].size();
  r.M = zeros(n, n), r.Q = zeros(n, n), r.K = zeros(n, n), r.B = zeros(n, m);
  for (std::size_t a = 0; a < n; ++a) {
    r.coordinates.push_back(lin.speeds[speeds[a]]);
    const std::size_t row = f + speeds[a];
    for (std::size_t b = 0; b < n; ++b) {
      r.M[a][b] = lin.E[row][f + speeds[b]];
      r.Q[a][b] = lin.A[row][f + speeds[b]].is_zero() ? ex(0) : ex(-lin.A[row][f + speeds[b]]);
      r.K[a][b] = lin.A[row][coordinate_of[speeds[b]]].is_zero() ? ex(0) : ex(-lin.A[row][coordinate_of[speeds[b]]]);
    }
    for (std::size_t u = 0; u < m; ++u) r.B[a][u] = lin.Bx[row][u];
  }
  return r;
}

}  // namespace mbsgen

namespace mbsgen {

namespace {

// The parameters and powers of a monomial p1^k1 p2^k2 ... (empty for 1); false when it is not one.
bool monomial_powers(const Equations& eq, const ex& m, std::vector<std::pair<ex, int>>& out) {
  auto parameter = [&](const ex& x) { return std::find(eq.p.begin(), eq.p.end(), x) != eq.p.end(); };
  auto factor = [&](const ex& f) {
    if (GiNaC::is_a<GiNaC::symbol>(f) && parameter(f)) return out.push_back({f, 1}), true;
    if (GiNaC::is_a<GiNaC::power>(f) && GiNaC::is_a<GiNaC::symbol>(f.op(0)) && parameter(f.op(0)) &&
        f.op(1).info(GiNaC::info_flags::posint))
      return out.push_back({f.op(0), GiNaC::ex_to<GiNaC::numeric>(f.op(1)).to_int()}), true;
    return false;
  };
  if (m.is_equal(1)) return true;
  if (GiNaC::is_a<GiNaC::mul>(m)) {
    for (std::size_t i = 0; i < m.nops(); ++i)
      if (!factor(m.op(i))) return false;
    return true;
  }
  return factor(m);
}

// The coefficient of `powers` in the expression e (Taylor coefficient at zero of `zero`).
ex taylor_coefficient(Program& prog, ex e, const std::vector<std::pair<ex, int>>& powers, const GiNaC::exmap& zero) {
  GiNaC::numeric factorial = 1;
  for (const auto& [p, k] : powers)
    for (int i = 0; i < k; ++i) e = prog.diff(e, GiNaC::ex_to<GiNaC::symbol>(p)), factorial *= i + 1;
  Program::Substitution at_zero(zero);
  return prog.define(prog.substitute(e, at_zero) / factorial);
}

// Each matrix with named parts equals their sum, Σ monomial_i · C_i, at two pseudo-random points.
void check_named_parts(Equations& eq, const LinearEquations& lin, Program::Substitution& at_op) {
  const auto& parts = eq.model->reduced_coefficients();
  Program& prog = eq.program;
  const std::size_t n = lin.reduced.M.size();
  for (char c : {'M', 'Q', 'K'}) {
    const ExMatrix& X = c == 'M' ? lin.reduced.M : c == 'Q' ? lin.reduced.Q : lin.reduced.K;
    std::vector<ex> remainder, size;
    bool named = false;
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = 0; b < n; ++b) {
        ex r = X[a][b].is_zero() ? ex(0) : prog.substitute(X[a][b], at_op);
        size.push_back(r);
        for (std::size_t i = 0; i < parts.size(); ++i)
          if (parts[i].matrix == c) named = true, r -= parts[i].monomial * lin.reduced.named[i][a][b];
        remainder.push_back(prog.define(r));
      }
    if (!named) continue;
    const long digits = GiNaC::Digits;
    GiNaC::Digits = detail::PointEvaluator::kDigits;
    std::uint64_t state = 0x51ed2701f3a5c9b3ULL;
    for (int point = 0; point < 2; ++point) {
      const GiNaC::exmap values = detail::sample_point(eq, lin, state, false);
      // One evaluation of the remainders and the entries (they share their intermediates).
      std::vector<ex> entries = remainder;
      entries.insert(entries.end(), size.begin(), size.end());
      const auto v = detail::PointEvaluator(prog, values).evaluate(entries);
      const std::size_t count = remainder.size();
      GiNaC::numeric worst = 0, scale = 0;
      for (std::size_t k = 0; k < count; ++k)
        worst = std::max(worst, GiNaC::abs(v[k])), scale = std::max(scale, GiNaC::abs(v[count + k]));
      if (worst > scale * GiNaC::numeric(10).power(-30)) {
        GiNaC::Digits = digits;
        std::string list;
        for (const auto& p : parts)
          if (p.matrix == c) {
            std::ostringstream m;
            m << p.monomial;
            list += (list.empty() ? "" : " + ") + p.name + "·" + m.str();
          }
        throw ModelError(parts.front().where, std::string("the reduced ") + c + " is not the sum of its named parts (" + list +
                                                  "): a remainder of " + format(worst.to_double()) + " of " +
                                                  format(scale.to_double()) + " at a pseudo-random point");
      }
    }
    GiNaC::Digits = digits;
  }
}

}  // namespace

void name_reduced_parts(Equations& eq, LinearEquations& lin) {
  const Model& model = *eq.model;
  const auto& parts = model.reduced_coefficients();
  if (parts.empty()) return;
  if (!lin.reduced.exists)
    throw ModelError(parts.front().where, "the model names parts of its reduced second-order form, but it has none (no "
                                          "coordinates whose equations close on themselves)");
  Program& prog = eq.program;
  // The operating point: the independent coordinates' positions and every rate (in parameters).
  GiNaC::exmap op;
  for (std::size_t k = 0; k < eq.y.size(); ++k) {
    if (!std::binary_search(eq.loops.dependent.begin(), eq.loops.dependent.end(), k)) op[eq.y[k]] = lin.y0[k];
    op[eq.yd[k]] = lin.yd0[k];
  }
  Program::Substitution at_op(op);
  std::map<char, GiNaC::exmap> zero;  // per matrix: its monomials' parameters at 0
  std::vector<std::vector<std::pair<ex, int>>> powers(parts.size());
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (!monomial_powers(eq, parts[i].monomial, powers[i]))
      throw ModelError(parts[i].where, "reduced-form part '" + parts[i].name +
                                           "': the monomial must be a product of powers of parameters (v, g, v^2, g*v)");
    for (const auto& [p, k] : powers[i]) {
      zero[parts[i].matrix][p] = 0;
      for (const auto& e : eq.loops.equations)
        if (!prog.diff(e.phi, GiNaC::ex_to<GiNaC::symbol>(p)).is_zero())
          throw ModelError(parts[i].where, "reduced-form part '" + parts[i].name + "': constraint '" + e.constraint +
                                               "' depends on the monomial's parameter, so the matrices are not polynomials in it");
    }
  }
  auto matrix = [&](char c) -> const ExMatrix& { return c == 'M' ? lin.reduced.M : c == 'Q' ? lin.reduced.Q : lin.reduced.K; };
  const std::size_t n = lin.reduced.M.size();
  for (std::size_t i = 0; i < parts.size(); ++i) {
    ExMatrix C = zeros(n, n);
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = 0; b < n; ++b) {
        const ex x = matrix(parts[i].matrix)[a][b];
        if (!x.is_zero()) C[a][b] = taylor_coefficient(prog, prog.define(prog.substitute(x, at_op)), powers[i], zero[parts[i].matrix]);
      }
    lin.reduced.named.push_back(C);
  }
  check_named_parts(eq, lin, at_op);
}

}  // namespace mbsgen
