// A deterministic stand-in for libFuzzer's main(), buildable with any C++17 compiler, for the test
// suite: it feeds LLVMFuzzerTestOneInput (from fuzz_model_reader.cpp or fuzz_expression.cpp)
// every seed input, then inputs derived from them by simple mutations drawn from a fixed-seed
// std::mt19937 (byte flips, interesting bytes, truncations, line duplications, deletions and
// swaps, repeated chunks, dictionary tokens, splices), until a count or a time budget runs out.
//
//   smoke_driver [--seed N] [--mutations N] [--max-seconds S] [--timeout S] [--dict FILE]
//                [--lines FILE]... [FILE | DIR]...
//
// DIR contributes its regular files (sorted by name, recursively); --lines FILE contributes each
// non-empty line of FILE that does not start with '#'. An exception escaping the target, a
// crash, an abort or an input running longer than --timeout seconds fails the run: the input is
// written to fuzz-smoke-failure-N (or fuzz-smoke-crash) in the working directory, to be
// minimised and kept under tests/data/fuzz_regressions/ (docs/testing.md).
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <typeinfo>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__)
#define MBSGEN_SMOKE_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MBSGEN_SMOKE_ASAN 1
#endif
#endif
#ifdef MBSGEN_SMOKE_ASAN
#include <sanitizer/common_interface_defs.h>
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

namespace fs = std::filesystem;

struct Input {
  std::string name;
  std::string bytes;
};

// What is running now, for the signal handlers (which may only use async-signal-safe calls).
char g_current_name[512] = "";
const std::string* g_current_bytes = nullptr;

void write_stderr(const char* s) {
  const ssize_t n = ::write(2, s, std::strlen(s));
  (void)n;
}

// Writes the running input to `file` and says so on stderr (async-signal-safe).
void save_current(const char* file) {
  write_stderr("fuzz smoke: while running ");
  write_stderr(g_current_name);
  write_stderr("\n");
  if (!g_current_bytes) return;
  const int fd = ::open(file, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) return;
  const ssize_t n = ::write(fd, g_current_bytes->data(), g_current_bytes->size());
  (void)n;
  ::close(fd);
  write_stderr("fuzz smoke: input written to ");
  write_stderr(file);
  write_stderr("\n");
}

extern "C" void on_fatal_signal(int sig) {
  write_stderr(sig == SIGALRM ? "fuzz smoke: TIMEOUT (an input ran longer than --timeout)\n"
                              : "fuzz smoke: CRASH (fatal signal)\n");
  save_current("fuzz-smoke-crash");
  if (sig == SIGALRM) ::_exit(1);
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

#ifdef MBSGEN_SMOKE_ASAN
extern "C" void on_sanitizer_death() { save_current("fuzz-smoke-crash"); }
#endif

void install_handlers() {
  // An alternate stack, so that a stack overflow still reaches the handler.
  static std::vector<char> alt_stack(1 << 16);
  stack_t ss{};
  ss.ss_sp = alt_stack.data();
  ss.ss_size = alt_stack.size();
  sigaltstack(&ss, nullptr);
  struct sigaction sa {};
  sa.sa_handler = on_fatal_signal;
  sa.sa_flags = SA_ONSTACK;
  sigemptyset(&sa.sa_mask);
  std::vector<int> signals = {SIGABRT, SIGALRM};
#ifdef MBSGEN_SMOKE_ASAN
  // AddressSanitizer reports SEGV, stack overflow and the rest itself; add the input to its report.
  __sanitizer_set_death_callback(on_sanitizer_death);
#else
  signals.insert(signals.end(), {SIGSEGV, SIGBUS, SIGFPE, SIGILL});
#endif
  for (int s : signals) sigaction(s, &sa, nullptr);
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + p.string());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A libFuzzer dictionary: lines `name="value"` or `"value"` with \\, \" and \xNN escapes.
std::vector<std::string> read_dictionary(const fs::path& p) {
  std::vector<std::string> out;
  std::istringstream lines(read_file(p));
  std::string line;
  while (std::getline(lines, line)) {
    const std::size_t open = line.find('"');
    const std::size_t close = line.rfind('"');
    if (line.empty() || line[0] == '#' || open == std::string::npos || close <= open) continue;
    std::string v;
    for (std::size_t i = open + 1; i < close; ++i) {
      if (line[i] == '\\' && i + 1 < close) {
        ++i;
        if (line[i] == 'x' && i + 2 < close) {
          v += static_cast<char>(std::stoi(line.substr(i + 1, 2), nullptr, 16));
          i += 2;
        } else {
          v += line[i];
        }
      } else {
        v += line[i];
      }
    }
    if (!v.empty()) out.push_back(v);
  }
  return out;
}

std::vector<std::string> split_lines(const std::string& s) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start < s.size()) {
    std::size_t end = s.find('\n', start);
    if (end == std::string::npos) end = s.size();
    out.push_back(s.substr(start, end - start + (end < s.size() ? 1 : 0)));
    start = end + 1;
  }
  return out;
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += l;
  return out;
}

