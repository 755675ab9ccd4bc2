#include "mbsgen/runtime/study/study.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <sstream>
#include <thread>

#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

// OpenBLAS's own threads, when the library is OpenBLAS (a weak reference: null with another BLAS).
extern "C" void openblas_set_num_threads(int) __attribute__((weak));

namespace mbsgen {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kTwoPi = 6.283185307179586476925286766559;

std::string frequency_label(double hz) {
  std::ostringstream s;
  s.precision(10);
  s << hz;
  return s.str();
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// What one thread needs: its own copy of the model (parameters), and its timings.
struct Worker {
  GeneratedModel model;
  std::vector<double> parameters;
  double kernels = 0, modes = 0, response = 0;
  std::vector<StudyFailure> failures;
};

// The lowest modes' f_n and ζ into out (2·K values); throws Error when there are fewer.
void lowest_modes(const LinearModel& lin, int count, double* out) {
  QuadraticEigenOptions opt;
  opt.one_per_conjugate_pair = true;
  QuadraticEigenSolver solver(lin.size(), opt);
  solver.compute(lin);
  std::vector<const Mode*> finite;
  for (const Mode& m : solver.modes())
    if (m.kind == EigenvalueKind::finite && !m.zero_within_bound) finite.push_back(&m);
  std::stable_sort(finite.begin(), finite.end(),
                   [](const Mode* a, const Mode* b) { return a->natural_frequency_hz < b->natural_frequency_hz; });
  if (static_cast<int>(finite.size()) < count)
    throw Error("the model has " + std::to_string(finite.size()) + " finite modes at this point, fewer than the " +
                std::to_string(count) + " asked for");
  for (int k = 0; k < count; ++k) {
    out[2 * k] = finite[static_cast<std::size_t>(k)]->natural_frequency_hz;
    out[2 * k + 1] = finite[static_cast<std::size_t>(k)]->damping_ratio;
  }
}

}  // namespace

std::vector<std::string> scalar_names(const StudyQuantities& q) {
  std::vector<std::string> names;
  for (int k = 1; k <= q.modes; ++k) {
    names.push_back("f" + std::to_string(k) + "_hz");
    names.push_back("zeta" + std::to_string(k));
  }
  for (double hz : q.at_hz) names.push_back("L_" + frequency_label(hz) + "Hz_dB");
  return names;
}

StudyResults evaluate(const GeneratedModel& model, const StudyDesign& design, const StudyQuantities& q,
                      std::size_t first, std::size_t count, int threads,
                      const std::function<void(std::size_t)>& progress) {
  if (first > design.size() || count > design.size() - first)
    throw DimensionError("mbsgen::evaluate (study): evaluations " + std::to_string(first) + " to " +
                         std::to_string(first + count) + " of a design of " + std::to_string(design.size()));
  // Names first: a typo fails before any work.
  const std::vector<std::string>& names = model.parameter_names();
  std::vector<std::size_t> slot;
  for (const auto& d : design.distributions()) {
    const auto it = std::find(names.begin(), names.end(), d.name);
    if (it == names.end()) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      throw NameError("study: model '" + std::string(model.kernels().model) + "' has no parameter '" + d.name +
                      "' (parameters: " + list + ")");
    }
    slot.push_back(static_cast<std::size_t>(it - names.begin()));
  }
  const bool response = !q.input.empty() || !q.output.empty();
  Eigen::Index input = 0, output = 0;
  if (response) input = model.input_index(q.input), output = model.output_index(q.output);
  if (model.is_descriptor() && (q.modes > 0 || response))
    throw Error("study: model '" + std::string(model.kernels().model) +
                "' has rolling constraints; a study of its modes and responses is not available yet");
  FrfOptions frf_options;
  frf_options.method = parse_frf_method(q.method);
  Eigen::VectorXd omega(static_cast<Eigen::Index>(q.sweep_hz.size() + q.at_hz.size()));
  for (std::size_t i = 0; i < q.sweep_hz.size(); ++i) omega[static_cast<Eigen::Index>(i)] = kTwoPi * q.sweep_hz[i];
  for (std::size_t i = 0; i < q.at_hz.size(); ++i)
    omega[static_cast<Eigen::Index>(q.sweep_hz.size() + i)] = kTwoPi * q.at_hz[i];

  // One BLAS thread: the study's threads share out the evaluations, and OpenBLAS's results for a
  // given matrix depend on how many threads it splits the work over (its blocking), so that a
  // rank of an MPI job (one thread, as mpirun binds it) and a process on its own (all cores)
  // would differ in the last bits.
  if (openblas_set_num_threads) openblas_set_num_threads(1);
  StudyResults r;
  r.first = first, r.count = count;
  r.scalar_names = scalar_names(q);
  const std::size_t ns = r.scalar_names.size(), nw = q.sweep_hz.size(), nm = 2 * static_cast<std::size_t>(q.modes);
  r.scalars.assign(count * ns, kNaN);
  r.sweep.assign(count * nw, kNaN);

