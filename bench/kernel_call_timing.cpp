// Time per call of a generated model's mass_matrix, residual and linear kernels, loaded from a
// shared library (issue 17 §1: the kernels cut into parts and compiled at -O1 against the whole
// kernels at -O2, the form before issue 17). Run by bench/compile_scale.py; prints one line per
// kernel: "<kernel> <median_s> <min_s> <max_s> <checksum>", the checksum a sum of the outputs at
// a fixed state, so that two builds of the same model can be seen to compute the same numbers.
//
//   kernel_call_timing LIBRARY ID
#include "harness.hpp"

#include <dlfcn.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace {

using MassMatrix = int (*)(const double*, const double*, double*);
using Residual = int (*)(const double*, const double*, const double*, const double*, double*);
using Linear = int (*)(const double*, const double*, const double*, double*, double*, double*, double*, double*,
                       double*);

std::size_t count(const char* const* names) {
  std::size_t n = 0;
  while (names && names[n]) ++n;
  return n;
}

double sum(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s;
}

void report(const char* kernel, const bench::Timing& t, double checksum) {
  std::printf("%s %.6g %.6g %.6g %.17g\n", kernel, t.median, t.min, t.max, checksum);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: kernel_call_timing LIBRARY ID\n");
    return 2;
  }
  void* lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
  if (!lib) {
    std::fprintf(stderr, "kernel_call_timing: %s\n", dlerror());
    return 1;
  }
  const std::string id = argv[2];
  auto symbol = [&](const char* name) { return dlsym(lib, (id + name).c_str()); };
  const auto* p = static_cast<const double*>(symbol("_parameter_defaults"));
  const std::size_t f = count(static_cast<const char* const*>(symbol("_coordinate_names")));
  const std::size_t m = count(static_cast<const char* const*>(symbol("_input_names")));
  const std::size_t r = count(static_cast<const char* const*>(symbol("_output_names")));
  auto mass_matrix = reinterpret_cast<MassMatrix>(symbol("_mass_matrix"));
  auto residual = reinterpret_cast<Residual>(symbol("_residual"));
  auto linear = reinterpret_cast<Linear>(symbol("_linear"));
  if (!p || f == 0 || !mass_matrix || !residual || !linear) {
    std::fprintf(stderr, "kernel_call_timing: %s lacks the kernels of %s\n", argv[1], id.c_str());
    return 1;
  }
  // A state away from the operating point (no exact zeros), the same for every build.
  std::vector<double> y(f), yd(f), u(std::max<std::size_t>(m, 1), 0.0);
  for (std::size_t i = 0; i < f; ++i) {
    y[i] = 0.3 * std::sin(1.7 * static_cast<double>(i) + 1);
    yd[i] = 0.2 * std::cos(0.9 * static_cast<double>(i));
  }
  std::vector<double> M(f * f), Q(f * f), K(f * f), B(std::max<std::size_t>(f * m, 1)),
      Cy(std::max<std::size_t>(r * f, 1)), Cv(Cy.size()), res(f);
  const int reps = 21;
  mass_matrix(y.data(), p, M.data());
  report("mass_matrix", bench::time_calls([&] { mass_matrix(y.data(), p, M.data()); }, reps), sum(M));
  residual(y.data(), yd.data(), u.data(), p, res.data());
  report("residual", bench::time_calls([&] { residual(y.data(), yd.data(), u.data(), p, res.data()); }, reps), sum(res));
  auto call_linear = [&] { linear(y.data(), yd.data(), p, M.data(), Q.data(), K.data(), B.data(), Cy.data(), Cv.data()); };
  call_linear();
  report("linear", bench::time_calls(call_linear, reps), sum(M) + sum(Q) + sum(K));
  return 0;
}
