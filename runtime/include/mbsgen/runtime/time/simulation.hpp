// Time-domain simulation of the nonlinear equations of motion M(y) ÿ + k(y, ẏ) − q(y, ẏ, u) = 0
// of a generated model (issue 18), on the explicit first-order form
//
//   x' = (v, ÿ),   ÿ = −M(y)⁻¹ (k − q)(y, v, u(t)),   x = (y, v),
//
// with a solve with M at each right-hand side (Cholesky's factors, block by block where M is
// block diagonal, or the LU's where Cholesky fails; mostly refined on the last factors where M
// is near them; a singular M is reported at the next fresh factorization, at most 64
// evaluations after it occurs: docs/simulation.md). Four methods: Radau IIA of orders 5 and 9 (ours,
// after RADAU5 and RADAU: stiff and oscillating motion, tight tolerances; order 9 with longer steps
// on smooth motion), and SUNDIALS CVODE's BDF (orders 1–5,
// for stiff models such as the middle ear) with Newton's iteration on the Jacobian
// ∂x'/∂x = [0, I; −M⁻¹ K_y, −M⁻¹ K_v] from the generated kernel `dynamics_jacobian`
// (K_y = ∂(M ÿ + k − q)/∂y at the current ÿ, K_v = ∂(k − q)/∂ẏ), or from difference quotients
// for kernels generated without it; and Adams–Moulton (orders 1–12, with
// fixed-point iteration) for non-stiff motion, where its higher order takes fewer and more
// accurate steps (a pendulum, a conservative linkage). docs/simulation.md compares them and says
// why CVODE rather than IDA.
#pragma once

#include <Eigen/Core>

#include <functional>
#include <string>
#include <vector>

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/model/generated_model.hpp"

namespace mbsgen {

/// A simulation that could not go on: the integrator could not meet its tolerance, the mass
/// matrix became singular, a kernel returned non-finite values. time() is where it happened; the
/// samples before it are not returned (no silently truncated result).
class SimulationError : public Error {
 public:
  SimulationError(const std::string& what, double time) : Error(what), time_(time) {}
  double time() const { return time_; }

 private:
  double time_;
};

/// `text` as a finite double, all of it; NameError "WHAT: 'TEXT' is not a finite number" otherwise
/// (the command line's values of `--input` and `--initial`).
double finite_number(const std::string& text, const std::string& what);

/// An input as a function of time.
class InputSignal {
 public:
  InputSignal() = default;  ///< zero
  static InputSignal constant(double value);
  /// offset + amplitude·sin(2π f t + phase).
  static InputSignal sine(double amplitude, double frequency_hz, double phase_rad = 0, double offset = 0);
  /// `before` until `time`, then `before + amplitude` (a breakpoint at `time`).
  static InputSignal step(double amplitude, double time = 0, double before = 0);
  /// amplitude·sin(φ(t)) with the frequency rising linearly from f0 at t = 0 to f1 at t = duration
  /// (and held at f1 after it).
  static InputSignal chirp(double amplitude, double f0_hz, double f1_hz, double duration);
  /// Linear interpolation in a table of strictly increasing times, the end values held outside;
  /// DimensionError / Error for mismatched sizes, fewer than one point, non-increasing times or
  /// non-finite values.
  static InputSignal table(std::vector<double> times, std::vector<double> values);
  /// Parses the command line's form (docs/cli.md, `simulate --input`): VALUE, `sine:AMPLITUDE,HZ
  /// [,PHASE_DEG[,OFFSET]]`, `step:AMPLITUDE[,TIME[,BEFORE]]`, `chirp:AMPLITUDE,F0_HZ,F1_HZ[,
  /// DURATION]` (default: `duration`), `table:FILE` (a CSV file of t,value lines; lines starting
  /// with # are comments, and a first line whose first field does not start like a number is a
  /// header). NameError with the reason for anything else.
  static InputSignal parse(const std::string& spec, double duration);

  double operator()(double t) const;
  /// True for the default signal (zero for all time).
  bool is_zero() const { return kind_ == Kind::constant && a_ == 0; }
  /// Times where the signal jumps (a step): the integrator restarts there.
  const std::vector<double>& breakpoints() const { return breakpoints_; }
  /// Times where its slope jumps (a table's points): the integrator stops there, so that it
  /// cannot step over a short feature of the table.
  const std::vector<double>& knots() const { return t_; }

