// Radau IIA of orders 5 and 9 on M(y) ÿ + r(y, ẏ, t) = 0 (radau.hpp).
#include "time/radau.hpp"

#include "time/radau_tableau.hpp"
#include "time/second_order_newton.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
#include <string>

namespace mbsgen::detail {

namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using complex = std::complex<double>;

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
constexpr double kKeepJacobian = 1e-3;  // RADAU5's THET: a Newton rate below it keeps the Jacobian
constexpr double kSafety = 0.9;
// A Newton iteration on a fresh Jacobian that stops contracting with corrections below this (in
// the error norm's units, where 1 is the tolerance) has reached the rounding in f: the middle ear
// at rtol 1e-8, whose smallest motions' absolute tolerances (1e-17) are below its kernels'
// rounding. Its iterate is kept, less a last correction that grew (RADAU5 and SciPy halve the
// step instead, again and again); the error test then judges the step.
constexpr double kStalled = 0.1;
constexpr double kMaxGrowth = 10, kMinShrink = 0.2;  // per step

// The step-size factor of the predictive controller (Gustafsson), from this step's error and
// the last accepted one's (none: h_old = 0); the error estimate is O(h^(s+1)).
double predicted_factor(double h, double h_old, double error, double error_old, double exponent) {
  double multiplier = 1;
  if (h_old > 0 && error > 0 && error_old > 0) multiplier = h / h_old * std::pow(error_old / error, exponent);
  return error == 0 ? kMaxGrowth : std::min(1.0, multiplier) * std::pow(error, -exponent);
}

}  // namespace

// S stages, S odd: the stage matrices 2n × S and the constants of fixed size.
template <int S>
class RadauIIA final : public Radau {
 public:
  RadauIIA(SecondOrderSystem& system, Index n, double rtol, const VectorXd& atol);
  bool start(double t, const VectorXd& x) override;
  Status step(double t_stop) override;
  double time() const override { return t_; }
  const VectorXd& state() const override { return x_; }
  double step_size() const override { return h_; }
  void interpolate(double t, double* x) const override;
  const RadauStatistics& statistics() const override { return stats_; }

 private:
  using Stages = Eigen::Matrix<double, Eigen::Dynamic, S>;
  using Square = Eigen::Matrix<double, S, S>;
  using Vector = Eigen::Matrix<double, S, 1>;
  static constexpr std::size_t kPairs = (S - 1) / 2;  // A⁻¹'s complex eigenvalue pairs
  // RADAU5's NIT, 7 for three stages; RADAU's for five, 12 (NIT + 5).
  static constexpr int kNewtonIterations = S == 3 ? 7 : 12;
  static constexpr double kExponent = 1.0 / (S + 1);  // the controller's: the estimate is O(h^(S+1))

  bool newton(double h, int& iterations, double& theta);
  bool residuals(double h);
  bool try_step(double h, int& iterations, double& theta);
  bool evaluate_jacobian(double t, const VectorXd& x);
  bool factor(double h);
  template <class Matrix>
  void equilibrate(Matrix& R) const;  // S R S, S = diag(equilibrate_)
  void solve_real(const double* b, double* out);
  void solve_complex(std::size_t k, const double* b_re, const double* b_im, double* out_re, double* out_im);
  static Vector powers(double theta);  // (θ, θ², …, θ^S)
  bool derivative(double t, const VectorXd& x, VectorXd& f);
  double error_norm(double h, const VectorXd& x_new, bool again);
  double norm(const VectorXd& e, const VectorXd& scale);
  bool accept(double t_new, double h, double error, double safety, int iterations, double theta);

  SecondOrderSystem& system_;
  Index n_;
  double rtol_;
  VectorXd atol_;
  double newton_tol_;
  // The tableau (radau_tableau.hpp): nodes, (A⁻¹)ᵀ, T⁻ᵀ, Tᵀ, dense output, error weights.
  Vector c_, E_;
  Square A_invT_, T_invT_, T_T_, P_;
  double gamma_ = 0;
  std::array<complex, kPairs> mu_;

