// Radau IIA of orders 5 and 9 (three and five stages, L-stable) for the equations of motion in
// their implicit form M(y) ÿ + r(y, ẏ, t) = 0, r = k − q (internal to simulation.cpp: `simulate
// --method radau` and `radau9`).
//
// The method and its step-size control are those of Hairer and Wanner's RADAU5 (Solving Ordinary
// Differential Equations II, 2nd ed., Springer 1996, Sect. IV.8), and for five stages those of
// their RADAU at its order 9 (Hairer and Wanner, Stiff differential equations solved by Radau
// methods, J. Comput. Appl. Math. 111, 1999): simplified Newton iterations on the stage
// increments Z in the coordinates W = (T⁻¹ ⊗ I) Z that split the Newton matrix into one real
// system and one complex one per pair of A⁻¹'s complex eigenvalues, the embedded error estimate
// (of order s) filtered by the real system, the predictive (Gustafsson) step-size controller, a
// step kept with its LUs when the controller asks for less than 1.2 times it, and the collocation
// polynomial as continuous output (order s). The constants: radau_tableau.hpp.
//
// What differs is the linear algebra, written for mechanical systems: on x = (y, v), ẋ = (v, ÿ),
// with J = [0, I; −M⁻¹K_y, −M⁻¹K_v] from the kernels (K_y = ∂(M ÿ + k − q)/∂y, K_v = ∂(k − q)/∂ẏ),
// each Newton system (σI − J)(Δy, Δv) = (b_y, b_v), σ = μ/h (μ an eigenvalue of A⁻¹), is solved
// through its n×n Schur complement (σ²M + σK_v + K_y) Δv = σ M b_v − K_y b_y, Δy = (b_y + Δv)/σ:
// n×n LUs per step size instead of 2n×2n ones, and no M⁻¹K products.
#pragma once

#include <Eigen/Core>

#include <memory>

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

/// Radau IIA with 3 stages (order 5, RADAU5) or 5 (order 9), on the equations of a
/// SecondOrderSystem (radau.cpp: RadauIIA<stages>).
class Radau {
 public:
  virtual ~Radau() = default;
  /// n coordinates; tolerances of x = (y, v): rtol and one atol per state (2n); 3 or 5 stages.
  static std::unique_ptr<Radau> make(SecondOrderSystem& system, Eigen::Index n, double rtol,
                                     const Eigen::VectorXd& atol, int stages = 3);

  /// Starts at (t, x) without history: the start, or a restart after an input jumps. False when
  /// the equations or their Jacobian fail there.
  virtual bool start(double t, const Eigen::VectorXd& x) = 0;
  /// step_too_small: the step had to shrink below 10 ulps of t (failing error tests or Newton
  /// iterations); failed: the Jacobian could not be evaluated at the accepted state.
  enum class Status { ok, step_too_small, failed };
  /// One accepted step, not past t_stop (> time()).
  virtual Status step(double t_stop) = 0;

  virtual double time() const = 0;
  virtual const Eigen::VectorXd& state() const = 0;
  /// The size of the last step tried (its failure: the step that could not be made smaller).
  virtual double step_size() const = 0;
  /// x(t) from the last step's collocation polynomial, t in [time() − last step, time()].
  virtual void interpolate(double t, double* x) const = 0;
  virtual const RadauStatistics& statistics() const = 0;
};

}  // namespace mbsgen::detail
