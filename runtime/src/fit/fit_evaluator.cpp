// The residuals of a fit and their exact Jacobian (fit_evaluator.hpp).
#include "fit/fit_evaluator.hpp"

#include <algorithm>
#include <cmath>

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"
#include "mbsgen/runtime/spectral/sensitivity.hpp"

namespace mbsgen::detail {

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string number_text(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}

// Whether point i of d has a magnitude (data without the column has_magnitude: every point).
bool magnitude(const FrfData& d, std::size_t i) { return d.has_magnitude.size() <= i || d.has_magnitude[i]; }

// The oscillatory modes (Im λ > 0) by natural frequency: what mode k of the data means.
std::vector<std::size_t> oscillatory(const std::vector<Mode>& modes) {
  std::vector<std::size_t> k;
  for (std::size_t i = 0; i < modes.size(); ++i)
    if (modes[i].kind == EigenvalueKind::finite && modes[i].lambda.imag() > 0) k.push_back(i);
  std::stable_sort(k.begin(), k.end(),
                   [&](std::size_t a, std::size_t b) { return modes[a].natural_frequency_hz < modes[b].natural_frequency_hz; });
  return k;
}

}  // namespace

FitEvaluator::FitEvaluator(const GeneratedModel& model, const MeasuredData& data, const std::vector<FitParameter>& parameters)
    : model_(model), data_(data), params_(parameters) {
  if (model.is_descriptor())
    throw Error("fit: model '" + std::string(model.kernels().model) +
                "' has rolling constraints; its sensitivities, and so fits, are not available");
  if (params_.empty()) throw Error("fit: no parameter to fit (--parameter NAME=LO:HI)");
  if (data.responses.empty() && data.modal.empty()) throw Error("fit: no data (--data FILE)");
  if (!model.has_sensitivities())
    throw Error("fit: the kernels of model '" + std::string(model.kernels().model) +
                "' have no sensitivity kernel (a model with closed loops, or a scene without the analysis 'sensitivity'): "
                "fit needs the exact derivatives it gives");
  const std::vector<std::string> have = model.sensitivity_parameters();
  const std::vector<std::string>& all = model.parameter_names();
  for (FitParameter& p : params_) {
    if (std::find(names_.begin(), names_.end(), p.name) != names_.end())
      throw NameError("fit: parameter '" + p.name + "' is fitted twice");
    const auto it = std::find(all.begin(), all.end(), p.name);
    if (it == all.end() || std::find(have.begin(), have.end(), p.name) == have.end()) {
      std::string known;
      for (std::size_t k = 0; k < have.size() && k < 40; ++k) known += (k ? ", " : "") + have[k];
      throw NameError("fit: unknown parameter '" + p.name + "' (the model's: " + known + (have.size() > 40 ? ", …" : "") + ")");
    }
    index_.push_back(static_cast<std::size_t>(it - all.begin()));
    names_.push_back(p.name);
    p.start = p.prior_center = model.parameters()[index_.back()];
    if (!(p.start >= p.lower && p.start <= p.upper))
      throw Error("fit: parameter '" + p.name + "' starts at " + number_text(p.start) + ", outside its bounds [" +
                  number_text(p.lower) + ", " + number_text(p.upper) + "]");
    if (p.log_space && !(p.start > 0)) throw Error("fit: parameter '" + p.name + "' is fitted in log space but starts at " + number_text(p.start));
  }
  const int n = cols();
  lower_.resize(n);
  upper_.resize(n);
  for (int j = 0; j < n; ++j) {
    const FitParameter& p = params_[static_cast<std::size_t>(j)];
    lower_[j] = p.log_space ? std::log(p.lower) : p.lower;
    upper_[j] = p.log_space ? std::log(p.upper) : p.upper;
    if (p.prior_width > 0) priors_.push_back(j);
  }
  for (const FrfData& d : data.responses) {
    std::pair<Eigen::Index, Eigen::Index> io;
    try {
      io = {model.input_index(d.input), model.output_index(d.output)};
    } catch (const NameError& e) {
      throw NameError(d.source + ":" + std::to_string(d.line.front()) + ": " + e.what());
    }
    const auto at = [](std::vector<Eigen::Index>& v, Eigen::Index i) {
      const auto it = std::find(v.begin(), v.end(), i);
      if (it != v.end()) return static_cast<Eigen::Index>(it - v.begin());
      v.push_back(i);
      return static_cast<Eigen::Index>(v.size() - 1);
    };
    io_.emplace_back(at(inputs_, io.first), at(outputs_, io.second));
    hz_.insert(hz_.end(), d.hz.begin(), d.hz.end());
    for (std::size_t i = 0; i < d.hz.size(); ++i) {
      data_rows_ += (magnitude(d, i) ? 1 : 0) + (d.has_phase[i] ? 1 : 0);
      weighted_ = weighted_ && (!magnitude(d, i) || !std::isnan(d.sigma_ln_magnitude[i])) &&
                  (!d.has_phase[i] || !std::isnan(d.sigma_phase_rad[i]));
    }
  }
  std::sort(hz_.begin(), hz_.end());
  hz_.erase(std::unique(hz_.begin(), hz_.end()), hz_.end());
  for (const FrfData& d : data.responses) {
    at_.emplace_back();
    for (double f : d.hz) at_.back().push_back(static_cast<std::size_t>(std::lower_bound(hz_.begin(), hz_.end(), f) - hz_.begin()));
  }
  for (const ModalData& d : data.modal) {
    modal_ = true;
    for (std::size_t i = 0; i < d.mode.size(); ++i) {
      data_rows_ += (std::isnan(d.frequency_hz[i]) ? 0 : 1) + (std::isnan(d.damping_ratio[i]) ? 0 : 1);
      weighted_ = weighted_ && (std::isnan(d.frequency_hz[i]) || !std::isnan(d.sigma_frequency[i])) &&
                  (std::isnan(d.damping_ratio[i]) || !std::isnan(d.sigma_damping[i]));
    }
  }
}

