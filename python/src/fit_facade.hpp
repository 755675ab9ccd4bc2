// The Python package's fit (issue 42; docs/fitting.md): fit() of runtime/fit with plain arguments
// and results, as facade.hpp does for the other analyses. Built when the runtime's fit is
// (MBSGEN_WITH_FIT: Ceres Solver found).
#pragma once

#include <cstdint>

#include "facade.hpp"

namespace mbsgen::python {

/// One measured response given as arrays: H at hz; NaN in sigma_*: no standard deviation.
struct FitArrays {
  std::string input, output, set;
  Vector hz;
  Eigen::VectorXcd values;
  Vector sigma_magnitude;  // of ln|H|
  Vector sigma_phase_rad;
};

struct FitRequest {
  std::vector<std::string> files;         // CSV data files (fit.hpp, read_measured_data)
  std::string input, output;              // for files without input/output columns
  std::vector<FitArrays> arrays;
  std::vector<std::string> parameters;    // "NAME=LO:HI[:xF | :+-W][:lin]"
  int starts = 1, threads = 0, max_iterations = 200, profile_points = 21;
  std::uint64_t seed = 1;
  bool optimize = true;
  std::vector<std::string> profile;
};

struct FitOutcome {
  std::vector<std::string> names, at_bound, warnings;
  Vector start, values, standard_error, lower95, upper95;
  Matrix covariance, correlation;  // covariance of θ (ln p in log space)
  double initial_cost = 0, cost = 0, data_cost = 0, residual_variance = 1, seconds = 0;
  int residuals = 0, degrees_of_freedom = 0, iterations = 0, evaluations = 0;
  bool weighted = false, converged = false;
  std::string termination;
  Vector fisher_eigenvalues, fisher_sigma;  // weakest first
  Matrix fisher_directions;                 // column k: direction k
  std::vector<std::string> fisher_verdicts, fisher_descriptions;
  Vector minima_costs;
  Matrix minima_values;                     // row k: minimum k's values
  std::vector<std::string> profile_names;
  Matrix profile_values, profile_costs;     // row k: profile k
  Vector profile_lower, profile_upper;
  std::vector<std::string> point_sets, point_kinds, point_inputs, point_outputs;
  Vector point_hz, residual_magnitude, residual_phase;
  Eigen::VectorXcd point_data, point_initial, point_fitted;
};

/// Fits, from the parameter values p (every one, in order): runtime/fit's fit(). stop (may be
/// empty) is asked between iterations; Stopped when it says true.
FitOutcome fit(const Model& model, const ConstVectorRef& p, const FitRequest& request, const std::function<bool()>& stop = {});

}  // namespace mbsgen::python
