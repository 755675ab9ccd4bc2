// Rolling contact (issue 16 §4): the Whipple bicycle's eigenvalues at 1,000 speeds, 0-10 m/s,
// through the shipped kernels (sweep_parameter, with the refinement of its two stability
// boundaries), median of 5 runs, beside one evaluation of the descriptor model and its
// eigenvalues at 5 m/s (the per-speed cost).
//   rolling_sweep_bench
#include "mbsgen/runtime/spectral/descriptor_eigen.hpp"
#include "mbsgen/runtime/spectral/parameter_sweep.hpp"
#include "whipple_benchmark_model.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <vector>

namespace {

double median_of_5(const std::function<void()>& f) {
  std::vector<double> t;
  for (int i = 0; i < 5; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  return t[2];
}

}  // namespace

int main() {
  mbsgen::GeneratedModel bicycle(whipple_benchmark::kernels());
  const double one = median_of_5([&] {
    for (int i = 0; i < 1000; ++i) {
      mbsgen::DescriptorEigenSolver solver;
      solver.compute(bicycle.descriptor_model());
    }
  }) / 1000;
  mbsgen::SweepResult r;
  const double t = median_of_5([&] { r = mbsgen::sweep_parameter(bicycle, "v", 0, 10, 1000); });
  std::printf("one speed (kernels and all 10 eigenvalues): %.1f us; 1,000 speeds with %zu boundaries refined: %.3f s",
              one * 1e6, r.boundaries.size(), t);
  for (const auto& b : r.boundaries) std::printf("; v = %.14f", b.value);
  std::printf("\n");
  return 0;
}
