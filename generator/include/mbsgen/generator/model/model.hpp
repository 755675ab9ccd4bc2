// The multibody model as the generator sees it: parameters, generalized coordinates, a tree of
// bodies with markers, force elements, inputs, outputs and an operating point. Every quantity is
// a GiNaC expression in the model's symbols. The YAML reader (yaml_reader.hpp) is one client of
// this API; tests and benchmarks build models with it directly.
#pragma once

#include <ginac/ginac.h>

#include <array>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace mbsgen {

/// Where something was written in a model file (1-based line and column; 0 when unknown).
struct SourceLocation {
  std::string file;
  int line = 0;
  int column = 0;
  /// "FILE:LINE:COL" (or what of it is known).
  std::string str() const;
};

/// A bad model: the message reads `FILE:LINE:COL: error: what` in the style of a compiler.
class ModelError : public std::runtime_error {
 public:
  ModelError(const SourceLocation& where, const std::string& what);
  const SourceLocation& where() const { return where_; }
  const std::string& message() const { return message_; }

 private:
  SourceLocation where_;
  std::string message_;
};

using Vec3 = std::array<GiNaC::ex, 3>;
using Mat3 = std::array<std::array<GiNaC::ex, 3>, 3>;

Vec3 zero_vec3();
Mat3 identity_mat3();
Mat3 zero_mat3();

/// The name of the inertial frame; usable as a parent body and as the body of a marker.
inline const char* const kWorld = "world";

enum class Axis { x, y, z };

/// Rotation by `angle` [rad] about a coordinate axis of the frame it is applied in.
struct ElementaryRotation {
  Axis axis = Axis::z;
  GiNaC::ex angle;
};

/// A point and a frame fixed on a body. position [m] and rotation (marker frame to body frame)
/// are expressed in the body frame.
struct Marker {
  std::string name;
  std::string body;  ///< owning body, or kWorld
  Vec3 position = zero_vec3();
  Mat3 rotation = identity_mat3();
  SourceLocation where;
};

/// A rigid body. Its frame is placed relative to the parent frame by `translation` [m] (in the
/// parent frame) and by the rotation R = R_1 R_2 … R_n of `rotations` (or by `rotation_matrix`
/// when given), so that r_i = r_p + S_p t_i and S_i = S_p R_i (seed eq. 3.3).
struct Body {
  std::string name;
  std::string parent = kWorld;
  Vec3 translation = zero_vec3();
  std::vector<ElementaryRotation> rotations;
  std::optional<Mat3> rotation_matrix;
  GiNaC::ex mass = 0;              ///< [kg]
  Vec3 com = zero_vec3();          ///< centre of mass in the body frame [m]
  Mat3 inertia = zero_mat3();      ///< inertia tensor about the centre of mass, body frame [kg m²]
  SourceLocation where;
};

/// Uniform gravitational acceleration [m/s²] in the world frame.
struct Gravity {
  std::string name = "gravity";
  Vec3 g = zero_vec3();
  SourceLocation where;
};

/// Linear point-to-point spring between two markers: potential ½ k (L − L0)².
struct Spring {
  std::string name;
  std::string marker_a, marker_b;
  GiNaC::ex stiffness;        ///< k [N/m]
  GiNaC::ex rest_length = 0;  ///< L0 [m]
  SourceLocation where;
};

/// Linear point-to-point damper between two markers: dissipation function ½ c L̇².
struct Damper {
  std::string name;
  std::string marker_a, marker_b;
  GiNaC::ex damping;  ///< c [N s/m]
  SourceLocation where;
};

/// Six-component linear bushing (a ligament or a compliant joint) between two markers. With
/// Δr = S_aᵀ (r_b − r_a) and the small relative rotation θ = vee(skew(S_aᵀ S_b)) both in the
/// frame of marker a: V = ½ Δrᵀ diag(k_t) Δr + ½ θᵀ diag(k_r) θ and
/// R = ½ Δṙᵀ diag(d_t) Δṙ + ½ ω_relᵀ diag(d_r) ω_rel.
struct Bushing {
  std::string name;
  std::string marker_a, marker_b;
  Vec3 k_translation = zero_vec3();  ///< [N/m]
  Vec3 k_rotation = zero_vec3();     ///< [N m/rad]
  Vec3 d_translation = zero_vec3();  ///< [N s/m]
  Vec3 d_rotation = zero_vec3();     ///< [N m s/rad]
  SourceLocation where;
};

