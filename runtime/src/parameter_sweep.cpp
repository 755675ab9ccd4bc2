#include "mbsgen/runtime/parameter_sweep.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace mbsgen {

namespace {

// The spectrum of the model at its current parameters.
SweepPoint spectrum(const GeneratedModel& model, double value) {
  const LinearModel lin = model.linear_model();
  QuadraticEigenOptions opt;
  opt.one_per_conjugate_pair = false;
  QuadraticEigenSolver solver(lin.size(), opt);
  solver.compute(lin);
  SweepPoint p;
  p.value = value;
  p.stability = solver.stability();
  p.abscissa = p.raw_abscissa = -std::numeric_limits<double>::infinity();
  for (const Mode& m : solver.modes()) {
    if (m.kind != EigenvalueKind::finite && m.kind != EigenvalueKind::zero) continue;
    p.eigenvalues.push_back(m.lambda);
    // A real part within the eigenvalue's error bound counts as 0: the data do not tell its sign
    // (an undamped model's ±1e-16), so only a decided sign makes a boundary.
    if (m.kind == EigenvalueKind::finite && !m.zero_within_bound) {
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

// Bisection between a and b, whose decided signs differ, on the sign of the largest real part
// itself (within the error band the computed sign is still the nearer one: the crossing is found
// to about error_bound / |d Re λ/dp| instead of that band's width).
StabilityBoundary refine(GeneratedModel& model, const std::string& parameter, SweepPoint a, SweepPoint b,
                         const SweepOptions& options) {
  const bool a_unstable = a.abscissa > 0;
  for (int i = 0; i < 200; ++i) {
    const double width = std::abs(b.value - a.value);
    if (width <= options.relative_tolerance * std::max(1.0, std::abs(a.value))) break;
    const SweepPoint mid = at(model, parameter, (a.value + b.value) / 2);
    if ((mid.raw_abscissa > 0) == a_unstable)
      a = mid;
    else
      b = mid;
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
