// Static equilibrium k(y, 0) = q(y, 0) (docs/design.md, "Linearization", the operating point of the linearization):
// Newton's method with a backtracking line search on r(y) = k(y,0) − q(y,0).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>

namespace mbsgen {

/// Residual callback: r(y) (f, in the units of the generalized forces: N or N·m) written into r.
using ResidualFunction = std::function<void(const Eigen::VectorXd& y, Eigen::VectorXd& r)>;
/// Jacobian callback: J = ∂r/∂y (f×f; at an equilibrium this is the stiffness K) written into J.
using JacobianFunction = std::function<void(const Eigen::VectorXd& y, Eigen::MatrixXd& J)>;

/// Options of StaticEquilibrium.
struct StaticEquilibriumOptions {
  int max_iterations = 50;        ///< Newton steps
  /// Converged when ‖r‖₂ ≤ residual_tolerance·max(1, ‖r(y0)‖₂) or the step
  /// ‖Δy‖₂ ≤ step_tolerance·max(1, ‖y‖₂) with ‖r‖ already below √residual_tolerance scale.
  double residual_tolerance = 1e-12;
  double step_tolerance = 1e-14;
  int max_backtracks = 30;        ///< halvings of the step in the Armijo line search
  double armijo = 1e-4;           ///< sufficient decrease constant c in ‖r(y+tΔ)‖² ≤ (1−2ct)‖r‖²
};

/// Newton's method with an Armijo backtracking line search on ½‖r‖² (Dennis & Schnabel 1983,
/// §6.3). Each step solves J Δy = −r by LU with partial pivoting and reports its rcond; a
/// numerically singular J (rcond < f·u) or a failed line search ends the iteration with a
/// failure report, never a silent result.
class StaticEquilibrium {
 public:
  explicit StaticEquilibrium(Eigen::Index f = 0, StaticEquilibriumOptions options = {});

  /// Runs Newton from y0 (f). Does not throw for non-convergence: check info() and report().
  StaticEquilibrium& compute(const ResidualFunction& residual, const JacobianFunction& jacobian,
                             const Eigen::VectorXd& y0);

  /// Eigen::Success when converged, Eigen::NoConvergence otherwise, Eigen::NumericalIssue for a
  /// singular Jacobian or non-finite residual.
  Eigen::ComputationInfo info() const { return info_; }
  const Eigen::VectorXd& solution() const { return y_; }  ///< last iterate y (f)
  int iterations() const { return iterations_; }          ///< Newton steps taken
  double residual_norm() const { return residual_norm_; } ///< ‖r(y)‖₂ at the last iterate
  double jacobian_rcond() const { return rcond_; }        ///< rcond of the last Jacobian
  /// One line: "converged in 5 iterations, |r| = 1e-15" or the reason for failure.
  const std::string& report() const { return report_; }
  /// Throws ConvergenceError (or SingularSystemError) with report() unless info() == Success.
  const StaticEquilibrium& throw_if_failed() const;

 private:
  StaticEquilibriumOptions options_;
  Eigen::ComputationInfo info_ = Eigen::InvalidInput;
  Eigen::VectorXd y_, r_, dy_, ytrial_, rtrial_;
  Eigen::MatrixXd J_;
  int iterations_ = 0;
  double residual_norm_ = 0.0, rcond_ = 0.0;
  std::string report_;
};

}  // namespace mbsgen
