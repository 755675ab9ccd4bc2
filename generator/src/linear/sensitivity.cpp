#include "mbsgen/generator/linear/sensitivity.hpp"

#include "linear/sample_points.hpp"
#include "symbolic/zero_proof.hpp"

#include <algorithm>
#include <stdexcept>

namespace mbsgen {

using GiNaC::ex;

namespace {

// The matrices of the linear model that exist for this model, with their structural zeros.
std::vector<std::pair<const ExMatrix*, MatrixDerivative>> linear_matrices(const LinearEquations& lin,
                                                                         std::size_t f, std::size_t m,
                                                                         std::size_t r) {
  std::vector<std::pair<const ExMatrix*, MatrixDerivative>> out;
  auto add = [&](const char* name, const ExMatrix& A, std::size_t rows, std::size_t cols, const ZeroPattern& z) {
    MatrixDerivative d;
    d.name = name, d.rows = rows, d.cols = cols, d.zeros = &z;
    out.emplace_back(&A, std::move(d));
  };
  add("M", lin.M, f, f, lin.zeros.M);
  add("Q", lin.Q, f, f, lin.zeros.Q);
  add("K", lin.K, f, f, lin.zeros.K);
  add("B", lin.B, f, m, lin.zeros.B);
  add("Cy", lin.Cy, r, f, lin.zeros.Cy);
  add("Cv", lin.Cv, r, f, lin.zeros.Cv);
  if (!lin.Ca.empty()) {
    add("Ca", lin.Ca, r, f, lin.zeros.Ca);
    add("D", lin.Du, r, m, lin.zeros.Du);
  }
  if (!lin.B1.empty()) {
    add("B1", lin.B1, f, m, lin.zeros.B1);
    add("B2", lin.B2, f, m, lin.zeros.B2);
    add("D1", lin.D1, r, m, lin.zeros.D1);
  }
  return out;
}

// Replaces the partial derivatives that are zero for every argument by exact zeros. A candidate
// is a derivative whose size p_j·|∂A/∂p_j| is below 1e-30 of the matrix's largest entry at both
// sample points (50 digits: the same screen and margin as structural_zeros.hpp); only a symbolic
// proof makes it 0. A point where the evaluation fails (a pole) screens nothing out.
void screen_zeros(Equations& eq, const LinearEquations& lin, LinearSensitivity& s,
                  const std::vector<std::pair<const ExMatrix*, MatrixDerivative>>& mats) {
  detail::SamplePoints points(eq, lin);
  const long digits = GiNaC::Digits;
  GiNaC::Digits = detail::PointEvaluator::kDigits;
  const std::size_t np = s.parameters.size();
  for (std::size_t a = 0; a < mats.size(); ++a) {
    MatrixDerivative& d = s.matrices[a];
    const ExMatrix& A = *mats[a].first;
    // Only the entries of A that are nonzero at the operating point: one that vanishes there
    // (structural_zeros.hpp) is rounding noise at the sample points, a scale that would make the
    // screen's verdicts depend on the order of the sums (GiNaC's, from run to run); its
    // derivative is a conditional zero of the kernel already.
    auto nonzero = [&](std::size_t i, std::size_t c) {
      return d.zeros->empty() || (*d.zeros)[i][c] == EntryZero::nonzero;
    };
    std::vector<ex> entries;  // those entries of A, then the parameters, then their nonzero derivatives
    for (std::size_t i = 0; i < d.rows; ++i)
      for (std::size_t c = 0; c < d.cols; ++c)
        if (nonzero(i, c)) entries.push_back(A[i][c]);
    const std::size_t n_a = entries.size();
    for (std::size_t j : s.parameters) entries.push_back(eq.p[j]);
    std::vector<std::size_t> at;
    for (std::size_t k = 0; k < d.values.size(); ++k) {
      const std::size_t within = k % (d.rows * d.cols);
      if (!d.values[k].is_zero() && nonzero(within % d.rows, within / d.rows)) at.push_back(k), entries.push_back(d.values[k]);
    }
    if (at.empty()) continue;
    std::vector<bool> small(at.size(), true);
    try {
      for (std::size_t point = 0; point < 2; ++point) {
        const std::vector<GiNaC::numeric> v = points.evaluate(false, point, entries);
        GiNaC::numeric scale = 0;
        for (std::size_t k = 0; k < n_a; ++k) scale = std::max(scale, GiNaC::abs(v[k]));
        const GiNaC::numeric tol = scale * GiNaC::numeric(1, 1000000) * GiNaC::numeric(10).power(-24);
        for (std::size_t k = 0; k < at.size(); ++k) {
          const std::size_t j = at[k] / (d.rows * d.cols);
          small[k] = small[k] && GiNaC::abs(v[n_a + j] * v[n_a + np + k]) <= tol;
        }
      }
    } catch (const std::exception&) {
      small.assign(at.size(), false);
    }
    for (std::size_t k = 0; k < at.size(); ++k) {
      if (!small[k]) continue;
      if (proved_zero(eq.program, d.values[at[k]])) {
        d.values[at[k]] = 0;
        ++s.proved_zero;
      } else {
        ++s.unproved;
      }
    }
  }
  GiNaC::Digits = digits;
}

// The substitution of the operating point's fixed values into the residual (u = 0, ÿ = 0, the
// motion inputs' rates and the rates fixed at zero), as linearize() takes it.
Program::Substitution operating_point_substitution(const Equations& eq, const LinearEquations& lin) {
  GiNaC::exmap at_op;
  for (const auto& x : eq.u) at_op[x] = 0;
  for (const auto& x : eq.ydd) at_op[x] = 0;
  for (const auto& x : eq.motion.rates) at_op[x] = 0;
  for (std::size_t k : lin.zero_rates) at_op[eq.yd[k]] = 0;
  return Program::Substitution(at_op);
}

// The terms of a moving operating point: Σ_k ∂A/∂y_k dy0_kj + Σ_k ∂A/∂ẏ_k dẏ0_kj, and the
// operating point's own derivatives (operating_point_sensitivity).
void add_moving_point(Equations& eq, const LinearEquations& lin, LinearSensitivity& s,
                      const std::vector<std::pair<const ExMatrix*, MatrixDerivative>>& mats) {
  Program& prog = eq.program;
  const std::size_t f = eq.y.size(), np = s.parameters.size();
  for (std::size_t j = 0; j < np; ++j)
    for (std::size_t k = 0; k < f; ++k) {
      s.dy0.emplace_back("sens_dy0_" + std::to_string(k) + "_" + std::to_string(j));
      s.dyd0.emplace_back("sens_dyd0_" + std::to_string(k) + "_" + std::to_string(j));
    }
  std::vector<std::size_t> free_rates;  // rates that are arguments of the linear kernels
  if (!lin.at_rest)
    for (std::size_t k = 0; k < f; ++k)
      if (std::find(lin.zero_rates.begin(), lin.zero_rates.end(), k) == lin.zero_rates.end()) free_rates.push_back(k);
  for (std::size_t a = 0; a < mats.size(); ++a) {
    const ExMatrix& A = *mats[a].first;
    MatrixDerivative& d = s.matrices[a];
    for (std::size_t c = 0; c < d.cols; ++c)
      for (std::size_t r = 0; r < d.rows; ++r) {
        if (A[r][c].is_zero()) continue;
        const ex e = prog.define(A[r][c]);
        for (std::size_t k = 0; k < f; ++k)
          if (prog.depends_on(e, eq.y[k])) {
            const ex dk = prog.diff(e, eq.y[k]);
            for (std::size_t j = 0; j < np; ++j) d.values[j * d.rows * d.cols + c * d.rows + r] += dk * s.dy0[j * f + k];
          }
        for (std::size_t k : free_rates)
          if (prog.depends_on(e, eq.yd[k])) {
            const ex dk = prog.diff(e, eq.yd[k]);
            for (std::size_t j = 0; j < np; ++j) d.values[j * d.rows * d.cols + c * d.rows + r] += dk * s.dyd0[j * f + k];
          }
      }
  }
  // The operating point's derivatives: of the given expressions, or, for an equilibrium,
  // ∂r/∂p_j + Q dẏ0/dp_j (the runtime solves K dy0/dp_j = −that).
  Program::Substitution sub = operating_point_substitution(eq, lin);
  for (std::size_t j = 0; j < np; ++j) {
    const GiNaC::symbol& pj = eq.p[s.parameters[j]];
    std::vector<ex> rates(f);
    for (std::size_t k = 0; k < f; ++k) rates[k] = prog.diff(lin.yd0[k], pj);
    for (std::size_t k = 0; k < f; ++k) {
      if (!lin.equilibrium) {
        s.op_first.push_back(prog.diff(lin.y0[k], pj));
        continue;
      }
      ex first = prog.diff(prog.define(prog.substitute(eq.residual[k], sub)), pj);
      for (std::size_t l = 0; l < f; ++l)
        if (!rates[l].is_zero()) first += lin.Q[k][l] * rates[l];
      s.op_first.push_back(first);
    }
    s.op_rates.insert(s.op_rates.end(), rates.begin(), rates.end());
  }
}

}  // namespace

LinearSensitivity linear_sensitivity(Equations& eq, const LinearEquations& lin, std::vector<std::size_t> parameters) {
  if (eq.loops.active || eq.nonholonomic.active || lin.descriptor)
    throw std::invalid_argument(
        "parameter sensitivities are not available for a model with closed loops or rolling constraints: its "
        "linear model depends on the parameters also through the dependent coordinates that Newton's method finds "
        "(drop `sensitivity` from the scene's analyses)");
  if (parameters.empty())
    for (std::size_t j = 0; j < eq.p.size(); ++j) parameters.push_back(j);
  LinearSensitivity s;
  s.active = true;
  s.parameters = parameters;
  Program& prog = eq.program;
  const std::size_t f = lin.M.size(), m = eq.u.size(), r = eq.outputs.size(), np = parameters.size();
  auto mats = linear_matrices(lin, f, m, r);
  for (auto& [A, d] : mats) {
    d.values.assign(np * d.rows * d.cols, 0);
    for (std::size_t c = 0; c < d.cols; ++c)
      for (std::size_t i = 0; i < d.rows; ++i) {
        if ((*A)[i][c].is_zero()) continue;
        // Named first, as linearize() names the residual: the chain rule then runs through the
        // program's intermediates in their canonical order, not GiNaC's operand order (which
        // follows hashes that differ from run to run).
        const ex x = prog.define((*A)[i][c]);
        for (std::size_t j = 0; j < np; ++j)
          if (prog.depends_on(x, eq.p[parameters[j]]))
            d.values[j * d.rows * d.cols + c * d.rows + i] = prog.diff(x, eq.p[parameters[j]]);
      }
    s.matrices.push_back(d);
  }
  screen_zeros(eq, lin, s, mats);

  s.moving_point = lin.equilibrium;
  for (std::size_t k = 0; k < f && !s.moving_point; ++k)
    for (std::size_t j : parameters)
      s.moving_point = s.moving_point || lin.y0[k].has(eq.p[j]) || lin.yd0[k].has(eq.p[j]);
  if (s.moving_point) add_moving_point(eq, lin, s, mats);
  return s;
}

}  // namespace mbsgen
