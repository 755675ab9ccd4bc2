// Test models for the runtime suites: the hard cases of issue 3 §6, built from their published
// definitions (closed forms where they exist). All units SI.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "mbsgen/runtime/spectral/frequency_response.hpp"

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

/// Skew matrix [r]× with [r]× v = r × v.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& r) {
  Eigen::Matrix3d S;
  S << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
  return S;
}

/// An ossicular-chain-like model of 18 coordinates (issue 14 §2): three rigid bodies (malleus,
/// incus, stapes), each with displacement u and small rotation θ (coordinates 6i..6i+5: u_x, u_y,
/// u_z, θ_x, θ_y, θ_z), masses 1e-6..3e-5 kg, principal inertias m·(0.3..0.6 mm)², point masses at
/// the umbo (on body 0) and the footplate (on body 2), and six 6-component bushings (three to
/// the ground, two joints between the bodies, one more to the ground) at points offset by
/// fractions of a millimetre, translational stiffness 1e2..1e4 N/m, rotational k·(0.5 mm)²,
/// damping ratios of about 0.1. The velocity of a point r of body i is S(r) q_i with
/// S(r) = [E, −[r]×]; a bushing between points r_a of body a and r_b of body b adds Gᵀ diag(k) G
/// (and the same with c) with G = [[S(r_a), −S(r_b)], [0 E, 0 −E]] on the coordinates of a, b.
/// Many entries of M, Q, K are exactly zero (diagonal principal inertias, offsets with zero
/// components, bodies that share no bushing).
inline Qep ossicle_like() {
  const int n = 18;
  Qep p{Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n)};
  auto S = [](const Eigen::Vector3d& r) {
    Eigen::Matrix<double, 3, 6> s;
    s << Eigen::Matrix3d::Identity(), -skew(r);
    return s;
  };
  const double mass[3] = {2.3e-5, 2.7e-5, 3.0e-6};
  const double arm[3] = {6e-4, 5e-4, 3e-4};
  for (int i = 0; i < 3; ++i) {
    p.M.block(6 * i, 6 * i, 3, 3) = mass[i] * Eigen::Matrix3d::Identity();
    const double J = mass[i] * arm[i] * arm[i];
    p.M.block(6 * i + 3, 6 * i + 3, 3, 3) = Eigen::Vector3d(J, 0.7 * J, 0.4 * J).asDiagonal();
  }
  auto point_mass = [&](int body, double m, const Eigen::Vector3d& r) {
    const Eigen::Matrix<double, 3, 6> s = S(r);
    p.M.block(6 * body, 6 * body, 6, 6) += m * s.transpose() * s;
  };
  point_mass(0, 1.0e-6, Eigen::Vector3d(0, -4e-3, 0));   // umbo
  point_mass(2, 1.5e-6, Eigen::Vector3d(0, 0, -1e-3));   // footplate
  // body b < 0: ground.
  auto bushing = [&](int a, const Eigen::Vector3d& ra, int b, const Eigen::Vector3d& rb,
                     const Eigen::Vector3d& kt, double cscale) {
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(6, n);
    G.block(0, 6 * a, 3, 6) = S(ra);
    G.block(3, 6 * a + 3, 3, 3).setIdentity();
    if (b >= 0) {
      G.block(0, 6 * b, 3, 6) = -S(rb);
      G.block(3, 6 * b + 3, 3, 3) = -Eigen::Matrix3d::Identity();
    }
    const double l2 = 0.25e-6;  // (0.5 mm)²
    Eigen::VectorXd k(6), c(6);
    k << kt, kt * l2;
    c = cscale * k;
    p.K += G.transpose() * k.asDiagonal() * G;
    p.Q += G.transpose() * c.asDiagonal() * G;
  };
  const double cs = 2e-6;  // c = 2e-6 s · k: ζ ≈ ½ω·2e-6 ≈ 0.1 near 10 kHz
  bushing(0, Eigen::Vector3d(0, -3e-3, 0), -1, Eigen::Vector3d::Zero(), Eigen::Vector3d(2e3, 4e2, 8e2), cs);
  bushing(0, Eigen::Vector3d(1e-3, 0, 0), -1, Eigen::Vector3d::Zero(), Eigen::Vector3d(1e2, 3e2, 1e2), cs);
  bushing(0, Eigen::Vector3d(0, 1e-3, 5e-4), 1, Eigen::Vector3d(0, -1e-3, 0),
          Eigen::Vector3d(1e4, 5e3, 8e3), cs);
  bushing(1, Eigen::Vector3d(-1e-3, 0, 0), -1, Eigen::Vector3d::Zero(), Eigen::Vector3d(3e2, 1e2, 2e2), cs);
  bushing(1, Eigen::Vector3d(0, -2e-3, 0), 2, Eigen::Vector3d(0, 0, 5e-4),
          Eigen::Vector3d(4e3, 4e3, 1e4), cs);
  bushing(2, Eigen::Vector3d(0, 0, -1e-3), -1, Eigen::Vector3d::Zero(), Eigen::Vector3d(1e3, 1e3, 3e3), cs);
  return p;
}

/// The same matrices with every exact zero replaced by rounding-level noise, as kernels that
/// evaluate identically-zero expressions produce (issue 14 §1: 6.6e-24 in a zero block of M,
/// ±1e-16-level residue in K): entry (i, j) becomes ±(0.5..1)·1e-17·√(|A_ii A_jj|), and every
/// seventh such entry a tiny absolute 6.6e-24 instead. Deterministic (Lcg).
inline Qep with_noise_in_zeros(Qep p, std::uint64_t seed = 3) {
  Lcg r(seed);
  int count = 0;
  for (Eigen::MatrixXd* A : {&p.M, &p.Q, &p.K}) {
    const Eigen::MatrixXd D = *A;
    for (Eigen::Index j = 0; j < A->cols(); ++j)
      for (Eigen::Index i = 0; i < A->rows(); ++i) {
        if (D(i, j) != 0.0) continue;
        const double sign = r() < 0.5 ? -1.0 : 1.0;
        const double mag = 0.5 + 0.5 * r();
        (*A)(i, j) = (++count % 7 == 0) ? 6.6e-24
                                        : sign * mag * 1e-17 * std::sqrt(std::abs(D(i, i) * D(j, j)));
      }
  }
  return p;
}

/// count angular frequencies [rad/s] log-spaced from f0_hz to f1_hz (both included).
inline Eigen::VectorXd log_omegas(double f0_hz, double f1_hz, int count) {
  constexpr double kTwoPi = 6.283185307179586;
  Eigen::VectorXd w(count);
  for (int k = 0; k < count; ++k) w[k] = kTwoPi * f0_hz * std::pow(f1_hz / f0_hz, k / double(count - 1));
  return w;
}

/// Frequency-response options with the given method, the rest default.
inline mbsgen::FrfOptions with(mbsgen::FrfMethod method) {
  mbsgen::FrfOptions o;
  o.method = method;
  return o;
}

}  // namespace testmodels