/// The kinds of effect a scene can switch on and off (docs/model-format.md, "scenes"):
/// gravity elements; springs (and the stiffness of bushings); dampers (and the damping of
/// bushings); the velocity-quadratic inertia terms (gyroscopic, centrifugal and Coriolis forces);
/// generalized forces; applied forces.
enum class Category { gravity, springs, dampers, gyroscopic, generalized, applied };

/// "gravity", "springs", "dampers", "gyroscopic", "generalized", "applied".
const char* to_string(Category category);

/// A generalized force on one coordinate (may depend on coordinates, rates and inputs).
struct GeneralizedForce {
  std::string name;
  std::string coordinate;
  GiNaC::ex value;
  SourceLocation where;
  /// The category scenes select it by: generalized (the default), springs or dampers.
  Category category = Category::generalized;
};

enum class ForceFrame { world, marker };

/// A force [N] at a marker's point and a torque [N m], resolved in the world frame or in the
/// marker's frame.
struct AppliedForce {
  std::string name;
  std::string marker;
  ForceFrame frame = ForceFrame::world;
  Vec3 force = zero_vec3();
  Vec3 torque = zero_vec3();
  SourceLocation where;
};

/// A named excitation amplitude. A force input's symbol may appear (linearly) in force
/// expressions. A motion input prescribes motion (docs/model-format.md, "Prescribed motion"):
/// its symbol u is a coordinate whose value is given, with the rate `NAME_dot`; it may appear in
/// body translations and rotations, in the positions and rotations of markers on the world, and
/// in forces. Linearized, it excites through h = B0 u + B1 u̇ + B2 ü (prescribed_motion.hpp).
struct Input {
  std::string name;
  std::string unit;
  SourceLocation where;
  bool motion = false;
  GiNaC::symbol rate;  ///< motion: u̇, written `NAME_dot`
};

/// A holonomic constraint Φ(y) = 0 that closes a kinematic loop (docs/model-format.md,
/// "constraints"). The joint kinds act between the points and frames of two markers on different
/// bodies (or a body and the world), with d = r_b − r_a and (x_a, y_a, z_a), (x_b, y_b, z_b) the
/// axes of the marker frames, all in the world frame:
///   spherical  d = 0                                            (3 equations)
///   revolute   d = 0, z_b·x_a = 0, z_b·y_a = 0                  (5: the z axes stay aligned)
///   prismatic  d·x_a = 0, d·y_a = 0, y_b·z_a = 0, z_b·x_a = 0, x_b·y_a = 0
///                                         (5: slides along z_a, the frames keep their orientation)
///   planar     d·z_a = 0, z_b·x_a = 0, z_b·y_a = 0               (3: b moves in a's x–y plane)
///   distance   (d·d − L²)/(2L) = 0                               (1: a massless rigid rod of length L)
///   expression Φ = expression                                   (1: any expression in coordinates
///                                                                and parameters)
///   rolling    ((n·C)² − r² |n × a|²)/(2r) = 0                   (1: a thin disk touches the ground)
/// A rolling constraint is a thin disk (wheel) of radius r rolling without slipping on the ground
/// plane n·x = 0 (n the unit normal, pointing from the ground to the wheel; world frame): marker a
/// sits at the wheel's centre C on the wheel body, and its `axis` (x, y or z) is the wheel's axle
/// a. The contact point is P = C − r (n − (n·a) a)/|n × a|; besides the holonomic contact
/// condition above, the nonholonomic stage (nonholonomic.hpp) adds the two no-slip conditions
/// t·v_P = 0 along the ground (v_P the velocity of the wheel's material point at P).
/// The joint equations are scaled so that their multipliers λ are the reaction forces [N] and
/// torques [N m] in the world frame. Equations that vanish identically (a 3-D joint in a planar
/// model) are dropped.
enum class ConstraintKind { spherical, revolute, prismatic, planar, distance, expression, rolling };

