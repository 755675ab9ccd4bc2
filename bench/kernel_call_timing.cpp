// Time per call of generated models' mass_matrix, residual and linear kernels, loaded from
// shared libraries (issue 17 §1: the kernels cut into parts and compiled at -O1 against the whole
// kernels at -O2, the form before issue 17). Run by bench/compile_scale.py. The libraries are
// timed in one process, batch after batch in turn (51 rounds of batches of about 2 ms each), in
// thread CPU time: on a shared machine a wall-clock comparison of two runs was off by 50 % (the
// other jobs' load changes between them), interleaved CPU time by a few per cent. Prints one
// line per library and kernel: "<library index> <kernel> <median_s> <checksum>", the checksum a
// sum of the outputs at a fixed state, so that builds of the same model can be seen to compute
// the same numbers. A path ending in .tape is a tape (`mbsgen generate --tape`) evaluated by the
// runtime's TapeModel instead of compiled code (issue 40 §5: the tape's speed per call against
// the compiled kernels', bench/tape_speed.sh).
//
//   kernel_call_timing ID LIBRARY|TAPE...
#include "mbsgen/runtime/model/tape.hpp"

#include <dlfcn.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace {

using MassMatrix = int (*)(const double*, const double*, double*);
using Residual = int (*)(const double*, const double*, const double*, const double*, double*);
using Linear = int (*)(const double*, const double*, const double*, double*, double*, double*, double*, double*,
                       double*);

double thread_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

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

// One library's kernels and buffers.
struct Model {
  const double* p = nullptr;
  std::size_t f = 0, m = 0, r = 0;
  MassMatrix mass_matrix = nullptr;
  Residual residual = nullptr;
  Linear linear = nullptr;
  std::vector<double> y, yd, u, M, Q, K, B, Cy, Cv, res;
};

bool buffers(const char* path, const std::string& id, Model& model);
std::vector<std::unique_ptr<mbsgen::TapeModel>> tapes;  // alive while their kernels are timed

bool load(const char* path, const std::string& id, Model& model) {
  const std::string file = path;
  if (file.size() > 5 && file.compare(file.size() - 5, 5, ".tape") == 0) {
    try {
      tapes.push_back(mbsgen::TapeModel::load(file));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "kernel_call_timing: %s\n", e.what());
      return false;
    }
    const mbsgen::ModelKernels& k = tapes.back()->kernels();
    model.p = k.parameter_defaults;
    model.f = static_cast<std::size_t>(k.n_coordinates);
    model.m = static_cast<std::size_t>(k.n_inputs);
    model.r = static_cast<std::size_t>(k.n_outputs);
    model.mass_matrix = k.mass_matrix;
    model.residual = k.residual;
    model.linear = k.linear;
    return buffers(path, id, model);
  }
  void* lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
  if (!lib) {
    std::fprintf(stderr, "kernel_call_timing: %s\n", dlerror());
    return false;
  }
  auto symbol = [&](const char* name) { return dlsym(lib, (id + name).c_str()); };
  model.p = static_cast<const double*>(symbol("_parameter_defaults"));
  model.f = count(static_cast<const char* const*>(symbol("_coordinate_names")));
  model.m = count(static_cast<const char* const*>(symbol("_input_names")));
  model.r = count(static_cast<const char* const*>(symbol("_output_names")));
  model.mass_matrix = reinterpret_cast<MassMatrix>(symbol("_mass_matrix"));
  model.residual = reinterpret_cast<Residual>(symbol("_residual"));
  model.linear = reinterpret_cast<Linear>(symbol("_linear"));
  return buffers(path, id, model);
}

bool buffers(const char* path, const std::string& id, Model& model) {
  if (!model.p || model.f == 0 || !model.mass_matrix || !model.residual || !model.linear) {
    std::fprintf(stderr, "kernel_call_timing: %s lacks the kernels of %s\n", path, id.c_str());
    return false;
  }
  const std::size_t f = model.f;
  // A state away from the operating point (no exact zeros), the same for every build.
  model.y.resize(f);
  model.yd.resize(f);
  for (std::size_t i = 0; i < f; ++i) {
    model.y[i] = 0.3 * std::sin(1.7 * static_cast<double>(i) + 1);
    model.yd[i] = 0.2 * std::cos(0.9 * static_cast<double>(i));
  }
  model.u.assign(std::max<std::size_t>(model.m, 1), 0.0);
  model.M.resize(f * f);
  model.Q.resize(f * f);
  model.K.resize(f * f);
  model.B.resize(std::max<std::size_t>(f * model.m, 1));
  model.Cy.resize(std::max<std::size_t>(model.r * f, 1));
  model.Cv.resize(model.Cy.size());
  model.res.resize(f);
  return true;
}

// Median seconds per call of each of the calls, timed in turn.
std::vector<double> interleaved(const std::vector<std::function<void()>>& calls) {
  std::vector<long> batch(calls.size(), 1);
  for (std::size_t k = 0; k < calls.size(); ++k) {  // size the batches to about 2 ms
    const double t0 = thread_seconds();
    calls[k]();
    const double once = std::max(thread_seconds() - t0, 1e-8);
    batch[k] = std::max(1L, static_cast<long>(2e-3 / once));
  }
  std::vector<std::vector<double>> per_call(calls.size());
  for (int round = 0; round < 51; ++round)
    for (std::size_t k = 0; k < calls.size(); ++k) {
      const double t0 = thread_seconds();
      for (long c = 0; c < batch[k]; ++c) calls[k]();
      per_call[k].push_back((thread_seconds() - t0) / static_cast<double>(batch[k]));
    }
  std::vector<double> medians;
  for (auto& v : per_call) {
    std::sort(v.begin(), v.end());
    medians.push_back(v[v.size() / 2]);
  }
  return medians;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: kernel_call_timing ID LIBRARY...\n");
    return 2;
  }
  const std::string id = argv[1];
  std::vector<Model> models(static_cast<std::size_t>(argc - 2));
  for (std::size_t k = 0; k < models.size(); ++k)
    if (!load(argv[k + 2], id, models[k])) return 1;
  for (const char* kernel : {"mass_matrix", "residual", "linear"}) {
    std::vector<std::function<void()>> calls;
    for (auto& x : models) {
      Model* q = &x;
      if (std::string(kernel) == "mass_matrix")
        calls.push_back([q] { q->mass_matrix(q->y.data(), q->p, q->M.data()); });
      else if (std::string(kernel) == "residual")
        calls.push_back([q] { q->residual(q->y.data(), q->yd.data(), q->u.data(), q->p, q->res.data()); });
      else
        calls.push_back([q] {
          q->linear(q->y.data(), q->yd.data(), q->p, q->M.data(), q->Q.data(), q->K.data(), q->B.data(), q->Cy.data(),
                    q->Cv.data());
        });
    }
    const std::vector<double> t = interleaved(calls);
    for (std::size_t k = 0; k < models.size(); ++k) {
      const Model& q = models[k];
      const double checksum = std::string(kernel) == "mass_matrix" ? sum(q.M)
                              : std::string(kernel) == "residual"  ? sum(q.res)
                                                                   : sum(q.M) + sum(q.Q) + sum(q.K);
      std::printf("%zu %s %.6g %.17g\n", k, kernel, t[k], checksum);
    }
  }
  return 0;
}
