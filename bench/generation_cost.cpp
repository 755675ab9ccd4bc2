// Generation: what CSE and the structure-aware (composite) projection cost and save (issue 7
// §3, docs/accuracy-vs-time.md). For the N-link planar chain (N = 2 … 40) and the N-link
// spatial chain, four variants — projection composite or naive (DeriveOptions, dynamics.hpp) ×
// CSE on or off (EmitOptions) — each: generation time (derive + linearize + emit, in process,
// median of 3 runs, 1 when a run takes over 2 s), operation counts of the emitted kernels,
// compile time of the emitted file (the C++ compiler this was built with, -O2, shared
// library), evaluation time of the `linear` kernel (median of 21 batches of at least 30 ms),
// and the largest difference of its M, Q, K, B from those of the default variant (composite,
// CSE), relative to the largest entry.
//
//   generation_cost OUT_DIR [--quick] [--planar 2,5,10] [--spatial 2,5] [--compile-timeout S]
//
// A compilation that takes longer than S seconds (default 180, --quick 60) is stopped, and one
// whose variant took over S/6 at the previous N is not tried; their compile and kernel times are
// reported as NaN (stopped or skipped).
// Writes OUT_DIR/generation.csv and OUT_DIR/gen_matrices/planar_<N>.txt (M, Q, K of the planar
// chain at y0 = 0 with the default parameters, for the comparison with SymPy in
// bench/peers/sympy_chain.py).
#include "harness.hpp"

#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/model/parametric_chains.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <stdexcept>

#ifndef MBSGEN_BENCH_CXX
#define MBSGEN_BENCH_CXX "c++"
#endif

