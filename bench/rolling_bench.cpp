// Rolling contact (issue 16 §4): generation of the Whipple bicycle and of the rolling disk from
// their model files (read, derive, linearize, emit), medians of 5 runs beside the double
// pendulum's in the same run, and their kernels' operation counts (Markdown table; the sweep's
// time is rolling_sweep_bench's: the generator and the runtime do not share a translation unit).
//   rolling_bench
#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double median_of_5(const std::function<void()>& f) {
  std::vector<double> t;
  for (int i = 0; i < 5; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    t.push_back(seconds_since(t0));
  }
  std::sort(t.begin(), t.end());
  return t[2];
}

std::size_t ops(const mbsgen::GeneratedCode& code, const std::string& kernel) {
  for (const auto& k : code.kernels)
    if (k.name == kernel) return k.operations;
  return 0;
}

void generation_row(const std::string& name, const std::string& file) {
  mbsgen::GeneratedCode code;
  const double t = median_of_5([&] {
    const mbsgen::Model model = mbsgen::read_model_file(std::string(MBSGEN_SOURCE_DIR) + "/" + file);
    mbsgen::Equations eq = mbsgen::derive(model);
    mbsgen::LinearEquations lin = mbsgen::linearize(eq);
    code = mbsgen::emit(model, eq, lin);
  });
  std::printf("| %s | %.3f | %zu | %zu | %zu |\n", name.c_str(), t, ops(code, "descriptor"), ops(code, "reduced"),
              ops(code, "linear"));
}

}  // namespace

int main() {
  std::printf("| model | generation median [s] | descriptor ops | reduced ops | linear ops |\n|---|---|---|---|---|\n");
  generation_row("double pendulum (baseline, second order)", "models/textbook/double_pendulum.yaml");
  generation_row("rolling disk", "models/rolling/rolling_disk.yaml");
  generation_row("Whipple bicycle", "models/bicycle/whipple_benchmark.yaml");
  return 0;
}