Eigen::VectorXd FitEvaluator::start() const {
  Eigen::VectorXd p(cols());
  for (int j = 0; j < cols(); ++j) p[j] = params_[static_cast<std::size_t>(j)].start;
  return p;
}

Eigen::VectorXd FitEvaluator::theta_of(const Eigen::VectorXd& p) const {
  Eigen::VectorXd t(cols());
  for (int j = 0; j < cols(); ++j) t[j] = log_space(j) ? std::log(p[j]) : p[j];
  return t;
}

Eigen::VectorXd FitEvaluator::values(const Eigen::VectorXd& theta) const {
  Eigen::VectorXd p(cols());
  for (int j = 0; j < cols(); ++j) p[j] = log_space(j) ? std::exp(theta[j]) : theta[j];
  return p;
}

void FitEvaluator::compute(const Eigen::VectorXd& theta, bool jacobian, Responses& out, Eigen::MatrixXd* dre,
                           Eigen::MatrixXd* dim, Eigen::MatrixXd* df, Eigen::MatrixXd* dz) {
  const Eigen::VectorXd p = values(theta);
  std::vector<double> all = model_.parameters();
  for (int j = 0; j < cols(); ++j) all[index_[static_cast<std::size_t>(j)]] = p[j];
  model_.set_parameters(all);
  const OperatingPoint op = model_.operating_point();
  const LinearModel lin = model_.linear_model(op);
  std::vector<MatrixSensitivity> d = jacobian ? model_.linear_sensitivities(op, names_) : std::vector<MatrixSensitivity>{};
  const auto chain = [&](int j) { return log_space(j) ? p[j] : 1.0; };  // dp/dθ
  out.frf.assign(data_.responses.size(), {});
  Eigen::Index row = 0;
  if (!data_.responses.empty()) {
    std::vector<MatrixSensitivity> dr;
    for (const MatrixSensitivity& x : d) dr.push_back(select(x, inputs_, outputs_));
    // Only the data's inputs and outputs: one right-hand side per measured input.
    const FrequencyResponseSensitivity s = frequency_response_sensitivity(lin.select(inputs_, outputs_), dr, hz_);
    for (std::size_t k = 0; k < data_.responses.size(); ++k)
      for (std::size_t i = 0; i < at_[k].size(); ++i, ++row) {
        const std::size_t f = at_[k][i];
        const std::complex<double> h = s.response[f](io_[k].second, io_[k].first);
        if (!std::isfinite(std::abs(h)) || h == 0.0)
          throw SingularSystemError("the response is " + std::string(h == 0.0 ? "zero" : "not finite") + " at " +
                                    number_text(hz_[f]) + " Hz");
        out.frf[k].push_back(h);
        for (int j = 0; jacobian && j < cols(); ++j) {
          const std::complex<double> g = s.derivative[static_cast<std::size_t>(j)][f](io_[k].second, io_[k].first) / h * chain(j);
          (*dre)(row, j) = g.real();
          (*dim)(row, j) = g.imag();
        }
      }
  }
  out.modal.assign(data_.modal.size(), {});
  if (!modal_) return;
  QuadraticEigenOptions opt;
  opt.one_per_conjugate_pair = false;
  QuadraticEigenSolver solver(lin.size(), opt);
  solver.compute(lin);
  const std::vector<Mode>& modes = solver.modes();
  const std::vector<std::size_t> osc = oscillatory(modes);
  const auto sens = jacobian ? eigenvalue_sensitivities(lin, modes, d) : std::vector<std::vector<EigenvalueSensitivity>>{};
  row = 0;
  for (std::size_t k = 0; k < data_.modal.size(); ++k)
    for (std::size_t i = 0; i < data_.modal[k].mode.size(); ++i, ++row) {
      const auto m = static_cast<std::size_t>(data_.modal[k].mode[i]);
      if (m > osc.size())
        throw Error(data_.modal[k].source + ":" + std::to_string(data_.modal[k].line[i]) + ": mode " + std::to_string(m) +
                    ", but the model has " + std::to_string(osc.size()) + " oscillatory modes at these values");
      const Mode& mode = modes[osc[m - 1]];
      out.modal[k].emplace_back(mode.natural_frequency_hz, mode.damping_ratio);
      for (int j = 0; jacobian && j < cols(); ++j) {
        const EigenvalueSensitivity& e = sens[osc[m - 1]][static_cast<std::size_t>(j)];
        if (!e.defined) throw Error("mode " + std::to_string(m) + " has no derivative (" + e.note + ")");
        (*df)(row, j) = e.dfrequency_hz * chain(j);
        (*dz)(row, j) = e.ddamping_ratio * chain(j);
      }
    }
}

