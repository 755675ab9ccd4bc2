// Timing harness of the accuracy-versus-time benchmarks (bench/frf_accuracy.cpp,
// bench/modes_accuracy.cpp, bench/generation_cost.cpp; docs/accuracy-vs-time.md): the median of
// several repetitions, each a batch of calls long enough to be timed, and CSV output. The
// machine is shared, so medians (not means, not minima) are reported, with the spread (min and
// max of the repetitions) beside them, and every comparison is a ratio against a baseline
// measured in the same run.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <functional>
#include <string>
#include <vector>

namespace bench {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// Median, smallest and largest of the repetitions, in seconds per call.
struct Timing {
  double median = NAN, min = NAN, max = NAN;
  int repetitions = 0;
  long calls_per_repetition = 0;
};

inline double median_of(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Times `call`: a first call sizes the batch; then `repetitions` batches of calls, each at least
/// `min_batch_s` long. When one call is longer than that, the first call is itself the first
/// repetition (one call per batch), and a call longer than `long_call_s` is repeated at most
/// twice more (3 repetitions), one longer than 10·long_call_s not at all (1 repetition), so
/// that slow cases stay within the run's budget.
template <class F>
Timing time_calls(F&& call, int repetitions, double min_batch_s = 0.05, double long_call_s = 2.0) {
  const auto t0 = Clock::now();
  call();
  const double first = seconds_since(t0);
  Timing t;
  std::vector<double> per_call;
  t.calls_per_repetition = first >= min_batch_s ? 1 : static_cast<long>(std::ceil(min_batch_s / std::max(first, 1e-9)));
  t.repetitions = first > 10 * long_call_s ? 1 : first > long_call_s ? std::min(repetitions, 3) : repetitions;
  if (first >= min_batch_s) per_call.push_back(first);
  for (int r = static_cast<int>(per_call.size()); r < t.repetitions; ++r) {
    const auto t1 = Clock::now();
    for (long c = 0; c < t.calls_per_repetition; ++c) call();
    per_call.push_back(seconds_since(t1) / static_cast<double>(t.calls_per_repetition));
  }
  t.median = median_of(per_call);
  t.min = *std::min_element(per_call.begin(), per_call.end());
  t.max = *std::max_element(per_call.begin(), per_call.end());
  return t;
}

/// A CSV file with a fixed header; a field holding a comma or a quote is quoted (RFC 4180).
class Csv {
 public:
  Csv(const std::string& path, const std::string& header) : f_(std::fopen(path.c_str(), "w")) {
    if (f_) std::fprintf(f_, "%s\n", header.c_str());
  }
  ~Csv() {
    if (f_) std::fclose(f_);
  }
  Csv(const Csv&) = delete;
  Csv& operator=(const Csv&) = delete;
  bool ok() const { return f_ != nullptr; }
  void row(const std::vector<std::string>& fields) {
    for (std::size_t i = 0; i < fields.size(); ++i) {
      std::string v = fields[i];
      if (v.find_first_of(",\"\n") != std::string::npos) {
        std::string q = "\"";
        for (char c : v) q += c == '"' ? std::string("\"\"") : std::string(1, c);
        v = q + "\"";
      }
      std::fprintf(f_, "%s%s", i ? "," : "", v.c_str());
    }
    std::fprintf(f_, "\n");
    std::fflush(f_);
  }

 private:
  std::FILE* f_;
};

inline std::string num(double x) {
  if (std::isnan(x)) return "nan";
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", x);
  return b;
}

/// "10,30,100" → {10, 30, 100} (command-line size lists); empty items are skipped.
inline std::vector<int> parse_int_list(const std::string& text) {
  std::vector<int> v;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    if (end > start) v.push_back(std::stoi(text.substr(start, end - start)));
    start = end + 1;
  }
  return v;
}

// ---- engines against our kernels, interleaved (bench/engines_bench.cpp, bench/urdf_engines.cpp) --

/// This thread's CPU time [s]. The kernels and the engines compute on one thread without waiting,
/// so its CPU time is their time without the intervals in which the shared machine ran something
/// else on this core (wall-clock medians were off by factors at load 6 on 2 cores).
inline double thread_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// A timed quantity: `run(calls)` makes `calls` calls, cycling through the states.
struct Timed {
  std::string engine, quantity;
  std::function<void(long)> run;
  double agreement = 0;  ///< against the reference, where the caller keeps it here
  std::size_t ops = 0;   ///< our kernel's operation count, where known
  Timing t;
};

/// Sizes a batch of each to at least min_batch_s, then times `repetitions` batches of each in
/// round robin, in thread CPU time; per call, the median and spread of the batches.
inline void time_interleaved(std::vector<Timed>& timed, int repetitions, double min_batch_s) {
  std::vector<std::vector<double>> per_call(timed.size());
  for (Timed& x : timed) {
    // A cold first call (the 30-link chain's kernels are 0.6 MB of code) or one interruption must
    // not size the batch: a warm-up call, then the faster of two tries of each batch size.
    x.run(1);
    long calls = 1;
    for (;;) {
      double s = INFINITY;
      for (int attempt = 0; attempt < 2; ++attempt) {
        const double t0 = thread_seconds();
        x.run(calls);
        s = std::min(s, thread_seconds() - t0);
      }
      if (s >= min_batch_s / 4 || calls > (1L << 30)) {
        x.t.calls_per_repetition =
            std::max(1L, static_cast<long>(std::ceil(static_cast<double>(calls) * min_batch_s / std::max(s, 1e-9))));
        break;
      }
      calls *= 4;
    }
    x.t.repetitions = repetitions;
  }
  for (int rep = 0; rep < repetitions; ++rep)
    for (std::size_t i = 0; i < timed.size(); ++i) {
      const double t0 = thread_seconds();
      timed[i].run(timed[i].t.calls_per_repetition);
      per_call[i].push_back((thread_seconds() - t0) / static_cast<double>(timed[i].t.calls_per_repetition));
    }
  for (std::size_t i = 0; i < timed.size(); ++i) {
    timed[i].t.median = median_of(per_call[i]);
    timed[i].t.min = *std::min_element(per_call[i].begin(), per_call[i].end());
    timed[i].t.max = *std::max_element(per_call[i].begin(), per_call[i].end());
  }
}

}  // namespace bench
