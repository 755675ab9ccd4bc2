// Comparing two kernels that compute the same values by different operations (tests).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace mbsgen::test {

/// The unit roundoff of double, u = 2⁻⁵³.
constexpr double kUnitRoundoff = 1.1102230246251565e-16;

/// The largest |x| of v.
inline double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

/// The largest |a_k − b_k| in units of u times a's largest entry: the same values summed in
/// another association differ by rounding of the scale of the terms summed (the largest entry),
/// not of each entry's own size.
inline double difference_in_units(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0;
  for (std::size_t k = 0; k < a.size() && k < b.size(); ++k) d = std::max(d, std::abs(a[k] - b[k]));
  const double scale = max_abs(a);
  return scale > 0 ? d / (kUnitRoundoff * scale) : d;
}

}  // namespace mbsgen::test
