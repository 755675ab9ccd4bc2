// Test models for the runtime suites: the hard cases of issue 3 §6, built from their published
// definitions (closed forms where they exist). All units SI.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace testmodels {

/// Unit roundoff u = 2⁻⁵³.
inline constexpr double u = std::numeric_limits<double>::epsilon() / 2;

struct Qep {
  Eigen::MatrixXd M, Q, K;
};

/// Chain of n masses; spring k[i] (i = 0..n) connects mass i−1 and i, with k[0] to the left
/// ground and k[n] to the right ground (0 = no spring); dampers c likewise (empty = none).
inline Qep chain(const std::vector<double>& m, const std::vector<double>& k,
                 const std::vector<double>& c = {}) {
  const Eigen::Index n = static_cast<Eigen::Index>(m.size());
  Qep p{Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n)};
  auto assemble = [n](Eigen::MatrixXd& A, const std::vector<double>& e) {
    for (Eigen::Index i = 0; i <= n; ++i) {
      const double v = e[static_cast<std::size_t>(i)];
      if (v == 0.0) continue;
      if (i > 0) A(i - 1, i - 1) += v;
      if (i < n) A(i, i) += v;
      if (i > 0 && i < n) {
        A(i - 1, i) -= v;
        A(i, i - 1) -= v;
      }
    }
  };
  for (Eigen::Index i = 0; i < n; ++i) p.M(i, i) = m[static_cast<std::size_t>(i)];
  assemble(p.K, k);
  if (!c.empty()) assemble(p.Q, c);
  return p;
}

/// Ear-scaled chain (issue 3): n masses log-spaced 1e-6..3e-5 kg, n+1 springs log-spaced
/// 1e2..1e4 N/m (both ends grounded), dampers giving damping ratios of order 0.01-0.3.
inline Qep ear_chain(int n = 8, bool damped = true) {
  std::vector<double> m, k, c;
  for (int i = 0; i < n; ++i) m.push_back(1e-6 * std::pow(30.0, i / double(n - 1)));
  for (int i = 0; i <= n; ++i) k.push_back(1e2 * std::pow(100.0, i / double(n)));
  for (int i = 0; i <= n; ++i) c.push_back(damped ? 2e-3 * std::pow(0.1, i / double(n)) : 0.0);
  return chain(m, k, damped ? c : std::vector<double>{});
}

/// Small deterministic generator in [0,1) (64-bit LCG, Knuth's MMIX constants) for the synthetic
/// NLEVP-structured problems, so the tests do not depend on a library's random engine.
struct Lcg {
  std::uint64_t s;
  explicit Lcg(std::uint64_t seed) : s(seed) {}
  double operator()() {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(s >> 11) * 0x1.0p-53;
  }
  Eigen::MatrixXd matrix(Eigen::Index r, Eigen::Index c) {
    Eigen::MatrixXd A(r, c);
    for (Eigen::Index j = 0; j < c; ++j)
      for (Eigen::Index i = 0; i < r; ++i) A(i, j) = (*this)();
    return A;
  }
};

/// NLEVP spring_dashpot (Betcke et al. 2013; Gotts 2005): a spring in parallel with n/2−1 Maxwell
/// elements; M = blkdiag(ρM₁, 0) (rank 2), D = kron(diag(0, η), K₂) (rank deficient),
/// K = kron(diag(Σe, e), K₂) + arrowhead coupling kron(η, K₂). The 2×2 K₂ = RRᵀ, M₁ = SSᵀ and e, η
/// come from our Lcg instead of MATLAB's rand (the structure is the published definition).
inline Qep spring_dashpot(int n = 10, double rho = 7850.0) {
  const int m = n / 2 - 1;
  n = 2 * (m + 1);
  Lcg r(7);
  Eigen::MatrixXd K2 = r.matrix(2, 2);
  K2 = (K2 * K2.transpose()).eval();
  Eigen::MatrixXd M1 = r.matrix(2, 2);
  M1 = (M1 * M1.transpose()).eval();
  Eigen::VectorXd e(m), eta(m);
  for (int i = 0; i < m; ++i) e[i] = r();
  for (int i = 0; i < m; ++i) eta[i] = r();
  Qep p{Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n)};
  p.M.topLeftCorner(2, 2) = rho * M1;
  p.K.topLeftCorner(2, 2) = e.sum() * K2;
  for (int i = 0; i < m; ++i) {
    p.Q.block(2 + 2 * i, 2 + 2 * i, 2, 2) = eta[i] * K2;
    p.K.block(2 + 2 * i, 2 + 2 * i, 2, 2) = e[i] * K2;
    p.K.block(0, 2 + 2 * i, 2, 2) = eta[i] * K2;
    p.K.block(2 + 2 * i, 0, 2, 2) = eta[i] * K2.transpose();
  }
  return p;
}

