// Stage 2b: prescribed motion (prescribed_motion.hpp).
#include "mbsgen/generator/mechanics/prescribed_motion.hpp"

#include "mbsgen/generator/mechanics/dynamics.hpp"

namespace mbsgen {

using GiNaC::ex;

namespace {

bool moves(const Marker& m, const std::vector<GiNaC::symbol>& motion) {
  for (const auto& s : motion) {
    for (const auto& x : m.position)
      if (x.has(s)) return true;
    for (const auto& row : m.rotation)
      for (const auto& x : row)
        if (x.has(s)) return true;
  }
  return false;
}

}  // namespace

// A name no body, marker, force or output of the model has (a friend of Model).
std::string fresh_body(const Model& model, std::string base) {
  while (model.element_names_.count(base)) base += "_";
  return base;
}

// The motion inputs become coordinates after the model's own (their symbols and rates are the
// inputs'), and leave the inputs; a marker on the world that moves with them is carried by a
// massless body of its own, driven by them, appended after the model's bodies.
Model with_motion_coordinates(const Model& model) {
  Model moving = model;
  moving.inputs_.clear();
  moving.input_symbols_.clear();
  std::vector<GiNaC::symbol> motion;
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    const Input& in = model.inputs()[i];
    if (!in.motion) {
      moving.inputs_.push_back(in);
      moving.input_symbols_.push_back(model.input_symbols()[i]);
      continue;
    }
    motion.push_back(model.input_symbols()[i]);
    moving.coordinates_.push_back({in.name, in.unit, model.input_symbols()[i], in.rate, in.where});
  }
  for (Marker& m : moving.markers_) {
    if (m.body != kWorld || !moves(m, motion)) continue;
    Body carrier;
    carrier.name = fresh_body(moving, "support_of_" + m.name);
    carrier.translation = m.position;
    carrier.rotation_matrix = m.rotation;
    carrier.where = m.where;
    m.body = carrier.name;
    m.position = zero_vec3();
    m.rotation = identity_mat3();
    moving.add_body(carrier);
  }
  return moving;
}

void split_prescribed_motion(const Model& model, std::size_t bodies, Equations& eq) {
  Program& prog = eq.program;
  const std::size_t n = model.coordinates().size(), all = eq.y.size();
  PrescribedMotion& pm = eq.motion;
  pm.active = true;
  GiNaC::exmap zero;
  for (std::size_t c = n; c < all; ++c) {
    zero[eq.y[c]] = 0;
    zero[eq.yd[c]] = 0;
    pm.rates.push_back(eq.yd[c]);
  }
  // The inputs in the model's order; the motion coordinates follow the motion inputs' order.
  eq.u = model.input_symbols();
  for (std::size_t i = 0; i < model.inputs().size(); ++i)
    if (model.inputs()[i].motion) pm.inputs.push_back(i);

  pm.M.assign(n, std::vector<ex>(all - n, 0));
  for (std::size_t j = 0; j < n; ++j)
    for (std::size_t c = n; c < all; ++c) pm.M[j][c - n] = eq.M[j][c];
  pm.residual.assign(eq.residual.begin(), eq.residual.begin() + static_cast<long>(n));
  pm.outputs = eq.outputs;

  Program::Substitution sub(zero);
  // The equations at the support's rest, without the motion coordinates and the carrier bodies
  // of moving markers on the world (appended after the model's).
  for (ExMatrix* J : {&eq.JT, &eq.JR}) J->resize(3 * bodies);
  eq.kinematics.bodies.resize(bodies);
  restrict_equations(eq, n, [&](const ex& e) { return prog.substitute(e, sub); });
}

}  // namespace mbsgen
