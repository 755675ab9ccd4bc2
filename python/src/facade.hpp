// The C++ side of the Python package (issue 41): a model loaded from its tape and the analyses of
// the runtime, with plain arguments and results — vectors and matrices of doubles, strings —
// that any binding library converts. module.cpp binds them with pybind11; nothing here includes
// it. The rules that keep a move to nanobind mechanical (docs/python.md, "The facade"): arrays
// come in as Eigen::Ref (no copy of a NumPy array in the right layout), results are structs of
// Eigen matrices and std::strings (no container of Eigen types), and no function here knows of
// Python objects, the GIL or exceptions of the binding.
#pragma once

#include <Eigen/Dense>

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace mbsgen {
class TapeModel;
struct ModelKernels;
}

namespace mbsgen::python {

using Vector = Eigen::VectorXd;
using Matrix = Eigen::MatrixXd;
using ConstVectorRef = Eigen::Ref<const Eigen::VectorXd>;
using ConstMatrixRef = Eigen::Ref<const Eigen::MatrixXd>;

/// The linear model at the operating point: M ÿ + Q ẏ + K y = B u (+ B1 u̇ + B2 ü),
/// z = C_y y + C_v ẏ + C_a ÿ + D u (+ D1 u̇). C_a, D, B1, B2, D1 are 0×0 when zero; for a model with
/// rolling constraints (descriptor) E ẋ = A x + B u, z = C x instead, M … D1 empty.
struct Linear {
  bool descriptor = false;
  Matrix M, Q, K, B, C_y, C_v, C_a, D, B1, B2, D1;
  Matrix E, A, C;                       // descriptor models only
  std::vector<std::string> state_names;  // descriptor models: the coordinates, then "NAME_dot"
};

/// How the operating point was found.
struct OperatingPoint {
  Vector y0, yd0;
  bool equilibrium = false;
  int iterations = 0;
  double residual_norm = 0;
  std::string report;
};

/// Eigenvalues of λ²M + λQ + K (or λE − A), one per conjugate pair unless all.
struct Modes {
  Eigen::VectorXcd eigenvalues;  // 1/s
  Vector natural_frequency_hz, damped_frequency_hz, damping_ratio, backward_error, error_bound;
  std::vector<std::string> kinds;  // "finite", "zero", "infinite", "zero_within_bound"
  Eigen::MatrixXcd shapes;         // column k: mode k's right eigenvector
  std::string stability, method;
};

/// One input's response at one output over frequencies in Hz.
struct Response {
  Eigen::VectorXcd values;
  Vector rcond;
  std::vector<std::string> flags, warnings;
  std::string method;
};

/// Eigenvalue sensitivities (runtime/spectral/sensitivity.hpp): every eigenvalue, both members of
/// a conjugate pair, by each parameter asked for. Entries of a mode whose derivative is not defined
/// (a repeated, defective, zero or infinite eigenvalue) are NaN, its note says why.
struct ModeSensitivities {
  Modes modes;
  std::vector<std::string> parameters;
  Vector parameter_values;
  Eigen::MatrixXcd dlambda;  // modes × parameters, 1/s per unit of the parameter
  Matrix dfrequency_hz, relative_frequency, ddamping_ratio;  // modes × parameters
  std::vector<std::string> notes;  // per mode: "" or "repeated", "defective", "zero", "infinite"
};

/// A response and its derivatives by parameters (the direct method).
struct ResponseSensitivity {
  Eigen::VectorXcd values;
  Eigen::MatrixXcd derivatives;  // parameters × frequencies: dz/dp
  Vector rcond;
  std::vector<std::string> parameters;
  Vector parameter_values;
};

/// A simulation's samples (columns are times) and the integrator's statistics.
struct Simulation {
  Vector t;
  Matrix y, yd, u, z;  // coordinates, rates, inputs, outputs × samples (z: 0 rows without outputs)
  bool analytic_jacobian = false;
  double constraint_drift = 0;
  long steps = 0, rhs_evaluations = 0, jacobian_evaluations = 0, error_test_failures = 0, nonlinear_failures = 0;
};

/// What simulate integrates: the method (bdf, adams, radau, radau9), the span and sampling, the
/// tolerances, initial values by name (`phi`, `phi_dot`), and one signal per input: a
/// command-line form (`sine:1,5`, `step:2,0.1`, a number; "" is zero) or a table of times and
/// values (table_times[j] non-empty).
struct SimulationRequest {
  std::string method = "bdf";
  double duration = 1, step = 0, rtol = 1e-8, atol = 1e-10;
  std::vector<std::string> initial_names;
  std::vector<double> initial_values;
  std::vector<std::string> input_specs;
  std::vector<Vector> table_times, table_values;
  bool outputs = true;
};

/// Eigenvalues against a parameter and the values where the stability changes
/// (runtime/spectral/parameter_sweep.hpp). eigenvalues: one row per value, the finite eigenvalues
/// (both members of a pair) in the solver's order, NaN after a row's last.
struct Sweep {
  Vector values;
  Eigen::MatrixXcd eigenvalues;
  std::vector<long> zeros;  // per value: how many of the first eigenvalues are exact (deflated) zeros
  Vector abscissa;          // max Re λ respecting the error bounds (−∞: none)
  std::vector<std::string> stability;
  Vector boundary_values, boundary_tolerances;
  std::vector<int> becomes_unstable;
  Eigen::VectorXcd boundary_eigenvalues;
  std::vector<std::string> below, above;
};

/// A parameter study (runtime/study/study.hpp): each parameter's distribution in the command
/// line's form ("NAME=uniform:LO:HI", "NAME=normal:MEAN:SD", "NAME=lognormal:MEDIAN:FACTOR"), the
/// design ("monte-carlo", "latin-hypercube", "saltelli"), what each evaluation records.
struct StudyRequest {
  std::vector<std::string> parameters;
  std::string design = "monte-carlo";
  long samples = 100;
  unsigned long long seed = 1;
  int modes = 0;
  std::string input, output, method = "auto";
  Vector sweep_hz, at_hz;
  int threads = 0;
  long bootstrap = 1000;  // Saltelli: resamples of the Sobol' indices' intervals
};

/// Its results, a row per evaluation: the parameter values, the scalars (f1_hz, zeta1, …,
/// L_<f>Hz_dB), the response magnitude at sweep_hz; NaN where an evaluation failed. With a
/// Saltelli design, the Sobol' indices of every scalar (scalars × parameters) with the bounds of
/// their 95 % bootstrap intervals.
struct Study {
  std::vector<std::string> parameter_names, scalar_names;
  Matrix samples, scalars, sweep;
  std::vector<long> failed;
  std::vector<std::string> reasons;
  Matrix first, first_low, first_high, total, total_low, total_high;
};

/// One response per parameter set: row k of values for set k, NaN where the set failed.
struct BatchResponse {
  Eigen::MatrixXcd values;
  std::vector<long> failed;          // the sets that failed, in order
  std::vector<std::string> reasons;  // why, one per failed set
};

using ConstRowMajorRef = Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;

/// Thrown by a long computation that `stop` ended (the binding turns it into the Python
/// exception that stop found pending, such as KeyboardInterrupt).
class Stopped : public std::runtime_error {
 public:
  Stopped() : std::runtime_error("stopped") {}
};

/// A model from a tape file (`mbsgen tape MODEL` prints the cached one's path) or from a shared
/// library of compiled kernels (`mbsgen kernels MODEL`: any model, closed loops included), told
/// apart by their first bytes.
class Model {
 public:
  explicit Model(const std::string& path);
  ~Model();
  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;