/// Structure of NLEVP cd_player (Chahlaoui & Van Dooren 2002): M = E, nonsymmetric D and K with
/// ‖D‖ ≫ √(‖M‖‖K‖) (τ ≫ 1, the case for tropical scaling). Synthetic data, n = 12.
inline Qep cd_player_like(int n = 12) {
  Lcg r(11);
  Qep p{Eigen::MatrixXd::Identity(n, n), Eigen::MatrixXd(n, n), Eigen::MatrixXd(n, n)};
  p.Q = 1e3 * (r.matrix(n, n) - 0.5 * Eigen::MatrixXd::Ones(n, n)) +
        4e3 * Eigen::MatrixXd::Identity(n, n);
  p.K = 1e2 * (r.matrix(n, n) - 0.5 * Eigen::MatrixXd::Ones(n, n)) +
        3e2 * Eigen::MatrixXd::Identity(n, n);
  return p;
}

/// Structure of NLEVP speaker_box: real symmetric, coefficient norms far apart
/// (‖M‖ ≈ 1, ‖D‖ ≈ 1e-3, ‖K‖ ≈ 1e7) and eigenvalues spread over decades. Synthetic, n = 12.
inline Qep speaker_box_like(int n = 12) {
  Lcg r(5);
  Eigen::MatrixXd A = r.matrix(n, n), B = r.matrix(n, n), C = r.matrix(n, n);
  Qep p;
  p.M = A * A.transpose() / n + 1e-2 * Eigen::MatrixXd::Identity(n, n);
  p.Q = 1e-3 * (B * B.transpose()) / n;
  Eigen::VectorXd d(n);
  for (int i = 0; i < n; ++i) d[i] = std::pow(10.0, 7.0 * i / (n - 1));
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(C);
  const Eigen::MatrixXd U = qr.householderQ();
  p.K = U * d.asDiagonal() * U.transpose();
  p.K = (0.5 * (p.K + p.K.transpose())).eval();
  return p;
}

/// Structure of NLEVP shaft (a shaft on bearings with one damper): symmetric banded K (beam-like
/// pentadiagonal), M rank deficient (every third coordinate massless, a rotational coordinate of
/// a lumped-mass model), D = a e_k e_kᵀ. n = 12.
inline Qep shaft_like(int n = 12) {
  Qep p{Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n)};
  for (int i = 0; i < n; ++i) {
    p.K(i, i) = 6.0e6;
    if (i + 1 < n) p.K(i, i + 1) = p.K(i + 1, i) = -4.0e6;
    if (i + 2 < n) p.K(i, i + 2) = p.K(i + 2, i) = 1.0e6;
    p.M(i, i) = (i % 3 == 2) ? 0.0 : 2.0 + 0.1 * i;
  }
  p.Q(n / 2, n / 2) = 50.0;
  return p;
}

/// Jeffcott-type rotor with two disks at spin Ω_s (rad/s): tilts (φx, φy) of each disk,
/// M = diag(Jt), G = Ω_s Jp skew, K = shaft stiffness coupling the disks.
inline Qep rotor(double spin) {
  const double Jt1 = 0.02, Jp1 = 0.035, Jt2 = 0.01, Jp2 = 0.015, k1 = 4e4, k12 = 1e4;
  Qep p{Eigen::MatrixXd::Zero(4, 4), Eigen::MatrixXd::Zero(4, 4), Eigen::MatrixXd::Zero(4, 4)};
  p.M.diagonal() << Jt1, Jt1, Jt2, Jt2;
  p.Q(0, 1) = spin * Jp1;
  p.Q(1, 0) = -spin * Jp1;
  p.Q(2, 3) = spin * Jp2;
  p.Q(3, 2) = -spin * Jp2;
  for (int a = 0; a < 2; ++a) {
    p.K(a, a) = k1 + k12;
    p.K(a + 2, a + 2) = k12;
    p.K(a, a + 2) = p.K(a + 2, a) = -k12;
  }
  return p;
}

/// Ziegler's column (Ziegler 1952): two rigid bars (m l² = 1, k = 1, l = 1) under a follower load
/// P: M = [[3,1],[1,1]], K = [[2−P, P−1],[−1, 1]] (circulatory). det(λ²M + K) = 2λ⁴ + (7−2P)λ² + 1,
/// flutter for P > 7/2 − √2 ≈ 2.0858.
inline Qep ziegler(double P) {
  Qep p{Eigen::MatrixXd(2, 2), Eigen::MatrixXd::Zero(2, 2), Eigen::MatrixXd(2, 2)};
  p.M << 3, 1, 1, 1;
  p.K << 2 - P, P - 1, -1, 1;
  return p;
}

}  // namespace testmodels