namespace {

namespace fs = std::filesystem;

using LinearKernel = int (*)(const double*, const double*, const double*, double*, double*, double*, double*,
                             double*, double*);

struct Variant {
  const char* name;
  mbsgen::Projection projection;
  bool cse;
};

const Variant kVariants[] = {{"composite_cse", mbsgen::Projection::composite, true},
                             {"composite_nocse", mbsgen::Projection::composite, false},
                             {"naive_cse", mbsgen::Projection::naive, true},
                             {"naive_nocse", mbsgen::Projection::naive, false}};

std::size_t ops(const mbsgen::GeneratedCode& code, const std::string& kernel) {
  for (const auto& k : code.kernels)
    if (k.name == kernel) return k.operations;
  return 0;
}

mbsgen::GeneratedCode generate(const mbsgen::Model& model, const Variant& v, const std::string& id) {
  mbsgen::DeriveOptions d;
  d.projection = v.projection;
  mbsgen::Equations eq = mbsgen::derive(model, d);
  mbsgen::LinearEquations lin = mbsgen::linearize(eq);
  mbsgen::EmitOptions e;
  e.cse = v.cse;
  e.id = id;
  return mbsgen::emit(model, eq, lin, e);
}

struct Kernel {
  void* handle = nullptr;
  LinearKernel linear = nullptr;
};

/// Compiles the emitted file into a shared library and loads it; a compilation longer than
/// `timeout_s` is stopped (seconds = NaN, no kernel).
Kernel compile(const mbsgen::GeneratedCode& code, const fs::path& dir, int timeout_s, double& seconds) {
  mbsgen::write_generated(code, dir.string());
  const fs::path lib = dir / ("lib" + code.id + ".so");
  const std::string command = "timeout " + std::to_string(timeout_s) + " " + std::string(MBSGEN_BENCH_CXX) +
                              " -O2 -std=c++17 -shared -fPIC -o '" + lib.string() + "' '" +
                              (dir / (code.id + ".cpp")).string() + "'";
  const auto t0 = bench::Clock::now();
  const int status = std::system(command.c_str());
  seconds = bench::seconds_since(t0);
  Kernel k;
  if (status != 0) {
    if (seconds < timeout_s - 1) throw std::runtime_error("compiling failed: " + command);
    seconds = NAN;
    return k;
  }
  k.handle = dlopen(lib.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!k.handle) throw std::runtime_error(std::string("dlopen: ") + dlerror());
  k.linear = reinterpret_cast<LinearKernel>(dlsym(k.handle, (code.id + "_linear").c_str()));
  if (!k.linear) throw std::runtime_error("no linear kernel in " + lib.string());
  return k;
}

struct Matrices {
  std::vector<double> M, Q, K, B, Cy, Cv;
};

Matrices evaluate(LinearKernel f, const mbsgen::Model& model, double y0_value) {
  const std::size_t n = model.coordinates().size();
  const std::size_t m = std::max<std::size_t>(1, model.inputs().size());
  const std::size_t r = std::max<std::size_t>(1, model.outputs().size());
  std::vector<double> y0(n, y0_value), yd0(n, 0.0), p;
  for (const auto& q : model.parameters()) p.push_back(q.value);
  Matrices x{std::vector<double>(n * n), std::vector<double>(n * n), std::vector<double>(n * n),
             std::vector<double>(n * m), std::vector<double>(r * n), std::vector<double>(r * n)};
  f(y0.data(), yd0.data(), p.data(), x.M.data(), x.Q.data(), x.K.data(), x.B.data(), x.Cy.data(), x.Cv.data());
  return x;
}

double max_rel_diff(const Matrices& a, const Matrices& b) {
  double d = 0, s = 0;
  const std::vector<double> Matrices::*fields[] = {&Matrices::M, &Matrices::Q, &Matrices::K, &Matrices::B};
  for (auto f : fields)
    for (std::size_t i = 0; i < (a.*f).size(); ++i) {
      d = std::max(d, std::abs((a.*f)[i] - (b.*f)[i]));
      s = std::max(s, std::abs((a.*f)[i]));
    }
  return s > 0 ? d / s : d;
}

bench::Timing time_kernel(LinearKernel f, const mbsgen::Model& model) {
  const std::size_t n = model.coordinates().size();
  const std::size_t m = std::max<std::size_t>(1, model.inputs().size());
  const std::size_t r = std::max<std::size_t>(1, model.outputs().size());
  std::vector<double> y0(n, 0.1), yd0(n, 0.0), p, M(n * n), Q(n * n), K(n * n), B(n * m), Cy(r * n), Cv(r * n);
  for (const auto& q : model.parameters()) p.push_back(q.value);
  long i = 0;
  return bench::time_calls(
      [&] {
        y0[0] = 0.1 + 1e-12 * static_cast<double>(++i % 1000);  // defeat hoisting
        f(y0.data(), yd0.data(), p.data(), M.data(), Q.data(), K.data(), B.data(), Cy.data(), Cv.data());
      },
      21, 0.03);
}

void write_matrices(const Matrices& x, std::size_t n, const fs::path& file) {
  std::ofstream o(file);
  o.precision(17);
  const char* names[] = {"M", "Q", "K"};
  const std::vector<double>* mats[] = {&x.M, &x.Q, &x.K};
  for (int k = 0; k < 3; ++k) {
    o << names[k] << "\n";
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < n; ++j) o << (j ? " " : "") << (*mats[k])[i + j * n];
      o << "\n";
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: generation_cost OUT_DIR [--quick] [--planar 2,5,10] [--spatial 2,5] [--compile-timeout S]\n";
    return 2;
  }
  const fs::path out = argv[1];
  std::vector<int> planar{2, 5, 10, 20, 40}, spatial{2, 5, 10};
  int timeout_s = 180;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") {
      planar = {2, 5, 10, 20};
      spatial = {2, 5};
      timeout_s = 60;
    } else if (a == "--compile-timeout" && i + 1 < argc) {
      timeout_s = std::stoi(argv[++i]);
    } else if (a == "--planar" && i + 1 < argc) {
      planar = bench::parse_int_list(argv[++i]);
    } else if (a == "--spatial" && i + 1 < argc) {
      spatial = bench::parse_int_list(argv[++i]);
    }
  }
  fs::create_directories(out / "gen_matrices");
  std::map<std::string, double> last_compile;  // per variant and chain: seconds, NaN if stopped
  const fs::path work = out / "gen_work";
  bench::Csv csv((out / "generation.csv").string(),
                 "chain,N,coordinates,variant,generation_s,generation_min_s,generation_max_s,reps,ops_mass_matrix,"
                 "ops_residual,ops_linear,ops_all,compile_s,kernel_s,kernel_min_s,kernel_max_s,max_rel_diff");
  for (const bool is_planar : {true, false}) {
    for (int N : is_planar ? planar : spatial) {
      const mbsgen::Model model = is_planar ? mbsgen::planar_chain(N) : mbsgen::spatial_chain(N);
      const std::string chain = is_planar ? "planar" : "spatial";
      Matrices reference;
      for (const Variant& v : kVariants) {
        double& previous_compile = last_compile[std::string(v.name) + chain];
        const std::string id = chain + "_" + std::to_string(N) + "_" + v.name;
        mbsgen::GeneratedCode code;
        const bench::Timing gen = bench::time_calls([&] { code = generate(model, v, id); }, 3, 0.0, 2.0);
        double compile_s = NAN;
        const fs::path dir = work / id;
        fs::create_directories(dir);
        // Compile time grew 4-10× per step of N (2, 5, 10, 20, 40) on the development machine:
        // skip what would exceed the limit anyway.
        const bool hopeless = !(previous_compile < timeout_s / 6.0);
        const Kernel k = hopeless ? Kernel{} : compile(code, dir, timeout_s, compile_s);
        previous_compile = hopeless ? INFINITY : compile_s;
        bench::Timing kt;
        double diff = NAN;
        if (k.linear) {
          kt = time_kernel(k.linear, model);
          const Matrices x = evaluate(k.linear, model, 0.1);
          if (&v == &kVariants[0]) {
            reference = x;
            if (is_planar)
              write_matrices(evaluate(k.linear, model, 0.0), model.coordinates().size(),
                             out / "gen_matrices" / ("planar_" + std::to_string(N) + ".txt"));
          }
          if (!reference.M.empty()) diff = max_rel_diff(x, reference);
        }
        std::size_t all = 0;
        for (const auto& kk : code.kernels) all += kk.operations;
        csv.row({chain, std::to_string(N), std::to_string(model.coordinates().size()), v.name, bench::num(gen.median),
                 bench::num(gen.min), bench::num(gen.max), std::to_string(gen.repetitions),
                 std::to_string(ops(code, "mass_matrix")), std::to_string(ops(code, "residual")),
                 std::to_string(ops(code, "linear")), std::to_string(all), bench::num(compile_s), bench::num(kt.median),
                 bench::num(kt.min), bench::num(kt.max), bench::num(diff)});
        std::cerr << "generation_cost: " << id << ": " << bench::num(gen.median) << " s, linear "
                  << ops(code, "linear") << " ops, compile " << bench::num(compile_s) << " s, kernel "
                  << bench::num(kt.median * 1e6) << " us\n";
        if (k.handle) dlclose(k.handle);
        fs::remove_all(dir);
      }
    }
  }
  return 0;
}