  double t_ = 0, h_ = 0, h_old_ = 0, error_old_ = 0, t_old_ = 0, h_last_ = 0, h_unclamped_ = 0;
  bool dense_ = false;         // a previous step's polynomial to start Newton from
  bool first_ = true;          // no step accepted since start()
  bool current_jacobian_ = false;
  bool jacobian_failed_ = false;
  bool factored_ = false;
  double fresh_theta_ = 0;   // θ of the last step's Newton iteration on a fresh Jacobian
  double faccon_ = 1;          // RADAU5's FACCON: θ/(1 − θ) of the last Newton iteration
  double h_factored_ = 0;
  VectorXd x_, x_old_, f0_, scale_;  // f0_: ẋ at the step's start
  Stages Z_, W_, Q_;  // stage increments, transformed, dense output
  MatrixXd MJ_, Ky_, Kv_;
  VectorXd equilibrate_;  // S = diag(|M_ii|)^(-1/2) of MJ
  Eigen::PartialPivLU<MatrixXd> lu_real_;
  std::array<Eigen::PartialPivLU<Eigen::MatrixXcd>, kPairs> lu_complex_;
  double sigma_real_ = 0;
  std::array<complex, kPairs> sigma_complex_;
  // Work space.
  Stages G_, dW_, stage_;
  MatrixXd R_;
  Eigen::MatrixXcd Rc_;
  VectorXd x_new_;
  VectorXd b_, e_, f_, ze_, a_, work_re_, work_im_, quotient_, x_shifted_, a0_;
  Eigen::VectorXcd bc_, yc_;
  RadauStatistics stats_;
};

template <int S>
RadauIIA<S>::RadauIIA(SecondOrderSystem& system, Index n, double rtol, const VectorXd& atol)
    : system_(system), n_(n), rtol_(rtol), atol_(atol),
      newton_tol_(std::max(10 * kEpsilon / rtol, std::min(0.03, std::sqrt(rtol)))), x_(2 * n), x_old_(2 * n),
      f0_(2 * n), scale_(2 * n), Z_(2 * n, S), W_(2 * n, S), Q_(2 * n, S), MJ_(n, n), Ky_(n, n), Kv_(n, n),
      equilibrate_(n), lu_real_(n), G_(2 * n, S), dW_(2 * n, S), stage_(2 * n, S), R_(n, n), Rc_(n, n),
      x_new_(2 * n), b_(2 * n), e_(2 * n), f_(2 * n), ze_(2 * n), a_(n), work_re_(n), work_im_(n), quotient_(2 * n),
      x_shifted_(2 * n), a0_(n), bc_(n), yc_(n) {
  const RadauTableau& t = RadauTableau::of(S);
  c_ = t.c;
  A_invT_ = t.A_inv.transpose();
  T_invT_ = t.T_inv.transpose();
  T_T_ = t.T.transpose();
  P_ = t.P;
  E_ = t.E;
  gamma_ = t.gamma;
  for (std::size_t k = 0; k < kPairs; ++k) {
    mu_[k] = t.mu[k];
    lu_complex_[k] = Eigen::PartialPivLU<Eigen::MatrixXcd>(n);
  }
}

// ẋ = f(t, x) = (v, ÿ(t, y, v)).
template <int S>
bool RadauIIA<S>::derivative(double t, const VectorXd& x, VectorXd& f) {
  ++stats_.evaluations;
  if (!system_.accelerations(t, x.data(), x.data() + n_, a_)) return false;
  f.head(n_) = x.tail(n_);
  f.tail(n_) = a_;
  return f.allFinite();
}

template <int S>
double RadauIIA<S>::norm(const VectorXd& e, const VectorXd& scale) {  // RMS, without overflow
  if (e.size() == 0) return 0.0;
  quotient_ = e.array() / scale.array();
  return quotient_.stableNorm() / std::sqrt(static_cast<double>(e.size()));
}