 private:
  enum class Kind { constant, sine, step, chirp, table } kind_ = Kind::constant;
  double a_ = 0, b_ = 0, c_ = 0, d_ = 0;
  std::vector<double> t_, v_, breakpoints_;
};

/// bdf and adams: SUNDIALS CVODE; radau: Radau IIA of order 5 (three stages; radau.hpp in the
/// runtime's sources; Hairer and Wanner's RADAU5 on the implicit form M(y) ÿ + k − q = 0);
/// radau9: Radau IIA of order 9 (five stages; fewer, longer steps on smooth motion, from
/// moderate tolerances on: the middle ear at rtol 1e-4 takes a quarter of radau's steps).
enum class IntegrationMethod { bdf, adams, radau, radau9 };

struct SimulationOptions {
  IntegrationMethod method = IntegrationMethod::bdf;
  double duration = 1;  ///< s, > 0
  double step = 1e-2;   ///< output sampling, s, > 0; the last sample is at `duration`
  double rtol = 1e-8, atol = 1e-10;
  /// Absolute tolerances of single coordinates (`phi`) or rates (`phi_dot`) instead of `atol`,
  /// in their own units: for states of different sizes (metres and radians, or nanometres beside
  /// a rotation), atol of about rtol × the size each reaches.
  std::vector<std::pair<std::string, double>> atol_of;
  /// Initial coordinates and rates by name (`phi`, `phi_dot`); the others start at the
  /// operating point's values.
  std::vector<std::pair<std::string, double>> initial;
  /// One signal per input, in the kernels' order, or empty for all inputs zero.
  std::vector<InputSignal> inputs;
  /// BDF and Radau: difference-quotient Jacobians even when the kernels have `dynamics_jacobian`.
  bool difference_quotients = false;
  /// False: the outputs are not evaluated (SimulationResult::z has no rows). Outputs that depend
  /// on ÿ cost one evaluation of the equations of motion per sample.
  bool outputs = true;
  /// Called after each output sample with its time (a progress bar).
  std::function<void(double)> progress;
};

struct SimulationResult {
  Eigen::VectorXd t;      ///< sample times, s
  Eigen::MatrixXd y, yd;  ///< n_coordinates × samples
  Eigen::MatrixXd u;      ///< n_inputs × samples
  Eigen::MatrixXd z;      ///< n_outputs × samples (0 × samples when !simulates_outputs() or !options.outputs)
  bool analytic_jacobian = false;  ///< BDF's Newton matrices from `dynamics_jacobian`
  /// Closed loops: the largest |Φ| over the samples, in the constraints' units (metres for a
  /// pin). The kernels close the loops by Newton's method at every evaluation (coordinate
  /// partitioning: the state holds the independent coordinates), so this is the closure's own
  /// residual; 0 for a model without loops.
  double constraint_drift = 0;
  long steps = 0, rhs_evaluations = 0, jacobian_evaluations = 0, error_test_failures = 0,
       nonlinear_failures = 0, restarts = 0;
};

/// Whether simulate() gives the outputs of kernels k (SimulationResult::z): they need
/// `outputs_general`, or `outputs` when no output depends on ÿ or u.
bool simulates_outputs(const ModelKernels& k);

/// Integrates the model from the operating point `op` (with options.initial applied) over
/// [0, duration]. Throws NameError for an unknown initial name, DimensionError for a wrong number
/// of input signals, Error for invalid options or a model without second-order kernels (a
/// nonholonomic model), SimulationError when the integration fails.
SimulationResult simulate(const GeneratedModel& model, const OperatingPoint& op, const SimulationOptions& options);

struct SineResponseOptions {
  IntegrationMethod method = IntegrationMethod::bdf;
  int periods = 20;              ///< simulated periods
  int fit_periods = 10;          ///< the last ones, over which the fundamental is fitted
  int samples_per_period = 64;
  double rtol = 1e-9;
  /// atol = rtol × atol_fraction × the largest entry of the linear steady state's |ŷ|: the
  /// motion's size sets what "absolute" means (the middle ear's is nanometres).
  double atol_fraction = 1e-3;
};

/// The steady state of the nonlinear model under u_input = A sin(2π f t) (the other inputs 0).
struct SineResponse {
  /// Per output, the complex amplitude Z of its fundamental, z ≈ c + Im(Z e^{iΩt}) (so Z/A is
  /// the frequency response's value when the model is linear), and the constant c.
  Eigen::VectorXcd fundamental;
  Eigen::VectorXd offset;
  /// Per output, the RMS of what the fit leaves (harmonics, the rest of the transient) relative
  /// to |Z|.
  Eigen::VectorXd distortion;
  long steps = 0;
};

/// Integrates from the linear steady state y = y0 + Im(ŷ e^{iΩt}), ŷ = (K − Ω²M + iΩQ)⁻¹ B A
/// (so that only the nonlinearity's own transient remains) over options.periods periods and fits
/// the outputs' fundamentals by least squares over the last fit_periods. Throws like simulate(),
/// DimensionError for a bad input index, Error for a model without outputs or a non-positive
/// frequency or amplitude.
SineResponse sine_response(const GeneratedModel& model, const OperatingPoint& op, Eigen::Index input, double hz,
                           double amplitude, const SineResponseOptions& options = {});

}  // namespace mbsgen
