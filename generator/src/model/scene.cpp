#include "mbsgen/generator/model/scene.hpp"

#include "mbsgen/generator/model/yaml_reader.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>

namespace mbsgen {

using GiNaC::ex;

std::vector<std::string> SceneSelection::all_kernels() {
  return {"mass_matrix", "residual", "linear", "linear_structured", "operating_point", "outputs", "bodies", "dynamics",
          "sensitivity", "physical"};
}

std::vector<std::string> SceneSelection::full_kernels() {
  std::vector<std::string> k = all_kernels();
  k.erase(std::find(k.begin(), k.end(), "sensitivity"));
  return k;
}

bool SceneSelection::emits(const std::string& kernel) const {
  return std::find(kernels.begin(), kernels.end(), kernel) != kernels.end();
}

bool SceneSelection::asks(Analysis analysis) const {
  return std::find(analyses.begin(), analyses.end(), analysis) != analyses.end();
}

std::vector<std::string> kernels_of(Analysis analysis) {
  switch (analysis) {
    case Analysis::modes: return {"linear", "linear_structured"};
    case Analysis::frf: return {"linear"};
    case Analysis::statics: return {"residual", "linear"};
    // The operating point's equilibrium, when the model asks for one, takes its Jacobian from
    // dynamics_jacobian (GeneratedModel::operating_point): no `linear`.
    case Analysis::simulate: return {"mass_matrix", "residual", "dynamics", "outputs"};
    case Analysis::sensitivity: return {"linear", "sensitivity"};
  }
  return {};
}

namespace {

const Category kCategories[] = {Category::gravity,    Category::springs,     Category::dampers,
                                Category::gyroscopic, Category::generalized, Category::applied};

std::vector<std::string> category_names() {
  std::vector<std::string> names;
  for (Category c : kCategories) names.push_back(to_string(c));
  return names;
}

std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out;
}

bool nonzero(const Vec3& v) { return !v[0].is_zero() || !v[1].is_zero() || !v[2].is_zero(); }

// One force element, or one part of a bushing, as an effect.
struct ForceEffect {
  std::string name;
  Category category;
};

std::vector<ForceEffect> force_effects(const Model& m) {
  std::vector<ForceEffect> out;
  for (const auto& g : m.gravity()) out.push_back({g.name, Category::gravity});
  for (const auto& s : m.springs()) out.push_back({s.name, Category::springs});
  for (const auto& d : m.dampers()) out.push_back({d.name, Category::dampers});
  for (const auto& b : m.bushings()) {
    if (nonzero(b.k_translation) || nonzero(b.k_rotation)) out.push_back({b.name, Category::springs});
    if (nonzero(b.d_translation) || nonzero(b.d_rotation)) out.push_back({b.name, Category::dampers});
  }
  for (const auto& g : m.generalized_forces()) out.push_back({g.name, g.category});
  for (const auto& a : m.applied_forces()) out.push_back({a.name, Category::applied});
  return out;
}

std::set<std::string> force_names(const Model& m) {
  std::set<std::string> names;
  for (const auto& f : force_effects(m)) names.insert(f.name);
  // Bushings without stiffness or damping are still force elements a scene may name.
  for (const auto& b : m.bushings()) names.insert(b.name);
  return names;
}

// What a name that is not an effect is, for the message ("a body", …), or "".
std::string kind_of(const Model& m, const std::string& name) {
  for (const auto& b : m.bodies())
    if (b.name == name) return "a body";
  if (m.has_marker(name)) return "a marker";
  for (const auto& o : m.outputs())
    if (o.name == name) return "an output";
  for (const auto& c : m.coordinates())
    if (c.name == name || c.name + "_dot" == name) return "a coordinate";
  for (const auto& p : m.parameters())
    if (p.name == name) return "a parameter";
  return "";
}

void collect_symbols(const ex& e, std::set<std::string>& out) {
  if (GiNaC::is_a<GiNaC::symbol>(e)) {
    out.insert(GiNaC::ex_to<GiNaC::symbol>(e).get_name());
    return;
  }
  for (std::size_t i = 0; i < e.nops(); ++i) collect_symbols(e.op(i), out);
}

// Throws when an item of `items` was listed before.
void check_unique(const std::vector<SceneItem>& items, const std::string& scene,
                  std::map<std::string, SourceLocation>& seen) {
  for (const auto& it : items) {
    auto [at, inserted] = seen.emplace(it.name, it.where);
    if (!inserted)
      throw ModelError(it.where, "'" + it.name + "' is listed twice in scene '" + scene +
                                     "' (first at " + at->second.str() + ")");
  }
}

}  // namespace