template <int S>
bool RadauIIA<S>::start(double t, const VectorXd& x) {
  t_ = t;
  x_ = x;
  dense_ = false;
  first_ = true;
  factored_ = false;
  faccon_ = 1;
  fresh_theta_ = 0;
  jacobian_failed_ = false;
  h_old_ = error_old_ = 0;
  if (!derivative(t, x_, f0_) || !evaluate_jacobian(t, x_)) return false;
  // The first step (Hairer, Nørsett and Wanner I, II.4, as SciPy's select_initial_step, for an
  // error estimate of order S): from the sizes of x, ẋ and ẍ in the tolerances' units.
  scale_ = atol_.array() + rtol_ * x_.array().abs();
  const double d0 = norm(x_, scale_), d1 = norm(f0_, scale_);
  const double h0 = d0 < 1e-5 || d1 < 1e-5 ? 1e-6 : 0.01 * d0 / d1;
  b_ = x_ + h0 * f0_;
  if (!derivative(t + h0, b_, f_)) return false;
  f_ -= f0_;
  const double d2 = norm(f_, scale_) / h0;
  const double h1 =
      d1 <= 1e-15 && d2 <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / std::max(d1, d2), kExponent);
  h_ = std::min(100 * h0, h1);
  return std::isfinite(h_) && h_ > 0;
}

// M, K_y, K_v at (t, x): the kernels', or difference quotients of the accelerations
// (K_y = −M ∂ÿ/∂y, K_v = −M ∂ÿ/∂v), steps √ε · max(|x_j|, atol_j / rtol).
template <int S>
bool RadauIIA<S>::evaluate_jacobian(double t, const VectorXd& x) {
  ++stats_.jacobians;
  current_jacobian_ = true;
  factored_ = false;
  if (system_.has_jacobian()) {
    ++stats_.evaluations;
    if (!system_.jacobian(t, x.data(), x.data() + n_, MJ_, Ky_, Kv_)) return false;
  } else {
    VectorXd& xs = x_shifted_;
    VectorXd& a0 = a0_;
    xs = x;
    ++stats_.evaluations;
    if (!system_.jacobian_mass(t, x.data(), x.data() + n_, MJ_, a0)) return false;
    for (Index j = 0; j < 2 * n_; ++j) {
      const double delta = std::sqrt(kEpsilon) * std::max(std::abs(x[j]), atol_[j] / rtol_);
      xs[j] = x[j] + delta;
      ++stats_.evaluations;
      if (!system_.accelerations(t, xs.data(), xs.data() + n_, a_)) return false;
      work_re_ = a_ - a0;
      auto column = j < n_ ? Ky_.col(j) : Kv_.col(j - n_);
      column.noalias() = MJ_ * work_re_;
      column /= -(xs[j] - x[j]);
      xs[j] = x[j];
    }
  }
  if (!(MJ_.allFinite() && Ky_.allFinite() && Kv_.allFinite())) return false;
  mass_scale(MJ_, equilibrate_);
  return true;
}

template <int S>
template <class Matrix>
void RadauIIA<S>::equilibrate(Matrix& R) const {
  for (Index j = 0; j < n_; ++j)
    for (Index i = 0; i < n_; ++i) R(i, j) *= equilibrate_[i] * equilibrate_[j];
}

// The LUs of the Schur complements σ²M + σK_v + K_y for σ = γ/h and each μ_k/h, equilibrated as
// M is; false when one is singular to working precision.

template <int S>
bool RadauIIA<S>::factor(double h) {
  ++stats_.factorizations;
  auto pivots_ok = [this](const auto& lu) {
    const auto d = lu.matrixLU().diagonal().cwiseAbs();
    const double largest = d.maxCoeff(), smallest = d.minCoeff();
    return std::isfinite(largest) && smallest > static_cast<double>(n_) * kEpsilon * largest;
  };
  sigma_real_ = gamma_ / h;
  R_ = sigma_real_ * sigma_real_ * MJ_ + sigma_real_ * Kv_ + Ky_;
  equilibrate(R_);
  lu_real_.compute(R_);
  factored_ = pivots_ok(lu_real_);
  for (std::size_t k = 0; k < kPairs; ++k) {
    const complex sigma = sigma_complex_[k] = mu_[k] / h;
    Rc_ = (sigma * sigma) * MJ_.cast<complex>() + sigma * Kv_.cast<complex>() + Ky_.cast<complex>();
    equilibrate(Rc_);
    lu_complex_[k].compute(Rc_);
    factored_ = factored_ && pivots_ok(lu_complex_[k]);
  }
  h_factored_ = h;
  return factored_;
}

