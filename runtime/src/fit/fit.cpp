// fit(): nonlinear least squares over named parameters with the exact Jacobian, Ceres Solver's
// Levenberg–Marquardt with bounds, multi-start on threads, and the statistics of the fit
// (covariance, Fisher information, profiles). The mathematics: fit.hpp.
#include "mbsgen/runtime/fit/fit.hpp"

#include <ceres/ceres.h>
#include <glog/logging.h>

#include <boost/math/distributions/students_t.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include <Eigen/Eigenvalues>

#include "fit/fit_evaluator.hpp"
#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/study/study_design.hpp"

namespace mbsgen {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
const double kInf = std::numeric_limits<double>::infinity();
const double kNaN = std::numeric_limits<double>::quiet_NaN();

// The residuals and Jacobian for Ceres (one parameter block θ). An evaluation the model refuses
// (unphysical values, no equilibrium) is an unsuccessful step, never an exception through Ceres.
// Ceres evaluates a trial point without the Jacobian and, when it accepts the step, the same
// point again with it: the Jacobian is computed with the residuals and kept for that second
// call (a response less per step; a rejected step wastes a Jacobian, and LM rejects few).
class Cost final : public ceres::CostFunction {
 public:
  explicit Cost(detail::FitEvaluator& e) : e_(e) {
    set_num_residuals(e.rows());
    mutable_parameter_block_sizes()->push_back(e.cols());
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const VectorXd> theta(parameters[0], e_.cols());
    if (!(kept_ && theta == theta_)) {
      kept_ = false;
      if (!e_.evaluate(theta, r_, &J_)) return false;
      theta_ = theta;
      kept_ = true;
    }
    Eigen::Map<VectorXd>(residuals, r_.size()) = r_;
    if (jacobians != nullptr && jacobians[0] != nullptr)
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[0], J_.rows(), J_.cols()) = J_;
    return true;
  }

 private:
  detail::FitEvaluator& e_;
  mutable bool kept_ = false;
  mutable VectorXd theta_, r_;
  mutable MatrixXd J_;
};

class StopCallback final : public ceres::IterationCallback {
 public:
  explicit StopCallback(const std::function<bool()>& stop) : stop_(stop) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    if (stop_ && stop_()) {
      stopped = true;
      return ceres::SOLVER_ABORT;
    }
    return ceres::SOLVER_CONTINUE;
  }
  bool stopped = false;

 private:
  const std::function<bool()>& stop_;
};

struct Solution {
  VectorXd theta;
  double cost = kInf;
  bool converged = false;
  std::string termination;
  int iterations = 0, evaluations = 0;
};

// Ceres reports through glog, whose default writes errors to standard error ("Terminating:
// Residual and Jacobian evaluation failed" for a start where the model cannot be evaluated): the
// fit reports those itself. Once per process, and only if the host program has not set glog up.
void quiet_glog() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (!google::IsGoogleLoggingInitialized()) {
      FLAGS_minloglevel = google::GLOG_FATAL;
      FLAGS_logtostderr = false;
      FLAGS_stderrthreshold = google::GLOG_FATAL;
      google::InitGoogleLogging("mbsgen-fit");
    }
  });
}