class Mutator {
 public:
  Mutator(std::uint32_t seed, std::vector<std::string> dictionary)
      : rng_(seed), dictionary_(std::move(dictionary)) {}

  // An index below n (n > 0); raw engine output, so the sequence is the same on every platform.
  std::size_t below(std::size_t n) { return static_cast<std::size_t>(rng_() % n); }

  std::string mutate(const std::vector<Input>& corpus, std::string s, std::string& how) {
    const std::size_t count = 1 + below(3);
    for (std::size_t k = 0; k < count; ++k) {
      const std::size_t kind = below(10);
      how += (how.empty() ? "" : "+") + std::string(kNames[kind]);
      apply(kind, corpus, s);
      if (s.size() > kMaxSize) s.resize(kMaxSize);
    }
    return s;
  }

 private:
  static constexpr std::size_t kMaxSize = 1 << 16;
  static constexpr const char* kNames[10] = {"flip",   "byte",  "truncate", "dup-line", "del-line",
                                             "swap",   "token", "repeat",   "splice",   "erase"};

  void apply(std::size_t kind, const std::vector<Input>& corpus, std::string& s) {
    static const std::string interesting = "{}[]:,-'\"#&*!|>%@\n\t ()^./+eE0912_\\?";
    switch (kind) {
      case 0:  // flip one bit
        if (!s.empty()) s[below(s.size())] ^= static_cast<char>(1u << below(8));
        return;
      case 1:  // an interesting byte
        if (!s.empty()) s[below(s.size())] = interesting[below(interesting.size())];
        return;
      case 2:  // truncate
        s.resize(below(s.size() + 1));
        return;
      case 3:
      case 4:
      case 5: {  // duplicate, delete or swap lines
        std::vector<std::string> lines = split_lines(s);
        if (lines.empty()) return;
        const std::size_t i = below(lines.size());
        if (kind == 3) lines.insert(lines.begin() + static_cast<long>(i), lines[i]);
        if (kind == 4) lines.erase(lines.begin() + static_cast<long>(i));
        if (kind == 5) std::swap(lines[i], lines[below(lines.size())]);
        s = join_lines(lines);
        return;
      }
      case 6:  // a dictionary token
        if (!dictionary_.empty()) s.insert(below(s.size() + 1), dictionary_[below(dictionary_.size())]);
        return;
      case 7: {  // a short chunk repeated (deep nesting, long runs)
        if (s.empty()) return;
        const std::size_t at = below(s.size());
        const std::string chunk = s.substr(at, 1 + below(4));
        const std::size_t times = below(4) == 0 ? 1 + below(4096) : 1 + below(32);
        std::string run;
        for (std::size_t t = 0; t < times; ++t) run += chunk;
        s.insert(at, run);
        return;
      }
      case 8: {  // splice: a prefix of this input and a suffix of another
        const std::string& other = corpus[below(corpus.size())].bytes;
        s = s.substr(0, below(s.size() + 1)) + other.substr(below(other.size() + 1));
        return;
      }
      case 9: {  // erase a range
        if (s.empty()) return;
        const std::size_t at = below(s.size());
        s.erase(at, 1 + below(16));
        return;
      }
    }
  }

  std::mt19937 rng_;
  std::vector<std::string> dictionary_;
};

