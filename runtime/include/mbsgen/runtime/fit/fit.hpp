// Parameter identification (issue 42): named parameters of a generated model fitted to measured
// frequency responses and modal data by nonlinear least squares with the exact Jacobian of the
// sensitivity kernels (GeneratedModel::linear_sensitivities), solved by Ceres Solver's
// Levenberg–Marquardt with bounds.
//
// Unknowns. θ_j = ln p_j for a parameter fitted in log space (the default for positive bounds),
// θ_j = p_j in linear space; bounds lo ≤ p ≤ hi become bounds on θ.
//
// Residuals (weighted by the data's standard deviations; unit weights where none are given):
//   frequency response:  ln|H(Ω)| − ln|H_d|  over σ_ln|H| (a relative magnitude error), and
//                        wrap(arg H(Ω) − arg H_d) over σ_arg [rad], wrap to (−π, π]:
//                        the real and imaginary parts of the complex log ratio log(H/H_d), so that
//                        a 10 % error counts the same at 100 Hz and at 10 kHz;
//   modal data:          (f_k − f_d)/(σ_f f_d) (σ_f relative) and (ζ_k − ζ_d)/σ_ζ, mode k the
//                        k-th oscillatory mode by natural frequency;
//   priors:              (θ_j − θ_j0)/w_j: log-normal about the model's value with one standard
//                        deviation a factor F (w = ln F), normal with standard deviation W in
//                        linear space.
// Jacobian: d ln H/dθ_j = (∂H/∂p_j / H) dp_j/dθ_j (frequency_response_sensitivity), df/dθ and
// dζ/dθ from eigenvalue_sensitivities: exact, no differencing.
//
// Results. The cost ½Σr²; the Gauss–Newton covariance C = s² (JᵀJ)⁻¹ (J with the priors' rows;
// s² = 2 cost/(m − n) when the data carry no standard deviations, 1 otherwise), standard errors,
// 95 % intervals (exp(θ ± z σ_θ) in log space: z the normal quantile, or Student's t with m − n
// degrees of freedom when s² is estimated), correlations; the Fisher information of the data
// alone F = JᵀJ/s² in relative coordinates (d ln p, or dp/|p̂| in linear space), whose
// eigenvectors with a standard deviation 1/√λ above 1 (a factor e) are the combinations the data
// cannot identify, named ("identified only as their ratio a/b"); profile likelihoods; the
// residual per data point.
#pragma once

#include <Eigen/Core>

#include <complex>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "mbsgen/runtime/model/generated_model.hpp"

