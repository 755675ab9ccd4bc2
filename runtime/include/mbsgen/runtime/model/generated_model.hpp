// A model compiled from generated kernels (issue 4): parameters by name, the operating point
// (given, or a static equilibrium found by Newton's method) and the LinearModel there.
//
// The generator writes, beside the C kernels <id>.cpp, a typed API <id>_model.hpp whose
// `kernels()` returns the ModelKernels below; GeneratedModel works on any of them, so the solver
// command line (solver_cli.hpp) is one program for every model.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/model/descriptor_model.hpp"
#include "mbsgen/runtime/model/linear_model.hpp"

namespace mbsgen {

/// ABI version of the generated kernels this runtime understands (the generator's kAbiVersion).
constexpr int kKernelAbiVersion = 1;

/// Description of one generated model (one scene): sizes, names, defaults and the C kernels.
/// Kernels a scene does not need are null. Matrices are column-major.
struct ModelKernels {
  const char* id;
  const char* model;
  const char* scene;
  int abi_version;
  int n_coordinates, n_inputs, n_outputs, n_parameters;
  bool at_rest;      ///< the operating point has ẏ0 = 0 (yd0 is not an argument of `linear`)
  bool equilibrium;  ///< the operating point is a static equilibrium (operating_point = guess)
  double default_from_hz, default_to_hz;  ///< the scene's frequency range (0, 0: none given)
  const char* const* coordinate_names;
  const char* const* coordinate_units;
  const char* const* parameter_names;
  const char* const* parameter_units;
  const double* parameter_defaults;
  const char* const* input_names;
  const char* const* input_units;
  const char* const* output_names;
  const char* const* output_units;
  int (*operating_point)(const double* p, double* y0, double* yd0);
  int (*linear)(const double* y0, const double* yd0, const double* p, double* M, double* Q,
                double* K, double* B, double* Cy, double* Cv);
  int (*residual)(const double* y, const double* yd, const double* u, const double* p, double* r);
  int (*mass_matrix)(const double* y, const double* p, double* M);
  // After the kernels, with defaults, so that a typed API generated before these fields existed
  // still initialises the struct (and means: not recorded).
  int default_points = 0;                   ///< the scene's number of frequencies (0: none given)
  bool default_linear_spacing = false;      ///< the scene's spacing is linear (else logarithmic)
  const char* generator_version = nullptr;  ///< mbsgen version that generated the kernels, or null
  /// Optional (null: the outputs depend on y and ẏ only): the output terms z += C_a ÿ + D u of
  /// outputs that depend on the accelerations or directly on the inputs (joint loads, issue 15
  /// §3), at the operating point, column-major: Ca n_outputs×n_coordinates, D
  /// n_outputs×n_inputs. Returns a status like `linear`. Trailing, so the ABI version is
  /// unchanged (docs/generated-abi.md).
  int (*output_terms)(const double* y0, const double* yd0, const double* p, double* Ca,
                      double* D) = nullptr;
  /// Optional (null: not recorded): the outputs z(y, ẏ) at any state (for outputs that depend
  /// on ÿ and u, at ÿ = 0 and u = 0: the static loads that `static` prints). Trailing.
  int (*outputs)(const double* y, const double* yd, const double* p, double* z) = nullptr;
  /// Nonholonomic models (issue 16): the number of independent speeds, their names (the
  /// coordinates whose rates they are), and the descriptor kernel E x' = A x + B u, z = C x at
  /// (y0, yd0) with x = (the n_coordinates coordinates, the n_speeds speeds), column-major:
  /// E, A n×n, B n×n_inputs, C n_outputs×n (n = n_coordinates + n_speeds). `linear`, `residual`
  /// and `mass_matrix` are then null. Trailing.
  int n_speeds = 0;
  const char* const* speed_names = nullptr;
  int (*descriptor)(const double* y0, const double* yd0, const double* p, double* E, double* A, double* B,
                    double* C) = nullptr;
  /// Where it exists, the reduced second-order form M q'' + Q q' + K q = B u of the descriptor
  /// model on n_reduced of the coordinates (a bicycle's lean and steer), column-major. Trailing.
  int n_reduced = 0;
  const char* const* reduced_coordinate_names = nullptr;
  int (*reduced)(const double* y0, const double* yd0, const double* p, double* M, double* Q, double* K,
                 double* B) = nullptr;
  /// The model's named parts of the reduced form (`reduced_form` in the model file: the bicycle's
  /// M, C1, K0, K2), n_reduced×n_reduced each, column-major, one after the other. Trailing.
  int n_reduced_parts = 0;
  const char* const* reduced_part_names = nullptr;
  int (*reduced_parts)(const double* y0, const double* p, double* C) = nullptr;
  /// Time integration (issue 18; `mbsgen generate --dynamics`, EmitOptions::dynamics): M(y) and
  /// k − q in one kernel, and the Jacobians of F = M(y) ÿ + k − q at any state, Ky = ∂F/∂y (f×f,
  /// with ∂(M ÿ)/∂y) and Kv = ∂F/∂ẏ, column-major (null: not emitted; the full model only, and
  /// not the Jacobian of a model with closed loops). Trailing.
  int (*dynamics)(const double* y, const double* yd, const double* u, const double* p, double* M,
                  double* r) = nullptr;
  int (*dynamics_jacobian)(const double* y, const double* yd, const double* ydd, const double* u,
                           const double* p, double* Ky, double* Kv) = nullptr;
  /// The outputs at any state, z(y, ẏ, ÿ, u) (null: the model has no outputs on ÿ or u, and
  /// `outputs` gives them). Trailing.
  int (*outputs_general)(const double* y, const double* yd, const double* ydd, const double* u,
                         const double* p, double* z) = nullptr;
  /// Closed loops (issue 15; null, 0: none): the tree's coordinates y (n_tree_coordinates) from the
  /// independent ones, and the constraints Φ(y) (n_constraints), for the drift a simulation
  /// reports. Trailing.
  int n_tree_coordinates = 0, n_constraints = 0;
  int (*assemble)(const double* yi, const double* p, double* y) = nullptr;
  int (*constraints)(const double* y, const double* p, double* phi) = nullptr;
  /// Closed loops, for a simulation that follows the motion through any range: `assemble`
  /// starting from the tree coordinates y holds on entry (Newton from a nearby closed
  /// configuration), and `dynamics`, `outputs` and `outputs_general` in the tree's coordinates y (closed)
  /// with the independent rates (null: not emitted, or generated before them). Trailing.
  int (*assemble_from)(const double* yi, const double* p, double* y) = nullptr;
  int (*dynamics_full)(const double* y, const double* yd, const double* u, const double* p, double* M,
                       double* r) = nullptr;
  int (*outputs_full)(const double* y, const double* yd, const double* p, double* z) = nullptr;
  int (*outputs_general_full)(const double* y, const double* yd, const double* ydd, const double* u,
                              const double* p, double* z) = nullptr;
  /// Prescribed motion (issue 19; null: every input is a force): per input "force" or "motion",
  /// and the terms a moving support adds at the operating point, column-major: B1, B2
  /// (n_coordinates×n_inputs) of h = B u + B1 u̇ + B2 ü, and D1 (n_outputs×n_inputs) of
  /// z += D1 u̇ (the outputs' D u comes from output_terms). Trailing.
  const char* const* input_kinds = nullptr;
  int (*excitation)(const double* y0, const double* yd0, const double* p, double* B1, double* B2,
                    double* D1) = nullptr;
  /// Parameter sensitivities (issue 20; null: not emitted): the s parameters, and the
  /// derivatives of the linear matrices by them at (y0, yd0), each matrix's s blocks one after
  /// the other, column-major (empty for matrices the model does not have: Ca, D without
  /// output_terms, B1, B2, D1 without excitation). dy0, dyd0 (f×s) are the operating point's
  /// derivatives, read only when operating_point_sensitivity is not null; that kernel gives
  /// them: for a given point dy0 and dyd0, for an equilibrium dr = ∂r/∂p + Q dyd0 (then
  /// K dy0 = −dr) and dyd0. Trailing.
  int n_sensitivity_parameters = 0;
  const char* const* sensitivity_parameter_names = nullptr;
  int (*sensitivity)(const double* y0, const double* yd0, const double* p, const double* dy0, const double* dyd0,
                     double* dM, double* dQ, double* dK, double* dB, double* dCy, double* dCv, double* dCa,
                     double* dD, double* dB1, double* dB2, double* dD1) = nullptr;
  int (*operating_point_sensitivity)(const double* y0, const double* yd0, const double* p, double* dy0,
                                     double* dyd0) = nullptr;
  /// The model file's physical conditions on the parameters (issue 39 §1; null, 0: none depend
  /// on a parameter, or generated before them): per check its kind ("positive": one value > 0;
  /// "nonnegative": one value >= 0; "body": seven values, mass, Ixx, Iyy, Izz, Ixy, Ixz, Iyz — a
  /// mass >= 0 and an inertia tensor of a mass distribution), its label ("body 'wheel'"), the unit
  /// of a one-value check, and the parameters it depends on (comma-separated); `physical` gives
  /// the values, one check after the other. GeneratedModel::check_parameters judges them. Trailing.
  int n_checks = 0;
  const char* const* check_kinds = nullptr;
  const char* const* check_labels = nullptr;
  const char* const* check_units = nullptr;
  const char* const* check_parameters = nullptr;
  int (*physical)(const double* p, double* v) = nullptr;
  /// How the kernels are evaluated (issue 40 §1): null for compiled code, "tape" for a
  /// TapeModel (model/tape.hpp), which `info` reports. Trailing.
  const char* evaluation = nullptr;
  /// `sensitivity` and `operating_point_sensitivity` along chosen parameters only (null: not
  /// offered): the same arguments after `count` and `which` (0-based indices into the sensitivity
  /// parameters), dy0, dyd0 and every derivative with `count` blocks. A tape offers them: its
  /// forward mode costs a pass per parameter, and a fit of 10 of the middle ear's 87 parameters
  /// needs 10 (issue 42); compiled kernels derive every parameter at once. Trailing.
  int (*sensitivity_along)(int count, const int* which, const double* y0, const double* yd0, const double* p,
                           const double* dy0, const double* dyd0, double* dM, double* dQ, double* dK, double* dB,
                           double* dCy, double* dCv, double* dCa, double* dD, double* dB1, double* dB2,
                           double* dD1) = nullptr;
  int (*operating_point_sensitivity_along)(int count, const int* which, const double* y0, const double* yd0,
                                           const double* p, double* dy0, double* dyd0) = nullptr;
};

/// True when input j of the kernels prescribes motion (input_kinds, prescribed motion).
inline bool is_motion_input(const ModelKernels& k, int j) {
  return k.input_kinds && k.input_kinds[j] && std::string(k.input_kinds[j]) == "motion";
}

/// The first n entries of a kernel name array (null entries become "").
std::vector<std::string> name_list(const char* const* names, int n);

/// A bad name or value from the user (unknown parameter, input or output; malformed value).
/// The message names what is wrong and lists what exists.
class NameError : public Error {
 public:
  using Error::Error;
};

/// A parameter value that breaks one of the model file's physical conditions (a negative mass or
/// wheel radius, an inertia tensor no mass distribution has): a bad value from the user.
class ParameterError : public NameError {
 public:
  using NameError::NameError;
};

/// The operating point of a GeneratedModel.
struct OperatingPoint {
  Eigen::VectorXd y0, yd0;
  bool equilibrium = false;  ///< found by Newton's method (otherwise given by the model)
  int iterations = 0;        ///< Newton steps
  double residual_norm = 0;  ///< ‖k − q‖₂ at (y0, yd0, u = 0), N or N·m
  std::string report;        ///< one line: how the point was obtained
};

/// Throws Error "<what> is not positive semi-definite with these parameter values (eigenvalues
/// …): a negative mass or inertia?" when the symmetric part of M has an eigenvalue below
/// −1e-12·n·‖M‖ (rounding). What linear_model, descriptor_model and simulate check, so that a
/// negative mass given at run time (--set, a sweep, a study sample) is refused everywhere.
void check_mass_semidefinite(const Eigen::MatrixXd& M, const std::string& what);

class GeneratedModel {
 public:
  /// Throws mbsgen::Error when the kernels' ABI version differs from kKernelAbiVersion.
  explicit GeneratedModel(const ModelKernels& kernels);