void check_scene(const Model& model, const Scene& scene) {
  const std::string in_scene = " in scene '" + scene.name + "'";
  const std::set<std::string> forces = force_names(model);
  const std::vector<std::string> categories = category_names();
  std::vector<std::string> effect_names(categories);
  effect_names.insert(effect_names.end(), forces.begin(), forces.end());

  auto check_effect = [&](const SceneItem& it) {
    if (forces.count(it.name) ||
        std::find(categories.begin(), categories.end(), it.name) != categories.end())
      return;
    for (const auto& i : model.inputs())
      if (i.name == it.name)
        throw ModelError(it.where, "'" + it.name + "' is an input, not an effect: list it under 'inputs'" +
                                       in_scene);
    std::string message = "unknown effect '" + it.name + "'" + in_scene;
    const std::string hint = detail::suggestion(it.name, effect_names);
    const std::string kind = kind_of(model, it.name);
    if (!hint.empty())
      message += hint;
    else if (!kind.empty())
      message = "'" + it.name + "' is " + kind + ", not an effect" + in_scene;
    if (hint.empty())
      message += " (effects: the force elements by name and the categories " + join(categories) + ")";
    throw ModelError(it.where, message);
  };
  std::map<std::string, SourceLocation> seen;
  if (scene.effects) {
    for (const auto& it : *scene.effects) check_effect(it);
    check_unique(*scene.effects, scene.name, seen);
  }
  for (const auto& it : scene.without) check_effect(it);
  check_unique(scene.without, scene.name, seen);

  auto check_names = [&](const std::vector<SceneItem>& items, const char* what,
                         const std::vector<std::string>& known) {
    for (const auto& it : items) {
      if (std::find(known.begin(), known.end(), it.name) != known.end()) continue;
      std::string hint = detail::suggestion(it.name, known);
      if (hint.empty())
        hint = known.empty() ? std::string(" (the model has no ") + what + "s)"
                             : std::string(" (") + what + "s: " + join(known) + ")";
      throw ModelError(it.where, std::string("unknown ") + what + " '" + it.name + "'" + in_scene + hint);
    }
    std::map<std::string, SourceLocation> once;
    check_unique(items, scene.name, once);
  };
  if (scene.inputs) {
    std::vector<std::string> known;
    for (const auto& i : model.inputs()) known.push_back(i.name);
    check_names(*scene.inputs, "input", known);
  }
  if (scene.outputs) {
    std::vector<std::string> known;
    for (const auto& o : model.outputs()) known.push_back(o.name);
    check_names(*scene.outputs, "output", known);
  }
  if (scene.sensitivity) {
    std::vector<std::string> known;
    for (const auto& p : model.parameters()) known.push_back(p.name);
    check_names(*scene.sensitivity, "parameter", known);
    if (std::find(scene.analyses.begin(), scene.analyses.end(), Analysis::sensitivity) == scene.analyses.end())
      throw ModelError(scene.sensitivity->empty() ? scene.where : scene.sensitivity->front().where,
                       "scene '" + scene.name + "' lists sensitivity parameters but does not ask for the analysis "
                       "'sensitivity' (add it to its analyses)");
  }

  std::set<std::string> parameters;
  for (const auto& p : model.parameters()) parameters.insert(p.name);
  const OperatingPointOverride& op = scene.operating_point;
  for (const auto* values : {&op.position, &op.velocity})
    for (const auto& [name, value] : *values) {
      if (model.coordinate_index(name) < 0)
        throw ModelError(op.where, "the operating point of scene '" + scene.name +
                                       "' names an unknown coordinate '" + name + "'");
      std::set<std::string> syms;
      collect_symbols(value, syms);
      for (const auto& s : syms)
        if (!parameters.count(s))
          throw ModelError(op.where, "an operating point may depend on parameters only; '" + s +
                                         "' is not a parameter");
    }

  if (scene.analyses.empty())
    throw ModelError(scene.where, "scene '" + scene.name + "' asks for no analysis (modes, frf, static, simulate, sensitivity)");
  for (std::size_t i = 0; i < scene.analyses.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (scene.analyses[i] == scene.analyses[j])
        throw ModelError(scene.where, std::string("analysis '") + to_string(scene.analyses[i]) +
                                          "' is listed twice" + in_scene);
  if (const auto& f = scene.frequency_range) {
    if (!(f->from_hz >= 0) || !(f->to_hz > f->from_hz))
      throw ModelError(f->where, "a frequency range needs 0 <= from < to (Hz)");
    if (f->logarithmic && !(f->from_hz > 0))
      throw ModelError(f->where, "a logarithmic frequency range needs from > 0");
    if (f->points < 2) throw ModelError(f->where, "a frequency range needs at least 2 points");
  }
}

std::vector<EffectState> effects_of(const Model& model) {
  std::vector<EffectState> effects;
  for (const auto& f : force_effects(model)) effects.push_back({f.name, to_string(f.category), true, ""});
  effects.push_back({"gyroscopic", to_string(Category::gyroscopic), model.inertial_velocity_terms(), ""});
  for (const auto& i : model.inputs()) effects.push_back({i.name, "inputs", true, ""});
  return effects;
}

// The kinematics of a scene without some motion inputs: those supports stay in their reference
// place (their inputs and rates 0 in body translations and rotations and in markers on the world).
void hold_dropped_supports(Model& m, const GiNaC::exmap& dropped) {
  if (dropped.empty()) return;
  auto held = [&](const ex& e) { return e.subs(dropped, GiNaC::subs_options::no_pattern); };
  auto vec = [&](Vec3& v) {
    for (auto& x : v) x = held(x);
  };
  auto mat = [&](Mat3& A) {
    for (auto& row : A) vec(row);
  };
  for (Body& b : m.bodies_) {
    vec(b.translation);
    for (auto& r : b.rotations) r.angle = held(r.angle);
    if (b.rotation_matrix) mat(*b.rotation_matrix);
  }
  for (Marker& mk : m.markers_) vec(mk.position), mat(mk.rotation);
}

namespace {

// Records what the scene made of one effect.
void record(std::vector<EffectState>& effects, const std::string& name, Category c, bool on,
            const std::string& note = "") {
  effects.push_back({name, to_string(c), on, note});
}

// The scene's name, analyses and sensitivity parameters, and the kernels its analyses need.
void select_analyses(SceneSelection& sel, const Model& model, const Scene& scene) {
  sel.name = scene.name;
  sel.description = scene.description;
  sel.full = false;
  sel.analyses = scene.analyses;
  sel.frequency_range = scene.frequency_range;
  if (scene.sensitivity)  // in the model's order, as the kernel's outputs
    for (const auto& p : model.parameters())
      for (const auto& it : *scene.sensitivity)
        if (it.name == p.name) sel.sensitivity_parameters.push_back(p.name);
  sel.kernels.clear();
  for (const auto& k : SceneSelection::all_kernels()) {
    bool used = k == "operating_point" || k == "physical";  // every analysis checks the parameters
    for (Analysis a : sel.analyses) {
      const auto ks = kernels_of(a);
      used = used || std::find(ks.begin(), ks.end(), k) != ks.end();
    }
    if (used) sel.kernels.push_back(k);
  }
}

// Overrides the operating point `point` per coordinate, adding the kernels its equilibrium needs.
void override_operating_point(LinearizationPoint& point, SceneSelection& sel, const Model& model,
                              const OperatingPointOverride& op) {
  if (op.kind) point.kind = *op.kind;
  // A simulation's equilibrium takes its Jacobian from dynamics_jacobian, which a model with
  // loops does not have: `linear` then.
  if (sel.asks(Analysis::simulate) && point.kind == LinearizationPoint::Kind::equilibrium &&
      !model.constraints().empty() && !sel.emits("linear"))
    sel.kernels.insert(std::find(sel.kernels.begin(), sel.kernels.end(), "residual") + 1, "linear");
  // Any analysis at an equilibrium finds it first, by Newton's method on `residual`: without it
  // the runtime would linearize at the initial guess (a modes-only or sensitivity scene).
  if (point.kind == LinearizationPoint::Kind::equilibrium && sel.emits("linear") && !sel.emits("residual"))
    sel.kernels.insert(std::find(sel.kernels.begin(), sel.kernels.end(), "linear"), "residual");
  for (const auto& [c, v] : op.position) point.position[c] = v;
  for (const auto& [c, v] : op.velocity) point.velocity[c] = v;
  if (op.where.line > 0) point.where = op.where;
}

// Which effects are active: named (by force name, else by category) in `effects` (all when
// absent), and not in `without`.
struct ActiveEffects {
  const Scene& scene;
  std::set<std::string> forces;  // the model's force names

  // Whether `items` names the force element, or its category (by a name that is no force's).
  bool listed(const std::vector<SceneItem>& items, const std::string& force, Category c) const {
    for (const auto& it : items)
      if (it.name == force || (!forces.count(it.name) && it.name == to_string(c))) return true;
    return false;
  }
  bool operator()(const std::string& force, Category c) const {
    return (!scene.effects || listed(*scene.effects, force, c)) && !listed(scene.without, force, c);
  }
};

// The inputs of interest: those the scene lists, else all for frf, static and simulate (else none).
std::vector<std::string> inputs_of_interest(const Model& model, const Scene& scene, const SceneSelection& sel) {
  std::vector<std::string> inputs;
  if (scene.inputs) {
    for (const auto& it : *scene.inputs) inputs.push_back(it.name);
  } else if (sel.asks(Analysis::frf) || sel.asks(Analysis::statics) || sel.asks(Analysis::simulate)) {
    for (const auto& i : model.inputs()) inputs.push_back(i.name);
  }
  return inputs;
}

// The force elements a scene keeps, as it leaves them, and the names of those it drops.
struct KeptForces {
  std::vector<Gravity> gravity;
  std::vector<Spring> springs;
  std::vector<Damper> dampers;
  std::vector<Bushing> bushings;
  std::vector<GeneralizedForce> generalized;
  std::vector<AppliedForce> applied;
  std::vector<std::string> dropped_names;
};

// Keeps the active force elements, without the dropped inputs, recording each in `effects`.
KeptForces keep_forces(const Model& model, const ActiveEffects& active, const GiNaC::exmap& dropped,
                       std::vector<EffectState>& effects) {
  KeptForces kept;
  auto without_inputs = [&](const ex& e) {
    return dropped.empty() ? e : e.subs(dropped, GiNaC::subs_options::no_pattern);
  };
  auto remove_name = [&](const std::string& n) { kept.dropped_names.push_back(n); };

  for (const auto& g : model.gravity()) {
    const bool on = active(g.name, Category::gravity);
    record(effects, g.name, Category::gravity, on);
    if (on) kept.gravity.push_back(g); else remove_name(g.name);
  }
  for (const auto& s : model.springs()) {
    const bool on = active(s.name, Category::springs);
    record(effects, s.name, Category::springs, on);
    if (on) kept.springs.push_back(s); else remove_name(s.name);
  }
  for (const auto& d : model.dampers()) {
    const bool on = active(d.name, Category::dampers);
    record(effects, d.name, Category::dampers, on);
    if (on) kept.dampers.push_back(d); else remove_name(d.name);
  }
  for (Bushing b : model.bushings()) {
    const bool has_k = nonzero(b.k_translation) || nonzero(b.k_rotation);
    const bool has_d = nonzero(b.d_translation) || nonzero(b.d_rotation);
    const bool k_on = has_k && active(b.name, Category::springs);
    const bool d_on = has_d && active(b.name, Category::dampers);
    if (has_k) record(effects, b.name, Category::springs, k_on);
    if (has_d) record(effects, b.name, Category::dampers, d_on);
    if (!k_on) b.k_translation = b.k_rotation = zero_vec3();
    if (!d_on) b.d_translation = b.d_rotation = zero_vec3();
    if (k_on || d_on) kept.bushings.push_back(b); else remove_name(b.name);
  }
  const std::string no_input = "zero without the scene's inputs";
  for (GeneralizedForce g : model.generalized_forces()) {
    bool on = active(g.name, g.category);
    std::string note;
    if (on) {
      g.value = without_inputs(g.value);
      if (g.value.is_zero()) on = false, note = no_input;
    }
    record(effects, g.name, g.category, on, note);
    if (on) kept.generalized.push_back(g); else remove_name(g.name);
  }
  for (AppliedForce a : model.applied_forces()) {
    bool on = active(a.name, Category::applied);
    std::string note;
    if (on) {
      for (auto* v : {&a.force, &a.torque})
        for (auto& x : *v) x = without_inputs(x);
      if (!nonzero(a.force) && !nonzero(a.torque)) on = false, note = no_input;
    }
    record(effects, a.name, Category::applied, on, note);
    if (on) kept.applied.push_back(a); else remove_name(a.name);
  }
  return kept;
}

// The outputs of interest: those the scene lists, else all for frf and simulate (else none).
std::vector<std::string> outputs_of_interest(const Model& model, const Scene& scene, const SceneSelection& sel) {
  std::vector<std::string> outputs;
  if (scene.outputs) {
    for (const auto& it : *scene.outputs) outputs.push_back(it.name);
  } else if (sel.asks(Analysis::frf) || sel.asks(Analysis::simulate)) {
    for (const auto& o : model.outputs()) outputs.push_back(o.name);
  }
  return outputs;
}

// A force output sums the elements the scene keeps (those of `pruned`); with none left it is 0.
void prune_force_outputs(std::vector<Output>& outputs, const Model& pruned) {
  for (Output& o : outputs) {
    if (o.kind != OutputKind::force) continue;
    std::vector<std::string> kept;
    for (const auto& e : o.elements) {
      bool present = false;
      for (const auto& x : pruned.springs()) present = present || x.name == e;
      for (const auto& x : pruned.dampers()) present = present || x.name == e;
      for (const auto& x : pruned.bushings()) present = present || x.name == e;
      if (present) kept.push_back(e);
    }
    o.elements = kept;
    if (kept.empty()) o.kind = OutputKind::expression, o.expression = 0;
  }
}

}  // namespace

void Model::request_sensitivity(const std::vector<std::string>& parameters) {
  if (!selection_.full)
    throw std::invalid_argument("model '" + name_ + "' is pruned for scene '" + selection_.name +
                                "': a scene has sensitivities when its analyses list 'sensitivity' (with its "
                                "'sensitivity: [names]'), not on request");
  std::vector<std::string> known;
  for (const auto& p : parameters_) known.push_back(p.name);
  for (const auto& name : parameters)
    if (std::find(known.begin(), known.end(), name) == known.end())
      throw std::invalid_argument("sensitivity: model '" + name_ + "' has no parameter '" + name + "'" +
                                  detail::suggestion(name, known) + " (parameters: " + join(known) + ")");
  selection_.sensitivity_parameters.clear();
  for (const auto& p : known)  // in the model's order, once each
    if (std::find(parameters.begin(), parameters.end(), p) != parameters.end())
      selection_.sensitivity_parameters.push_back(p);
  if (!selection_.emits("sensitivity"))
    selection_.kernels.insert(std::find(selection_.kernels.begin(), selection_.kernels.end(), "physical"), "sensitivity");
}

Model apply_scene(const Model& model, const std::string& name) {
  const Scene* scene = model.scene(name);
  if (!scene && name != kFullScene) {
    std::vector<std::string> names = {kFullScene};
    for (const auto& s : model.scenes()) names.push_back(s.name);
    throw std::invalid_argument("model '" + model.name() + "' has no scene '" + name + "'" +
                                detail::suggestion(name, names) + " (scenes: " + join(names) + ")");
  }
  Model m = model;
  m.scenes_.clear();
  m.selection_ = SceneSelection{};
  SceneSelection& sel = m.selection_;
  if (!scene) {  // the full model: every effect, input, output and kernel
    sel.effects = effects_of(model);
    return m;
  }
  check_scene(model, *scene);
  select_analyses(sel, model, *scene);

  // The operating point, overridden per coordinate.
  override_operating_point(m.operating_point_, sel, model, scene->operating_point);
  bool at_rest = true;
  for (const auto& [c, v] : m.operating_point_.velocity) at_rest = at_rest && v.is_zero();

  const ActiveEffects active{*scene, force_names(model)};

  // Inputs of interest; the others are zero from now on.
  const std::vector<std::string> inputs = inputs_of_interest(model, *scene, sel);
  GiNaC::exmap dropped;
  m.inputs_.clear();
  m.input_symbols_.clear();
  for (const auto& name_kept : inputs)
    for (std::size_t i = 0; i < model.inputs().size(); ++i)
      if (model.inputs()[i].name == name_kept) {
        m.inputs_.push_back(model.inputs()[i]);
        m.input_symbols_.push_back(model.input_symbols()[i]);
      }
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    const std::string& n = model.inputs()[i].name;
    if (std::find(inputs.begin(), inputs.end(), n) != inputs.end()) continue;
    dropped[model.input_symbols()[i]] = 0;
    m.symtab_.erase(n);
    m.symbol_names_.erase(n);
    if (model.inputs()[i].motion) {  // a support the scene holds still in its reference place
      dropped[model.inputs()[i].rate] = 0;
      m.symtab_.erase(n + "_dot");
      m.symbol_names_.erase(n + "_dot");
    }
  }
  hold_dropped_supports(m, dropped);

  KeptForces kept = keep_forces(model, active, dropped, sel.effects);
  m.gravity_ = std::move(kept.gravity);
  m.springs_ = std::move(kept.springs);
  m.dampers_ = std::move(kept.dampers);
  m.bushings_ = std::move(kept.bushings);
  m.generalized_forces_ = std::move(kept.generalized);
  m.applied_forces_ = std::move(kept.applied);
  for (const auto& n : kept.dropped_names) m.element_names_.erase(n);

  // Velocity-quadratic inertia terms: their value and first derivatives vanish at ẏ = 0, so
  // about rest they cannot reach M, Q, K, nor the residual of a static equilibrium; a simulation
  // leaves rest, and keeps them.
  const bool gyroscopic = active("gyroscopic", Category::gyroscopic);
  const bool simulates = sel.asks(Analysis::simulate);
  m.inertial_velocity_terms_ = gyroscopic && (!at_rest || simulates);
  record(sel.effects, "gyroscopic", Category::gyroscopic, m.inertial_velocity_terms_,
         gyroscopic && at_rest && !simulates ? "cannot contribute at rest (yd0 = 0)" : "");
  for (const auto& i : model.inputs())
    sel.effects.push_back({i.name, "inputs", std::find(inputs.begin(), inputs.end(), i.name) != inputs.end(), ""});

  // Outputs of interest.
  const std::vector<std::string> outputs = outputs_of_interest(model, *scene, sel);
  m.outputs_.clear();
  for (const auto& n : outputs)
    for (const auto& o : model.outputs())
      if (o.name == n) m.outputs_.push_back(o);
  for (const auto& o : model.outputs())
    if (std::find(outputs.begin(), outputs.end(), o.name) == outputs.end()) m.element_names_.erase(o.name);
  prune_force_outputs(m.outputs_, m);
  return m;
}

}  // namespace mbsgen