// One Levenberg–Marquardt solve from theta0 within the bounds; `fixed` ≥ 0 holds that
// coordinate (a profile). Throws FitStopped when options.stop asks.
Solution solve(detail::FitEvaluator& e, const VectorXd& theta0, int fixed, const FitOptions& options) {
  Solution s;
  s.theta = theta0;
  const int n = e.cols();
  if (fixed >= 0 && n == 1) {  // nothing left to optimize
    VectorXd r;
    s.converged = e.evaluate(s.theta, r, nullptr);
    s.cost = s.converged ? 0.5 * r.squaredNorm() : kInf;
    s.termination = "fixed";
    return s;
  }
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  problem.AddResidualBlock(new Cost(e), nullptr, s.theta.data());
  for (int j = 0; j < n; ++j) {
    problem.SetParameterLowerBound(s.theta.data(), j, e.theta_lower()[j]);
    problem.SetParameterUpperBound(s.theta.data(), j, e.theta_upper()[j]);
  }
  if (fixed >= 0) problem.SetManifold(s.theta.data(), new ceres::SubsetManifold(n, {fixed}));
  ceres::Solver::Options so;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_iterations;
  so.function_tolerance = 1e-12;
  so.gradient_tolerance = 1e-12;
  so.parameter_tolerance = 1e-10;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.num_threads = 1;
  StopCallback stop(options.stop);
  so.callbacks.push_back(&stop);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (stop.stopped) throw FitStopped("fit: stopped");
  s.cost = summary.final_cost;
  s.converged = summary.termination_type == ceres::CONVERGENCE;
  s.termination = summary.message;
  s.iterations = static_cast<int>(summary.iterations.size());
  s.evaluations = summary.num_residual_evaluations;
  if (summary.termination_type == ceres::FAILURE || !std::isfinite(s.cost)) {
    s.converged = false;
    s.cost = kInf;
  }
  return s;
}

// Starting points: the start, then a Latin hypercube over the bounds in θ.
std::vector<VectorXd> starting_points(const detail::FitEvaluator& e, const VectorXd& theta0, const FitOptions& o) {
  std::vector<VectorXd> points{theta0};
  if (o.starts <= 1) return points;
  std::vector<ParameterDistribution> d;
  for (int j = 0; j < e.cols(); ++j)
    d.push_back({e.names()[static_cast<std::size_t>(j)], Distribution::uniform, e.theta_lower()[j], e.theta_upper()[j]});
  const StudyDesign design(Design::latin_hypercube, d, static_cast<std::size_t>(o.starts - 1), o.seed);
  for (std::size_t i = 0; i < design.size(); ++i) {
    const std::vector<double> p = design.point(i);
    points.emplace_back(Eigen::Map<const VectorXd>(p.data(), static_cast<Eigen::Index>(p.size())));
  }
  return points;
}

// Every start solved, on threads, each with its own evaluator (and model copy).
std::vector<Solution> solve_all(const GeneratedModel& model, const MeasuredData& data,
                                const std::vector<FitParameter>& params, const std::vector<VectorXd>& starts,
                                const FitOptions& o) {
  std::vector<Solution> out(starts.size());
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t threads = std::min<std::size_t>(starts.size(), o.threads > 0 ? static_cast<unsigned>(o.threads) : hw);
  std::atomic<std::size_t> next{0};
  std::atomic<bool> halt{false};  // set by the first failure: the other threads stop at their next step
  FitOptions own = o;
  own.stop = [&halt, &o] { return halt.load() || (o.stop && o.stop()); };
  std::exception_ptr failure;
  std::mutex m;
  const auto work = [&] {
    try {
      detail::FitEvaluator e(model, data, params);
      for (std::size_t i; (i = next++) < starts.size();) out[i] = solve(e, starts[i], -1, own);
    } catch (...) {
      const std::lock_guard<std::mutex> lock(m);
      if (!failure) failure = std::current_exception();
      next = starts.size();
      halt = true;
    }
  };
  // The calling thread works too: a stop callback that only answers on the main thread (Python's
  // signal check) is asked there.
  std::vector<std::thread> pool;
  try {
    for (std::size_t t = 1; t < threads; ++t) pool.emplace_back(work);
  } catch (...) {  // no thread to be had: those started are stopped and joined
    halt = true;
    for (auto& t : pool) t.join();
    throw;
  }
  work();
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
  return out;
}

