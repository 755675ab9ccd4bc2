#include "mbsgen/generator/linearize.hpp"

namespace mbsgen {

using GiNaC::ex;

LinearEquations linearize(Equations& eq) {
  const Model& model = *eq.model;
  Program& prog = eq.program;
  LinearEquations lin;
  const std::size_t f = eq.y.size(), m = eq.u.size(), r = eq.outputs.size();

  const OperatingPoint& op = model.operating_point();
  lin.equilibrium = op.kind == OperatingPoint::Kind::equilibrium;
  for (const auto& c : model.coordinates()) {
    auto p = op.position.find(c.name);
    lin.y0.push_back(p == op.position.end() ? ex(0) : p->second);
    auto v = op.velocity.find(c.name);
    lin.yd0.push_back(v == op.velocity.end() ? ex(0) : v->second);
    if (!lin.yd0.back().is_zero()) lin.at_rest = false;
  }

  // The operating point has u = 0 and, at rest, ẏ = 0: substituted through the program so that
  // every term that vanishes there (gyroscopic, centrifugal, damping forces) drops out.
  GiNaC::exmap at_op;
  for (const auto& s : eq.u) at_op[s] = 0;
  if (lin.at_rest)
    for (const auto& s : eq.yd) at_op[s] = 0;
  Program::Substitution sub(at_op);
  auto at = [&](const ex& e) { return prog.substitute(e, sub); };

  std::vector<ex> residual_at_rest(f);
  for (std::size_t i = 0; i < f; ++i) residual_at_rest[i] = prog.define(at(eq.residual[i]));

  lin.M = eq.M;
  lin.Q.assign(f, std::vector<ex>(f, 0));
  lin.K.assign(f, std::vector<ex>(f, 0));
  lin.B.assign(f, std::vector<ex>(m, 0));
  for (std::size_t i = 0; i < f; ++i) {
    ex ri = prog.define(eq.residual[i]);
    for (std::size_t j = 0; j < f; ++j) {
      lin.Q[i][j] = at(prog.diff(ri, eq.yd[j]));
      // ∂/∂y commutes with setting ẏ = 0 and u = 0, which are independent of y.
      lin.K[i][j] = prog.diff(residual_at_rest[i], eq.y[j]);
    }
    for (std::size_t j = 0; j < m; ++j) lin.B[i][j] = -at(prog.diff(ri, eq.u[j]));
  }
  lin.Cy.assign(r, std::vector<ex>(f, 0));
  lin.Cv.assign(r, std::vector<ex>(f, 0));
  for (std::size_t i = 0; i < r; ++i) {
    ex zi = prog.define(eq.outputs[i]);
    for (std::size_t j = 0; j < f; ++j) {
      lin.Cy[i][j] = at(prog.diff(zi, eq.y[j]));
      lin.Cv[i][j] = at(prog.diff(zi, eq.yd[j]));
    }
  }
  auto split = [&](const ExMatrix& A, ExMatrix& S, ExMatrix& W) {
    S.assign(f, std::vector<ex>(f, 0));
    W.assign(f, std::vector<ex>(f, 0));
    for (std::size_t i = 0; i < f; ++i)
      for (std::size_t j = 0; j < f; ++j) {
        S[i][j] = (A[i][j] + A[j][i]) / 2;
        W[i][j] = (A[i][j] - A[j][i]) / 2;
      }
  };
  split(lin.Q, lin.D, lin.G);
  split(lin.K, lin.Ks, lin.N);
  return lin;
}

}  // namespace mbsgen
