// Evaluation time of a generated `linear` kernel (M, Q, K, B, C): median over batches of
// repeated calls. Built by bench/CMakeLists.txt against the planar_chain_10 kernels that
// `generation_bench --emit` writes.
#include "planar_chain_10.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

int main() {
  const int n = planar_chain_10_n_coordinates;
  std::vector<double> y0(n, 0.1), yd0(n, 0.0), M(n * n), Q(n * n), K(n * n), B(1), Cy(1), Cv(1);
  const double* p = planar_chain_10_parameter_defaults;
  std::vector<double> per_call;
  const int calls = 100000;
  for (int batch = 0; batch < 21; ++batch) {
    auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < calls; ++i) {
      y0[0] = 0.1 + 1e-9 * i;  // defeat hoisting
      planar_chain_10_linear(y0.data(), yd0.data(), p, M.data(), Q.data(), K.data(), B.data(), Cy.data(), Cv.data());
    }
    per_call.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / calls);
  }
  std::sort(per_call.begin(), per_call.end());
  std::printf("planar_chain_10_linear: median %.3f us per call (min %.3f, max %.3f), M[0] = %g\n",
              per_call[10] * 1e6, per_call[0] * 1e6, per_call[20] * 1e6, M[0]);
  return 0;
}