  std::string name() const;
  std::string scene() const;
  std::string evaluation() const;  // "tape" or "compiled"
  std::vector<std::string> parameter_names() const;
  std::vector<std::string> parameter_units() const;
  Vector parameter_defaults() const;
  std::vector<std::string> coordinate_names() const;
  std::vector<std::string> coordinate_units() const;
  std::vector<std::string> input_names() const;
  std::vector<std::string> input_units() const;
  std::vector<std::string> output_names() const;
  std::vector<std::string> output_units() const;
  bool descriptor() const;
  /// The scene's frequency range and count (0, 0, 0: none given) and whether it is linear.
  double default_from_hz() const;
  double default_to_hz() const;
  int default_points() const;

  // Each analysis takes every parameter's value, in parameter_names()' order (DimensionError for
  // another count, NonFiniteError for NaN or ∞, ParameterError for values no body has).
  OperatingPoint operating_point(const ConstVectorRef& p) const;
  Linear linear(const ConstVectorRef& p) const;
  Modes modes(const ConstVectorRef& p, bool all) const;
  /// input and output by name (NameError listing the known ones); method as `frf --method`.
  Response frf(const ConstVectorRef& p, const std::string& input, const std::string& output,
               const ConstVectorRef& hz, const std::string& method) const;
  /// The derivatives of the modes by the named parameters (all when empty): forward mode over
  /// the tape, or the compiled sensitivity kernel. Error for a model with rolling constraints.
  ModeSensitivities modes_sensitivity(const ConstVectorRef& p, const std::vector<std::string>& names) const;
  ResponseSensitivity frf_sensitivity(const ConstVectorRef& p, const std::string& input, const std::string& output,
                                      const ConstVectorRef& hz, const std::vector<std::string>& names) const;
  /// frf for each row of sets (every parameter, in order), on `threads` threads (0: one per
  /// core). A set that fails (a negative mass, no equilibrium) leaves a row of NaN and its reason;
  /// the others are what frf gives for them, bit for bit. stop (may be empty) is asked after each
  /// set the calling thread computes; when it says true, the threads finish their sets and
  /// Stopped is thrown.
  BatchResponse frf_batch(const ConstRowMajorRef& sets, const std::string& input, const std::string& output,
                          const ConstVectorRef& hz, const std::string& method, int threads,
                          const std::function<bool()>& stop = {}) const;
  /// The outputs at the operating point.
  Vector outputs(const ConstVectorRef& p) const;
  /// `parameter` from `from` to `to` at `points` values (linear), the others at p.
  Sweep sweep(const ConstVectorRef& p, const std::string& parameter, double from, double to, int points,
              double relative_tolerance) const;
  Study study(const ConstVectorRef& p, const StudyRequest& request) const;
  /// Integrates the nonlinear equations of motion from the operating point (runtime/time/
  /// simulation.hpp); stop (may be empty) is asked after each sample, and Stopped thrown when it
  /// says true.
  Simulation simulate(const ConstVectorRef& p, const SimulationRequest& request,
                      const std::function<bool()>& stop = {}) const;
  /// M(y) and the accelerations ÿ = −M(y)⁻¹ r(y, ẏ, u) of the equations of motion M ÿ + r = 0
  /// (r = k − q, the `residual` kernel): the right-hand side an integrator calls. A model with
  /// closed loops or rolling constraints has no such explicit form here (Error); DimensionError
  /// for vectors of the wrong size, NonFiniteError for a kernel value that is not finite,
  /// SingularSystemError for a singular M.
  Matrix mass_matrix(const ConstVectorRef& p, const ConstVectorRef& y) const;
  Vector accelerations(const ConstVectorRef& p, const ConstVectorRef& y, const ConstVectorRef& yd,
                       const ConstVectorRef& u) const;
  /// The kernels (for the fit's facade, fit_facade.hpp).
  const ModelKernels& kernels() const { return *kernels_; }

 private:
  std::shared_ptr<void> library_;  // the compiled kernels' dlopen handle (declared first: closed last)
  std::unique_ptr<TapeModel> tape_;
  const ModelKernels* kernels_ = nullptr;
};

/// Modes of M ÿ + Q ẏ + K y = 0 given as matrices (Q may be 0×0: zero).
Modes modes_of(const ConstMatrixRef& M, const ConstMatrixRef& Q, const ConstMatrixRef& K, bool all);
/// The response of output row `output` to input column `input` (0-based) of
/// M ÿ + Q ẏ + K y = B u, z = C_y y + C_v ẏ (C_v may be 0×0: zero), at frequencies in Hz.
Response frf_of(const ConstMatrixRef& M, const ConstMatrixRef& Q, const ConstMatrixRef& K, const ConstMatrixRef& B,
                const ConstMatrixRef& C_y, const ConstMatrixRef& C_v, Eigen::Index input, Eigen::Index output,
                const ConstVectorRef& hz, const std::string& method);

}  // namespace mbsgen::python
