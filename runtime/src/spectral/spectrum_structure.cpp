// Spectral facts from zero patterns (spectrum_structure.hpp).
#include "spectral/spectrum_structure.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <functional>
#include <limits>

namespace mbsgen::detail {

using Eigen::Index;
using cd = std::complex<double>;

Eigen::Index structural_rank(const Eigen::MatrixXd& A) {
  const Index m = A.rows();
  std::vector<Index> match_of_col(static_cast<std::size_t>(m), -1);
  std::vector<char> seen;
  // Iterative DFS would do for huge m; the recursion depth is at most m (model sizes: hundreds).
  std::function<bool(Index)> augment = [&](Index i) {
    for (Index j = 0; j < m; ++j) {
      if (A(i, j) == 0.0 || seen[static_cast<std::size_t>(j)]) continue;
      seen[static_cast<std::size_t>(j)] = 1;
      const Index owner = match_of_col[static_cast<std::size_t>(j)];
      if (owner < 0 || augment(owner)) {
        match_of_col[static_cast<std::size_t>(j)] = i;
        return true;
      }
    }
    return false;
  };
  Index rank = 0;
  for (Index i = 0; i < m; ++i) {
    seen.assign(static_cast<std::size_t>(m), 0);
    if (augment(i)) ++rank;
  }
  return rank;
}

bool reversible_sign_pattern(const std::vector<std::pair<const Eigen::MatrixXd*, int>>& pattern) {
  if (pattern.empty()) return true;
  const Index m = pattern.front().first->rows();
  std::vector<int> sign(static_cast<std::size_t>(m), 0);
  for (Index root = 0; root < m; ++root) {
    if (sign[static_cast<std::size_t>(root)] != 0) continue;
    sign[static_cast<std::size_t>(root)] = 1;
    std::vector<Index> stack{root};
    while (!stack.empty()) {
      const Index i = stack.back();
      stack.pop_back();
      for (const auto& [X, parity] : pattern)
        for (Index j = 0; j < m; ++j) {
          if ((*X)(i, j) == 0.0 && (*X)(j, i) == 0.0) continue;
          const int want = parity * sign[static_cast<std::size_t>(i)];
          int& sj = sign[static_cast<std::size_t>(j)];
          if (sj == 0) {
            sj = want;
            stack.push_back(j);
          } else if (sj != want) {
            return false;  // includes a nonzero diagonal entry of an odd matrix
          }
        }
    }
  }
  return true;
}

Eigen::Index snap_to_axis(std::vector<Mode>& modes) {
  std::vector<std::size_t> on_axis;  // decided on the data as computed, then applied
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const Mode& md = modes[k];
    if (md.kind != EigenvalueKind::finite || md.zero_within_bound) continue;
    const double r = md.error_bound;
    if (!(std::abs(md.lambda.real()) <= r) || md.lambda.real() == 0.0) continue;
    if (!(std::abs(md.lambda.imag()) > r)) continue;  // its conjugate's disk, or a real eigenvalue
    // The conjugate partner (the data are real): the one mode in the lower half-plane within
    // the two bounds of λ̄. Every other mode's disk must miss λ's and λ̄'s.
    const Mode* partner = nullptr;
    int near_conj = 0;
    for (const Mode& other : modes)
      if (&other != &md && other.kind == EigenvalueKind::finite &&
          other.lambda.imag() * md.lambda.imag() < 0 &&
          std::abs(other.lambda - std::conj(md.lambda)) <= r + other.error_bound) {
        partner = &other;
        ++near_conj;
      }
    bool isolated = near_conj <= 1;
    for (const Mode& other : modes) {
      if (&other == &md || &other == partner || other.kind == EigenvalueKind::infinite) continue;
      for (const cd mu : {other.lambda, std::conj(other.lambda)})
        if (std::abs(mu - md.lambda) <= r + other.error_bound) isolated = false;
    }
    if (isolated) on_axis.push_back(k);
  }
  for (std::size_t k : on_axis) {
    Mode& md = modes[k];
    md.lambda = cd(0.0, md.lambda.imag());
    md.alpha = md.lambda * md.beta;
    md.damping_ratio = 0.0;
  }
  return static_cast<Index>(on_axis.size());
}

double RangeScaling::gamma() const { return std::ldexp(1.0, k); }

Eigen::MatrixXd RangeScaling::scaled(const Eigen::MatrixXd& X, int j) const {
  const int p = j * k + e;
  return X.unaryExpr([p](double x) { return std::ldexp(x, p); });
}

RangeScaling range_scaling(const std::vector<double>& largest) {
  constexpr int kBand = 450;
  RangeScaling r;
  std::vector<int> ex(largest.size(), 0);
  bool any = false;
  for (std::size_t j = 0; j < largest.size(); ++j) {
    if (!(largest[j] > 0)) continue;
    std::frexp(largest[j], &ex[j]);
    any = true;
    if (std::abs(ex[j]) > kBand) r.active = true;
  }
  if (!any || !r.active) return RangeScaling{};
  // γ from the highest and lowest present coefficients: 2^(e_0 − e_d)/d.
  std::size_t lo = largest.size(), hi = 0;
  for (std::size_t j = 0; j < largest.size(); ++j)
    if (largest[j] > 0) {
      lo = std::min(lo, j);
      hi = std::max(hi, j);
    }
  r.k = hi > lo ? static_cast<int>(std::lround(static_cast<double>(ex[lo] - ex[hi]) / static_cast<double>(hi - lo))) : 0;
  int top = std::numeric_limits<int>::min();
  for (std::size_t j = 0; j < largest.size(); ++j)
    if (largest[j] > 0) top = std::max(top, ex[j] + static_cast<int>(j) * r.k);
  r.e = -top;
  return r;
}

void unscale_modes(std::vector<Mode>& modes, double gamma) {
  for (Mode& m : modes) {
    if (m.kind != EigenvalueKind::finite) continue;
    m.lambda *= gamma;
    m.natural_frequency_hz *= gamma;
    m.damped_frequency_hz *= gamma;
    m.error_bound *= gamma;
    // (α, β) of λ = α/β: α·γ, renormalized (|α|² + β² = 1).
    const std::complex<double> a = m.alpha * gamma;
    const double s = std::hypot(std::abs(a), m.beta);
    if (s > 0 && std::isfinite(s)) {
      m.alpha = a / s;
      m.beta /= s;
    }
  }
}

}  // namespace mbsgen::detail
