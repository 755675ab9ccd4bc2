#include "mbsgen/runtime/model/static_equilibrium.hpp"

#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <sstream>

#include "mbsgen/runtime/error.hpp"

namespace mbsgen {

StaticEquilibrium::StaticEquilibrium(Eigen::Index f, StaticEquilibriumOptions options)
    : options_(options), y_(f), r_(f), dy_(f), ytrial_(f), rtrial_(f), J_(f, f) {}

StaticEquilibrium& StaticEquilibrium::compute(const ResidualFunction& residual,
                                              const JacobianFunction& jacobian,
                                              const Eigen::VectorXd& y0) {
  const Eigen::Index f = y0.size();
  y_ = y0;
  r_.resize(f);
  J_.resize(f, f);
  iterations_ = 0;
  rcond_ = 0.0;
  auto fail = [&](Eigen::ComputationInfo info, const std::string& why) -> StaticEquilibrium& {
    info_ = info;
    std::ostringstream s;
    s << "StaticEquilibrium: " << why << " after " << iterations_ << " iterations, |r| = "
      << residual_norm_;
    report_ = s.str();
    return *this;
  };
  residual(y_, r_);
  residual_norm_ = r_.norm();
  if (!std::isfinite(residual_norm_)) return fail(Eigen::NumericalIssue, "non-finite residual");
  const double scale = std::max(1.0, residual_norm_);
  const double u = std::numeric_limits<double>::epsilon() / 2;
  while (true) {
    if (residual_norm_ <= options_.residual_tolerance * scale) break;
    if (iterations_ >= options_.max_iterations) return fail(Eigen::NoConvergence, "no convergence");
    jacobian(y_, J_);
    if (!J_.allFinite()) return fail(Eigen::NumericalIssue, "non-finite Jacobian");
    Eigen::PartialPivLU<Eigen::MatrixXd> lu(J_);
    rcond_ = lu.rcond();
    if (!(rcond_ > static_cast<double>(f) * u)) {
      std::ostringstream s;
      s << "singular Jacobian (rcond " << rcond_ << ")";
      return fail(Eigen::NumericalIssue, s.str());
    }
    dy_ = -lu.solve(r_);
    ++iterations_;
    // Armijo backtracking on φ(t) = ½‖r(y + tΔy)‖²; φ'(0) = −‖r‖² for the Newton direction.
    double t = 1.0;
    const double phi0 = r_.squaredNorm();
    bool accepted = false;
    for (int k = 0; k <= options_.max_backtracks; ++k, t *= 0.5) {
      ytrial_ = y_ + t * dy_;
      residual(ytrial_, rtrial_);
      const double phi = rtrial_.squaredNorm();
      if (std::isfinite(phi) && phi <= (1.0 - 2.0 * options_.armijo * t) * phi0) {
        accepted = true;
        break;
      }
    }
    const double step = (t * dy_).norm();
    if (!accepted) {
      // Rounding floor: the full step is tiny and the residual does not decrease any more.
      if (dy_.norm() <= 1e3 * options_.step_tolerance * std::max(1.0, y_.norm()) &&
          residual_norm_ <= std::sqrt(options_.residual_tolerance) * scale)
        break;
      return fail(Eigen::NoConvergence, "line search failed (no sufficient decrease)");
    }
    y_ = ytrial_;
    r_ = rtrial_;
    residual_norm_ = r_.norm();
    if (step <= options_.step_tolerance * std::max(1.0, y_.norm()) &&
        residual_norm_ <= std::sqrt(options_.residual_tolerance) * scale)
      break;
  }
  info_ = Eigen::Success;
  std::ostringstream s;
  s << "StaticEquilibrium: converged in " << iterations_ << " iterations, |r| = "
    << residual_norm_;
  report_ = s.str();
  return *this;
}

const StaticEquilibrium& StaticEquilibrium::throw_if_failed() const {
  if (info_ == Eigen::Success) return *this;
  if (info_ == Eigen::NumericalIssue) throw SingularSystemError(report_);
  throw ConvergenceError(report_);
}

}  // namespace mbsgen
