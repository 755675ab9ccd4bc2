#include "mbsgen/generator/linear/linearize.hpp"

#include "linear/sample_points.hpp"
#include "symbolic/zero_proof.hpp"

#include <algorithm>
#include <cstdint>
#include <unordered_map>

namespace mbsgen {

using GiNaC::ex;

namespace {

struct Structure {
  bool D_zero = false, G_zero = false, N_zero = false;
};

// Whether sym Q, skew Q and skew K vanish identically: as functions of all the kernels'
// arguments (y0, ẏ0, p), or, with at_operating_point, of the parameters p with (y0, ẏ0) the
// operating point (y0 free for an equilibrium, which Newton's method finds). They are evaluated
// at two pseudo-random points with 50 digits and called zero when every entry is below 1e-35 of
// the largest entry of Q and K at both points. A nonzero analytic function vanishes only on a set
// of measure zero, and 15 digits of margin cover the cancellation in the sums, so the test errs
// in neither direction in practice; a point where the evaluation fails (a pole) gives
// "nonzero", the safe answer. A numerical "zero" is then proved symbolically entry by entry
// (structural_zeros.hpp), so that a part 1e-40 of the rest is not taken for zero.
Structure structure_of(Equations& eq, const LinearEquations& lin, bool at_operating_point,
                       detail::SamplePoints& points) {
  const std::size_t f = lin.Q.size();
  // Only entries that are not exact zeros are evaluated (a large model's matrices are mostly
  // zeros: evaluating all f^2 of them dominated mbsgen check of 2,000 oscillators).
  std::vector<ex> entries;
  std::vector<std::size_t> slot(2 * f * f, SIZE_MAX);
  for (std::size_t m = 0; m < 2; ++m) {
    const ExMatrix& A = m == 0 ? lin.Q : lin.K;
    for (std::size_t i = 0; i < f; ++i)
      for (std::size_t j = 0; j < f; ++j)
        if (!A[i][j].is_zero()) {
          slot[m * f * f + i * f + j] = entries.size();
          entries.push_back(A[i][j]);
        }
  }
  Structure s{true, true, true};
  const long digits = GiNaC::Digits;
  GiNaC::Digits = detail::PointEvaluator::kDigits;
  try {
    for (std::size_t point = 0; point < 2; ++point) {
      const std::vector<GiNaC::numeric> v = points.evaluate(at_operating_point, point, entries);
      const GiNaC::numeric zero = 0;
      auto at = [&](std::size_t matrix, std::size_t i, std::size_t j) -> const GiNaC::numeric& {
        const std::size_t k = slot[matrix * f * f + i * f + j];
        return k == SIZE_MAX ? zero : v[k];
      };
      // One scale for Q and K: Q of an undamped model at rest vanishes as a whole, and a
      // tolerance relative to its largest entry, rounding noise, decided by the luck of the rounding.
      GiNaC::numeric scale = 0;
      for (const GiNaC::numeric& x : v) scale = std::max(scale, GiNaC::abs(x));
      for (std::size_t matrix = 0; matrix < 2; ++matrix) {
        GiNaC::numeric sym = 0, skew = 0;
        for (std::size_t i = 0; i < f; ++i)
          for (std::size_t j = 0; j < f; ++j) {
            if (slot[matrix * f * f + i * f + j] == SIZE_MAX && slot[matrix * f * f + j * f + i] == SIZE_MAX)
              continue;  // both exact zeros: no contribution
            sym = std::max(sym, GiNaC::abs(at(matrix, i, j) + at(matrix, j, i)));
            skew = std::max(skew, GiNaC::abs(at(matrix, i, j) - at(matrix, j, i)));
          }
        const GiNaC::numeric tol = scale * GiNaC::numeric(1, 100000) * GiNaC::numeric(10).power(-30);
        if (matrix == 0) {
          s.D_zero = s.D_zero && sym <= tol;
          s.G_zero = s.G_zero && skew <= tol;
        } else {
          s.N_zero = s.N_zero && skew <= tol;
        }
      }
    }
  } catch (const std::exception&) {
    s = Structure{};
  }
  GiNaC::Digits = digits;
  // The screen's "zero" is a candidate; only a symbolic proof of every entry makes it so (a part
  // 1e-40 of the rest is not zero).
  GiNaC::exmap op_values;
  if (at_operating_point)
    for (std::size_t k = 0; k < eq.y.size(); ++k) {
      if (!lin.equilibrium && !eq.loops.active) op_values[eq.y[k]] = lin.y0[k];
      op_values[eq.yd[k]] = lin.yd0[k];
    }
  Program::Substitution op(op_values);
  auto proved = [&](const ExMatrix& A, int sign) {
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    for (std::size_t i = 0; i < f; ++i)
      for (std::size_t j = 0; j <= i; ++j)
        if (!(A[i][j].is_zero() && A[j][i].is_zero())) pairs.emplace_back(i, j);
    return all_proved_zero(eq.program, pairs.size(), [&](std::size_t k) {
      const ex e = A[pairs[k].first][pairs[k].second] + sign * A[pairs[k].second][pairs[k].first];
      return at_operating_point ? eq.program.substitute(e, op) : e;
    });
  };
  s.D_zero = s.D_zero && proved(lin.Q, 1);
  s.G_zero = s.G_zero && proved(lin.Q, -1);
  s.N_zero = s.N_zero && proved(lin.K, -1);
  return s;
}

}  // namespace

namespace {

// Prescribed motion (prescribed_motion.hpp): the motion inputs' columns of B (B0), B1 and B2, and
// of the outputs' D (D0) and D1, at the operating point (where u = u̇ = 0).
void linearize_motion(Equations& eq, LinearEquations& lin, Program::Substitution& sub, ExMatrix& Ca,
                      ExMatrix& Du) {
  Program& prog = eq.program;
  const PrescribedMotion& pm = eq.motion;
  const std::size_t f = eq.y.size(), m = eq.u.size(), r = pm.outputs.size();
  lin.B1.assign(f, std::vector<ex>(m, 0));
  lin.B2.assign(f, std::vector<ex>(m, 0));
  lin.D1.assign(r, std::vector<ex>(m, 0));
  if (Du.empty()) {
    Ca.assign(r, std::vector<ex>(f, 0));
    Du.assign(r, std::vector<ex>(m, 0));
  }
  for (std::size_t i = 0; i < f; ++i) {
    const ex ri = prog.define(pm.residual[i]);
    for (std::size_t k = 0; k < pm.inputs.size(); ++k) {
      const std::size_t j = pm.inputs[k];
      lin.B[i][j] = -prog.diff_at(ri, eq.u[j], sub);
      lin.B1[i][j] = -prog.diff_at(ri, pm.rates[k], sub);
      lin.B2[i][j] = -prog.substitute(pm.M[i][k], sub);
    }
  }
  for (std::size_t i = 0; i < r; ++i) {
    const ex zi = prog.define(pm.outputs[i]);
    for (std::size_t k = 0; k < pm.inputs.size(); ++k) {
      const std::size_t j = pm.inputs[k];
      Du[i][j] = prog.diff_at(zi, eq.u[j], sub);
      lin.D1[i][j] = prog.diff_at(zi, pm.rates[k], sub);
    }
  }
}

}  // namespace

// The tree's M, Q, K, B, C_y, C_v (and C_a, D) at the operating point, reduced to the
// independent coordinates when the loops are closed (at rest).
void linearize_tree(Equations& eq, LinearEquations& lin, std::size_t f) {  // f = n here
  const Model& model = *eq.model;
  Program& prog = eq.program;
  const std::size_t m = eq.u.size(), r = eq.outputs.size();
  // The operating point has u = 0 and, at rest, ẏ = 0: substituted through the program so that
  // every term that vanishes there (gyroscopic, centrifugal, damping forces) drops out. A scene
  // (apply_scene) also fixes the rates its steady motion sets to zero (a spinning rotor's tilt
  // rates), so that only the nonzero rates remain arguments of the kernels.
  GiNaC::exmap at_op;
  for (const auto& s : eq.u) at_op[s] = 0;
  for (const auto& s : eq.ydd) at_op[s] = 0;
  for (const auto& s : eq.motion.rates) at_op[s] = 0;
  for (std::size_t k = 0; k < f; ++k)
    if (lin.at_rest || (!model.selection().full && lin.yd0[k].is_zero())) {
      at_op[eq.yd[k]] = 0;
      lin.zero_rates.push_back(k);
    }
  Program::Substitution sub(at_op);
  auto at = [&](const ex& e) { return prog.substitute(e, sub); };

  // With closed loops the tree is linearized first, then reduced (loop_closure.hpp).
  const bool loops = eq.loops.active;
  const std::vector<ex>& residual = loops ? eq.tree.residual : eq.residual;
  const std::vector<ex>& outputs = loops ? eq.tree.outputs : eq.outputs;
  std::vector<ex> residual_at_rest(f);
  for (std::size_t i = 0; i < f; ++i) residual_at_rest[i] = prog.define(at(residual[i]));

  lin.M = loops ? eq.tree.M : eq.M;
  lin.Q.assign(f, std::vector<ex>(f, 0));
  lin.K.assign(f, std::vector<ex>(f, 0));
  lin.B.assign(f, std::vector<ex>(m, 0));
  for (std::size_t i = 0; i < f; ++i) {
    ex ri = prog.define(residual[i]);
    for (std::size_t j = 0; j < f; ++j) {
      lin.Q[i][j] = prog.diff_at(ri, eq.yd[j], sub);
      // ∂/∂y commutes with setting ẏ = 0 and u = 0, which are independent of y.
      lin.K[i][j] = prog.diff(residual_at_rest[i], eq.y[j]);
    }
    for (std::size_t j = 0; j < m; ++j) lin.B[i][j] = -prog.diff_at(ri, eq.u[j], sub);
  }
  lin.Cy.assign(r, std::vector<ex>(f, 0));
  lin.Cv.assign(r, std::vector<ex>(f, 0));
  ExMatrix Ca(eq.ydd.empty() ? 0 : r, std::vector<ex>(f, 0)), Du(eq.ydd.empty() ? 0 : r, std::vector<ex>(m, 0));
  for (std::size_t i = 0; i < r; ++i) {
    ex zi = prog.define(outputs[i]);
    for (std::size_t j = 0; j < f; ++j) {
      lin.Cy[i][j] = prog.diff_at(zi, eq.y[j], sub);
      lin.Cv[i][j] = prog.diff_at(zi, eq.yd[j], sub);
    }
    if (eq.ydd.empty()) continue;  // only reaction outputs depend on ÿ and u
    for (std::size_t j = 0; j < f; ++j) Ca[i][j] = prog.diff_at(zi, eq.ydd[j], sub);
    for (std::size_t j = 0; j < m; ++j) Du[i][j] = prog.diff_at(zi, eq.u[j], sub);
  }
  if (eq.motion.active) linearize_motion(eq, lin, sub, Ca, Du);
  for (std::size_t k = 0; k < f; ++k) lin.coordinates.push_back(k);
  if (loops) {
    reduce_linear(eq, residual_at_rest, lin.M, lin.Q, lin.K, lin.B, lin.Cy, lin.Cv);
    Ca = reduce_columns(eq, Ca);
    lin.coordinates = eq.loops.independent;
  }
  // C_a and D_u: kept only when some entry can be nonzero.
  bool any = false;
  for (const ExMatrix* A : {&Ca, &Du})
    for (const auto& row : *A)
      for (const auto& x : row) any = any || !x.is_zero();
  if (any) lin.Ca = Ca, lin.Du = Du;
}

LinearEquations linearize(Equations& eq) {
  const Model& model = *eq.model;
  LinearEquations lin;
  std::size_t f = eq.y.size();

  const LinearizationPoint& op = model.operating_point();
  lin.equilibrium = op.kind == LinearizationPoint::Kind::equilibrium;
  for (const auto& c : model.coordinates()) {
    auto p = op.position.find(c.name);
    lin.y0.push_back(p == op.position.end() ? ex(0) : p->second);
    auto v = op.velocity.find(c.name);
    lin.yd0.push_back(v == op.velocity.end() ? ex(0) : v->second);
    if (!lin.yd0.back().is_zero()) lin.at_rest = false;
  }

  if (eq.nonholonomic.active || (eq.loops.active && !lin.at_rest)) {
    // Rolling wheels, or closed loops in steady motion (nonholonomic.hpp).
    linearize_constrained(eq, lin);
    if (lin.descriptor) {
      lin.zeros = find_structural_zeros(eq, lin);
      lin.reduced = reduced_form(lin);
      name_reduced_parts(eq, lin);
      return lin;
    }
  } else {
    linearize_tree(eq, lin, f);
  }
  f = lin.coordinates.size();
  auto split = [&](const ExMatrix& A, ExMatrix& S, ExMatrix& W) {
    S.assign(f, std::vector<ex>(f, 0));
    W.assign(f, std::vector<ex>(f, 0));
    for (std::size_t i = 0; i < f; ++i)
      for (std::size_t j = 0; j < f; ++j) {
        if (A[i][j].is_zero() && A[j][i].is_zero()) continue;  // S and W stay 0
        S[i][j] = (A[i][j] + A[j][i]) / 2;
        W[i][j] = (A[i][j] - A[j][i]) / 2;
      }
  };
  // Identically vanishing parts are written as exact zeros, and the matching symmetry of Q and
  // K is made exact: each pair of entries is then computed once, and the kernels return exactly
  // symmetric (or skew) matrices.
  // The screen of the structural zeros evaluates the program at the same points.
  detail::SamplePoints points(eq, lin);
  const Structure st = structure_of(eq, lin, false, points);
  Structure op_structure = st;
  if (!(st.D_zero && st.G_zero && st.N_zero)) {
    const Structure s = structure_of(eq, lin, true, points);
    op_structure = {st.D_zero || s.D_zero, st.G_zero || s.G_zero, st.N_zero || s.N_zero};
  }
  lin.D_zero = op_structure.D_zero;
  lin.G_zero = op_structure.G_zero;
  lin.N_zero = op_structure.N_zero;
  for (std::size_t i = 0; i < f; ++i)
    for (std::size_t j = 0; j <= i; ++j) {
      if (lin.Q[i][j].is_zero() && lin.Q[j][i].is_zero() && lin.K[i][j].is_zero() && lin.K[j][i].is_zero())
        continue;  // nothing to symmetrize
      if (st.D_zero && st.G_zero) {
        lin.Q[i][j] = lin.Q[j][i] = 0;
      } else if (st.G_zero) {
        lin.Q[i][j] = lin.Q[j][i];
      } else if (st.D_zero) {
        lin.Q[i][j] = i == j ? ex(0) : ex(-lin.Q[j][i]);
      }
      if (st.N_zero) lin.K[i][j] = lin.K[j][i];
    }
  split(lin.Q, lin.D, lin.G);
  split(lin.K, lin.Ks, lin.N);
  lin.zeros = detail::find_structural_zeros(eq, lin, points);
  return lin;
}

}  // namespace mbsgen