struct Options {
  std::uint32_t seed = 20240601;
  std::size_t mutations = 20000;
  double max_seconds = 5;
  unsigned timeout = 20;
  std::vector<std::string> dictionary;
  std::vector<Input> corpus;
};

void add_path(const fs::path& p, std::vector<Input>& corpus) {
  if (fs::is_directory(p)) {
    std::vector<fs::path> files;
    for (const auto& e : fs::recursive_directory_iterator(p))
      if (e.is_regular_file()) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const auto& f : files) corpus.push_back({f.string(), read_file(f)});
  } else {
    corpus.push_back({p.string(), read_file(p)});
  }
}

Options parse_options(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error("missing value after " + a);
      return argv[++i];
    };
    if (a == "--seed") o.seed = static_cast<std::uint32_t>(std::stoul(next()));
    else if (a == "--mutations") o.mutations = std::stoul(next());
    else if (a == "--max-seconds") o.max_seconds = std::stod(next());
    else if (a == "--timeout") o.timeout = static_cast<unsigned>(std::stoul(next()));
    else if (a == "--dict") o.dictionary = read_dictionary(next());
    else if (a == "--lines") {
      const std::string file = next();
      const std::vector<std::string> lines = split_lines(read_file(file));
      for (std::size_t k = 0; k < lines.size(); ++k) {
        std::string l = lines[k];
        if (!l.empty() && l.back() == '\n') l.pop_back();
        if (l.empty() || l[0] == '#') continue;
        o.corpus.push_back({file + ":" + std::to_string(k + 1), l});
      }
    } else if (!a.empty() && a[0] == '-') {
      throw std::runtime_error("unknown option " + a);
    } else {
      add_path(a, o.corpus);
    }
  }
  if (o.corpus.empty()) throw std::runtime_error("no inputs");
  return o;
}

// Runs one input; returns false (and saves the input) when an exception escapes the target.
bool run_one(const Input& in, unsigned timeout, std::size_t& failures) {
  std::snprintf(g_current_name, sizeof g_current_name, "%s", in.name.c_str());
  g_current_bytes = &in.bytes;
  std::string error;
  alarm(timeout);
  try {
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(in.bytes.data()), in.bytes.size());
  } catch (const std::exception& e) {
    error = std::string(typeid(e).name()) + ": " + e.what();
  } catch (...) {
    error = "an exception of unknown type";
  }
  alarm(0);
  g_current_bytes = nullptr;
  if (error.empty()) return true;
  const std::string file = "fuzz-smoke-failure-" + std::to_string(++failures);
  std::ofstream(file, std::ios::binary) << in.bytes;
  std::cerr << "fuzz smoke: FAIL: " << in.name << " raised " << error.substr(0, 2000)
            << "\n  (input written to " << file << ")\n";
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  try {
    o = parse_options(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "fuzz smoke: " << e.what() << "\n";
    return 2;
  }
  install_handlers();
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(clock::now() - start).count(); };

  std::size_t failures = 0, runs = 0;
  for (const auto& in : o.corpus) {
    run_one(in, o.timeout, failures);
    ++runs;
  }
  const double seed_seconds = elapsed();

  Mutator mutator(o.seed, o.dictionary);
  std::size_t mutations = 0;
  for (; mutations < o.mutations && elapsed() < o.max_seconds && failures < 10; ++mutations) {
    const Input& base = o.corpus[mutator.below(o.corpus.size())];
    std::string how;
    std::string bytes = mutator.mutate(o.corpus, base.bytes, how);
    Input in{base.name + " mutation " + std::to_string(mutations) + " (" + how + ")",
             std::move(bytes)};
    run_one(in, o.timeout, failures);
    ++runs;
  }
  // From here on a sanitizer report (LeakSanitizer's check at exit) concerns no single input.
  std::snprintf(g_current_name, sizeof g_current_name, "no input (the leak check at exit)");
  const double total = elapsed();
  std::printf("fuzz smoke: %zu seed inputs in %.2f s, %zu mutations (seed %u) in %.2f s, "
              "%.0f inputs/s, %zu failures\n",
              o.corpus.size(), seed_seconds, mutations, o.seed, total - seed_seconds,
              total > 0 ? static_cast<double>(runs) / total : 0.0, failures);
  return failures == 0 ? 0 : 1;
}