/// "spherical", "revolute", "prismatic", "planar", "distance", "expression", "rolling".
const char* to_string(ConstraintKind kind);

struct Constraint {
  std::string name;
  ConstraintKind kind = ConstraintKind::spherical;
  std::string marker_a, marker_b;  ///< every kind but expression
  GiNaC::ex length;                ///< distance: L [m] (> 0); rolling: the wheel radius r [m]
  GiNaC::ex expression;            ///< expression: Φ (in coordinates and parameters)
  int axis = 2;                    ///< rolling: the axle is marker a's x (0), y (1) or z (2) axis
  Vec3 normal = {0, 0, 1};         ///< rolling: the ground's unit normal (world frame, constants)
  SourceLocation where;
};

/// A named part of the reduced second-order form (docs/model-format.md, `reduced_form`): the
/// coefficient of `monomial` (a product of powers of parameters, or 1) in the reduced matrix
/// `matrix` (M, Q or K), as the bicycle's Q = v C1 and K = g K0 + v² K2.
struct NamedCoefficient {
  std::string name;
  char matrix = 'M';
  GiNaC::ex monomial = 1;
  SourceLocation where;
};

/// A nonholonomic constraint A(y) ẏ + a(y) = 0 (docs/model-format.md, "nonholonomic"): one
/// expression in coordinates, rates and parameters, linear in the rates, that the motion keeps at
/// zero (a velocity that no choice of coordinates removes, such as a skate's sideways speed).
struct VelocityConstraint {
  std::string name;
  GiNaC::ex expression;
  SourceLocation where;
};

enum class OutputKind { position, velocity, coordinate, rate, expression, force, reaction };

/// What a `force` output measures of its force elements.
enum class ForceQuantity { force, torque };

/// A measured quantity z(y, ẏ); its linearization gives a row of C_y and C_v.
struct Output {
  std::string name;
  OutputKind kind = OutputKind::coordinate;
  std::string marker;               ///< position, velocity
  Vec3 direction = zero_vec3();     ///< world frame, position and velocity
  /// position, velocity: when set, the motion relative to this marker's point and frame,
  /// directionᵀ S_Rᵀ (r − r_R) and its time derivative, with direction in the frame of R (the
  /// stapes relative to the vibrating cochlea).
  std::string relative_to;
  std::string coordinate;           ///< coordinate, rate
  GiNaC::ex expression;             ///< expression
  /// force: the force [N] (or torque [N m], about the point of marker b) that the named force
  /// elements (springs, dampers, bushings) exert on the body of their marker b, summed, as
  /// directionᵀ (that vector) with direction in the world frame, or in the frame of marker b of
  /// the first element when force_frame is marker.
  std::vector<std::string> elements;
  ForceQuantity quantity = ForceQuantity::force;  ///< force and reaction
  ForceFrame force_frame = ForceFrame::world;
  /// reaction: the load a joint transmits (reactions.hpp), as directionᵀ (force [N] or torque
  /// [N m]) with direction in the world frame, or in the frame of `frame_marker` when given.
  /// `reaction_of` names a body (the joint to its parent: the load the parent exerts on the body,
  /// torque about the body frame's origin) or a constraint (the load on the body of its marker b;
  /// for an expression constraint, its multiplier λ times direction[0]).
  std::string reaction_of;
  std::string frame_marker;
  std::string unit;
  SourceLocation where;
};

/// Where the model is linearized: given values, or a static equilibrium found from a guess;
/// steady velocities (zero unless given) allow steady motions such as a spinning rotor.
struct LinearizationPoint {
  enum class Kind { given, equilibrium };
  Kind kind = Kind::given;
  std::map<std::string, GiNaC::ex> position;  ///< coordinate name → value (or initial guess)
  std::map<std::string, GiNaC::ex> velocity;  ///< coordinate name → steady rate
  SourceLocation where;
};

/// An analysis a scene asks for; it decides which kernels are emitted.
enum class Analysis {
  modes,  ///< eigenvalues of λ²M + λQ + K: kernels linear and linear_structured
  frf,    ///< frequency responses: kernel linear (M, Q, K, B, C)
  statics, ///< static equilibrium by Newton's method: kernels residual and linear (K)
  simulate, ///< time integration: mass_matrix, residual, dynamics (with its Jacobian), outputs
  sensitivity ///< parameter sensitivities of the linear model: linear and sensitivity (issue 20)
};

