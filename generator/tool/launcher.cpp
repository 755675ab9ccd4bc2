// The `mbsgen` command as a user starts it: a launcher that answers `mbsgen run` from a sound
// cache entry without loading the generator, and hands every other request — and a run whose
// entry is missing, damaged or needs checking against the model (--sensitivity NAMES) — to
// mbsgen-core, the generator, beside it, with the same arguments (issue 45). Loading GiNaC, CLN
// and LAPACK took 25 ms of mbsgen's 30 ms start, more than a warm run may add to its solver.
// The request's key is the one mbsgen-core computes (run_key.hpp), and the entry is checked,
// locked and marked as used as mbsgen-core does (cache.hpp).
#include "cache.hpp"
#include "mbsgen_build_config.hpp"
#include "run_key.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

namespace {

using mbsgen::tool::EntryLock;
namespace fs = std::filesystem;

// Replaces this process with program; returns only when it cannot.
void exec_with(const fs::path& program, std::vector<std::string> argv) {
  std::vector<char*> v;
  for (auto& a : argv) v.push_back(a.data());
  v.push_back(nullptr);
  ::execv(program.c_str(), v.data());
}

#ifdef MBSGEN_RUN_AVAILABLE
// The model file's bytes, when it is a regular file mbsgen-core would read (64 MiB at most);
// nothing otherwise (mbsgen-core reports why). Opened without blocking: a FIFO is not read.
bool read_regular(const std::string& path, std::string& text) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) return false;
  struct stat st {};
  bool ok = ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size <= (off_t{64} << 20);
  char buffer[65536];
  for (ssize_t n; ok && (n = ::read(fd, buffer, sizeof buffer)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) text.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fd);
  return ok;
}

// Whether dir holds a sound `artifact`, locked (kept in lock) and marked as used.
bool cached(const fs::path& dir, const std::string& artifact, std::optional<EntryLock>& lock) {
  lock = EntryLock::shared(dir);
  std::string why;
  if (!lock || !mbsgen::tool::sound_artifact(dir, artifact, why)) return false;
  mbsgen::tool::touch_entry(dir);
  return true;
}

// `mbsgen run MODEL [--scene NAME] [--compiled] [--debug] -- ARGS` answered by the cached tape or
// solver, as mbsgen-core would choose and find it; returns when it cannot.
void run_cached(int argc, char** argv) {
  const mbsgen::tool::RunRequest r = mbsgen::tool::parse_run(argc, argv);
  if (r.help || !r.error.empty()) return;  // mbsgen-core's
  const std::string& scene = r.scene;
  const std::vector<std::string>& args = r.args;
  const bool compiled = r.compiled, debug = r.debug;
  std::string text;
  if (mbsgen::tool::sensitivity_request(scene, args) || !read_regular(r.model_file, text)) return;
  fs::path root;
  try {
    mbsgen::tool::cache_limit();  // a malformed limit is reported by mbsgen-core
    root = mbsgen::tool::cache_root();
  } catch (const std::exception&) {
    return;
  }
  struct stat st;
  if (::lstat(root.c_str(), &st) != 0 || !S_ISDIR(st.st_mode) || st.st_uid != ::getuid() || (st.st_mode & S_IWOTH))
    return;  // missing, or refused by mbsgen-core with its reason
  std::optional<EntryLock> lock;
  const bool many_calls = !args.empty() && (args[0] == "simulate" || args[0] == "study");
  if (!compiled && !debug && !many_calls) {
    const fs::path dir = root / mbsgen::tool::hex_key(mbsgen::tool::tape_key(text, scene));
    if (!cached(dir, "tape", lock)) return;
    std::error_code ec;
    if (fs::file_size(dir / "tape", ec) > 0 && !ec) {  // (empty: closed loops, a compiled solver answers)
      const fs::path solver = mbsgen::tool::tape_solver();
      std::vector<std::string> v = {solver.string(), (dir / "tape").string()};
      v.insert(v.end(), args.begin(), args.end());
      exec_with(solver, v);
      return;
    }
  }
  const bool dynamics = !args.empty() && args[0] == "simulate" && scene == "full";
  const fs::path dir = root / mbsgen::tool::hex_key(mbsgen::tool::solver_key(text, scene, dynamics, debug, std::nullopt,
                                                                             mbsgen::tool::toolchain()));
  if (!cached(dir, "solve", lock)) return;
  std::vector<std::string> v = {mbsgen::tool::entry_id(dir, r.model_file) + "-solve"};
  v.insert(v.end(), args.begin(), args.end());
  exec_with(dir / "solve", v);
}
#endif

}  // namespace

int main(int argc, char** argv) {
#ifdef MBSGEN_RUN_AVAILABLE
  if (argc >= 2 && std::strcmp(argv[1], "run") == 0) {
    try {
      run_cached(argc, argv);
    } catch (const std::exception&) {
      // mbsgen-core does it all again, and says what failed.
    }
  }
#endif
  const fs::path core = mbsgen::tool::core_program();
  exec_with(core, std::vector<std::string>(argv, argv + argc));
  std::cerr << "mbsgen: error: cannot execute " << core.string() << ": " << std::strerror(errno) << "\n";
  return 1;
}