// The starts of this process (i mod ranks = rank), solved, and every process's shared: each
// solution packed as (index, cost, converged, iterations, evaluations, θ, the message's length and
// bytes), after a flag for a process that failed.
std::vector<Solution> solve_starts(const GeneratedModel& model, const MeasuredData& data,
                                   const std::vector<FitParameter>& params, const std::vector<VectorXd>& starts,
                                   const FitOptions& o) {
  if (o.ranks <= 1 || !o.share) return solve_all(model, data, params, starts, o);
  std::vector<VectorXd> mine;
  std::vector<std::size_t> index;
  for (std::size_t i = 0; i < starts.size(); ++i)
    if (static_cast<int>(i % static_cast<std::size_t>(o.ranks)) == o.rank) mine.push_back(starts[i]), index.push_back(i);
  std::vector<Solution> local;
  std::string failure;
  try {
    if (!mine.empty()) local = solve_all(model, data, params, mine, o);
  } catch (const std::exception& e) {
    failure = e.what();
  }
  std::vector<double> pack{failure.empty() ? 0.0 : 1.0, static_cast<double>(local.size())};
  for (std::size_t k = 0; k < local.size(); ++k) {
    const Solution& x = local[k];
    pack.insert(pack.end(), {static_cast<double>(index[k]), x.cost, x.converged ? 1.0 : 0.0, static_cast<double>(x.iterations),
                             static_cast<double>(x.evaluations)});
    pack.insert(pack.end(), x.theta.data(), x.theta.data() + x.theta.size());
    pack.push_back(static_cast<double>(x.termination.size()));
    for (char c : x.termination) pack.push_back(static_cast<unsigned char>(c));
  }
  const std::vector<double> all = o.share(pack);
  std::vector<Solution> out(starts.size());
  bool failed = false;
  const auto n = static_cast<std::size_t>(starts.front().size());
  for (std::size_t at = 0; at + 1 < all.size();) {
    failed = failed || all[at] != 0;
    const auto count = static_cast<std::size_t>(all[at + 1]);
    at += 2;
    for (std::size_t k = 0; k < count; ++k) {
      Solution x;
      const auto i = static_cast<std::size_t>(all[at]);
      x.cost = all[at + 1];
      x.converged = all[at + 2] != 0;
      x.iterations = static_cast<int>(all[at + 3]);
      x.evaluations = static_cast<int>(all[at + 4]);
      x.theta = Eigen::Map<const VectorXd>(all.data() + at + 5, static_cast<Eigen::Index>(n));
      at += 5 + n;
      const auto length = static_cast<std::size_t>(all[at++]);
      for (std::size_t c = 0; c < length; ++c) x.termination += static_cast<char>(static_cast<int>(all[at++]));
      out[i] = std::move(x);
    }
  }
  if (failed) throw Error("fit: a process failed" + (failure.empty() ? std::string(" (another rank)") : ": " + failure));
  return out;
}

// Distinct local minima: solutions within 1e-6 relative cost and 1e-3 in every θ are one.
std::vector<LocalMinimum> distinct_minima(const detail::FitEvaluator& e, std::vector<Solution> s) {
  std::sort(s.begin(), s.end(), [](const Solution& a, const Solution& b) { return a.cost < b.cost; });
  std::vector<LocalMinimum> minima;
  std::vector<VectorXd> thetas;
  for (const Solution& x : s) {
    if (!std::isfinite(x.cost)) continue;
    bool same = false;
    for (std::size_t k = 0; k < minima.size() && !same; ++k) {
      const double scale = (e.theta_upper() - e.theta_lower()).cwiseMin(1.0).maxCoeff();
      same = std::abs(x.cost - minima[k].cost) <= 1e-6 * std::max(1.0, minima[k].cost) &&
             (x.theta - thetas[k]).cwiseAbs().maxCoeff() <= 1e-3 * std::max(scale, 1e-12);
      if (same) ++minima[k].starts;
    }
    if (same) continue;
    minima.push_back({x.cost, e.values(x.theta), 1, x.converged});
    thetas.push_back(x.theta);
  }
  return minima;
}

