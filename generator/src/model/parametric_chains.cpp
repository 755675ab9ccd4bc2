#include "mbsgen/generator/model/parametric_chains.hpp"

#include <cmath>
#include <string>

namespace mbsgen {

namespace {

void add_chain_scenes(Model& model) {
  Scene undamped;
  undamped.name = "no_damping";
  undamped.description = "modes without the joint dampers";
  undamped.analyses = {Analysis::modes};
  undamped.without = {{"dampers", {}}};
  model.add_scene(undamped);
  Scene weightless;
  weightless.name = "no_gravity";
  weightless.description = "modes and statics without gravity";
  weightless.analyses = {Analysis::modes, Analysis::statics};
  weightless.without = {{"gravity", {}}};
  model.add_scene(weightless);
}

}  // namespace

Model planar_chain(int n) {
  Model model("planar_chain_" + std::to_string(n));
  GiNaC::ex g = model.add_parameter("g", 9.81, "m/s^2");
  std::vector<GiNaC::ex> m, l, k, c;
  for (int i = 1; i <= n; ++i) {
    const std::string s = std::to_string(i);
    m.push_back(model.add_parameter("m" + s, 1.0, "kg"));
    l.push_back(model.add_parameter("l" + s, 0.5, "m"));
    k.push_back(model.add_parameter("k" + s, 10.0, "N m/rad"));
    c.push_back(model.add_parameter("c" + s, 0.1, "N m s/rad"));
  }
  for (int i = 1; i <= n; ++i) model.add_coordinate("q" + std::to_string(i), "rad");
  for (int i = 0; i < n; ++i) {
    Body b;
    b.name = "link" + std::to_string(i + 1);
    b.parent = i == 0 ? std::string(kWorld) : "link" + std::to_string(i);
    if (i > 0) b.translation = {GiNaC::ex(0), -l[static_cast<std::size_t>(i - 1)], GiNaC::ex(0)};
    b.rotations = {{Axis::z, model.coordinates()[static_cast<std::size_t>(i)].position}};
    b.mass = m[static_cast<std::size_t>(i)];
    b.com = {GiNaC::ex(0), -l[static_cast<std::size_t>(i)], GiNaC::ex(0)};
    model.add_body(b);
  }
  model.add_gravity({"gravity", {GiNaC::ex(0), -g, GiNaC::ex(0)}, {}});
  for (int i = 0; i < n; ++i) {
    const Coordinate& q = model.coordinates()[static_cast<std::size_t>(i)];
    const std::string s = std::to_string(i + 1);
    model.add_generalized_force({"joint_spring" + s, q.name, -k[static_cast<std::size_t>(i)] * q.position,
                                 {}, Category::springs});
    model.add_generalized_force({"joint_damper" + s, q.name, -c[static_cast<std::size_t>(i)] * q.velocity,
                                 {}, Category::dampers});
  }
  add_chain_scenes(model);
  return model;
}

Model spatial_chain(int n) {
  Model model("spatial_chain_" + std::to_string(n));
  GiNaC::ex g = model.add_parameter("g", 9.81, "m/s^2");
  GiNaC::ex l = model.add_parameter("l", 0.3, "m");
  GiNaC::ex m = model.add_parameter("m", 0.8, "kg");
  GiNaC::ex Ixx = model.add_parameter("Ixx", 6.0e-3, "kg m^2");
  GiNaC::ex Iyy = model.add_parameter("Iyy", 5.5e-3, "kg m^2");
  GiNaC::ex Izz = model.add_parameter("Izz", 1.0e-3, "kg m^2");
  GiNaC::ex Ixy = model.add_parameter("Ixy", 2.0e-4, "kg m^2");
  GiNaC::ex Ixz = model.add_parameter("Ixz", -1.0e-4, "kg m^2");
  GiNaC::ex Iyz = model.add_parameter("Iyz", 1.5e-4, "kg m^2");
  GiNaC::ex k = model.add_parameter("k", 20.0, "N m/rad");
  GiNaC::ex c = model.add_parameter("c", 0.05, "N m s/rad");
  for (int i = 1; i <= n; ++i) {
    model.add_coordinate("a" + std::to_string(i), "rad");
    model.add_coordinate("b" + std::to_string(i), "rad");
  }
  for (int i = 0; i < n; ++i) {
    Body b;
    b.name = "link" + std::to_string(i + 1);
    b.parent = i == 0 ? std::string(kWorld) : "link" + std::to_string(i);
    if (i > 0) b.translation = {GiNaC::ex(0), GiNaC::ex(0), -l};
    const auto& ca = model.coordinates()[static_cast<std::size_t>(2 * i)];
    const auto& cb = model.coordinates()[static_cast<std::size_t>(2 * i + 1)];
    b.rotations = {{Axis::x, ca.position}, {Axis::y, cb.position}};
    b.mass = m;
    b.com = {GiNaC::ex(0), GiNaC::ex(0), -l / 2};
    b.inertia = {{{Ixx, Ixy, Ixz}, {Ixy, Iyy, Iyz}, {Ixz, Iyz, Izz}}};
    model.add_body(b);
  }
  model.add_gravity({"gravity", {GiNaC::ex(0), GiNaC::ex(0), -g}, {}});
  for (const auto& q : std::vector<Coordinate>(model.coordinates())) {
    model.add_generalized_force({"spring_" + q.name, q.name, -k * q.position, {}, Category::springs});
    model.add_generalized_force({"damper_" + q.name, q.name, -c * q.velocity, {}, Category::dampers});
  }
  add_chain_scenes(model);
  return model;
}

}  // namespace mbsgen