  const ModelKernels& kernels() const { return k_; }
  Eigen::Index size() const { return k_.n_coordinates; }

  const std::vector<std::string>& parameter_names() const { return parameter_names_; }
  const std::vector<double>& parameters() const { return p_; }
  /// Sets a parameter by name; NameError for an unknown name (listing the known ones),
  /// NonFiniteError for a NaN or infinite value.
  void set(const std::string& name, double value);
  /// Sets all parameters, in the kernels' order; DimensionError for a wrong count,
  /// NonFiniteError for a NaN or infinite value (naming the parameter).
  void set_parameters(const std::vector<double>& values);
  /// Parses "NAME=VALUE" (as `--set` gives it) and calls set(); NameError when malformed.
  void set(const std::string& assignment);

  /// Index of a coordinate, input or output by name; NameError listing the known ones.
  Eigen::Index input_index(const std::string& name) const;
  Eigen::Index output_index(const std::string& name) const;

  /// Throws ParameterError when the parameter values break one of the model file's physical
  /// conditions (ModelKernels::physical: masses >= 0, inertia tensors positive semi-definite with
  /// A + B >= C and zero with a zero mass, rod lengths and wheel radii > 0, rest lengths >= 0),
  /// naming the element, its value and the parameters it depends on with their values. Judged
  /// here, not by set(), so that several values set together are judged together;
  /// operating_point() calls it, so every analysis does.
  void check_parameters() const;

