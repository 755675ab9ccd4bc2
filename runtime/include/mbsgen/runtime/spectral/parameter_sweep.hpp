// Eigenvalues against a parameter, and the parameter values where the stability changes (issue
// 16 §2: the bicycle's eigenvalues against its speed; any model: a rotor's threshold speed, a
// column's flutter load).
#pragma once

#include "mbsgen/runtime/model/generated_model.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

#include <complex>
#include <cstddef>
#include <string>
#include <vector>

namespace mbsgen {

/// The spectrum at one parameter value.
struct SweepPoint {
  double value = 0;
  /// Finite eigenvalues (both members of a conjugate pair), in QuadraticEigenSolver's order:
  /// zeros first, then by increasing |λ|.
  std::vector<std::complex<double>> eigenvalues;
  /// How many of the eigenvalues (the first ones) are exact zeros, kind zero: deflated by the
  /// solver, not computed (a bicycle's ignorable heading and wheel angles). A finite eigenvalue
  /// that merely rounds to 0 is not counted.
  std::size_t zeros = 0;
  /// max Re λ over the finite eigenvalues that are not zero (deflated or within their error
  /// bound), a real part within its error bound counted as 0; −∞ when there is none. The model
  /// is unstable at this value when it is > 0.
  double abscissa = 0;
  double raw_abscissa = 0;  ///< the same without the error bounds (for refining a boundary)
  Stability stability = Stability::stable;
};

/// A value where the model turns unstable (or stops being unstable), found only between two
/// decided verdicts (Stability: unstable on one side, stable or marginal on the other; undecided
/// points never make a boundary).
struct StabilityBoundary {
  double value = 0;  ///< the middle of the bracket below
  /// Half the bracket from the last parameter value with one decided verdict to the first with
  /// the other, refined by bisection: |value − true crossing| ≤ tolerance as long as the verdicts
  /// (which respect every eigenvalue's error bound) are right. Where the crossing eigenvalue is
  /// within its bound of the axis over a band (a Jordan block at the crossing, e.g. a rolling
  /// disk's merging lean pair), the band stays inside the bracket.
  double tolerance = 0;
  bool becomes_unstable = true;  ///< in the direction of increasing parameter
  std::complex<double> eigenvalue;  ///< the eigenvalue with the largest real part, unstable side
  Stability below = Stability::stable;  ///< the verdict at the bracket's lower end
  Stability above = Stability::stable;  ///< the verdict at the bracket's upper end
};

struct SweepResult {
  std::string parameter;
  std::vector<SweepPoint> points;
  std::vector<StabilityBoundary> boundaries;
};

struct SweepOptions {
  /// Bracket width at which a boundary's bisection stops, relative to max(1, |value|).
  double relative_tolerance = 1e-14;
};

/// Sets `parameter` of `model` to `points` values from `from` to `to` (linear spacing, both ends;
/// points ≥ 2), finds the operating point (Newton for an equilibrium) and the eigenvalues of the
/// linear model at each, and refines every change between the decided verdicts of neighbouring
/// decided values (unstable against stable or marginal; undecided values skipped) by bisection
/// (StabilityBoundary). The model's parameter is restored afterwards. Throws
/// NameError for an unknown parameter, Error for points < 2 or a non-finite range, and what the
/// model's analyses throw at a value (the message names the value).
SweepResult sweep_parameter(GeneratedModel& model, const std::string& parameter, double from, double to,
                            int points, const SweepOptions& options = {});

}  // namespace mbsgen