namespace mbsgen {

namespace {

// A uniform slender bar along its body x axis, rotated about z by `angle` relative to `parent`.
void add_bar(Model& model, const std::string& name, const std::string& parent, const Vec3& translation,
             const GiNaC::ex& angle, const GiNaC::ex& mass, const GiNaC::ex& length) {
  Body b;
  b.name = name;
  b.parent = parent;
  b.translation = translation;
  b.rotations = {{Axis::z, angle}};
  b.mass = mass;
  b.com = {length / 2, GiNaC::ex(0), GiNaC::ex(0)};
  b.inertia[1][1] = b.inertia[2][2] = mass * length * length / 12;
  model.add_body(b);
}

void add_marker(Model& model, const std::string& name, const std::string& body, const Vec3& position) {
  Marker m;
  m.name = name;
  m.body = body;
  m.position = position;
  model.add_marker(m);
}

void add_revolute(Model& model, const std::string& name, const std::string& a, const std::string& b) {
  Constraint c;
  c.name = name;
  c.kind = ConstraintKind::revolute;
  c.marker_a = a;
  c.marker_b = b;
  model.add_constraint(c);
}

}  // namespace

Model four_bar_linkage() {
  Model model("four_bar_linkage");
  const double a = 0.4, l1 = 0.1, l2 = 0.35, l3 = 0.25, theta1 = 1.0;
  const GiNaC::ex g = model.add_parameter("g", 9.81, "m/s^2"), A = model.add_parameter("a", a, "m"),
                  L1 = model.add_parameter("l1", l1, "m"), L2 = model.add_parameter("l2", l2, "m"),
                  L3 = model.add_parameter("l3", l3, "m"), m = model.add_parameter("m", 0.3, "kg"),
                  k = model.add_parameter("k", 40.0, "N/m"), L0 = model.add_parameter("L0", 0.1, "m");
  const GiNaC::ex t1 = model.add_coordinate("th1", "rad").position, t2 = model.add_coordinate("th2", "rad").position,
                  t3 = model.add_coordinate("th3", "rad").position;
  add_bar(model, "crank", kWorld, zero_vec3(), t1, m, L1);
  add_bar(model, "coupler", "crank", {L1, GiNaC::ex(0), GiNaC::ex(0)}, t2, m, L2);
  add_bar(model, "rocker", kWorld, {A, GiNaC::ex(0), GiNaC::ex(0)}, t3, m, L3);
  add_marker(model, "coupler_end", "coupler", {L2, GiNaC::ex(0), GiNaC::ex(0)});
  add_marker(model, "rocker_tip", "rocker", {L3, GiNaC::ex(0), GiNaC::ex(0)});
  add_marker(model, "coupler_middle", "coupler", {L2 / 2, GiNaC::ex(0), GiNaC::ex(0)});
  add_marker(model, "anchor", kWorld, {A / 2, GiNaC::ex(0.5), GiNaC::ex(0)});
  model.add_gravity({"gravity", {GiNaC::ex(0), -g, GiNaC::ex(0)}, {}});
  model.add_spring({"spring", "anchor", "coupler_middle", k, L0, {}});
  add_revolute(model, "pin", "coupler_end", "rocker_tip");
  // A torque on the crank as input; the loads at the pin and the crank's pivot as outputs.
  const GiNaC::ex T = model.add_input("T", "N m");
  model.add_generalized_force({"drive", "th1", T, {}, Category::generalized});
  auto load = [&](const std::string& name, const std::string& of, Vec3 direction) {
    Output o;
    o.name = name;
    o.kind = OutputKind::reaction;
    o.reaction_of = of;
    o.direction = direction;
    o.unit = "N";
    model.add_output(o);
  };
  load("pin_fx", "pin", {1, 0, 0});
  load("pin_fy", "pin", {0, 1, 0});
  load("pivot_fx", "crank", {1, 0, 0});
  load("pivot_fy", "crank", {0, 1, 0});
  // Initial guess of the equilibrium: the loop closed at crank angle theta1 (the intersection
  // of the circles about the crank's tip and the rocker's pivot, elbow up).
  const double Ax = l1 * std::cos(theta1), Ay = l1 * std::sin(theta1);
  const double dx = a - Ax, dy = -Ay, d = std::hypot(dx, dy);
  const double along = (l2 * l2 - l3 * l3 + d * d) / (2 * d), h = std::sqrt(l2 * l2 - along * along);
  const double Bx = Ax + (along * dx - h * dy) / d, By = Ay + (along * dy + h * dx) / d;
  LinearizationPoint op;
  op.kind = LinearizationPoint::Kind::equilibrium;
  op.position = {{"th1", theta1},
                 {"th2", std::atan2(By - Ay, Bx - Ax) - theta1},
                 {"th3", std::atan2(By, Bx - a)}};
  model.set_operating_point(op);
  return model;
}

Model ladder(int n) {
  Model model("ladder_" + std::to_string(n));
  const GiNaC::ex g = model.add_parameter("g", 9.81, "m/s^2"), h = model.add_parameter("h", 0.2, "m"),
                  w = model.add_parameter("w", 0.3, "m"), m = model.add_parameter("m", 0.2, "kg"),
                  k = model.add_parameter("k", 2.0, "N m/rad");
  LinearizationPoint op;
  for (int i = 1; i <= n; ++i) {
    const std::string s = std::to_string(i);
    for (const char* side : {"a", "b"}) {
      const GiNaC::ex q = model.add_coordinate(std::string(side) + s, "rad").position;
      const std::string parent = i == 1 ? std::string(kWorld) : std::string(side) + std::to_string(i - 1);
      const Vec3 at = i == 1 ? Vec3{std::string(side) == "a" ? GiNaC::ex(0) : w, GiNaC::ex(0), GiNaC::ex(0)}
                             : Vec3{h, GiNaC::ex(0), GiNaC::ex(0)};
      add_bar(model, std::string(side) + s, parent, at, q, m, h);
      add_marker(model, std::string(side) + s + "_tip", std::string(side) + s, {h, GiNaC::ex(0), GiNaC::ex(0)});
      const GiNaC::ex hanging = i == 1 ? -GiNaC::Pi / 2 : GiNaC::ex(0);
      model.add_generalized_force({std::string("spring_") + side + s, std::string(side) + s,
                                   -k * (q - hanging), {}, Category::springs});
      op.position[std::string(side) + s] = hanging;
    }
    const GiNaC::ex r = model.add_coordinate("r" + s, "rad").position;
    add_bar(model, "rung" + s, "a" + s, {h, GiNaC::ex(0), GiNaC::ex(0)}, r, m, w);
    add_marker(model, "rung" + s + "_end", "rung" + s, {w, GiNaC::ex(0), GiNaC::ex(0)});
    add_revolute(model, "pin" + s, "rung" + s + "_end", "b" + s + "_tip");
    op.position["r" + s] = GiNaC::Pi / 2;
  }
  model.add_gravity({"gravity", {GiNaC::ex(0), -g, GiNaC::ex(0)}, {}});
  model.set_operating_point(op);
  return model;
}

}  // namespace mbsgen