/// "modes", "frf", "static", "simulate", "sensitivity".
const char* to_string(Analysis analysis);

/// A name written in a scene, with its place in the model file.
struct SceneItem {
  std::string name;
  SourceLocation where;
};

/// Default frequency range of a scene's frequency responses [Hz].
struct FrequencyRange {
  double from_hz = 1;
  double to_hz = 1000;
  int points = 200;
  bool logarithmic = true;
  SourceLocation where;
};

/// Changes a scene makes to the model's operating point: the given entries replace the model's
/// (per coordinate); the rest are kept.
struct OperatingPointOverride {
  std::optional<LinearizationPoint::Kind> kind;
  std::map<std::string, GiNaC::ex> position;
  std::map<std::string, GiNaC::ex> velocity;
  SourceLocation where;
};

/// A named analysis request (docs/model-format.md, "scenes"): the active effects, the operating
/// point, the analyses and the inputs and outputs of interest. apply_scene() (scene.hpp) turns a
/// model and one of its scenes into the pruned model that the generator derives.
struct Scene {
  std::string name;
  std::string description;
  /// Active effects: force element names or categories (to_string(Category)); all when absent.
  std::optional<std::vector<SceneItem>> effects;
  /// Effects removed from the active ones (names or categories).
  std::vector<SceneItem> without;
  /// Inputs of interest, in the order of B's columns. When absent: every input if the scene asks
  /// for frf or static, none otherwise. Inputs not listed are set to zero.
  std::optional<std::vector<SceneItem>> inputs;
  /// Outputs of interest, in the order of C's rows. When absent: every output if the scene asks
  /// for frf, none otherwise.
  std::optional<std::vector<SceneItem>> outputs;
  std::vector<Analysis> analyses = {Analysis::modes, Analysis::frf, Analysis::statics};
  OperatingPointOverride operating_point;
  std::optional<FrequencyRange> frequency_range;
  /// The parameters whose sensitivities the scene asks for (analysis `sensitivity`): all when
  /// absent.
  std::optional<std::vector<SceneItem>> sensitivity;
  SourceLocation where;
};

/// The name of the implicit scene that is the whole model.
inline const char* const kFullScene = "full";

/// What a scene made of one effect: a force element (a bushing has a springs and a dampers
/// part), the inertia terms ("gyroscopic"), or an input (category "inputs").
struct EffectState {
  std::string name;
  std::string category;  ///< to_string(Category), or "inputs"
  bool active = true;
  std::string note;  ///< why an effect the scene did not switch off is inactive, or ""
};

/// A scene resolved against its model (apply_scene in scene.hpp): what the emitter writes.
struct SceneSelection {
  std::string name = kFullScene;
  std::string description;
  bool full = true;  ///< the implicit full scene: every kernel, nothing pruned
  std::vector<Analysis> analyses = {Analysis::modes, Analysis::frf, Analysis::statics};
  /// The kernels to emit, in emission order (names as in docs/generator.md). The full scene
  /// emits every kernel but `sensitivity`, which is made only on request
  /// (Model::request_sensitivity: `mbsgen generate --sensitivity`, issue 40 §2).
  std::vector<std::string> kernels = full_kernels();
  /// Every effect of the original model and whether the scene keeps it (empty for the full
  /// model: everything is active).
  std::vector<EffectState> effects;
  std::optional<FrequencyRange> frequency_range;
  /// The parameters of the `sensitivity` kernel, by name, in the model's order (empty: all).
  std::vector<std::string> sensitivity_parameters;

  /// mass_matrix, residual, linear, linear_structured, operating_point, outputs, bodies, dynamics
  /// (`dynamics` and `dynamics_jacobian`: in the full scene only with EmitOptions::dynamics).
  static std::vector<std::string> all_kernels();
  /// all_kernels() but `sensitivity`: what the full scene emits unless asked for more.
  static std::vector<std::string> full_kernels();
  bool emits(const std::string& kernel) const;
  bool asks(Analysis analysis) const;
};

