// Radau IIA's constants (radau_tableau.hpp).
#include "time/radau_tableau.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

namespace mbsgen::detail {

namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using Real = long double;
using MatrixL = Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic>;
using VectorL = Eigen::Matrix<Real, Eigen::Dynamic, 1>;

// q(ξ) = P_s(ξ) − P_{s−1}(ξ) and q'(ξ), by Legendre's recurrence.
void radau_polynomial(int s, Real xi, Real& q, Real& dq) {
  Real p_old = 1, p = xi, d_old = 0, d = 1;  // P_0, P_1 and their derivatives
  for (int k = 1; k < s; ++k) {
    const Real p_new = ((2 * k + 1) * xi * p - k * p_old) / (k + 1);
    const Real d_new = d_old + (2 * k + 1) * p;
    p_old = p, p = p_new, d_old = d, d = d_new;
  }
  q = p - p_old;
  dq = d - d_old;
}

// The nodes, ascending: the roots of q in ξ = 2c − 1, by Newton's method with the roots found
// deflated (Maehly), from cos(2πk/(2s − 1)), near Radau's points; ξ = 1 is a root. Throws where
// an iteration does not converge or the roots are not distinct inside (−1, 1].
VectorL nodes(int s) {
  std::vector<Real> roots{1.0L};
  const Real pi = std::acos(-1.0L);
  for (int k = 1; k < s; ++k) {
    Real xi = std::cos(2 * pi * k / (2 * s - 1));
    bool converged = false;
    for (int iteration = 0; iteration < 100 && !converged; ++iteration) {
      Real q, dq;
      radau_polynomial(s, xi, q, dq);
      Real deflation = 0;
      for (const Real r : roots) deflation += 1 / (xi - r);
      const Real delta = q / (dq - q * deflation);
      xi -= delta;
      converged = std::abs(delta) <= 4 * std::numeric_limits<Real>::epsilon();
    }
    if (!converged) throw std::logic_error("RadauTableau::compute: a node of " + std::to_string(s) + " stages did not converge");
    roots.push_back(xi);
  }
  std::sort(roots.begin(), roots.end());
  for (std::size_t i = 0; i < roots.size(); ++i)
    if (!(roots[i] > -1) || (i > 0 && !(roots[i] > roots[i - 1])))
      throw std::logic_error("RadauTableau::compute: the nodes of " + std::to_string(s) + " stages are not distinct in (0, 1]");
  VectorL c(s);
  for (int i = 0; i < s; ++i) c[i] = (roots[static_cast<std::size_t>(i)] + 1) / 2;
  c[s - 1] = 1;
  return c;
}

}  // namespace

