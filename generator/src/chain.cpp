#include "mbsgen/generator/chain.hpp"

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