// How far a relative standard deviation σ (of ln p) spreads: "±0.9 %" for small ones, "a factor 2.7"
// for large ones, "unbounded" for none.
std::string spread_text(double sigma) {
  if (!std::isfinite(sigma)) return "the data do not depend on it at all";
  char b[96];
  if (sigma < 0.1)
    std::snprintf(b, sizeof b, "one standard deviation %.2g %%", 100 * sigma);
  else if (sigma <= 5)
    std::snprintf(b, sizeof b, "one standard deviation a factor %.3g", std::exp(sigma));
  else
    std::snprintf(b, sizeof b, "one standard deviation %.3g in ln p: practically unbounded", sigma);
  return b;
}

// What a direction v of the parameters (ln p, or p/|p̂|) with standard deviation σ means: for a
// poorly determined one, "a and b are identified only as their ratio a/b" and the like.
std::string describe_direction(const detail::FitEvaluator& e, const VectorXd& v, double sigma, const std::string& verdict) {
  const std::vector<std::string>& names = e.names();
  std::vector<int> big;
  for (int j = 0; j < v.size(); ++j)
    if (std::abs(v[j]) >= 0.3) big.push_back(j);
  if (big.empty()) {  // spread over many parameters, none above 0.3: the largest three name it
    std::vector<int> all(static_cast<std::size_t>(v.size()));
    for (int j = 0; j < v.size(); ++j) all[static_cast<std::size_t>(j)] = j;
    std::sort(all.begin(), all.end(), [&](int a, int b) { return std::abs(v[a]) > std::abs(v[b]); });
    big.assign(all.begin(), all.begin() + std::min<std::ptrdiff_t>(3, static_cast<std::ptrdiff_t>(all.size())));
  }
  std::sort(big.begin(), big.end(), [&](int a, int b) { return std::abs(v[a]) > std::abs(v[b]); });
  const std::string spread = spread_text(sigma);
  const bool weak = verdict != "identified";
  // A log-space parameter's coordinate is ln p; a linear one's p/|p̂| (fisher_analysis).
  const auto coordinate = [&](int j) {
    const std::string& n = names[static_cast<std::size_t>(j)];
    return e.log_space(j) ? "ln " + n : n + "/|" + n + "|";
  };
  std::ostringstream s;
  s.precision(2);
  const double rest = v.squaredNorm() - (big.size() >= 2 ? v[big[0]] * v[big[0]] + v[big[1]] * v[big[1]] : 0.0);
  if (big.size() == 1 || std::abs(v[big[0]]) > 0.9) {
    s << names[static_cast<std::size_t>(big[0])] << " is " << verdict << " (" << spread << ")";
  } else if (weak && big.size() == 2 && rest < 0.1 && e.log_space(big[0]) && e.log_space(big[1])) {
    // Along v = (1, 1)/√2 both grow by the same factor: only a/b is fixed; along (1, −1), only a·b.
    const std::string& a = names[static_cast<std::size_t>(big[0])];
    const std::string& b = names[static_cast<std::size_t>(big[1])];
    if (v[big[0]] * v[big[1]] > 0)
      s << a << " and " << b << " are identified only as their ratio " << a << "/" << b << " (their product: " << spread << ")";
    else
      s << a << " and " << b << " are identified only as their product " << a << "·" << b << " (their ratio: " << spread << ")";
  } else {
    s << "the combination";
    for (std::size_t k = 0; k < big.size(); ++k)
      s << (k == 0 ? (v[big[k]] < 0 ? " −" : " ") : (v[big[k]] < 0 ? " − " : " + ")) << std::abs(v[big[k]]) << "·"
        << coordinate(big[k]);
    s << " is " << verdict << " (" << spread << ")";
  }
  return s.str();
}