struct Parameter {
  std::string name;
  double value = 0;  ///< SI default
  std::string unit;
  std::string source;
  GiNaC::symbol symbol;
  SourceLocation where;
};

struct Coordinate {
  std::string name;
  std::string unit;
  GiNaC::symbol position;  ///< y_k
  GiNaC::symbol velocity;  ///< ẏ_k, written `NAME_dot` in expressions
  SourceLocation where;
};

/// Where a function call or a power of an expression was written (`text` as written, such as
/// `abs(x_dot)`), so that validate() can point at it when its derivative does not exist at the
/// operating point.
struct CallSite {
  std::string text;
  SourceLocation where;
};

/// A condition on the parameters that the model file's checks impose (Model::validate) and that a
/// parameter value given at run time must meet too: the generator emits the values as the
/// `physical` kernel, and GeneratedModel judges them before each analysis (issue 39 §1).
struct PhysicalCheck {
  /// positive: one value > 0 (a rod length, a wheel radius); nonnegative: one value >= 0 (a
  /// spring's rest length); body: seven values, the mass and the inertia tensor's Ixx, Iyy, Izz,
  /// Ixy, Ixz, Iyz (mass >= 0, tensor positive semi-definite with A + B >= C, zero with the mass).
  enum class Kind { positive, nonnegative, body };
  Kind kind = Kind::positive;
  std::string label;                    ///< what the values are: "body 'wheel'", "radius of rolling constraint 'c'"
  std::string unit;                     ///< of a positive or nonnegative value
  std::vector<std::string> parameters;  ///< the parameters the values depend on, in the model's order
  std::vector<GiNaC::ex> values;
};
const char* to_string(PhysicalCheck::Kind kind);

class Model;
/// The model as one of its scenes sees it (scene.hpp).
Model apply_scene(const Model& model, const std::string& scene);
/// The model with six probe coordinates in the joints of the named bodies (reactions.hpp).
Model with_joint_probes(const Model& model, const std::vector<std::string>& bodies);
/// The model with its motion inputs as coordinates after its own (prescribed_motion.hpp).
Model with_motion_coordinates(const Model& model);
/// Sets the dropped motion inputs of a scene (and their rates) to 0 in the kinematics (scene.hpp).
void hold_dropped_supports(Model& m, const GiNaC::exmap& dropped);
/// `base`, with '_' appended until no element (body, marker, force, output) has that name.
std::string fresh_body(const Model& model, std::string base);

/// A multibody model. Add parameters, coordinates and inputs first (they create the symbols that
/// expressions use), then bodies, markers, forces and outputs. `validate()` checks the whole.
class Model {
 public:
  explicit Model(std::string name);

  const std::string& name() const { return name_; }