  /// The operating point: given by the model, or a static equilibrium from the model's initial
  /// guess (Newton with line search on the residual kernel, Jacobian K from the linear kernel).
  /// Checks the parameters first (check_parameters).
  /// Throws ConvergenceError or SingularSystemError when no equilibrium is found, NonFiniteError
  /// when a kernel returns a non-finite value.
  OperatingPoint operating_point() const;

  /// M, Q, K, B, C_y, C_v (and C_a, D when the kernels have `output_terms`) at the operating
  /// point, with names and units. Throws NonFiniteError
  /// when a kernel returns a non-finite value, and Error when M is not positive semi-definite
  /// (smallest eigenvalue below −1e-12·n·‖M‖): no mass distribution gives that, so a parameter
  /// set this way (a negative mass or inertia) would give numbers that only look like results.
  LinearModel linear_model(const OperatingPoint& op) const;
  LinearModel linear_model() const { return linear_model(operating_point()); }
  /// True when the kernels have `sensitivity` (issue 20: the full model, or a scene that asks
  /// for the analysis `sensitivity`; not for closed loops or rolling constraints).
  bool has_sensitivities() const { return k_.sensitivity != nullptr; }
  /// The parameters of the sensitivity kernel, in its order (empty without it).
  std::vector<std::string> sensitivity_parameters() const;
  /// The derivatives of the linear matrices at op by the named parameters (all of the kernel's
  /// when empty), in the order asked: the total derivatives, with the operating point's own
  /// (an equilibrium's by K dy0 = −(∂r/∂p + Q dẏ0)). Throws Error when the kernels have no
  /// sensitivity kernel (saying how to get one), NameError for a parameter the kernel does not
  /// have (listing those it has), SingularSystemError when an equilibrium's K is singular.
  std::vector<MatrixSensitivity> linear_sensitivities(const OperatingPoint& op,
                                                      const std::vector<std::string>& names = {}) const;
  /// True for a model with nonholonomic constraints, whose linear model is first order:
  /// descriptor_model() (linear_model() throws).
  bool is_descriptor() const { return k_.descriptor != nullptr; }
  /// E, A, B, C of E x' = A x + B u, z = C x at the operating point, with x = (coordinates,
  /// independent speeds): state names are the coordinates' and "NAME_dot" for the speeds. Throws
  /// Error for a model that is not a descriptor model, NonFiniteError for a non-finite kernel value.
  DescriptorModel descriptor_model(const OperatingPoint& op) const;
  DescriptorModel descriptor_model() const { return descriptor_model(operating_point()); }
  /// True when the descriptor model has a reduced second-order form (reduced_model()).
  bool has_reduced_form() const { return k_.reduced != nullptr; }
  /// M, Q, K, B of the reduced second-order form at the operating point, its coordinates named
  /// (outputs: the coordinates). Throws Error when the model has none.
  LinearModel reduced_model(const OperatingPoint& op) const;
  LinearModel reduced_model() const { return reduced_model(operating_point()); }
  /// The named parts of the reduced form at the operating point, by name (empty when the model
  /// names none).
  std::vector<std::pair<std::string, Eigen::MatrixXd>> reduced_parts(const OperatingPoint& op) const;
  /// The outputs z at the operating point (for outputs that depend on ÿ and u: at ÿ = 0 and
  /// u = 0, the static loads); empty when the kernels do not provide `outputs`.
  Eigen::VectorXd outputs(const OperatingPoint& op) const;
  /// The outputs z (joint loads included) at any state: coordinates y, rates ẏ, accelerations ÿ
  /// and inputs u (issue 39 §4; before, only a one-step simulation gave them). ÿ and u enter
  /// the outputs that depend on them (reactions, accelerations); the others read y and ẏ only.
  /// For a model with closed loops y are the independent coordinates, the loops closed by the
  /// kernels. Throws Error for a model with nonholonomic constraints (its coordinate rates are
  /// not free: a state that violates the velocity constraints would give numbers that mean
  /// nothing, and the kernels cannot check it), DimensionError for vectors of the wrong size,
  /// NonFiniteError for non-finite entries.
  Eigen::VectorXd outputs_at(const Eigen::VectorXd& y, const Eigen::VectorXd& yd, const Eigen::VectorXd& ydd,
                             const Eigen::VectorXd& u) const;

 private:
  Eigen::VectorXd residual(const Eigen::VectorXd& y, const Eigen::VectorXd& yd) const;
  const ModelKernels& k_;
  std::vector<std::string> parameter_names_;
  std::vector<double> p_;
};

}  // namespace mbsgen