RadauTableau RadauTableau::compute(int s) {
  if (s < 1 || s % 2 == 0) throw std::invalid_argument("RadauTableau::compute: the stages must be odd, not " + std::to_string(s));
  RadauTableau t;
  t.stages = s;
  const VectorL c = nodes(s);
  // A = C V⁻¹ (collocation: A_ij = ∫₀^{c_i} ℓ_j), V_ik = c_i^k, C_ik = c_i^{k+1}/(k + 1), k < s.
  MatrixL V(s, s), C(s, s), W(s, s);  // W_ik = c_i^{k+1}, for the dense output
  for (int i = 0; i < s; ++i)
    for (int k = 0; k < s; ++k) {
      V(i, k) = std::pow(c[i], static_cast<Real>(k));
      C(i, k) = std::pow(c[i], static_cast<Real>(k + 1)) / (k + 1);
      W(i, k) = std::pow(c[i], static_cast<Real>(k + 1));
    }
  const MatrixL A = V.transpose().fullPivLu().solve(C.transpose()).transpose();
  const MatrixL A_inv = A.fullPivLu().inverse();
  t.c = c.cast<double>();
  t.A_inv = A_inv.cast<double>();
  // Z = Q Wᵀ at the nodes: P = W⁻ᵀ.
  t.P = W.transpose().fullPivLu().inverse().cast<double>();

  // A⁻¹'s real eigenvector first, then each complex pair's real and imaginary parts.
  Eigen::EigenSolver<MatrixXd> eigen(t.A_inv);
  if (eigen.info() != Eigen::Success) throw std::logic_error("RadauTableau::compute: A⁻¹'s eigenvalues did not converge");
  const Eigen::VectorXcd lambda = eigen.eigenvalues();
  const Eigen::MatrixXcd vectors = eigen.eigenvectors();
  t.T.resize(s, s);
  Index column = 1;
  int real_count = 0;
  for (Index k = 0; k < s; ++k) {
    if (std::abs(lambda[k].imag()) <= 1e-10 * std::abs(lambda[k])) {
      t.T.col(0) = vectors.col(k).real();
      ++real_count;
    } else if (lambda[k].imag() > 0) {
      t.T.col(column) = vectors.col(k).real();
      t.T.col(column + 1) = vectors.col(k).imag();
      column += 2;
    }
  }
  if (real_count != 1 || column != s) throw std::logic_error("RadauTableau::compute: A⁻¹'s eigenvalues are not one real and complex pairs");
  t.T_inv = t.T.inverse();
  const MatrixXd Lambda = t.T_inv * t.A_inv * t.T;
  t.gamma = Lambda(0, 0);
  for (Index k = 1; k < s; k += 2) t.mu.emplace_back(Lambda(k, k), -Lambda(k, k + 1));

  // The embedded method ŷ = y₀ + h (γ₀ f(x₀) + Σ b̂_i f(Y_i)), γ₀ = 1/γ, of order s:
  // γ₀ [k = 1] + Σ b̂_i c_i^{k−1} = 1/k, k = 1 … s. ŷ − y = γ₀ h (f(x₀) + Σ_j E_j Z_j / h) with
  // E = γ A⁻ᵀ (b̂ − b), since h f(Y_i) = Σ_j (A⁻¹)_ij Z_j.
  const Real gamma = static_cast<Real>(t.gamma);
  VectorL rhs(s);
  for (int k = 0; k < s; ++k) rhs[k] = 1.0L / (k + 1) - (k == 0 ? 1 / gamma : 0);
  const VectorL b_hat = V.transpose().fullPivLu().solve(rhs);
  const VectorL b = A.row(s - 1).transpose();
  t.E = (gamma * (A_inv.transpose() * (b_hat - b))).cast<double>();
  return t;
}

const RadauTableau& RadauTableau::of(int s) {
  static std::mutex mutex;
  static std::map<int, RadauTableau> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  auto found = cache.find(s);
  if (found != cache.end()) return found->second;
  RadauTableau t;
  if (s == 3) {  // RADAU5's (Hairer and Wanner)
    const double r6 = std::sqrt(6.0);
    t.stages = 3;
    t.c = Eigen::Vector3d((4 - r6) / 10, (4 + r6) / 10, 1);
    Eigen::Matrix3d A;
    A << (88 - 7 * r6) / 360, (296 - 169 * r6) / 1800, (-2 + 3 * r6) / 225,  //
        (296 + 169 * r6) / 1800, (88 + 7 * r6) / 360, (-2 - 3 * r6) / 225,   //
        (16 - r6) / 36, (16 + r6) / 36, 1.0 / 9;
    t.A_inv = A.inverse();
    Eigen::Matrix3d T;
    T << 0.09443876248897524, -0.14125529502095421, 0.03002919410514742,  //
        0.25021312296533332, 0.20412935229379994, -0.38294211275726192,    //
        1, 1, 0;
    t.T = T;
    t.T_inv = T.inverse();
    t.gamma = 3 + std::cbrt(9.0) - std::cbrt(3.0);
    t.mu = {std::complex<double>(3 + 0.5 * (std::cbrt(3.0) - std::cbrt(9.0)),
                                 -0.5 * (std::pow(3.0, 5.0 / 6) + std::pow(3.0, 7.0 / 6)))};
    t.E = Eigen::Vector3d((-13 - 7 * r6) / 3, (-13 + 7 * r6) / 3, -1.0 / 3);
    Eigen::Matrix3d P;
    P << 13.0 / 3 + 7 * r6 / 3, -23.0 / 3 - 22 * r6 / 3, 10.0 / 3 + 5 * r6,  //
        13.0 / 3 - 7 * r6 / 3, -23.0 / 3 + 22 * r6 / 3, 10.0 / 3 - 5 * r6,   //
        1.0 / 3, -8.0 / 3, 10.0 / 3;
    t.P = P;
  } else {
    t = compute(s);
  }
  return cache.emplace(s, std::move(t)).first->second;
}

}  // namespace mbsgen::detail