namespace mbsgen {

/// Thrown when FitOptions::stop asked the fit to end.
class FitStopped : public Error {
 public:
  using Error::Error;
};

/// One measured frequency response point set: output `output` per input `input`.
struct FrfData {
  std::string source;  ///< file (for messages and the report)
  std::string set;     ///< data set label (a bone, a specimen); "" for one
  std::string input, output;
  std::vector<double> hz;
  std::vector<std::complex<double>> value;  ///< H_d (magnitude only: real, positive; has_phase false)
  std::vector<bool> has_phase;
  std::vector<bool> has_magnitude;          ///< false: a phase alone (|value| = 1)
  std::vector<double> sigma_ln_magnitude;   ///< > 0, or NaN: no standard deviation given
  std::vector<double> sigma_phase_rad;      ///< > 0, or NaN
  std::vector<int> line;                    ///< the file's line of each point
};

/// Measured natural frequencies and damping ratios.
struct ModalData {
  std::string source, set;
  std::vector<int> mode;                  ///< 1-based, among the oscillatory modes by frequency
  std::vector<double> frequency_hz;       ///< NaN: not given
  std::vector<double> sigma_frequency;    ///< relative, > 0 or NaN
  std::vector<double> damping_ratio;      ///< NaN: not given
  std::vector<double> sigma_damping;      ///< absolute, > 0 or NaN
  std::vector<int> line;
};

/// Reads measured data from CSV text (comments start with '#'; a header row names the columns).
/// Frequency responses: `frequency_hz` and either `re`,`im` or `magnitude` (or `magnitude_db`)
/// with optional `phase_deg` (a row with a phase and an empty magnitude gives the phase alone); optional `sigma_magnitude` (relative: σ of ln|H|),
/// `sigma_phase_deg`, `input`, `output`, `set`. Modal data: `mode` and `frequency_hz` and/or
/// `damping_ratio`, optional `sigma_frequency` (relative), `sigma_damping`, `set`. Empty cells
/// are "not given". Defaults for a file without input/output columns: default_input and
/// default_output. Throws ParseError "file:line:col: what" for a malformed file, NaN or
/// non-positive uncertainties, a magnitude ≤ 0, or unknown columns.
struct MeasuredData {
  std::vector<FrfData> responses;
  std::vector<ModalData> modal;
};
MeasuredData read_measured_data(const std::string& text, const std::string& origin, const std::string& default_input,
                                const std::string& default_output);
MeasuredData read_measured_data_file(const std::string& path, const std::string& default_input,
                                     const std::string& default_output);

/// One fitted parameter.
struct FitParameter {
  std::string name;
  double lower = 0, upper = 0;  ///< bounds on p (lower < upper)
  bool log_space = true;        ///< θ = ln p (needs lower > 0)
  double prior_width = 0;       ///< 0: none; log space: the factor F > 1 at one σ; linear: σ
  double start = 0;             ///< the starting value (the model's value unless set)
  double prior_center = 0;      ///< the model's value
};

/// Parses "NAME=LO:HI[:PRIOR][:lin]": PRIOR "xF" (log-normal, a factor F > 1 at one σ) or "±W"
/// / "+-W" (normal, σ W, linear space); "lin" fits in linear space (the default is log space for
/// LO > 0, linear otherwise). Throws Error quoting the text and what is expected.
FitParameter parse_fit_parameter(const std::string& text);

struct FitOptions {
  int starts = 1;           ///< 1: from the start values; more: the others a Latin hypercube in θ
  int threads = 0;          ///< 0: every core
  std::uint64_t seed = 1;   ///< of the Latin hypercube
  int max_iterations = 200; ///< Levenberg–Marquardt steps per start
  bool optimize = true;     ///< false: only the analysis at the start (Fisher information)
  std::vector<std::string> profile;  ///< parameters whose profile likelihood is traced
  int profile_points = 21;
  std::function<bool()> stop;        ///< polled between iterations; true ends the fit (Stopped)
  /// Several processes (MPI ranks): each solves the starts i with i mod ranks = rank, and share
  /// (an all-gather: every rank's vector concatenated in rank order, on every rank) hands each the
  /// others'; every rank then has the same results, equal to one process's.
  int rank = 0, ranks = 1;
  std::function<std::vector<double>(const std::vector<double>&)> share;
};

/// A distinct local minimum among the starts.
struct LocalMinimum {
  double cost = 0;
  Eigen::VectorXd values;   ///< p
  int starts = 0;           ///< how many starts ended here
  bool converged = false;
};

/// A direction of the parameter space the data determine poorly (FitResult::fisher).
struct FisherDirection {
  double eigenvalue = 0;       ///< of F (relative coordinates)
  double sigma = 0;            ///< 1/√eigenvalue: the relative standard deviation along it
  Eigen::VectorXd direction;   ///< unit eigenvector over the fitted parameters
  std::string verdict;         ///< "identified", "weakly identified", "not identified"
  std::string description;     ///< e.g. "a and b are identified only as their ratio a/b"
};

struct ProfilePoint {
  double value = 0, cost = 0;
  bool converged = false;
};
struct Profile {
  std::string parameter;
  std::vector<ProfilePoint> points;
  double lower = 0, upper = 0;  ///< where 2Δcost/s² crosses χ²₁(0.95) = 3.84; NaN where it does not
};

struct FitResult {
  std::vector<std::string> names;
  std::vector<bool> log_space;     ///< per parameter: fitted as ln p
  Eigen::VectorXd start, values;   ///< p at the start and at the best minimum
  Eigen::VectorXd standard_error;  ///< of p (delta method in log space); inf: not identified
  Eigen::VectorXd lower95, upper95;
  Eigen::MatrixXd covariance;      ///< of θ
  Eigen::MatrixXd correlation;
  std::vector<std::string> at_bound;  ///< "" or "lower"/"upper" per parameter
  double initial_cost = 0, cost = 0;  ///< ½Σr² at the start and the end (priors included)
  double data_cost = 0;               ///< the data's part of cost
  int residuals = 0;                  ///< m (data only)
  int degrees_of_freedom = 0;         ///< m − n
  double residual_variance = 1;       ///< s²
  bool weighted = false;              ///< every point has standard deviations: s² = 1
  bool converged = false;
  std::string termination;            ///< the solver's report of the best start
  int iterations = 0, evaluations = 0;
  double seconds = 0;
  std::vector<LocalMinimum> minima;   ///< by cost, the best first
  std::vector<FisherDirection> fisher;///< by eigenvalue, the weakest first
  std::vector<Profile> profiles;
  // Per data point, in the data's order: the frequency responses' points then the modal data.
  struct Point {
    std::string set, input, output, kind;  ///< kind: "frf", "frequency", "damping"
    double hz = 0;                         ///< or the mode number for modal data
    std::complex<double> data, initial, fitted;
    double residual_magnitude = 0, residual_phase = 0;  ///< weighted, at the fit (NaN: not given)
    int line = 0;
    std::string source;
  };
  std::vector<Point> points;
  std::vector<std::string> warnings;  ///< on a bound, not converged, unidentified parameters
};

/// Fits the parameters to the data, starting from `model`'s parameter values. Throws NameError
/// for an unknown parameter, input or output (naming the data file and line), Error for bounds
/// that exclude the start, an empty problem, a model with rolling constraints or without the
/// sensitivity kernel; a fit that does not converge is returned with converged false and a
/// warning, never silently.
FitResult fit(const GeneratedModel& model, const MeasuredData& data, const std::vector<FitParameter>& parameters,
              const FitOptions& options = {});

/// The residual vector r and its Jacobian J (rows: data residuals then priors; columns θ) at
/// parameter values p (in the order of `parameters`): what the solver minimizes, for tests.
struct FitResiduals {
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  int data_rows = 0;
};
FitResiduals fit_residuals(const GeneratedModel& model, const MeasuredData& data,
                           const std::vector<FitParameter>& parameters, const Eigen::VectorXd& p, bool jacobian = true);

}  // namespace mbsgen
