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
  const auto where = [&](const Error& e) {
    std::ostringstream s;
    s << "sweep of " << parameter << ": at " << parameter << " = " << value << ": " << e.what();
    return s.str();
  };
  try {
    return spectrum(model, value);
  } catch (const ParameterError& e) {  // a value the model file's conditions refuse: the user's
    throw ParameterError(where(e));
  } catch (const Error& e) {
    throw Error(where(e));
  }
}

std::complex<double> rightmost(const SweepPoint& p) {
  std::complex<double> best(-std::numeric_limits<double>::infinity(), 0);
  for (const auto& l : p.eigenvalues)
    if (l.real() > best.real() || (l.real() == best.real() && l.imag() > best.imag())) best = l;
  return best;
}

// The decided verdict at a point: +1 unstable (an eigenvalue with Re λ > its error bound), −1
// not unstable and decided (stable or marginal: every eigenvalue decided to lie left of or
// exactly on the imaginary axis, zeros exact), 0 undecided (an eigenvalue within its bound of the
// axis or of zero). Only decided verdicts make or bound a boundary.
int verdict(const SweepPoint& p) {
  if (p.abscissa > 0) return 1;
  return p.stability == Stability::undecided ? 0 : -1;
}

// Bisection of [lo, hi] where `lo` has the decided verdict v and `hi` does not: the last point
// with verdict v, to the sweep's tolerance.
SweepPoint last_with(GeneratedModel& model, const std::string& parameter, int v, SweepPoint lo,
                     SweepPoint hi, const SweepOptions& options) {
  for (int i = 0; i < 200; ++i) {
    if (std::abs(hi.value - lo.value) <= options.relative_tolerance * std::max(1.0, std::abs(lo.value)))
      break;
    SweepPoint mid = at(model, parameter, (lo.value + hi.value) / 2);
    if (mid.value == lo.value || mid.value == hi.value) break;  // adjacent doubles
    if (verdict(mid) == v) {
      lo = std::move(mid);
    } else {
      hi = std::move(mid);
    }
  }
  return lo;
}

// The boundary between a and b, whose decided verdicts differ (one unstable): the bracket from
// the last point with a's verdict to the first with b's. Bisection narrows it while the midpoint
// is decided; a midpoint whose verdict is undecided (the crossing eigenvalue within its bound of
// the axis: a Jordan block at the crossing, the rolling disk's merging pair) splits the search,
// and the bracket keeps the undecided band, since the data do not tell where in it the crossing
// lies. So |value − crossing| ≤ tolerance whenever the verdicts are right.
StabilityBoundary refine(GeneratedModel& model, const std::string& parameter, SweepPoint a, SweepPoint b,
                         const SweepOptions& options) {
  const int va = verdict(a), vb = verdict(b);
  for (int i = 0; i < 200; ++i) {
    if (std::abs(b.value - a.value) <= options.relative_tolerance * std::max(1.0, std::abs(a.value))) break;
    SweepPoint mid = at(model, parameter, (a.value + b.value) / 2);
    if (mid.value == a.value || mid.value == b.value) break;
    const int v = verdict(mid);
    if (v == va) {
      a = std::move(mid);
    } else if (v == vb) {
      b = std::move(mid);
    } else {
      a = last_with(model, parameter, va, a, mid, options);
      b = last_with(model, parameter, vb, b, mid, options);
      break;
    }
  }
  StabilityBoundary s;
  s.value = (a.value + b.value) / 2;
  s.tolerance = std::abs(b.value - a.value) / 2;
  s.becomes_unstable = (a.value < b.value) ? vb > 0 : va > 0;
  s.eigenvalue = rightmost(va > 0 ? a : b);
  s.below = a.value < b.value ? a.stability : b.stability;
  s.above = a.value < b.value ? b.stability : a.stability;
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
    // Between neighbouring decided points (undecided ones skipped) whose verdicts differ.
    const SweepPoint* last = nullptr;
    for (const SweepPoint& p : r.points) {
      if (verdict(p) == 0) continue;
      if (last && verdict(*last) != verdict(p)) r.boundaries.push_back(refine(model, parameter, *last, p, options));
      last = &p;
    }
  } catch (...) {
    model.set(parameter, saved);
    throw;
  }
  model.set(parameter, saved);
  return r;
}

}  // namespace mbsgen