bool FitEvaluator::evaluate(const Eigen::VectorXd& theta, Eigen::VectorXd& r, Eigen::MatrixXd* J, std::string* why) {
  Eigen::Index frf_points = 0, modal_points = 0;
  for (const FrfData& d : data_.responses) frf_points += static_cast<Eigen::Index>(d.hz.size());
  for (const ModalData& d : data_.modal) modal_points += static_cast<Eigen::Index>(d.mode.size());
  Eigen::MatrixXd dre(frf_points, cols()), dim(frf_points, cols()), df(modal_points, cols()), dz(modal_points, cols());
  Responses h;
  try {
    compute(theta, J != nullptr, h, &dre, &dim, &df, &dz);
  } catch (const Error& e) {
    if (why) *why = e.what();
    return false;
  }
  r.resize(rows());
  if (J) J->setZero(rows(), cols());
  Eigen::Index row = 0, point = 0;
  for (std::size_t k = 0; k < data_.responses.size(); ++k) {
    const FrfData& d = data_.responses[k];
    for (std::size_t i = 0; i < d.hz.size(); ++i, ++point) {
      const std::complex<double> lr = std::log(h.frf[k][i] / d.value[i]);  // imag part: the wrapped phase difference
      if (magnitude(d, i)) {
        const double sm = std::isnan(d.sigma_ln_magnitude[i]) ? 1.0 : d.sigma_ln_magnitude[i];
        r[row] = lr.real() / sm;
        if (J) J->row(row) = dre.row(point) / sm;
        ++row;
      }
      if (!d.has_phase[i]) continue;
      const double sp = std::isnan(d.sigma_phase_rad[i]) ? 1.0 : d.sigma_phase_rad[i];
      r[row] = lr.imag() / sp;
      if (J) J->row(row) = dim.row(point) / sp;
      ++row;
    }
  }
  point = 0;
  for (std::size_t k = 0; k < data_.modal.size(); ++k) {
    const ModalData& d = data_.modal[k];
    for (std::size_t i = 0; i < d.mode.size(); ++i, ++point) {
      if (!std::isnan(d.frequency_hz[i])) {
        const double w = (std::isnan(d.sigma_frequency[i]) ? 1.0 : d.sigma_frequency[i]) * d.frequency_hz[i];
        r[row] = (h.modal[k][i].first - d.frequency_hz[i]) / w;
        if (J) J->row(row) = df.row(point) / w;
        ++row;
      }
      if (!std::isnan(d.damping_ratio[i])) {
        const double w = std::isnan(d.sigma_damping[i]) ? 1.0 : d.sigma_damping[i];
        r[row] = (h.modal[k][i].second - d.damping_ratio[i]) / w;
        if (J) J->row(row) = dz.row(point) / w;
        ++row;
      }
    }
  }
  for (int j : priors_) {
    const FitParameter& p = params_[static_cast<std::size_t>(j)];
    const double w = p.log_space ? std::log(p.prior_width) : p.prior_width;
    const double center = p.log_space ? std::log(p.prior_center) : p.prior_center;
    r[row] = (theta[j] - center) / w;
    if (J) (*J)(row, j) = 1.0 / w;
    ++row;
  }
  if (!r.allFinite() || (J && !J->allFinite())) {
    if (why) *why = "a residual or derivative is not finite";
    return false;
  }
  return true;
}