// The Fisher information of the data alone in relative coordinates, by eigenvalue (weakest
// first), each direction judged and named. A parameter whose column of J is zero (to the
// threshold below which an eigenvalue counts as zero: ‖J_j‖² ≤ 4nε ‖J‖²_max, the response's own
// rounding reaching 1e-8 of it where A(Ω) is ill-conditioned) has no effect on the data at all: it is its own direction, said
// so, and the others are analysed without it (otherwise the null space's basis, which any
// rotation of it is as good as, would mix such parameters into arbitrary combinations).
std::vector<FisherDirection> fisher_analysis(const detail::FitEvaluator& e, const MatrixXd& J_data, const VectorXd& theta,
                                             double s2) {
  MatrixXd Jr = J_data;
  const VectorXd p = e.values(theta);
  const int n = e.cols();
  for (int j = 0; j < n; ++j)
    if (!e.log_space(j)) Jr.col(j) *= p[j] != 0 ? std::abs(p[j]) : e.theta_upper()[j] - e.theta_lower()[j];
  const double largest = Jr.size() ? Jr.colwise().norm().maxCoeff() : 0.0;
  std::vector<FisherDirection> out;
  std::vector<int> live;
  for (int j = 0; j < n; ++j) {
    if (Jr.col(j).squaredNorm() > 4.0 * n * std::numeric_limits<double>::epsilon() * largest * largest) {
      live.push_back(j);
      continue;
    }
    FisherDirection d;
    d.sigma = kInf;
    d.direction = VectorXd::Unit(n, j);
    d.verdict = "not identified";
    d.description = describe_direction(e, d.direction, d.sigma, d.verdict);
    out.push_back(std::move(d));
  }
  if (live.empty()) return out;  // no fitted parameter reaches the data
  MatrixXd Jl(Jr.rows(), static_cast<Eigen::Index>(live.size()));
  for (std::size_t k = 0; k < live.size(); ++k) Jl.col(static_cast<Eigen::Index>(k)) = Jr.col(live[k]);
  const MatrixXd F = Jl.transpose() * Jl / s2;
  const Eigen::SelfAdjointEigenSolver<MatrixXd> es(F);
  const double top = F.size() ? std::max(es.eigenvalues().maxCoeff(), 0.0) : 0.0;
  for (int k = 0; k < F.rows(); ++k) {
    FisherDirection d;
    d.eigenvalue = es.eigenvalues()[k];
    // Eigenvalues within rounding of zero (n ε λ_max) are zero: nothing identifies that direction.
    const bool zero = d.eigenvalue <= 4.0 * F.rows() * std::numeric_limits<double>::epsilon() * top;
    d.sigma = zero ? kInf : 1.0 / std::sqrt(d.eigenvalue);
    d.direction = VectorXd::Zero(n);
    for (std::size_t q = 0; q < live.size(); ++q) d.direction[live[q]] = es.eigenvectors()(static_cast<Eigen::Index>(q), k);
    Eigen::Index big = 0;
    d.direction.cwiseAbs().maxCoeff(&big);
    if (d.direction[big] < 0) d.direction = -d.direction;
    d.verdict = d.sigma <= 0.1 ? "identified" : d.sigma <= 1.0 ? "weakly identified" : "not identified";
    d.description = zero ? "" : describe_direction(e, d.direction, d.sigma, d.verdict);
    out.push_back(std::move(d));
  }
  // The directions with a zero eigenvalue span a space whose basis any rotation gives as well:
  // each is described by that space, through how much of each parameter lies in it.
  std::vector<int> null;
  for (std::size_t k = 0; k < out.size(); ++k)
    if (std::isinf(out[k].sigma) && out[k].description.empty()) null.push_back(static_cast<int>(k));
  if (!null.empty()) {
    std::string whole, part;
    for (int j = 0; j < n; ++j) {
      double share = 0;  // ‖projection of e_j onto the null space‖²
      for (int k : null) share += out[static_cast<std::size_t>(k)].direction[j] * out[static_cast<std::size_t>(k)].direction[j];
      if (share > 0.99) whole += (whole.empty() ? "" : ", ") + e.names()[static_cast<std::size_t>(j)];
      else if (share > 0.01) part += (part.empty() ? "" : ", ") + e.names()[static_cast<std::size_t>(j)];
    }
    const std::string text = std::to_string(null.size()) + " direction" + (null.size() > 1 ? "s" : "") +
                             " the data do not depend on at all" + (whole.empty() ? "" : "; entirely in them: " + whole) +
                             (part.empty() ? "" : "; partly (only some combinations of these are identified): " + part);
    for (int k : null) out[static_cast<std::size_t>(k)].description = text;
  }
  return out;
}

}  // namespace

