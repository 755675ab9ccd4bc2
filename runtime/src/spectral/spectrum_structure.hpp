// What the zero pattern of a model's matrices proves about its spectrum, for every value of the
// nonzero entries (the generator writes structurally zero entries as exact 0.0): eigenvalues that
// are exactly zero, and spectra symmetric about the imaginary axis. Private to spectral/.
#pragma once

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

namespace mbsgen::detail {

/// Structural rank of a square A: the largest number of nonzero entries no two in one row or
/// column (maximum bipartite matching by augmenting paths, O(m·nnz)). rank A ≤ this for every
/// value of the nonzero entries, so m minus it bounds dim null(A) from below.
Eigen::Index structural_rank(const Eigen::MatrixXd& A);

/// Whether a signature R = diag(±1) makes R X R = parity·X for each (X, parity) given, on the
/// zero patterns: r_i r_j = parity wherever X(i, j) ≠ 0 (a two-colouring with parities). For the
/// pencil λE − A with {(E, +1), (A, −1)}, R(λE − A)R = λE + A; for λ²M + λQ + K with
/// {(M, +1), (Q, −1), (K, +1)}, R P(λ) R = P(−λ). Either way det P(λ) = 0 iff det P(−λ) = 0: the
/// spectrum is symmetric about the imaginary axis for every value of the data (an undamped
/// system, positions even and speeds odd under time reversal: a rolling disk's lean, a sleeping
/// top's nutation and precession, a gyroscopic rotor's whirl).
bool reversible_sign_pattern(const std::vector<std::pair<const Eigen::MatrixXd*, int>>& pattern);

/// With a spectrum symmetric about the imaginary axis by structure: a finite eigenvalue whose
/// error disk (radius error_bound) crosses the axis but meets no other eigenvalue's disk (nor the
/// mirror of one, nor 0; its conjugate partner excepted) holds exactly one eigenvalue of the data,
/// which must equal its own mirror −λ̄: it is on the axis. Its real part is set to 0 exactly, and
/// its damping ratio to 0. Returns how many were.
Eigen::Index snap_to_axis(std::vector<Mode>& modes);

/// Exact scaling by powers of two for data near the ends of the range of double (entries beyond
/// 2^±450 ≈ 1e±135, where norms that square entries overflow or underflow): λ = γμ with
/// γ = 2^k balancing the highest and lowest coefficients, and every coefficient times 2^e so that
/// the largest entry is about 1. Coefficient j (of λ^j) is multiplied by 2^(j·k + e): exact unless
/// an entry becomes subnormal. active is false for data inside the band (nothing changes there).
struct RangeScaling {
  bool active = false;
  int k = 0, e = 0;
  double gamma() const;
  /// Coefficient j of the scaled problem.
  Eigen::MatrixXd scaled(const Eigen::MatrixXd& X, int j) const;
};
/// From the largest absolute entries of the coefficients of λ⁰, λ¹, (λ²) (zero: absent).
RangeScaling range_scaling(const std::vector<double>& largest);
/// Undoes the λ-scaling on modes computed from the scaled problem: λ, α, the frequencies and the
/// error bound times γ (the relative quantities, vectors and backward errors are unchanged).
void unscale_modes(std::vector<Mode>& modes, double gamma);

}  // namespace mbsgen::detail
