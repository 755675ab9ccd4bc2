// The cache of `mbsgen run` and `mbsgen cache list|info|clean` (issue 45; docs/cli.md "The
// cache"), run as a user runs them. What the command says is checked against the directory
// itself (sizes summed here, times set here), and "in use" against a lock this test takes with
// flock(2) as a running solver holds it, and against a real solver blocked on its output.
#include "mbsgen_build_config.hpp"
#include "run_process.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>

#include <algorithm>
#include <ctime>

namespace {

const fs::path kOscillator = fs::path(MBSGEN_SOURCE_DIR) / "tests/data/hostile_models/unit_backquote.yaml";
const fs::path kPendulum = fs::path(MBSGEN_SOURCE_DIR) / "models/textbook/double_pendulum.yaml";

// The entries of a cache directory (named by their 16-digit key) and anything else in it.
std::vector<fs::path> keyed(const fs::path& cache, std::vector<fs::path>* others = nullptr) {
  std::vector<fs::path> out;
  if (!fs::exists(cache)) return out;
  for (const auto& e : fs::directory_iterator(cache))
    (e.path().filename().string().size() == 16 ? out : *others).push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

std::uintmax_t bytes_under(const fs::path& dir) {
  std::uintmax_t n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) n += e.file_size();
  return n;
}

void set_age(const fs::path& p, long seconds) {
  const timespec t[2] = {{std::time(nullptr) - seconds, 0}, {std::time(nullptr) - seconds, 0}};
  ASSERT_EQ(::utimensat(AT_FDCWD, p.c_str(), t, 0), 0);
}

// A tape entry (modes) and a compiled one (--compiled modes) of the oscillator: listed with
// their kind, model file, scene and size; cleaned by age, by size and all at once; the compiled
// solver linked without debug information is a few MB (it was 219 MB).
TEST(MbsgenCache, ListInfoAndCleanDescribeTheEntries) {
  const fs::path dir = temporary_directory(), cache = dir / "cache";
  const std::map<std::string, std::string> env = {{"MBSGEN_CACHE_DIR", cache.string()}};
  Result r = run({MBSGEN_TOOL, "run", kOscillator.string(), "--", "modes"}, dir, env);
  ASSERT_EQ(r.status, 0) << r.output;
  r = run({MBSGEN_TOOL, "run", kOscillator.string(), "--compiled", "--", "modes"}, dir, env);
  ASSERT_EQ(r.status, 0) << r.output;
  std::vector<fs::path> entries = keyed(cache);
  ASSERT_EQ(entries.size(), 2u);
  const fs::path solver_entry = fs::exists(entries[0] / "solve") ? entries[0] : entries[1];
  const fs::path tape_entry = solver_entry == entries[0] ? entries[1] : entries[0];
  // No debug information (readelf, an independent reader of the file); a few MB (under the
  // sanitizers their instrumentation makes every program far larger).
  const Result sections = run({"readelf", "-S", "-W", (solver_entry / "solve").string()}, dir);
  EXPECT_NE(sections.output.find(".text"), std::string::npos) << sections.output;
  EXPECT_EQ(sections.output.find(".debug_info"), std::string::npos) << sections.output;
#ifndef __SANITIZE_ADDRESS__
  EXPECT_LT(fs::file_size(solver_entry / "solve"), 8u << 20);
#endif
  for (const auto& e : fs::directory_iterator(solver_entry)) EXPECT_NE(e.path().extension(), ".o") << e.path();

  r = run({MBSGEN_TOOL, "cache", "list"}, dir, env);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find(solver_entry.filename().string() + "  solver "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(tape_entry.filename().string() + "  tape "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("  oscillator  full  -  " + kOscillator.string() + "\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("2 entries, "), std::string::npos) << r.output;

  r = run({MBSGEN_TOOL, "cache", "info"}, dir, env);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("cache: " + cache.string() + "\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("entries: 2 (1 solvers, 1 tapes, 0 compiled kernels, 0 damaged)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("(" + std::to_string(bytes_under(cache)) + " bytes)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("limit: 4.0 GiB (the default"), std::string::npos) << r.output;

  r = run({MBSGEN_TOOL, "cache", "clean", "--dry-run"}, dir, env);
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.output.find("would remove 2 entries"), std::string::npos) << r.output;
  EXPECT_EQ(keyed(cache).size(), 2u);
  // By age: only the entry last used two days ago.
  set_age(tape_entry, 2 * 86400);
  r = run({MBSGEN_TOOL, "cache", "clean", "--older-than", "1d"}, dir, env);
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.output.find("removed 1 entries"), std::string::npos) << r.output;
  EXPECT_EQ(keyed(cache), std::vector<fs::path>{solver_entry});
  // Using an entry makes it the most recent: a run of the compiled solver touches it.
  set_age(solver_entry, 3 * 86400);
  r = run({MBSGEN_TOOL, "run", kOscillator.string(), "--compiled", "--", "modes"}, dir, env);
  ASSERT_EQ(r.status, 0) << r.output;
  r = run({MBSGEN_TOOL, "cache", "clean", "--older-than", "1h"}, dir, env);
  EXPECT_NE(r.output.find("removed 0 entries"), std::string::npos) << r.output;
  // By size: within 1 byte, nothing stays.
  r = run({MBSGEN_TOOL, "cache", "clean", "--max-size", "1"}, dir, env);
  EXPECT_NE(r.output.find("removed 1 entries"), std::string::npos) << r.output;
  std::vector<fs::path> others;
  EXPECT_TRUE(keyed(cache, &others).empty());
  EXPECT_TRUE(others.empty());
  fs::remove_all(dir);
}

// A bad size or duration is a usage error naming the option and the units; a malformed limit
// stops `mbsgen run` before any work.
TEST(MbsgenCache, BadSizesAndDurationsAreRefused) {
  const fs::path dir = temporary_directory();
  const std::map<std::string, std::string> env = {{"MBSGEN_CACHE_DIR", (dir / "cache").string()}};
  Result r = run({MBSGEN_TOOL, "cache", "clean", "--older-than", "3x"}, dir, env);
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.output, "mbsgen cache clean: --older-than '3x' is not a number ≥ 0 with a unit (s, m, h, d, w)\n");
  r = run({MBSGEN_TOOL, "cache", "clean", "--max-size", "-5G"}, dir, env);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.output.find("--max-size '-5G' is not a number ≥ 0 with a unit ((none), B, K, KiB, M"), std::string::npos)
      << r.output;
  std::map<std::string, std::string> bad = env;
  bad["MBSGEN_CACHE_MAX_SIZE"] = "lots";
  r = run({MBSGEN_TOOL, "run", kOscillator.string(), "--", "modes"}, dir, bad);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("MBSGEN_CACHE_MAX_SIZE 'lots' is not a number"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "cache"));
  fs::remove_all(dir);
}

// An entry in use is never evicted: one locked as a running solver locks it, and one whose
// solver is running (blocked on its full output pipe), are kept by `cache clean` and by the
// limit, and removed once free.
TEST(MbsgenCache, AnEntryInUseIsNotEvicted) {
  const fs::path dir = temporary_directory(), cache = dir / "cache";
  const std::map<std::string, std::string> env = {{"MBSGEN_CACHE_DIR", cache.string()}};
  Result r = run({MBSGEN_TOOL, "run", kOscillator.string(), "--", "modes"}, dir, env);
  ASSERT_EQ(r.status, 0) << r.output;
  ASSERT_EQ(keyed(cache).size(), 1u);
  const fs::path entry = keyed(cache)[0];
  {
    const int fd = ::open(entry.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::flock(fd, LOCK_SH), 0);
    r = run({MBSGEN_TOOL, "cache", "clean"}, dir, env);
    EXPECT_NE(r.output.find("removed 0 entries (0 B); 0 kept, 1 in use by a running solver (kept)"), std::string::npos)
        << r.output;
    EXPECT_TRUE(fs::exists(entry / "tape"));
    ::close(fd);
  }
  // A solver writing 20,000 lines into a pipe nobody reads yet.
  int pipe_fds[2];
  ASSERT_EQ(::pipe(pipe_fds), 0);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(pipe_fds[1], STDOUT_FILENO);
    ::close(pipe_fds[0]);
    ::close(pipe_fds[1]);
    ::setenv("MBSGEN_CACHE_DIR", cache.c_str(), 1);
    const char* argv[] = {MBSGEN_TOOL, "run", kOscillator.c_str(), "--", "frf", "--input", "F", "--output", "position",
                          "--points", "20000", "--format", "csv", nullptr};
    ::execv(MBSGEN_TOOL, const_cast<char**>(argv));
    ::_exit(127);
  }
  ::close(pipe_fds[1]);
  char first[256];
  ASSERT_GT(::read(pipe_fds[0], first, sizeof first), 0);  // it runs: the solver, past its checks
  std::map<std::string, std::string> tiny = env;
  tiny["MBSGEN_CACHE_MAX_SIZE"] = "1";
  r = run({MBSGEN_TOOL, "cache", "clean"}, dir, tiny);
  EXPECT_NE(r.output.find("1 in use by a running solver (kept)"), std::string::npos) << r.output;
  // A build under the limit of 1 byte evicts every other entry, but not this one.
  r = run({MBSGEN_TOOL, "run", kPendulum.string(), "--", "modes"}, dir, tiny);
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(entry / "tape"));
  char buffer[65536];
  std::size_t bytes = 0;
  for (ssize_t n; (n = ::read(pipe_fds[0], buffer, sizeof buffer)) > 0;) bytes += static_cast<std::size_t>(n);
  ::close(pipe_fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_GT(bytes, 65536u);  // more than a pipe holds: the solver waited for this reader
  r = run({MBSGEN_TOOL, "cache", "clean"}, dir, env);
  EXPECT_NE(r.output.find("removed 2 entries"), std::string::npos) << r.output;
  EXPECT_TRUE(keyed(cache).empty());
  fs::remove_all(dir);
}

// Runs of two models at once, four at a time, under a limit that makes every build evict every
// entry not in use: each answers right, and no half-built or half-removed directory is left.
TEST(MbsgenCache, ConcurrentRunsUnderATinyLimit) {
  const fs::path dir = temporary_directory(), cache = dir / "cache";
  const std::map<std::string, std::string> env = {{"MBSGEN_CACHE_DIR", cache.string()}, {"MBSGEN_CACHE_MAX_SIZE", "1"}};
  for (int round = 0; round < 3; ++round) {
    std::vector<std::pair<pid_t, fs::path>> running;
    for (int k = 0; k < 4; ++k) {
      const fs::path log = dir / ("log" + std::to_string(k));
      const fs::path& model = k % 2 ? kPendulum : kOscillator;
      running.push_back({start({MBSGEN_TOOL, "run", model.string(), "--", "modes"}, dir, log, env), log});
    }
    const Result clean = run({MBSGEN_TOOL, "cache", "clean"}, dir, env);
    EXPECT_EQ(clean.status, 0) << clean.output;
    for (int k = 0; k < 4; ++k) {
      const Result r = finish(running[k].first, running[k].second);
      EXPECT_EQ(r.status, 0) << r.output;
      // The oscillator's f_n = √(k/m)/2π = 1.591549 Hz (k = 100 N/m, m = 1 kg); the double
      // pendulum's first, √((g/l)(2 − √2))/2π = 0.3815261 Hz (equal masses and lengths, g = 9.81).
      EXPECT_NE(r.output.find(k % 2 ? "3.815261e-01" : "1.591549e+00"), std::string::npos) << r.output;
    }
  }
  std::vector<fs::path> others;
  EXPECT_LE(keyed(cache, &others).size(), 2u);
  EXPECT_TRUE(others.empty()) << others.front();
  fs::remove_all(dir);
}

}  // namespace
