// Evaluation time of the loaded four-bar's `linear` kernel (issue 15 §5: < 1 µs): median over
// batches of repeated calls at the operating point, where `assemble` starts on the loop (one
// Newton step confirms it), and at a displaced crank angle (a few Newton steps).
#include "four_bar_linkage.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

namespace {

double median_us(double offset) {
  const int n = four_bar_linkage_n_coordinates, m = four_bar_linkage_n_inputs, r = four_bar_linkage_n_outputs;
  std::vector<double> y0(n), yd0(n, 0.0), M(n * n), Q(n * n), K(n * n), B(n * m), Cy(r * n), Cv(r * n);
  const double* p = four_bar_linkage_parameter_defaults;
  four_bar_linkage_operating_point(p, y0.data(), yd0.data());
  const double start = y0[0] + offset;
  std::vector<double> per_call;
  const int calls = 100000;
  for (int batch = 0; batch < 21; ++batch) {
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < calls; ++i) {
      y0[0] = start + 1e-15 * (i & 1);  // defeat hoisting
      four_bar_linkage_linear(y0.data(), yd0.data(), p, M.data(), Q.data(), K.data(), B.data(), Cy.data(), Cv.data());
    }
    per_call.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / calls);
  }
  std::sort(per_call.begin(), per_call.end());
  std::printf("four_bar_linkage_linear (independent coordinate %+g rad from the operating point): median %.3f us "
              "per call (min %.3f, max %.3f), K = %.6g\n",
              offset, per_call[10] * 1e6, per_call[0] * 1e6, per_call[20] * 1e6, K[0]);
  return per_call[10];
}

}  // namespace

int main() {
  median_us(0.0);
  median_us(0.05);
  return 0;
}