// (σI − J)(Δy, Δv) = (b_y, b_v), J = [0, I; −M⁻¹K_y, −M⁻¹K_v], for the real σ: its second row
// times M is K_y Δy + (σM + K_v) Δv = M b_v, and through Δv, (σ²M + σK_v + K_y) Δv =
// σ M b_v − K_y b_y and Δy = (b_y + Δv)/σ (which divides Δv's rounding by σ; through Δy,
// Δv = σΔy − b_y would multiply Δy's by σ).
template <int S>
void RadauIIA<S>::solve_real(const double* b, double* out) {
  Eigen::Map<const VectorXd> by(b, n_), bv(b + n_, n_);
  Eigen::Map<VectorXd> dy(out, n_), dv(out + n_, n_);
  VectorXd& rhs = work_re_;
  rhs.noalias() = sigma_real_ * (MJ_ * bv);
  rhs.noalias() -= Ky_ * by;
  rhs.array() *= equilibrate_.array();
  dv = lu_real_.solve(rhs);
  dv.array() *= equilibrate_.array();
  dy = (by + dv) / sigma_real_;
}

// The same for the k-th complex σ, on b_re + i b_im.
template <int S>
void RadauIIA<S>::solve_complex(std::size_t k, const double* b_re, const double* b_im, double* out_re, double* out_im) {
  Eigen::Map<const VectorXd> yr(b_re, n_), vr(b_re + n_, n_), yi(b_im, n_), vi(b_im + n_, n_);
  const complex sigma = sigma_complex_[k];
  const double sr = sigma.real(), si = sigma.imag();
  work_re_.noalias() = MJ_ * vr;
  work_im_.noalias() = MJ_ * vi;
  bc_.real() = sr * work_re_ - si * work_im_;
  bc_.imag() = sr * work_im_ + si * work_re_;
  work_re_.noalias() = Ky_ * yr;
  work_im_.noalias() = Ky_ * yi;
  bc_.real() -= work_re_;
  bc_.imag() -= work_im_;
  bc_.array() *= equilibrate_.array().cast<complex>();
  yc_ = lu_complex_[k].solve(bc_);
  yc_.array() *= equilibrate_.array().cast<complex>();
  Eigen::Map<VectorXd>(out_re + n_, n_) = yc_.real();
  Eigen::Map<VectorXd>(out_im + n_, n_) = yc_.imag();
  bc_.real() = yr + yc_.real();
  bc_.imag() = yi + yc_.imag();
  bc_ /= sigma;
  Eigen::Map<VectorXd>(out_re, n_) = bc_.real();
  Eigen::Map<VectorXd>(out_im, n_) = bc_.imag();
}

// The stage residuals G_i = Ż_i − f(X_i), Ż = h⁻¹ Z A⁻ᵀ, of the stage increments Z_.
//
// The explicit form, ÿ = −M(Y_i)⁻¹ r at each stage, rather than M(Y_i) Ż_i + r: the Newton
// matrix holds one M for all the stages, and where M varies along the step (by 1e-5 of itself
// in the middle ear at 1 Pa), the implicit form's residual no longer matches it. A rotation
// that barely moves, held to its own small tolerance, then made Newton's iteration converge
// slowly (two to three iterations more per step, and a Jacobian at most steps).
template <int S>
bool RadauIIA<S>::residuals(double h) {
  G_.noalias() = Z_ * (A_invT_ / h);  // Ż
  for (int i = 0; i < S; ++i) {
    b_ = x_ + Z_.col(i);
    if (!derivative(t_ + c_[i] * h, b_, f_)) return false;
    G_.col(i) -= f_;
  }
  return true;
}

