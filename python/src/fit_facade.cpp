// The Python package's fit (fit_facade.hpp).
#include "fit_facade.hpp"

#include <cmath>

#include "mbsgen/runtime/fit/fit.hpp"
#include "mbsgen/runtime/model/generated_model.hpp"

namespace mbsgen::python {

namespace {

MeasuredData measured(const FitRequest& r) {
  MeasuredData data;
  for (const std::string& file : r.files) {
    MeasuredData d = read_measured_data_file(file, r.input, r.output);
    for (auto& x : d.responses) data.responses.push_back(std::move(x));
    for (auto& x : d.modal) data.modal.push_back(std::move(x));
  }
  for (std::size_t k = 0; k < r.arrays.size(); ++k) {
    const FitArrays& a = r.arrays[k];
    const Eigen::Index n = a.hz.size();
    const std::string where = "data[" + std::to_string(k) + "]";
    if (a.values.size() != n || a.sigma_magnitude.size() != n || a.sigma_phase_rad.size() != n)
      throw DimensionError(where + ": frequencies, values and standard deviations of different lengths");
    FrfData d;
    d.source = where;
    d.set = a.set;
    d.input = a.input.empty() ? r.input : a.input;
    d.output = a.output.empty() ? r.output : a.output;
    if (d.input.empty() || d.output.empty())
      throw NameError(where + ": which input and output? give them in the data ('input', 'output') or as input=, output=");
    for (Eigen::Index i = 0; i < n; ++i) {
      const std::string at = where + "[" + std::to_string(i) + "]: ";
      if (!(a.hz[i] > 0) || !std::isfinite(a.hz[i])) throw NameError(at + "a frequency that is not positive and finite");
      if (!std::isfinite(std::abs(a.values[i])) || a.values[i] == 0.0) throw NameError(at + "a response that is zero or not finite");
      for (double s : {a.sigma_magnitude[i], a.sigma_phase_rad[i]})
        if (!std::isnan(s) && !(s > 0 && std::isfinite(s))) throw NameError(at + "a standard deviation that is not positive");
      d.hz.push_back(a.hz[i]);
      d.value.push_back(a.values[i]);
      d.has_phase.push_back(true);
      d.has_magnitude.push_back(true);
      d.sigma_ln_magnitude.push_back(a.sigma_magnitude[i]);
      d.sigma_phase_rad.push_back(a.sigma_phase_rad[i]);
      d.line.push_back(static_cast<int>(i));
    }
    if (n > 0) data.responses.push_back(std::move(d));
  }
  return data;
}

void copy_points(const FitResult& f, FitOutcome& o) {
  const auto n = static_cast<Eigen::Index>(f.points.size());
  o.point_hz.resize(n);
  o.residual_magnitude.resize(n);
  o.residual_phase.resize(n);
  o.point_data.resize(n);
  o.point_initial.resize(n);
  o.point_fitted.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const FitResult::Point& p = f.points[static_cast<std::size_t>(i)];
    o.point_sets.push_back(p.set);
    o.point_kinds.push_back(p.kind);
    o.point_inputs.push_back(p.input);
    o.point_outputs.push_back(p.output);
    o.point_hz[i] = p.hz;
    o.residual_magnitude[i] = p.residual_magnitude;
    o.residual_phase[i] = p.residual_phase;
    o.point_data[i] = p.data;
    o.point_initial[i] = p.initial;
    o.point_fitted[i] = p.fitted;
  }
}

void copy_statistics(const FitResult& f, FitOutcome& o) {
  const auto q = static_cast<Eigen::Index>(f.fisher.size());
  o.fisher_eigenvalues.resize(q);
  o.fisher_sigma.resize(q);
  o.fisher_directions.resize(static_cast<Eigen::Index>(f.names.size()), q);
  for (Eigen::Index k = 0; k < q; ++k) {
    const FisherDirection& d = f.fisher[static_cast<std::size_t>(k)];
    o.fisher_eigenvalues[k] = d.eigenvalue;
    o.fisher_sigma[k] = d.sigma;
    o.fisher_directions.col(k) = d.direction;
    o.fisher_verdicts.push_back(d.verdict);
    o.fisher_descriptions.push_back(d.description);
  }
  const auto m = static_cast<Eigen::Index>(f.minima.size());
  o.minima_costs.resize(m);
  o.minima_values.resize(m, static_cast<Eigen::Index>(f.names.size()));
  for (Eigen::Index k = 0; k < m; ++k) {
    o.minima_costs[k] = f.minima[static_cast<std::size_t>(k)].cost;
    o.minima_values.row(k) = f.minima[static_cast<std::size_t>(k)].values.transpose();
  }
  const auto np = static_cast<Eigen::Index>(f.profiles.size());
  const Eigen::Index points = np ? static_cast<Eigen::Index>(f.profiles[0].points.size()) : 0;
  o.profile_values.resize(np, points);
  o.profile_costs.resize(np, points);
  o.profile_lower.resize(np);
  o.profile_upper.resize(np);
  for (Eigen::Index k = 0; k < np; ++k) {
    const Profile& p = f.profiles[static_cast<std::size_t>(k)];
    o.profile_names.push_back(p.parameter);
    o.profile_lower[k] = p.lower;
    o.profile_upper[k] = p.upper;
    for (Eigen::Index i = 0; i < points; ++i) {
      o.profile_values(k, i) = p.points[static_cast<std::size_t>(i)].value;
      o.profile_costs(k, i) = p.points[static_cast<std::size_t>(i)].cost;
    }
  }
}

}  // namespace

FitOutcome fit(const Model& model, const ConstVectorRef& p, const FitRequest& r, const std::function<bool()>& stop) {
  GeneratedModel m(model.kernels());
  m.set_parameters(std::vector<double>(p.data(), p.data() + p.size()));
  const MeasuredData data = measured(r);
  std::vector<FitParameter> params;
  for (const std::string& s : r.parameters) params.push_back(parse_fit_parameter(s));
  FitOptions o;
  o.starts = r.starts;
  o.threads = r.threads;
  o.seed = r.seed;
  o.max_iterations = r.max_iterations;
  o.optimize = r.optimize;
  o.profile = r.profile;
  o.profile_points = r.profile_points;
  o.stop = stop;
  FitResult f;
  try {
    f = mbsgen::fit(m, data, params, o);
  } catch (const FitStopped&) {
    throw Stopped();
  }
  FitOutcome out;
  out.names = f.names;
  out.at_bound = f.at_bound;
  out.warnings = f.warnings;
  out.start = f.start;
  out.values = f.values;
  out.standard_error = f.standard_error;
  out.lower95 = f.lower95;
  out.upper95 = f.upper95;
  out.covariance = f.covariance;
  out.correlation = f.correlation;
  out.initial_cost = f.initial_cost;
  out.cost = f.cost;
  out.data_cost = f.data_cost;
  out.residual_variance = f.residual_variance;
  out.seconds = f.seconds;
  out.residuals = f.residuals;
  out.degrees_of_freedom = f.degrees_of_freedom;
  out.iterations = f.iterations;
  out.evaluations = f.evaluations;
  out.weighted = f.weighted;
  out.converged = f.converged;
  out.termination = f.termination;
  copy_statistics(f, out);
  copy_points(f, out);
  return out;
}

}  // namespace mbsgen::python