  auto run_one = [&](Worker& w, std::size_t local) {
    const std::size_t index = first + local;
    std::vector<double> values(slot.size());
    double* scalars = r.scalars.data() + local * ns;
    try {
      design.point(index, values.data());
      for (std::size_t k = 0; k < slot.size(); ++k) w.parameters[slot[k]] = values[k];
      auto t0 = std::chrono::steady_clock::now();
      w.model.set_parameters(w.parameters);
      const LinearModel lin = w.model.linear_model(w.model.operating_point());
      w.kernels += seconds_since(t0);
      if (q.modes > 0) {
        t0 = std::chrono::steady_clock::now();
        lowest_modes(lin, q.modes, scalars);
        w.modes += seconds_since(t0);
      }
      if (response && omega.size() > 0) {
        t0 = std::chrono::steady_clock::now();
        FrequencyResponse frf(lin, frf_options);
        frf.compute(omega, input, {output});
        const Eigen::VectorXcd z = frf.response().row(0).transpose();
        for (std::size_t i = 0; i < nw; ++i) r.sweep[local * nw + i] = std::abs(z[static_cast<Eigen::Index>(i)]);
        for (std::size_t i = 0; i < q.at_hz.size(); ++i)
          scalars[nm + i] = 20 * std::log10(std::abs(z[static_cast<Eigen::Index>(nw + i)]));
        w.response += seconds_since(t0);
      }
    } catch (const std::exception& e) {
      std::fill(scalars, scalars + ns, kNaN);
      std::fill(r.sweep.begin() + static_cast<std::ptrdiff_t>(local * nw),
                r.sweep.begin() + static_cast<std::ptrdiff_t>((local + 1) * nw), kNaN);
      w.failures.push_back({index, values, e.what()});  // (out of memory here ends the worker: below)
    }
  };

  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t n_threads = std::max<std::size_t>(1, std::min<std::size_t>(threads > 0 ? static_cast<std::size_t>(threads) : hw, std::max<std::size_t>(count, 1)));
  std::vector<Worker> workers;
  for (std::size_t t = 0; t < n_threads; ++t) workers.push_back({model, model.parameters(), 0, 0, 0, {}});
  std::atomic<std::size_t> next{0}, done{0};
  constexpr std::size_t kChunk = 8;
  // A worker that cannot go on (out of memory while recording a failure) stops every worker and
  // its exception is rethrown here; nothing escapes a thread.
  std::exception_ptr stopped;
  std::mutex stopped_lock;
  auto work = [&](Worker& w) {
    try {
      for (std::size_t begin; (begin = next.fetch_add(kChunk)) < count;) {
        const std::size_t end = std::min(count, begin + kChunk);
        for (std::size_t i = begin; i < end; ++i) run_one(w, i);
        done += end - begin;
      }
    } catch (...) {
      next = count;
      done = count;
      const std::lock_guard<std::mutex> guard(stopped_lock);
      if (!stopped) stopped = std::current_exception();
    }
  };
  // With a progress report the calling thread only reports; otherwise it works too.
  std::vector<std::thread> pool;
  try {
    for (std::size_t t = progress ? 0 : 1; t < n_threads; ++t) pool.emplace_back(work, std::ref(workers[t]));
    if (progress) {
      while (done.load() < count) {
        progress(done.load());
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
      }
      progress(count);
    } else {
      work(workers[0]);
    }
  } catch (...) {  // a thread that could not start, or a progress report that threw
    next = count;
    for (auto& t : pool) t.join();
    throw;
  }
  for (auto& t : pool) t.join();
  if (stopped) std::rethrow_exception(stopped);
  for (auto& w : workers) {
    r.seconds_kernels += w.kernels, r.seconds_modes += w.modes, r.seconds_response += w.response;
    r.failures.insert(r.failures.end(), w.failures.begin(), w.failures.end());
  }
  std::sort(r.failures.begin(), r.failures.end(),
            [](const StudyFailure& a, const StudyFailure& b) { return a.index < b.index; });
  return r;
}

void append(StudyResults& a, const StudyResults& b) {
  if (a.count == 0 && a.scalars.empty() && a.sweep.empty()) {
    a = b;
    return;
  }
  if (b.first != a.first + a.count || b.scalar_names != a.scalar_names)
    throw DimensionError("mbsgen::append (study): results of evaluations " + std::to_string(b.first) +
                         " onward do not follow those up to " + std::to_string(a.first + a.count));
  a.count += b.count;
  a.scalars.insert(a.scalars.end(), b.scalars.begin(), b.scalars.end());
  a.sweep.insert(a.sweep.end(), b.sweep.begin(), b.sweep.end());
  a.failures.insert(a.failures.end(), b.failures.begin(), b.failures.end());
  a.seconds_kernels += b.seconds_kernels, a.seconds_modes += b.seconds_modes, a.seconds_response += b.seconds_response;
}

std::vector<std::vector<double>> percentile_bands(const StudyResults& results, std::size_t n_sweep,
                                                  const std::vector<double>& qs) {
  std::vector<std::vector<double>> bands(qs.size(), std::vector<double>(n_sweep, kNaN));
  if (n_sweep == 0) return bands;
  if (results.sweep.size() != results.count * n_sweep)
    throw DimensionError("mbsgen::percentile_bands: " + std::to_string(results.sweep.size()) + " sweep values for " +
                         std::to_string(results.count) + " evaluations of " + std::to_string(n_sweep) + " frequencies");
  std::vector<double> column(results.count);
  for (std::size_t i = 0; i < n_sweep; ++i) {
    for (std::size_t s = 0; s < results.count; ++s) column[s] = results.sweep[s * n_sweep + i];
    for (std::size_t k = 0; k < qs.size(); ++k) bands[k][i] = percentile(column, qs[k]);
  }
  return bands;
}

}  // namespace mbsgen