FitResiduals fit_residuals(const GeneratedModel& model, const MeasuredData& data,
                           const std::vector<FitParameter>& parameters, const VectorXd& p, bool jacobian) {
  detail::FitEvaluator e(model, data, parameters);
  if (p.size() != e.cols())
    throw DimensionError("fit_residuals: " + std::to_string(p.size()) + " values for " + std::to_string(e.cols()) +
                         " parameters");
  FitResiduals out;
  out.data_rows = e.data_rows();
  std::string why;
  if (!e.evaluate(e.theta_of(p), out.r, jacobian ? &out.J : nullptr, &why)) throw Error("fit_residuals: " + why);
  return out;
}

namespace {

// Covariance, standard errors, intervals and correlations of the fit at theta (r, J there).
void statistics(const detail::FitEvaluator& e, const VectorXd& theta, const MatrixXd& J, FitResult& f) {
  const int n = e.cols();
  f.degrees_of_freedom = f.residuals - n;
  f.residual_variance = f.weighted ? 1.0 : f.degrees_of_freedom > 0 ? 2.0 * f.data_cost / f.degrees_of_freedom : kNaN;
  const MatrixXd JtJ = J.transpose() * J;
  const Eigen::SelfAdjointEigenSolver<MatrixXd> es(JtJ);
  const double top = std::max(es.eigenvalues().maxCoeff(), 0.0);
  VectorXd inv(n);
  for (int k = 0; k < n; ++k) {
    const double l = es.eigenvalues()[k];
    inv[k] = l <= 4.0 * n * std::numeric_limits<double>::epsilon() * top ? kInf : 1.0 / l;
  }
  f.covariance = MatrixXd::Zero(n, n);
  for (int k = 0; k < n; ++k) {
    const VectorXd v = es.eigenvectors().col(k);
    if (std::isinf(inv[k])) {  // an undetermined direction: infinite variance where it reaches
      for (int i = 0; i < n; ++i)
        if (std::abs(v[i]) > 1e-8) f.covariance(i, i) = kInf;
      continue;
    }
    f.covariance += inv[k] * f.residual_variance * v * v.transpose();
  }
  const double q = f.weighted || f.degrees_of_freedom <= 0
                       ? 1.959963984540054
                       : boost::math::quantile(boost::math::students_t(f.degrees_of_freedom), 0.975);
  f.standard_error.resize(n);
  f.lower95.resize(n);
  f.upper95.resize(n);
  f.correlation.resize(n, n);
  for (int j = 0; j < n; ++j) {
    const double sd = std::sqrt(f.covariance(j, j));
    const double lo = std::max(theta[j] - q * sd, e.theta_lower()[j]), hi = std::min(theta[j] + q * sd, e.theta_upper()[j]);
    f.standard_error[j] = e.log_space(j) ? f.values[j] * sd : sd;
    f.lower95[j] = e.log_space(j) ? std::exp(lo) : lo;
    f.upper95[j] = e.log_space(j) ? std::exp(hi) : hi;
    for (int i = 0; i < n; ++i) {
      const double d = std::sqrt(f.covariance(i, i) * f.covariance(j, j));
      f.correlation(i, j) = std::isfinite(d) && d > 0 ? f.covariance(i, j) / d : kNaN;
    }
  }
}

// The profile likelihood of parameter j: θ_j on a grid, the others optimized from the fit.
Profile profile(detail::FitEvaluator& e, const FitResult& f, const VectorXd& theta, int j, const FitOptions& o) {
  Profile p;
  p.parameter = e.names()[static_cast<std::size_t>(j)];
  const double sd = std::sqrt(f.covariance(j, j));
  double lo = e.theta_lower()[j], hi = e.theta_upper()[j];
  if (std::isfinite(sd) && sd > 0) {
    lo = std::max(lo, theta[j] - 4 * sd);
    hi = std::min(hi, theta[j] + 4 * sd);
  }
  const int m = std::max(3, o.profile_points) | 1;  // odd: the fit itself is the middle point
  std::vector<ProfilePoint> pts(static_cast<std::size_t>(m));
  const int mid = m / 2;
  for (int side : {-1, 1}) {
    VectorXd t = theta;
    for (int k = 0; k <= mid; ++k) {
      const int i = mid + side * k;
      if (side == 1 && k == 0) continue;
      t[j] = k == 0 ? theta[j] : side < 0 ? theta[j] + (lo - theta[j]) * k / mid : theta[j] + (hi - theta[j]) * k / mid;
      const Solution s = solve(e, t, j, o);
      if (std::isfinite(s.cost)) t = s.theta;
      pts[static_cast<std::size_t>(i)] = {e.log_space(j) ? std::exp(t[j]) : t[j], s.cost, s.converged};
    }
  }
  p.points = pts;
  const double chi = 3.841458820694124;  // χ²₁ at 0.95
  const auto delta = [&](const ProfilePoint& x) { return 2.0 * (x.cost - f.cost) / f.residual_variance; };
  p.lower = p.upper = kNaN;
  for (int i = mid; i > 0; --i) {
    const double a = delta(pts[static_cast<std::size_t>(i)]), b = delta(pts[static_cast<std::size_t>(i - 1)]);
    if (!std::isfinite(b)) break;  // a point the model refused: no bound from beyond it
    if (a < chi && b >= chi) {
      const double w = (chi - a) / (b - a);
      p.lower = pts[static_cast<std::size_t>(i)].value + w * (pts[static_cast<std::size_t>(i - 1)].value - pts[static_cast<std::size_t>(i)].value);
      break;
    }
  }
  for (int i = mid; i + 1 < m; ++i) {
    const double a = delta(pts[static_cast<std::size_t>(i)]), b = delta(pts[static_cast<std::size_t>(i + 1)]);
    if (!std::isfinite(b)) break;
    if (a < chi && b >= chi) {
      const double w = (chi - a) / (b - a);
      p.upper = pts[static_cast<std::size_t>(i)].value + w * (pts[static_cast<std::size_t>(i + 1)].value - pts[static_cast<std::size_t>(i)].value);
      break;
    }
  }
  return p;
}

std::string number_text(double x) {
  std::ostringstream s;
  s.precision(6);
  s << x;
  return s.str();
}

// Warnings a reader must see: not converged, on a bound, not identified, a better profile point.
void collect_warnings(const detail::FitEvaluator& e, const VectorXd& theta, FitResult& f) {
  if (!f.converged) f.warnings.push_back("the fit did not converge: " + f.termination + "; the values are not a minimum");
  f.at_bound.assign(static_cast<std::size_t>(e.cols()), "");
  for (int j = 0; j < e.cols(); ++j) {
    const double w = 1e-6 * (e.theta_upper()[j] - e.theta_lower()[j]);
    const std::string& name = e.names()[static_cast<std::size_t>(j)];
    if (theta[j] - e.theta_lower()[j] <= w) f.at_bound[static_cast<std::size_t>(j)] = "lower";
    if (e.theta_upper()[j] - theta[j] <= w) f.at_bound[static_cast<std::size_t>(j)] = "upper";
    if (!f.at_bound[static_cast<std::size_t>(j)].empty())
      f.warnings.push_back(name + " ended on its " + f.at_bound[static_cast<std::size_t>(j)] + " bound " +
                           number_text(f.values[j]) + ": the data ask for a value beyond it; its interval is not a confidence interval");
  }
  std::size_t unidentified = 0;
  for (const FisherDirection& d : f.fisher) unidentified += d.verdict == "not identified";
  if (unidentified > 0)
    f.warnings.push_back(std::to_string(unidentified) + " of " + std::to_string(f.fisher.size()) +
                         " directions of the parameters are not identified by the data (one standard deviation above a "
                         "factor e; the identifiability analysis names them): their estimates rest on the start" +
                         std::string(e.rows() > e.data_rows() ? " or the priors" : ""));
  if (!std::isfinite(f.residual_variance))
    f.warnings.push_back("the data carry no standard deviations and leave no degree of freedom (" +
                         std::to_string(f.residuals) + " residuals, " + std::to_string(e.cols()) +
                         " parameters): their variance, and so the standard errors, cannot be estimated; give "
                         "sigma_magnitude and sigma_phase_deg");
  if (f.minima.size() > 1)
    f.warnings.push_back(std::to_string(f.minima.size()) + " distinct local minima among the starts (the best reported)");
  for (const Profile& p : f.profiles)
    for (const ProfilePoint& x : p.points)
      if (x.cost < f.cost * (1 - 1e-8) - 1e-12) {
        f.warnings.push_back("the profile of " + p.parameter + " found a lower cost (" + number_text(x.cost) +
                             ") than the fit: the fit is a local minimum");
        break;
      }
}

}  // namespace