// The simplified Newton iteration on the stage increments Z_ (from its initial value), in the
// coordinates W = Z T⁻ᵀ (RADAU5's convergence test: the rate θ of the last iterations, and a
// first iteration accepted when the last step's rate says it has converged). False when it
// diverges, is too slow, or an evaluation fails.
template <int S>
bool RadauIIA<S>::newton(double h, int& iterations, double& theta) {
  W_.noalias() = Z_ * T_invT_;
  double norm_old = 0, ratio_old = 0;
  theta = kKeepJacobian;
  faccon_ = std::pow(std::max(faccon_, kEpsilon), 0.8);
  for (int k = 1; k <= kNewtonIterations; ++k) {
    iterations = k;
    if (!residuals(h)) return false;
    stage_.noalias() = G_ * (-T_invT_);
    solve_real(stage_.col(0).data(), dW_.col(0).data());
    for (std::size_t p = 0; p < kPairs; ++p) {
      const Index re = static_cast<Index>(1 + 2 * p), im = re + 1;
      solve_complex(p, stage_.col(re).data(), stage_.col(im).data(), dW_.col(re).data(), dW_.col(im).data());
    }
    double sum = 0;
    for (int i = 0; i < S; ++i) sum += (dW_.col(i).array() / scale_.array()).square().sum();
    const double dW_norm = std::sqrt(sum / static_cast<double>(S * 2 * n_));
    if (!std::isfinite(dW_norm)) return false;
    if (k > 1) {
      const double ratio = dW_norm / norm_old;
      theta = k == 2 ? ratio : std::sqrt(ratio * ratio_old);
      ratio_old = ratio;
      const bool slow = theta >= 0.99 || (theta / (1 - theta)) * dW_norm *
                                                 std::pow(theta, kNewtonIterations - 1 - k) >= newton_tol_;
      if (slow && current_jacobian_ && dW_norm <= kStalled) {  // at the rounding in f
        if (ratio < 1) {  // the correction still helps; one that grows is not taken
          W_ += dW_;
          Z_.noalias() = W_ * T_T_;
        }
        theta = kKeepJacobian;  // no rate to judge the Jacobian by (accept())
        return true;
      }
      if (slow) return false;
      faccon_ = theta / (1 - theta);
    }
    norm_old = std::max(dW_norm, kEpsilon);
    W_ += dW_;
    Z_.noalias() = W_ * T_T_;
    if (faccon_ * dW_norm <= newton_tol_) return true;
  }
  return false;
}

// The embedded error estimate, filtered by the real system: e = (σ_r I − J)⁻¹ (f(x₀) + Z E/h),
// and again from f(x₀ + e) where the first one fails after a rejected step (Hairer and Wanner
// IV.8, (8.19)–(8.20)). Its RMS norm in the tolerances.
template <int S>
double RadauIIA<S>::error_norm(double h, const VectorXd& x_new, bool again) {
  ze_.noalias() = Z_ * (E_ / h);
  b_ = f0_ + ze_;
  solve_real(b_.data(), e_.data());
  f_ = atol_.array() + rtol_ * x_.array().abs().max(x_new.array().abs());  // the scale
  double error = norm(e_, f_);
  if (again && error > 1) {
    b_ = x_ + e_;
    if (!derivative(t_, b_, e_)) return std::numeric_limits<double>::infinity();
    b_ = e_ + ze_;
    solve_real(b_.data(), e_.data());
    error = norm(e_, f_);
  }
  return error;
}
// The stage increments of a step of size h from (t_, x_), by Newton's method from the last
// step's polynomial (or zero), with the Jacobian evaluated again where an old one fails.
template <int S>
bool RadauIIA<S>::try_step(double h, int& iterations, double& theta) {
  for (;;) {
    if (dense_) {
      for (int i = 0; i < S; ++i) {
        Z_.col(i) = x_old_ - x_;
        Z_.col(i).noalias() += Q_ * powers((t_ + c_[i] * h - t_old_) / h_last_);
      }
    } else {
      Z_.setZero();
    }
    if ((factored_ && h == h_factored_) || factor(h))
      if (newton(h, iterations, theta)) return true;
    if (current_jacobian_) return false;
    if (!evaluate_jacobian(t_, x_)) {
      jacobian_failed_ = true;
      return false;
    }
  }
}