  const GiNaC::symbol& add_parameter(const std::string& name, double value,
                                     const std::string& unit = "", const std::string& source = "",
                                     const SourceLocation& where = {});
  const Coordinate& add_coordinate(const std::string& name, const std::string& unit = "",
                                   const SourceLocation& where = {});
  /// A force input, or with `motion` a motion input (which also defines `NAME_dot`).
  const GiNaC::symbol& add_input(const std::string& name, const std::string& unit = "",
                                 const SourceLocation& where = {}, bool motion = false);
  void add_body(Body body);
  void add_marker(Marker marker);
  void add_gravity(Gravity gravity);
  void add_spring(Spring spring);
  void add_damper(Damper damper);
  void add_bushing(Bushing bushing);
  void add_generalized_force(GeneralizedForce force);
  void add_applied_force(AppliedForce force);
  void add_output(Output output);
  /// A loop-closure constraint (validate() checks its markers and symbols).
  void add_constraint(Constraint constraint);
  /// The coordinates the linear model keeps (the rest are dependent, found from the
  /// constraints); when not set, the generator chooses them by pivoted QR of the constraint
  /// Jacobian at the operating point (loop_closure.hpp).
  void set_independent_coordinates(std::vector<SceneItem> names) { independent_ = std::move(names); }
  /// A nonholonomic constraint (validate() checks that it is linear in the rates).
  void add_velocity_constraint(VelocityConstraint constraint);
  /// The rates that stay independent speeds with nonholonomic constraints (the rest follow from
  /// the constraints); when not set, chosen by pivoted QR at the operating point (nonholonomic.hpp).
  void set_independent_speeds(std::vector<SceneItem> names) { independent_speeds_ = std::move(names); }
  /// Named parts of the reduced second-order form (checked by the generator: each reduced matrix
  /// that has named parts must be their sum).
  void set_reduced_coefficients(std::vector<NamedCoefficient> c) { reduced_coefficients_ = std::move(c); }
  const std::vector<NamedCoefficient>& reduced_coefficients() const { return reduced_coefficients_; }
  void set_operating_point(LinearizationPoint op) { operating_point_ = std::move(op); }
  /// The full scene with the `sensitivity` kernel too, by `parameters` (empty: all), in the
  /// model's order (issue 40 §2: made only when asked). std::invalid_argument for an unknown
  /// parameter (listing the known ones) or a model pruned for a scene (whose analyses say whether
  /// it has sensitivities).
  void request_sensitivity(const std::vector<std::string>& parameters);
  /// Adds a scene; its references are checked by validate().
  void add_scene(Scene scene);
  /// Records where the subexpression `node` (a call or power) was written; the first record of
  /// equal nodes is kept. Optional: without it validate() reports at the element.
  void add_call_site(const GiNaC::ex& node, CallSite site) { call_sites_.emplace(node, std::move(site)); }
  /// The record of add_call_site for `node`, or nullptr.
  const CallSite* call_site(const GiNaC::ex& node) const {
    auto it = call_sites_.find(node);
    return it == call_sites_.end() ? nullptr : &it->second;
  }
  /// False drops the velocity-quadratic inertia terms (gyroscopic, centrifugal and Coriolis
  /// forces) from k(y, ẏ); apply_scene() does so when a scene deactivates them or linearizes
  /// about rest, where they cannot contribute.
  void set_inertial_velocity_terms(bool on) { inertial_velocity_terms_ = on; }

  /// Symbol of a parameter, coordinate (position), coordinate rate (`NAME_dot`) or input.
  GiNaC::ex symbol(const std::string& name) const;
  /// The table every expression of this model is parsed against.
  const GiNaC::symtab& symbol_table() const { return symtab_; }

  const std::vector<Parameter>& parameters() const { return parameters_; }
  const std::vector<Coordinate>& coordinates() const { return coordinates_; }
  const std::vector<Input>& inputs() const { return inputs_; }
  const std::vector<GiNaC::symbol>& input_symbols() const { return input_symbols_; }
  /// The symbols of the force inputs (those that must enter forces linearly).
  std::vector<GiNaC::symbol> force_input_symbols() const;
  /// True when some input prescribes motion.
  bool has_motion_inputs() const;
  const std::vector<Body>& bodies() const { return bodies_; }
  const std::vector<Marker>& markers() const { return markers_; }
  const std::vector<Gravity>& gravity() const { return gravity_; }
  const std::vector<Spring>& springs() const { return springs_; }
  const std::vector<Damper>& dampers() const { return dampers_; }
  const std::vector<Bushing>& bushings() const { return bushings_; }
  const std::vector<GeneralizedForce>& generalized_forces() const { return generalized_forces_; }
  const std::vector<AppliedForce>& applied_forces() const { return applied_forces_; }
  const std::vector<Output>& outputs() const { return outputs_; }
  const std::vector<Constraint>& constraints() const { return constraints_; }
  const std::vector<SceneItem>& independent_coordinates() const { return independent_; }
  const std::vector<VelocityConstraint>& velocity_constraints() const { return velocity_constraints_; }
  const std::vector<SceneItem>& independent_speeds() const { return independent_speeds_; }
  /// True when the motion has nonholonomic constraints (velocity constraints or rolling wheels):
  /// the linear model is then first order, E ẋ = A x + B u (nonholonomic.hpp).
  bool nonholonomic() const;
  const LinearizationPoint& operating_point() const { return operating_point_; }
  const std::vector<Scene>& scenes() const { return scenes_; }
  /// The scene of that name, or nullptr (also for the implicit "full").
  const Scene* scene(const std::string& name) const;
  bool inertial_velocity_terms() const { return inertial_velocity_terms_; }
  /// The scene this model was pruned for by apply_scene() (the full scene otherwise).
  const SceneSelection& selection() const { return selection_; }

