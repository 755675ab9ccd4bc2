// The constants of Radau IIA with s stages (s odd: one real eigenvalue of A⁻¹ and (s − 1)/2
// complex pairs), as the integrator of radau.hpp uses them: order 2s − 1 at the steps, stage
// order s, L-stable (Hairer and Wanner, Solving Ordinary Differential Equations II, 2nd ed.,
// Springer 1996, Sect. IV.5 and IV.8; Hairer and Wanner, Stiff differential equations solved by
// Radau methods, J. Comput. Appl. Math. 111 (1999) 93–111, for s = 5 and 7).
//
// s = 3 takes RADAU5's published constants; any s is computed from the nodes (compute()), which
// the tests check against those published ones.
#pragma once

#include <Eigen/Core>

#include <complex>
#include <vector>

namespace mbsgen::detail {

struct RadauTableau {
  int stages = 0;
  Eigen::VectorXd c;                     // the nodes, c_s = 1
  Eigen::MatrixXd A_inv;                 // the inverse of the Butcher matrix A
  // T⁻¹ A⁻¹ T = diag(γ, [α_k, β_k; −β_k, α_k]): the real system's σ = γ/h, and the complex
  // ones' σ = μ_k/h, μ_k = α_k − iβ_k, on the columns (1 + 2k, 2 + 2k) of W = Z T⁻ᵀ as real and
  // imaginary parts.
  Eigen::MatrixXd T, T_inv;
  double gamma = 0;
  std::vector<std::complex<double>> mu;
  // The embedded error estimate (Hairer and Wanner IV.8, (8.19)–(8.20), of order s):
  // e = (σ_r I − J)⁻¹ (f(x₀) + Z E / h).
  Eigen::VectorXd E;
  // The collocation polynomial: x(t₀ + θh) = x₀ + (Z P)(θ, θ², …, θ^s)ᵀ.
  Eigen::MatrixXd P;

  /// RADAU5's constants for s = 3; computed ones for other odd s (cached).
  static const RadauTableau& of(int stages);
  /// The constants of s stages from the nodes (the roots of P_s − P_{s−1} in 2c − 1, Legendre's
  /// polynomials), in long double where they are solutions of linear systems.
  static RadauTableau compute(int stages);
};

}  // namespace mbsgen::detail