template <int S>
typename RadauIIA<S>::Status RadauIIA<S>::step(double t_stop) {
  bool rejected = false;
  for (;;) {
    const double min_step = 10 * (std::nextafter(t_, std::numeric_limits<double>::infinity()) - t_);
    if (!(h_ >= min_step)) return Status::step_too_small;
    const bool last = t_stop - t_ <= 1.1 * h_;
    const double h = last ? t_stop - t_ : h_;
    h_unclamped_ = h_;
    const double t_new = last ? t_stop : t_ + h;
    scale_ = atol_.array() + rtol_ * x_.array().abs();
    int iterations = 0;
    double theta = 0;
    if (!try_step(h, iterations, theta)) {
      if (jacobian_failed_) return Status::failed;
      ++stats_.newton_failures;
      h_ = 0.5 * h;
      rejected = true;
      continue;
    }
    x_new_ = x_ + Z_.col(S - 1);
    const double error = error_norm(h, x_new_, rejected || first_);
    const double safety = kSafety * (2 * kNewtonIterations + 1) / (2 * kNewtonIterations + iterations);
    if (!std::isfinite(error)) {  // no factor to predict from
      ++stats_.rejected;
      rejected = true;
      h_ = 0.5 * h;
      continue;
    }
    if (!(error <= 1)) {
      ++stats_.rejected;
      rejected = true;
      h_ = h * std::max(kMinShrink, safety * predicted_factor(h, h_old_, error, error_old_, kExponent));
      continue;
    }
    if (!derivative(t_new, x_new_, b_)) {  // the next step's f(x₀): a step too far
      ++stats_.rejected;
      rejected = true;
      h_ = 0.5 * h;
      continue;
    }
    return accept(t_new, h, error, safety, iterations, theta) ? Status::ok : Status::failed;
  }
}

// Moves to the step's end (its f in b_), with the next step's size, and
// the Jacobian there when the Newton iteration converged slowly.
template <int S>
bool RadauIIA<S>::accept(double t_new, double h, double error, double safety, int iterations, double theta) {
  ++stats_.steps;
  x_old_.swap(x_);
  x_.swap(x_new_);
  t_old_ = t_;
  t_ = t_new;
  h_last_ = h;
  Q_.noalias() = Z_ * P_;
  dense_ = true;
  f0_ = b_;
  double factor = std::min(kMaxGrowth, safety * predicted_factor(h, h_old_, error, error_old_, kExponent));
  h_old_ = h;
  error_old_ = error;
  // A Jacobian again where the iteration converged slowly (RADAU5, SciPy), unless it converged
  // as slowly with a fresh one: then the rate is that of the rounding in f (the middle ear at
  // tight tolerances, whose smallest motions' tolerances are below its kernels' rounding), which
  // no Jacobian improves; more than four times that rate is the Jacobian's again.
  if (current_jacobian_ && iterations > 1) fresh_theta_ = theta;
  const bool recompute = iterations > 2 && theta > std::max(kKeepJacobian, 4 * fresh_theta_);
  // The same h, and so the same LUs, unless the controller asks for 1.2 times it or more (as
  // SciPy's Radau; RADAU5 keeps it between 1 and 1.2 only): a smaller step than the controller's
  // is still accepted by the next error test, and the middle ear then factors half as often.
  if (!recompute && factor < 1.2) factor = 1;
  h_ = h * factor;
  // A step cut short to land on a stop says nothing against the step before it (RADAU5's HOPT).
  if (h < h_unclamped_) h_ = std::max(h_, h_unclamped_);
  first_ = false;
  if (!recompute) {
    current_jacobian_ = false;
    return true;
  }
  jacobian_failed_ = !evaluate_jacobian(t_, x_);
  return !jacobian_failed_;
}

// (θ, θ², …, θ^s), for the collocation polynomial.
template <int S>
typename RadauIIA<S>::Vector RadauIIA<S>::powers(double theta) {
  Vector p;
  double q = 1;
  for (int k = 0; k < S; ++k) p[k] = q *= theta;
  return p;
}

template <int S>
void RadauIIA<S>::interpolate(double t, double* x) const {
  Eigen::Map<VectorXd> out(x, 2 * n_);
  out = x_old_;
  out.noalias() += Q_ * powers((t - t_old_) / h_last_);
}

std::unique_ptr<Radau> Radau::make(SecondOrderSystem& system, Index n, double rtol, const VectorXd& atol, int stages) {
  if (stages == 3) return std::make_unique<RadauIIA<3>>(system, n, rtol, atol);
  if (stages == 5) return std::make_unique<RadauIIA<5>>(system, n, rtol, atol);
  throw std::invalid_argument("Radau::make: 3 or 5 stages, not " + std::to_string(stages));
}

}  // namespace mbsgen::detail
