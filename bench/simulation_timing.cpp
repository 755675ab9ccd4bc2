// Issue 18 §4: what accuracy costs in time for simulate(). For each problem (the simple pendulum
// at 2.5 rad, 10 s; the double pendulum from 0.5 rad, 100 s; the middle ear under a 1 kHz tone of
// 1 Pa, 20 ms), each method and each tolerance: the median run time of `repeats` runs and the
// samples, written to OUT_DIR/ours_<problem>_<method>_<rtol>.csv (t, coordinates); the reference
// run (Radau at rtol 1e-13; the middle ear's 1e-11) is OUT_DIR/reference_<problem>.csv. bench/simulation_compare.py runs SciPy on
// the same problems and computes the errors.
//
//   simulation_timing OUT_DIR [REPEATS [PROBLEM]]
#include <Eigen/Core>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <string>
#include <vector>

#include "double_pendulum_model.hpp"
#include "mbsgen/runtime/time/simulation.hpp"
#include "middle_ear_model.hpp"
#include "simple_pendulum_model.hpp"

namespace {

struct Problem {
  std::string name;
  const mbsgen::ModelKernels* k;
  mbsgen::SimulationOptions base;
  double atol_scale;  // atol = rtol × atol_scale (the size of the motion)
};

std::vector<Problem> problems() {
  std::vector<Problem> p;
  {
    mbsgen::SimulationOptions o;
    o.duration = 10, o.step = 0.01, o.initial = {{"phi", 2.5}};
    p.push_back({"pendulum", &simple_pendulum::kernels(), o, 1.0});
  }
  {
    mbsgen::SimulationOptions o;
    o.duration = 100, o.step = 0.1, o.initial = {{"phi1", 0.5}};  // regular motion (from 1 rad it is chaotic)
    p.push_back({"double_pendulum", &double_pendulum::kernels(), o, 1.0});
  }
  {
    mbsgen::SimulationOptions o;
    o.duration = 0.02, o.step = 1e-5;
    // P (input 0); the others move the temporal bone (bone conduction), held still.
    o.inputs.assign(static_cast<std::size_t>(middle_ear::kernels().n_inputs), mbsgen::InputSignal());
    o.inputs[0] = mbsgen::InputSignal::sine(1.0, 1000);
    p.push_back({"middle_ear", &middle_ear::kernels(), o, 1e-9});  // displacements of nanometres
  }
  return p;
}

void write(const std::string& path, const mbsgen::SimulationResult& r) {
  std::ofstream f(path);
  f.precision(17);
  for (Eigen::Index j = 0; j < r.t.size(); ++j) {
    f << r.t[j];
    for (Eigen::Index i = 0; i < r.y.rows(); ++i) f << "," << r.y(i, j);
    f << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: simulation_timing OUT_DIR [REPEATS [PROBLEM]]\n");
    return 2;
  }
  const std::string dir = argv[1];
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 5;
  const std::string only = argc > 3 ? argv[3] : "";  // one problem (a quick look while tuning)
  std::ofstream summary(dir + "/ours_timing.csv");
  summary << "problem,method,rtol,seconds,steps\n";
  for (const Problem& p : problems()) {
    if (!only.empty() && p.name != only) continue;
    mbsgen::GeneratedModel model(*p.k);
    const mbsgen::OperatingPoint op = model.operating_point();
    const bool stiff = p.name == "middle_ear";
    {
      mbsgen::SimulationOptions o = p.base;
      // Radau, the most accurate per tolerance: the reference must be far more accurate than the
      // runs it judges. At these tolerances it agrees with itself at ten times the tolerance to a
      // few 1e-12 (pendulums) and 3e-11 (the middle ear), where BDF at 1e-11 was 3.7e-9 off (so
      // that every error below about 4e-9 had been the reference's own).
      o.method = mbsgen::IntegrationMethod::radau;
      o.rtol = stiff ? 1e-11 : 1e-13;  // below 1e-11 the middle ear's rounding in the kernels dominates
      o.atol = o.rtol * p.atol_scale;
      write(dir + "/reference_" + p.name + ".csv", mbsgen::simulate(model, op, o));
    }
    for (auto method : {mbsgen::IntegrationMethod::bdf, mbsgen::IntegrationMethod::radau, mbsgen::IntegrationMethod::radau9,
                        mbsgen::IntegrationMethod::adams}) {
      if (stiff && method == mbsgen::IntegrationMethod::adams) continue;  // 160,000 steps: not its kind of problem
      const char* name = method == mbsgen::IntegrationMethod::bdf      ? "bdf"
                         : method == mbsgen::IntegrationMethod::radau  ? "radau"
                         : method == mbsgen::IntegrationMethod::radau9 ? "radau9"
                                                                       : "adams";
      // Every half decade, from 1e-4 to 1e-12 (the middle ear's 1e-10): the comparison pairs each
      // SciPy run with our fastest run at least as accurate, so a coarse grid would pair it with a
      // run up to a decade more accurate (and slower) than needed.
      std::vector<double> rtols;
      for (int k = 8; k <= (stiff ? 20 : 24); ++k) rtols.push_back(std::pow(10.0, -0.5 * k));
      for (double rtol : rtols) {
        mbsgen::SimulationOptions o = p.base;
        o.outputs = false;  // the states only, as SciPy's runs give (the middle ear's F_cochlea needs ÿ at each sample)
        o.method = method;
        o.rtol = rtol;
        o.atol = rtol * p.atol_scale;
        std::vector<double> seconds;
        mbsgen::SimulationResult r;
        try {
          for (int k = 0; k < repeats; ++k) {
            const auto t0 = std::chrono::steady_clock::now();
            r = mbsgen::simulate(model, op, o);
            seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
          }
        } catch (const std::exception& e) {
          std::printf("%s %s %g: %s\n", p.name.c_str(), name, rtol, e.what());
          continue;
        }
        std::sort(seconds.begin(), seconds.end());
        const double median = seconds[seconds.size() / 2];
        char file[256];
        std::snprintf(file, sizeof file, "%s/ours_%s_%s_%g.csv", dir.c_str(), p.name.c_str(), name, rtol);
        write(file, r);
        summary << p.name << "," << name << "," << rtol << "," << median << "," << r.steps << "\n";
        std::printf("%-16s %-6s rtol %-6g %9.5f s  %7ld steps\n", p.name.c_str(), name, rtol, median, r.steps);
      }
    }
  }
  return 0;
}