std::vector<FitResult::Point> FitEvaluator::points(const Eigen::VectorXd& theta0, const Eigen::VectorXd& theta) {
  Responses h0, h1;
  compute(theta0, false, h0, nullptr, nullptr, nullptr, nullptr);
  compute(theta, false, h1, nullptr, nullptr, nullptr, nullptr);
  std::vector<FitResult::Point> out;
  for (std::size_t k = 0; k < data_.responses.size(); ++k) {
    const FrfData& d = data_.responses[k];
    for (std::size_t i = 0; i < d.hz.size(); ++i) {
      FitResult::Point p;
      p.set = d.set;
      p.input = d.input;
      p.output = d.output;
      p.kind = "frf";
      p.hz = d.hz[i];
      p.data = d.value[i];
      p.initial = h0.frf[k][i];
      p.fitted = h1.frf[k][i];
      const std::complex<double> lr = std::log(p.fitted / p.data);
      p.residual_magnitude =
          magnitude(d, i) ? lr.real() / (std::isnan(d.sigma_ln_magnitude[i]) ? 1.0 : d.sigma_ln_magnitude[i]) : kNaN;
      p.residual_phase = d.has_phase[i] ? lr.imag() / (std::isnan(d.sigma_phase_rad[i]) ? 1.0 : d.sigma_phase_rad[i]) : kNaN;
      if (!d.has_phase[i]) {  // magnitude data: the model's phase is shown, the data's is not known
        p.data = std::abs(p.data);
      }
      p.line = d.line[i];
      p.source = d.source;
      out.push_back(p);
    }
  }
  for (std::size_t k = 0; k < data_.modal.size(); ++k) {
    const ModalData& d = data_.modal[k];
    for (std::size_t i = 0; i < d.mode.size(); ++i)
      for (int q = 0; q < 2; ++q) {
        const double x = q == 0 ? d.frequency_hz[i] : d.damping_ratio[i];
        if (std::isnan(x)) continue;
        FitResult::Point p;
        p.set = d.set;
        p.kind = q == 0 ? "frequency" : "damping";
        p.hz = d.mode[i];
        p.data = x;
        p.initial = q == 0 ? h0.modal[k][i].first : h0.modal[k][i].second;
        p.fitted = q == 0 ? h1.modal[k][i].first : h1.modal[k][i].second;
        const double s = q == 0 ? (std::isnan(d.sigma_frequency[i]) ? 1.0 : d.sigma_frequency[i]) * x
                                : (std::isnan(d.sigma_damping[i]) ? 1.0 : d.sigma_damping[i]);
        p.residual_magnitude = (p.fitted.real() - x) / s;
        p.residual_phase = kNaN;
        p.line = d.line[i];
        p.source = d.source;
        out.push_back(p);
      }
  }
  return out;
}

}  // namespace mbsgen::detail
