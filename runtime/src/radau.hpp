// Radau IIA of order 5 (three stages, L-stable) for the equations of motion in their implicit
// form M(y) ÿ + r(y, ẏ, t) = 0, r = k − q (internal to simulation.cpp: `simulate --method radau`).
//
// The method and its step-size control are those of Hairer and Wanner's RADAU5 (Solving Ordinary
// Differential Equations II, 2nd ed., Springer 1996, Sect. IV.8): simplified Newton iterations on
// the stage increments Z in the coordinates W = (T⁻¹ ⊗ I) Z that split the Newton matrix into one
// real and one complex system, the embedded error estimate filtered by the real system, the
// predictive (Gustafsson) step-size controller, a step kept with its LU when the controller asks
// for less than 1.2 times it, and the collocation polynomial as continuous output (order 3).
//
// What differs is the linear algebra, written for mechanical systems: on x = (y, v), ẋ = (v, ÿ),
// with J = [0, I; −M⁻¹K_y, −M⁻¹K_v] from the kernels (K_y = ∂(M ÿ + k − q)/∂y, K_v = ∂(k − q)/∂ẏ),
// each Newton system (σI − J)(Δy, Δv) = (b_y, b_v), σ = μ/h (μ an eigenvalue of A⁻¹), is solved
// through its n×n Schur complement (σ²M + σK_v + K_y) Δv = σ M b_v − K_y b_y, Δy = (b_y + Δv)/σ:
// one real and one complex n×n LU per step size instead of 2n×2n ones, and no M⁻¹K products.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>

#include "radau_tableau.hpp"

#include <complex>
#include <vector>

namespace mbsgen::detail {

/// The equations as the integrator evaluates them.
class SecondOrderSystem {
 public:
  virtual ~SecondOrderSystem() = default;
  /// ÿ = −M⁻¹r at (t, y, v) (a factorization of M); false where a kernel fails or M is singular.
  virtual bool accelerations(double t, const double* y, const double* v, Eigen::VectorXd& a) = 0;
  /// Whether jacobian() is available (else the integrator takes difference quotients).
  virtual bool has_jacobian() const = 0;
  /// M, K_y = ∂(M ÿ + r)/∂y at ÿ = −M⁻¹r and K_v = ∂r/∂v at a state; false on failure.
  virtual bool jacobian(double t, const double* y, const double* v, Eigen::MatrixXd& M, Eigen::MatrixXd& Ky,
                        Eigen::MatrixXd& Kv) = 0;
  /// M and ÿ at a state (for difference quotients); false on failure.
  virtual bool jacobian_mass(double t, const double* y, const double* v, Eigen::MatrixXd& M, Eigen::VectorXd& a) = 0;
};

struct RadauStatistics {
  long steps = 0, evaluations = 0, jacobians = 0, factorizations = 0, rejected = 0, newton_failures = 0;
};

class Radau {
 public:
  /// n coordinates; tolerances of x = (y, v): rtol and one atol per state (2n); 3 stages
  /// (order 5, RADAU5) or 5 (order 9).
  Radau(SecondOrderSystem& system, Eigen::Index n, double rtol, const Eigen::VectorXd& atol, int stages = 3);

  /// Starts at (t, x) without history: the start, or a restart after an input jumps. False when
  /// the equations or their Jacobian fail there.
  bool start(double t, const Eigen::VectorXd& x);
  /// step_too_small: the step had to shrink below 10 ulps of t (failing error tests or Newton
  /// iterations); failed: the Jacobian could not be evaluated at the accepted state.
  enum class Status { ok, step_too_small, failed };
  /// One accepted step, not past t_stop (> time()).
  Status step(double t_stop);

  double time() const { return t_; }
  const Eigen::VectorXd& state() const { return x_; }
  /// The size of the last step tried (its failure: the step that could not be made smaller).
  double step_size() const { return h_; }
  /// x(t) from the last step's collocation polynomial, t in [time() − last step, time()].
  void interpolate(double t, double* x) const;
  const RadauStatistics& statistics() const { return stats_; }

 private:
  bool newton(double h, int& iterations, double& theta);
  bool residuals(double h);
  bool try_step(double h, int& iterations, double& theta);
  bool evaluate_jacobian(double t, const Eigen::VectorXd& x);
  bool factor(double h);
  template <class Matrix>
  void equilibrate(Matrix& R) const;  // S R S, S = diag(equilibrate_)
  void solve_real(const double* b, double* out);
  void solve_complex(std::size_t k, const double* b_re, const double* b_im, double* out_re, double* out_im);
  const Eigen::VectorXd& powers(double theta) const;
  bool derivative(double t, const Eigen::VectorXd& x, Eigen::VectorXd& f);
  double error_norm(double h, const Eigen::VectorXd& x_new, bool again);
  double norm(const Eigen::VectorXd& e, const Eigen::VectorXd& scale) const;
  bool accept(double t_new, double h, double error, double safety, int iterations, double theta);

  SecondOrderSystem& system_;
  const RadauTableau& tableau_;
  int s_;                 // stages
  int newton_iterations_;  // RADAU5's NIT: 7 for 3 stages, 10 for 5
  double exponent_;       // the step-size controller's, 1/(s + 1)
  Eigen::Index n_;
  double rtol_;
  Eigen::VectorXd atol_;
  double newton_tol_;

  double t_ = 0, h_ = 0, h_old_ = 0, error_old_ = 0, t_old_ = 0, h_last_ = 0, h_unclamped_ = 0;
  bool dense_ = false;         // a previous step's polynomial to start Newton from
  bool first_ = true;          // no step accepted since start()
  bool current_jacobian_ = false;
  bool jacobian_failed_ = false;
  bool factored_ = false;
  double fresh_theta_ = 0;   // θ of the last step's Newton iteration on a fresh Jacobian
  double faccon_ = 1;          // RADAU5's FACCON: θ/(1 − θ) of the last Newton iteration
  double h_factored_ = 0;
  Eigen::VectorXd x_, x_old_, f0_, scale_;  // f0_: ẋ at the step's start
  Eigen::MatrixXd Z_, W_, Q_;  // 2n × s: stage increments, transformed, dense output
  Eigen::MatrixXd MJ_, Ky_, Kv_;
  Eigen::VectorXd equilibrate_;  // S = diag(|M_ii|)^(-1/2) of MJ
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_real_;
  std::vector<Eigen::PartialPivLU<Eigen::MatrixXcd>> lu_complex_;  // one per complex pair
  double sigma_real_ = 0;
  std::vector<std::complex<double>> sigma_complex_;
  // Work space.
  Eigen::MatrixXd G_, dW_, stage_;
  Eigen::MatrixXd R_;
  Eigen::MatrixXcd Rc_;
  Eigen::VectorXd x_new_;
  Eigen::VectorXd b_, e_, f_, ze_, a_, work_re_, work_im_;
  Eigen::VectorXcd bc_, yc_;
  mutable Eigen::VectorXd powers_;
  Eigen::MatrixXd scaled_;    // A⁻ᵀ/h
  Eigen::VectorXd e_scaled_;  // E/h
  RadauStatistics stats_;
};

}  // namespace mbsgen::detail
