// Per-evaluation cost of a middle-ear study (issue 20 §4): kernel evaluation (the linear model at
// the operating point), the frequency response's set-up (its factorization or reduction: the
// first frequency) and the sweep (the other 299 of 300 frequencies), per method; medians over the
// evaluations of a Latin-hypercube design of the ligament and joint parameters.
//   study_breakdown [EVALUATIONS]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "mbsgen/runtime/model/generated_model.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/study/study_design.hpp"
#include "middle_ear_model.hpp"

extern "C" void openblas_set_num_threads(int) __attribute__((weak));

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

}  // namespace

int main(int argc, char** argv) {
  if (openblas_set_num_threads) openblas_set_num_threads(1);
  const std::size_t n = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 500;
  mbsgen::GeneratedModel model(middle_ear::kernels());
  const auto& names = model.parameter_names();
  auto slot = [&](const std::string& p) { return static_cast<std::size_t>(std::find(names.begin(), names.end(), p) - names.begin()); };
  std::vector<mbsgen::ParameterDistribution> d;  // each log-normal about its default, a factor of 2
  for (const char* p : {"k_aml_x", "kr_aml_x", "k_pil_x", "k_imj_x", "d_imj_x", "k_isj_z", "d_isj_z", "k_al_z", "kr_al_x", "d_al_z"})
    d.push_back({p, mbsgen::Distribution::lognormal, model.parameters()[slot(p)], 2.0});
  const mbsgen::StudyDesign design(mbsgen::Design::latin_hypercube, d, n, 1);
  Eigen::VectorXd omega(300);
  for (int i = 0; i < 300; ++i) omega[i] = 2 * M_PI * 100 * std::pow(100.0, i / 299.0);
  std::printf("method      kernels_us  setup_us  sweep_us  per_frequency_us  total_us\n");
  for (const auto method : {mbsgen::FrfMethod::automatic, mbsgen::FrfMethod::direct, mbsgen::FrfMethod::hessenberg,
                            mbsgen::FrfMethod::banded, mbsgen::FrfMethod::modal}) {
    std::vector<double> tk, ts, tw, tt;
    for (std::size_t i = 0; i < n; ++i) {
      std::vector<double> p = model.parameters();
      const auto x = design.point(i);
      for (std::size_t k = 0; k < d.size(); ++k) p[slot(d[k].name)] = x[k];
      const double t0 = now();
      model.set_parameters(p);
      const mbsgen::LinearModel lin = model.linear_model(model.operating_point());
      const double t1 = now();
      mbsgen::FrfOptions opt;
      opt.method = method;
      mbsgen::FrequencyResponse frf(lin, opt);
      frf.compute(omega.head(1), 0, {0});
      const double t2 = now();
      frf.compute(omega.tail(299), 0, {0});
      const double t3 = now();
      tk.push_back(1e6 * (t1 - t0)), ts.push_back(1e6 * (t2 - t1)), tw.push_back(1e6 * (t3 - t2)), tt.push_back(1e6 * (t3 - t0));
    }
    std::printf("%-11s %10.1f %9.1f %9.1f %17.2f %9.1f\n", mbsgen::to_string(method), median(tk), median(ts), median(tw),
                median(tw) / 299, median(tt));
  }
  return 0;
}