FitResult fit(const GeneratedModel& model, const MeasuredData& data, const std::vector<FitParameter>& parameters,
              const FitOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  quiet_glog();
  detail::FitEvaluator e(model, data, parameters);
  FitResult f;
  f.names = e.names();
  for (int j = 0; j < e.cols(); ++j) f.log_space.push_back(e.log_space(j));
  for (const std::string& name : options.profile)  // before the work, not after it
    if (std::find(f.names.begin(), f.names.end(), name) == f.names.end())
      throw NameError("fit: --profile '" + name + "' is not a fitted parameter");
  const VectorXd theta0 = e.theta_of(e.start());
  f.start = e.start();
  f.residuals = e.data_rows();
  f.weighted = e.weighted();
  VectorXd r;
  MatrixXd J;
  std::string why;
  if (!e.evaluate(theta0, r, &J, &why)) throw Error("fit: the model cannot be evaluated at the start: " + why);
  f.initial_cost = 0.5 * r.squaredNorm();
  VectorXd theta = theta0;
  if (options.optimize) {
    const std::vector<Solution> s = solve_starts(model, data, parameters, starting_points(e, theta0, options), options);
    const auto best = std::min_element(s.begin(), s.end(), [](const Solution& a, const Solution& b) { return a.cost < b.cost; });
    if (!std::isfinite(best->cost)) throw Error("fit: no start reached a point where the model can be evaluated");
    theta = best->theta;
    f.converged = best->converged;
    f.termination = best->termination;
    for (const Solution& x : s) {
      f.iterations += x.iterations;
      f.evaluations += x.evaluations;
    }
    f.minima = distinct_minima(e, s);
    if (!e.evaluate(theta, r, &J, &why)) throw Error("fit: the model cannot be evaluated at the fit: " + why);
  } else {
    f.converged = true;
    f.termination = "not optimized: the analysis at the start";
  }
  f.values = e.values(theta);
  f.cost = 0.5 * r.squaredNorm();
  f.data_cost = 0.5 * r.head(e.data_rows()).squaredNorm();
  statistics(e, theta, J, f);
  f.fisher = fisher_analysis(e, J.topRows(e.data_rows()), theta,
                             std::isfinite(f.residual_variance) && f.residual_variance > 0 ? f.residual_variance : 1.0);
  for (const std::string& name : options.profile) {
    const auto it = std::find(f.names.begin(), f.names.end(), name);
    f.profiles.push_back(profile(e, f, theta, static_cast<int>(it - f.names.begin()), options));
  }
  f.points = e.points(theta0, theta);
  collect_warnings(e, theta, f);
  f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return f;
}

}  // namespace mbsgen