  /// Index of a body (kWorld → -1); throws std::out_of_range for unknown names.
  int body_index(const std::string& name) const;
  /// Index of a coordinate; -1 when unknown.
  int coordinate_index(const std::string& name) const;
  const Marker& marker(const std::string& name) const;
  bool has_marker(const std::string& name) const;

  /// Checks references (parents, markers, coordinates), the tree (no cycles, every body reaches
  /// the world), masses and inertias (a physical tensor, decided exactly when its entries are
  /// rational at the default parameter values), rest lengths (>= 0), that every expression uses
  /// only known symbols, that inputs enter forces linearly, every scene (check_scene in
  /// scene.hpp), and, at a given operating point with the default parameter values, that every
  /// call and power of a state-dependent expression has the derivatives the linear model needs
  /// (not abs(x_dot) at x_dot = 0, sqrt(x) at x = 0) and that no spring (of nonzero rest length)
  /// or damper joins two coincident points. Throws ModelError at the offending element (at the
  /// call, when add_call_site recorded it).
  void validate() const;
  /// The conditions of validate() on masses, inertia tensors, rod lengths, wheel radii and rest
  /// lengths whose values depend on parameters (those that do not were decided by validate()),
  /// in the order bodies, constraints, springs.
  std::vector<PhysicalCheck> physical_checks() const;

 private:
  friend Model apply_scene(const Model& model, const std::string& scene);
  friend Model with_joint_probes(const Model& model, const std::vector<std::string>& bodies);
  friend Model with_motion_coordinates(const Model& model);
  friend std::string fresh_body(const Model& model, std::string base);
  friend void hold_dropped_supports(Model& m, const GiNaC::exmap& dropped);

  void check_new_symbol(const std::string& name, const SourceLocation& where);
  void check_new_element(const std::string& name, const char* kind, const SourceLocation& where);
  void validate_force_output(const Output& output) const;
  std::set<std::string> symbol_names(bool coordinates) const;
  static void check_symbols(const GiNaC::ex& e, const SourceLocation& where, const std::string& what,
                            const std::set<std::string>& allowed);
  void validate_constraints(const GiNaC::exmap& defaults) const;
  void validate_velocity_constraints() const;
  void validate_motion_inputs() const;
  void validate_rolling(const Constraint& c, const std::string& who, const GiNaC::exmap& defaults,
                        const std::set<std::string>& parameters_only) const;

  std::string name_;
  GiNaC::symtab symtab_;
  std::vector<Parameter> parameters_;
  std::vector<Coordinate> coordinates_;
  std::vector<Input> inputs_;
  std::vector<GiNaC::symbol> input_symbols_;
  std::vector<Body> bodies_;
  std::vector<Marker> markers_;
  std::vector<Gravity> gravity_;
  std::vector<Spring> springs_;
  std::vector<Damper> dampers_;
  std::vector<Bushing> bushings_;
  std::vector<GeneralizedForce> generalized_forces_;
  std::vector<AppliedForce> applied_forces_;
  std::vector<Output> outputs_;
  std::vector<Constraint> constraints_;
  std::vector<SceneItem> independent_;
  std::vector<VelocityConstraint> velocity_constraints_;
  std::vector<SceneItem> independent_speeds_;
  std::vector<NamedCoefficient> reduced_coefficients_;
  LinearizationPoint operating_point_;
  std::vector<Scene> scenes_;
  bool inertial_velocity_terms_ = true;
  SceneSelection selection_;
  std::map<std::string, int> body_index_;
  std::map<std::string, int> marker_index_;
  std::map<std::string, SourceLocation> symbol_names_;  // parameters, coordinates, rates, inputs
  std::map<std::string, std::pair<std::string, SourceLocation>> element_names_;  // name → kind
  std::map<GiNaC::ex, CallSite, GiNaC::ex_is_less> call_sites_;
};

}  // namespace mbsgen
