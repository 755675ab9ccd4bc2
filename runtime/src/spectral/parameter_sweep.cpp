#include "mbsgen/runtime/spectral/parameter_sweep.hpp"

#include "mbsgen/runtime/spectral/descriptor_eigen.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace mbsgen {

namespace {

// The spectrum of the model at its current parameters.
// (The first-order solver for a model with nonholonomic constraints.)
SweepPoint spectrum(const GeneratedModel& model, double value) {
  std::vector<Mode> modes;
  Stability stability = Stability::undecided;
  if (model.is_descriptor()) {
    DescriptorEigenSolver solver;
    solver.compute(model.descriptor_model());
    modes = solver.modes(), stability = solver.stability();
  } else {
    const LinearModel lin = model.linear_model();
    QuadraticEigenOptions opt;
    opt.one_per_conjugate_pair = false;
    QuadraticEigenSolver solver(lin.size(), opt);
    solver.compute(lin);
    modes = solver.modes(), stability = solver.stability();
  }
  SweepPoint p;
  p.value = value;
  p.stability = stability;
  p.abscissa = p.raw_abscissa = -std::numeric_limits<double>::infinity();
  // The exact zeros first (both solvers sort them first already), counted.
  for (const Mode& m : modes) {
    if (m.kind != EigenvalueKind::zero) continue;
    p.eigenvalues.push_back(m.lambda);
    ++p.zeros;
  }
  for (const Mode& m : modes) {
    if (m.kind != EigenvalueKind::finite) continue;
    p.eigenvalues.push_back(m.lambda);
    // A real part within the eigenvalue's error bound counts as 0: the data do not tell its sign
    // (an undamped model's ±1e-16), so only a decided sign makes a boundary.
    if (!m.zero_within_bound) {
      p.abscissa = std::max(p.abscissa, std::abs(m.lambda.real()) <= m.error_bound ? 0.0 : m.lambda.real());
      p.raw_abscissa = std::max(p.raw_abscissa, m.lambda.real());
    }
  }
  return p;
}

SweepPoint at(GeneratedModel& model, const std::string& parameter, double value) {
  model.set(parameter, value);
  try {
    return spectrum(model, value);
  } catch (const Error& e) {
    std::ostringstream s;
    s << "sweep of " << parameter << ": at " << parameter << " = " << value << ": " << e.what();
    throw Error(s.str());
  }
}

std::complex<double> rightmost(const SweepPoint& p) {
  std::complex<double> best(-std::numeric_limits<double>::infinity(), 0);
  for (const auto& l : p.eigenvalues)
    if (l.real() > best.real() || (l.real() == best.real() && l.imag() > best.imag())) best = l;
  return best;
}

// Whether the computed spectrum grows, by the signs of the real parts themselves (no error
// bounds): an eigenvalue counts when |λ| exceeds 100·u of the largest (below that it is the
// rounding of a zero, such as a rolling disk's neighbouring steady turn, whose normwise error
// bound is no guide), and grows when Re λ > 0.
bool grows(const SweepPoint& p) {
  const double u = std::numeric_limits<double>::epsilon();
  double scale = 0;
  for (const auto& l : p.eigenvalues) scale = std::max(scale, std::abs(l));
  for (const auto& l : p.eigenvalues)
    if (std::abs(l) > 100 * u * scale && l.real() > 0) return true;
  return false;
}

// Bisection between a and b, whose decided signs differ, on grows(): within the error band the
// computed sign is still the nearer one, so the crossing is found to about the eigenvalue's actual
// error / |d Re λ/dp| instead of its bound's (a bicycle's capsize root near the crossing has a
// normwise bound of 1e10, coupled to the heading's Jordan chain, and an error of 1e-13).
StabilityBoundary refine(GeneratedModel& model, const std::string& parameter, SweepPoint a, SweepPoint b,
                         const SweepOptions& options) {
  const bool a_unstable = a.abscissa > 0;
  // The decided verdicts (with error bounds) bracket the crossing only to the width of the band
  // where the crossing eigenvalue is within its bound; the computed signs may change just outside
  // the bracket (the bicycle's capsize root at 1,000 speeds). Widen by the bracket's width until
  // the signs at its ends differ.
  const double step = b.value - a.value;
  for (int k = 0; k < 64 && grows(a) != a_unstable; ++k) a = at(model, parameter, a.value - step);
  for (int k = 0; k < 64 && grows(b) == a_unstable; ++k) b = at(model, parameter, b.value + step);
  for (int i = 0; i < 200; ++i) {
    const double width = std::abs(b.value - a.value);
    if (width <= options.relative_tolerance * std::max(1.0, std::abs(a.value))) break;
    const SweepPoint mid = at(model, parameter, (a.value + b.value) / 2);
    if (grows(mid) == a_unstable) {
      a = mid;
    } else {
      b = mid;
    }
  }
  StabilityBoundary s;
  s.value = (a.value + b.value) / 2;
  s.tolerance = std::abs(b.value - a.value) / 2;
  s.becomes_unstable = (a.value < b.value) ? !a_unstable : a_unstable;
  s.eigenvalue = rightmost(a_unstable ? a : b);
  return s;
}

}  // namespace

SweepResult sweep_parameter(GeneratedModel& model, const std::string& parameter, double from, double to,
                            int points, const SweepOptions& options) {
  if (points < 2)
    throw Error("sweep_parameter: points must be at least 2 (got " + std::to_string(points) + ")");
  if (!std::isfinite(from) || !std::isfinite(to))
    throw NonFiniteError("sweep_parameter: the range of " + parameter + " must be finite");
  const std::vector<std::string>& names = model.parameter_names();
  const auto it = std::find(names.begin(), names.end(), parameter);
  if (it == names.end()) {
    model.set(parameter, 0.0);  // throws NameError listing the known parameters
  }
  const double saved = model.parameters()[static_cast<std::size_t>(it - names.begin())];
  SweepResult r;
  r.parameter = parameter;
  try {
    for (int i = 0; i < points; ++i) {
      const double v = from + (to - from) * i / (points - 1);
      r.points.push_back(at(model, parameter, i == points - 1 ? to : v));
    }
    for (std::size_t i = 1; i < r.points.size(); ++i) {
      const SweepPoint &a = r.points[i - 1], &b = r.points[i];
      if (std::isinf(a.abscissa) || std::isinf(b.abscissa)) continue;
      if ((a.abscissa > 0) != (b.abscissa > 0)) r.boundaries.push_back(refine(model, parameter, a, b, options));
    }
  } catch (...) {
    model.set(parameter, saved);
    throw;
  }
  model.set(parameter, saved);
  return r;
}

}  // namespace mbsgen
