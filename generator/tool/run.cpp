// `mbsgen run MODEL [--scene NAME] -- ARGS`: generate, compile and cache a model's solver, then
// run it with ARGS (docs/cli.md "Model solvers"). The solver is cached under a content hash of
// the model file, the scene, the generator version, the compile command and the size and time of
// the libraries it links, so a second run starts at once and any edit of the model (or rebuild of
// the runtime) rebuilds it. Nothing is written outside the cache.
#include "run.hpp"

#include "cache.hpp"
#include "progress.hpp"
#include "run_key.hpp"

#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/codegen/emit_api.hpp"
#include "mbsgen/generator/codegen/emit_tape.hpp"
#include "mbsgen/generator/codegen/output_files.hpp"
#include "mbsgen/generator/linear/operating_point_check.hpp"
#include "mbsgen/generator/model/scene.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"
#include "mbsgen_build_config.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>
#include <system_error>
#include <thread>

extern char** environ;


namespace mbsgen::tool {

namespace fs = std::filesystem;

#ifdef MBSGEN_RUN_AVAILABLE
namespace {

// Starts argv[0] (searched on PATH when it has no '/') with argv, its standard output and error
// going to log (created exclusively); returns its process id. The child leads a process group of
// its own, so that stopping it stops what it started (the compiler driver's cc1plus).
pid_t spawn_program(const std::vector<std::string>& args, const fs::path& log) {
  const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) throw std::runtime_error("cannot create " + log.string() + ": " + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fd, STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, fd, STDERR_FILENO);
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attributes, 0);
  pid_t pid = 0;
  const int error = ::posix_spawnp(&pid, argv[0], &actions, &attributes, argv.data(), environ);
  posix_spawnattr_destroy(&attributes);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fd);
  if (error != 0) throw std::runtime_error("cannot run " + args[0] + ": " + std::strerror(error));
  return pid;
}

// The exit status of a process that ended with status; -1 when it was killed.
int exit_status(int status) { return WIFEXITED(status) ? WEXITSTATUS(status) : -1; }

// A termination signal (SIGTERM, SIGHUP, SIGINT) received while the solver is built: the
// compilers are stopped and the private build directory removed (build_solver) instead of being
// left running and half-written. Without SA_RESTART, waitpid returns EINTR when it arrives.
volatile sig_atomic_t g_termination = 0;
extern "C" void on_termination(int signal) { g_termination = signal; }

class TerminationGuard {
 public:
  TerminationGuard() {
    struct sigaction action {};
    action.sa_handler = on_termination;
    sigemptyset(&action.sa_mask);
    for (std::size_t i = 0; i < 3; ++i) ::sigaction(kSignals[i], &action, &previous_[i]);
  }
  ~TerminationGuard() {
    for (std::size_t i = 0; i < 3; ++i) ::sigaction(kSignals[i], &previous_[i], nullptr);
  }
  TerminationGuard(const TerminationGuard&) = delete;
  TerminationGuard& operator=(const TerminationGuard&) = delete;

 private:
  static constexpr int kSignals[3] = {SIGTERM, SIGHUP, SIGINT};
  struct sigaction previous_[3] {};
};

// Thrown once the children are stopped; the exit status is 128 + the signal (run_main).
struct Terminated : std::runtime_error {
  int signal;
  explicit Terminated(int s) : std::runtime_error(std::string("stopped by signal ") + std::to_string(s)), signal(s) {}
};

// After a termination signal: stops the running children and their process groups, waits for
// them, throws Terminated.
void stop_if_terminated(const std::vector<pid_t>& running) {
  const int signal = g_termination;
  if (signal == 0) return;
  for (pid_t pid : running) ::kill(-pid, SIGTERM);
  for (pid_t pid : running) {
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  throw Terminated(signal);
}

// One compiler run and where its messages go.
struct Job {
  std::vector<std::string> args;
  fs::path log;
};

// Runs the jobs, at most `parallel` at a time, in order, reporting "k of n files" to progress.
// Returns the jobs that failed (after every started one has ended; none is started after a
// failure).
std::vector<std::size_t> run_jobs(const std::vector<Job>& jobs, std::size_t parallel, Progress& progress) {
  std::vector<std::pair<pid_t, std::size_t>> running;
  std::vector<std::size_t> failed;
  std::size_t next = 0, done = 0;
  auto report = [&] { progress.detail(std::to_string(done) + " of " + std::to_string(jobs.size()) + " files"); };
  report();
  auto pids = [&] {
    std::vector<pid_t> p;
    for (const auto& r : running) p.push_back(r.first);
    return p;
  };
  while (next < jobs.size() || !running.empty()) {
    stop_if_terminated(pids());
    while (failed.empty() && next < jobs.size() && running.size() < parallel) {
      running.push_back({spawn_program(jobs[next].args, jobs[next].log), next});
      ++next;
    }
    if (running.empty()) break;
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(std::string("waiting for the compiler: ") + std::strerror(errno));
    }
    const auto it = std::find_if(running.begin(), running.end(), [&](const auto& r) { return r.first == pid; });
    if (it == running.end()) continue;  // not one of ours
    if (exit_status(status) != 0) failed.push_back(it->second);
    running.erase(it);
    ++done;
    report();
  }
  return failed;
}

// How many compilers run at once: MBSGEN_JOBS when set (1 to 64), else the number of cores.
std::size_t parallel_jobs() {
  if (const char* j = std::getenv("MBSGEN_JOBS"); j && *j) {
    char* end = nullptr;
    const long n = std::strtol(j, &end, 10);
    if (*end != '\0' || n < 1 || n > 64)
      throw std::runtime_error(std::string("MBSGEN_JOBS must be a number from 1 to 64, not '") + j + "'");
    return static_cast<std::size_t>(n);
  }
  return std::max(1u, std::thread::hardware_concurrency());
}

// The optimisation level of the part files (docs/generator.md, "Compiling large models"): -O2 up
// to kPartsO2MaxOperations operations in all kernels, -O1 above. Measured on the spatial chains
// (parts against parts, same run): at 20 coordinates -O2's mass matrix is 1.4× faster for 1.3×
// the compile time, at 40 its linear kernel 1.26× faster for 1.1×; at 60 coordinates (164,000
// operations) the two run alike and -O2 takes 1.2× the compile time.
constexpr std::size_t kPartsO2MaxOperations = 100000;

const char* parts_level(const GeneratedCode& code) {
  std::size_t operations = 0;
  for (const auto& k : code.kernels)
    if (k.name != "linear_structured") operations += k.operations;  // it calls linear
  return operations <= kPartsO2MaxOperations ? "-O2" : "-O1";
}

// The compiler runs that build the solver in work: the kernels' part files first (the longest),
// then the kernels, the typed API and main, each to an object file; the link is separate. The
// part files hold only long straight-line arithmetic: -O1 compiles them faster than -O2, and
// for large models runs as fast (parts_level); the rest takes -O2.
std::vector<Job> compile_jobs(const Toolchain& tc, const fs::path& work, const GeneratedCode& code,
                              std::vector<fs::path>& objects, bool shared = false) {
  std::vector<std::pair<std::string, const char*>> units;
  const char* const parts = parts_level(code);
  for (std::size_t k = 0; k < code.parts.size(); ++k)
    if (code.parts[k].find("namespace") != std::string::npos)  // not an empty part
      units.push_back({"model_part" + std::to_string(k + 1), parts});
  for (const char* u : {"model", "model_model", "main"}) units.push_back({u, "-O2"});
  std::vector<Job> jobs;
  for (const auto& [unit, level] : units) {
    std::vector<std::string> args = {tc.compiler, level, "-std=c++17", "-c"};
    if (shared) args.insert(args.end(), {"-fPIC", "-ffunction-sections", "-fdata-sections"});
    args.insert(args.end(), tc.includes.begin(), tc.includes.end());
    objects.push_back(work / (unit + ".o"));
    args.insert(args.end(), {"-I" + work.string(), (work / (unit + ".cpp")).string(), "-o", objects.back().string()});
    jobs.push_back({args, work / ("compile-" + unit + ".log")});
  }
  return jobs;
}

// Runs the link command; removes the objects when it succeeded.
bool link_objects(const std::vector<std::string>& link, const fs::path& work, const std::vector<fs::path>& objects,
                  Progress& progress, const char* what) {
  const fs::path log = work / "link.log";
  int status = 0;
  stop_if_terminated({});
  const pid_t pid = spawn_program(link, log);
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return false;
    stop_if_terminated({pid});
  }
  if (exit_status(status) == 0) {
    std::error_code ec;
    for (const auto& o : objects) fs::remove(o, ec);
    return true;
  }
  progress.stop();
  std::cerr << "mbsgen run: error: linking " << what << " failed; see " << log.string() << "\n";
  return false;
}

// Compiles and links the solver in work; false (with a message naming the log) when the
// compiler failed. The solver is linked without the runtime libraries' debug information unless
// `debug` (issue 45: 219 MB of the double pendulum's solver were debug information, 2 MB code); the
// object files are removed once it is linked.
bool compile_solver(const Toolchain& tc, const fs::path& work, const GeneratedCode& code, std::size_t parallel,
                    bool debug, Progress& progress) {
  std::vector<fs::path> objects;
  const std::vector<Job> jobs = compile_jobs(tc, work, code, objects);
  progress.stage("compiling the solver");
  const std::vector<std::size_t> failed = run_jobs(jobs, parallel, progress);
  if (failed.empty()) {
    progress.stage("linking the solver");
    std::vector<std::string> link = {tc.compiler};
    for (const auto& o : objects) link.push_back(o.string());
    link.insert(link.end(), {"-o", (work / "solve").string()});
    link.insert(link.end(), tc.libraries.begin(), tc.libraries.end());
    if (!debug) link.push_back("-Wl,--strip-debug");
    return link_objects(link, work, objects, progress, "the solver");
  }
  progress.stop();
  std::cerr << "mbsgen run: error: compiling the solver failed; see " << jobs[failed.front()].log.string() << "\n";
  return false;
}

// Compiles the kernels, their parts and the typed API's kernels() into the shared library
// work/kernels (issue 41: what the Python package loads for a model without a tape, or when asked
// for compiled kernels). main.cpp exports one function, mbsgen_model_kernels(); the link keeps only
// it (a version script) and what it reaches (--gc-sections), so the typed API's functions that
// call the runtime are dropped and the library needs nothing but libc, libm and libstdc++.
bool compile_kernels(const Toolchain& tc, const fs::path& work, const GeneratedCode& code, std::size_t parallel,
                     Progress& progress) {
  std::vector<fs::path> objects;
  const std::vector<Job> jobs = compile_jobs(tc, work, code, objects, true);
  progress.stage("compiling the kernels");
  const std::vector<std::size_t> failed = run_jobs(jobs, parallel, progress);
  if (failed.empty()) {
    progress.stage("linking the kernels");
    std::vector<std::string> link = {tc.compiler, "-shared"};
    for (const auto& o : objects) link.push_back(o.string());
    link.insert(link.end(), {"-o", (work / "kernels").string(), "-Wl,--version-script=" + (work / "exports.map").string(),
                             "-Wl,--gc-sections", "-Wl,--strip-debug", "-Wl,-z,defs", "-lm"});
    return link_objects(link, work, objects, progress, "the kernels");
  }
  progress.stop();
  std::cerr << "mbsgen run: error: compiling the kernels failed; see " << jobs[failed.front()].log.string() << "\n";
  return false;
}


// The model of a cache entry derived, linearized, checked and emitted (with id "model").
struct Emitted {
  GeneratedCode code;
  GeneratedApi api;
  std::string tape;  // empty: closed loops
  std::string id;    // the model's id (Model's rule: an identifier)
};

// A model derived and linearized for a cache entry. The last one is kept: a run that derives a
// model for its tape and finds closed loops (which only compiled code evaluates) emits its
// solver from the same derivation.
struct Derivation {
  std::string key;
  Model model;  // the scene's, with the sensitivity asked for
  Equations* eq;
  LinearEquations* lin;
};

// The derivation of model_file's scene; `ahead` starts the kernels that need only the derivation
// on the second core (for options) when it derives.
Derivation& derivation(const std::string& model_file, const std::string& scene,
                       const std::optional<std::vector<std::string>>& sensitivity, const EmitOptions& options,
                       KernelsAhead& ahead, Progress& progress) {
  static auto* last = new std::optional<Derivation>;  // (never destroyed: see kept_until_exit)
  std::string key = model_file + '\0' + scene + '\0' + (sensitivity ? "s" : "-");
  if (sensitivity)
    for (const auto& name : *sensitivity) key += ',' + name;
  if (*last && (*last)->key == key) return **last;
  Model model = apply_scene(read_model_file(model_file), scene);  // ModelError for a scene the file lacks
  if (sensitivity) model.request_sensitivity(*sensitivity);
  ahead = progress.paused([&] { return emit_ahead(model, options); });
  progress.stage("deriving the equations");
  Equations& eq = kept_until_exit<Equations>([&] { return derive(model); });
  progress.stage("linearizing");
  LinearEquations& lin = kept_until_exit<LinearEquations>([&] { return linearize(eq); });
  progress.stage("checking the operating point");
  check_operating_point(eq, lin);
  *last = Derivation{key, std::move(model), &eq, &lin};
  return **last;
}

Emitted emit_model(const std::string& model_file, const std::string& scene, bool dynamics,
                   const std::optional<std::vector<std::string>>& sensitivity, std::size_t parts, Progress& progress) {
  EmitOptions options;
  options.scene = scene;
  options.source_file = model_file;
  options.id = "model";
  options.parts = parts;
  if (parts == 0) options.chunk_operations = 0;  // a tape: nothing is compiled, no kernel is cut
  options.dynamics = dynamics;
  options.solver_only = true;  // bodies and linear_structured: for the C API, never the solver's
  KernelsAhead ahead;
  Derivation& d = derivation(model_file, scene, sensitivity, options, ahead, progress);
  // A model with rolling constraints has no second-order form: its solver refuses `simulate`.
  if (d.eq->nonholonomic.active) options.dynamics = false;
  progress.stage("emitting the kernels");
  Emitted e;
  e.code = emit(d.model, *d.eq, *d.lin, options, &ahead);
  const auto& range = d.model.selection().frequency_range;
  const double from = range ? range->from_hz : 0.0, to = range ? range->to_hz : 0.0;
  const int points = range ? range->points : 0;
  const bool linear_spacing = range ? !range->logarithmic : false;
  e.api = emit_api(d.model, *d.lin, e.code, scene, from, to, points, linear_spacing);
  e.tape = emit_tape(d.model, *d.lin, e.code, scene, from, to, points, linear_spacing);
  e.id = d.model.name();
  return e;
}

// A private directory (mkdtemp) beside the cache entry dir, filled by fill and renamed to dir
// when complete, so that neither a concurrent nor an interrupted run leaves a half-built entry;
// false when fill returned false (nothing is left behind). The entry is locked (lock) before it
// is renamed into place, so that no eviction takes it before this run uses it; when another run
// won the race, its entry stands and lock stays empty.
template <class Fill>
bool make_entry(const fs::path& dir, std::optional<EntryLock>& lock, Fill&& fill) {
  std::string name = dir.string() + ".tmp-XXXXXX";
  if (!::mkdtemp(name.data()))
    throw std::runtime_error("cannot create a directory beside " + dir.string() + ": " + std::strerror(errno));
  const fs::path work = name;
  bool made = false;
  try {
    made = fill(work);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(work, ec);
    throw;
  }
  std::error_code ec;
  if (!made) {
    fs::remove_all(work, ec);
    return false;
  }
  lock = EntryLock::shared(work);
  fs::rename(work, dir, ec);  // fails if another run won the race: then use its entry
  if (ec) {
    lock.reset();
    fs::remove_all(work, ec);
  }
  return true;
}

// Generates and compiles the solver of model_file into the cache entry dir (make_entry).
// Returns false when the compiler failed. The kernels are split into 2 parts per compiler run at
// once (EmitOptions::parts), compiled in parallel.
bool build_solver(const std::string& model_file, const std::string& scene, bool dynamics,
                  const std::optional<std::vector<std::string>>& sensitivity, bool debug, const std::string& text,
                  const Toolchain& tc, const fs::path& dir, std::optional<EntryLock>& lock, Progress& progress) {
  const std::size_t parallel = parallel_jobs();
  const Emitted e = emit_model(model_file, scene, dynamics, sensitivity, 2 * parallel, progress);
  return make_entry(dir, lock, [&](const fs::path& work) {
    write_generated(e.code, e.api, work.string());
    write_files({{work / "main.cpp",
                  "#include \"model_model.hpp\"\n#include \"mbsgen/runtime/cli/solver_cli.hpp\"\n"
                  "int main(int argc, char** argv) { return mbsgen::cli::solver_main(model::kernels(), argc, argv); }\n"},
                 {work / "model.yaml", text},  // the model this solver was made from, for reference
                 // The model's id: the solver's name is `<id>-solve` whatever the file is called,
                 // as the generated code's (issue 39 §3).
                 {work / "id", e.id}});
    std::string options = dynamics ? "dynamics" : "";
    if (sensitivity) {
      options += std::string(options.empty() ? "" : " ") + "sensitivity=";
      for (std::size_t i = 0; i < sensitivity->size(); ++i) options += (i ? "," : "") + (*sensitivity)[i];
    }
    if (debug) options += std::string(options.empty() ? "" : " ") + "debug";
    describe_entry(work, model_file, scene, "solver", options);
    if (!compile_solver(tc, work, e.code, parallel, debug, progress)) return false;
    write_files({{work / "solve.sum", artifact_record(work / "solve")}});  // last: the entry is complete
    return true;
  });
}

// Compiles model_file's kernels into the shared library "kernels" of the cache entry dir
// (compile_kernels), for programs that load them (the Python package).
bool build_kernels(const std::string& model_file, const std::string& scene, const std::string& text, const Toolchain& tc,
                   const fs::path& dir, std::optional<EntryLock>& lock, Progress& progress) {
  const std::size_t parallel = parallel_jobs();
  const Emitted e = emit_model(model_file, scene, false, std::nullopt, 2 * parallel, progress);
  return make_entry(dir, lock, [&](const fs::path& work) {
    write_generated(e.code, e.api, work.string());
    write_files({{work / "main.cpp",
                  "#include \"model_model.hpp\"\n"
                  "extern \"C\" const mbsgen::ModelKernels* mbsgen_model_kernels() { return &model::kernels(); }\n"},
                 {work / "exports.map", "{ global: mbsgen_model_kernels; local: *; };\n"},
                 {work / "model.yaml", text},
                 {work / "id", e.id}});
    describe_entry(work, model_file, scene, "kernels", "");
    if (!compile_kernels(tc, work, e.code, parallel, progress)) return false;
    write_files({{work / "kernels.sum", artifact_record(work / "kernels")}});  // last: the entry is complete
    return true;
  });
}

// Generates the tape of model_file into the cache entry dir (make_entry): the file "tape", empty
// for a model with closed loops (which only a compiled solver evaluates).
void build_tape(const std::string& model_file, const std::string& scene, const std::string& text, const fs::path& dir,
                std::optional<EntryLock>& lock, Progress& progress) {
  // A joint or distance constraint closes a loop: known without deriving (rolling contacts may or
  // may not leave a holonomic condition, which only the derivation tells).
  const Model model = apply_scene(read_model_file(model_file), scene);
  const bool loops = std::any_of(model.constraints().begin(), model.constraints().end(),
                                 [](const Constraint& c) { return c.kind != ConstraintKind::rolling; });
  // (The tape's sensitivities come by forward mode, model/tape.hpp: no symbolic kernel is asked for.)
  const Emitted e = loops ? Emitted{} : emit_model(model_file, scene, false, std::nullopt, 0, progress);
  make_entry(dir, lock, [&](const fs::path& work) {
    write_files({{work / "tape", e.tape}, {work / "model.yaml", text}, {work / "id", e.id}});
    describe_entry(work, model_file, scene, "tape", loops ? "closed loops: no tape" : "");
    write_files({{work / "tape.sum", artifact_record(work / "tape")}});  // last: the entry is complete
    return true;
  });
}

}  // namespace
#endif  // MBSGEN_RUN_AVAILABLE

#ifdef MBSGEN_RUN_AVAILABLE
namespace {

// The cache entry of key: a private directory of the cache, by the key's hash.
fs::path entry_dir(const std::string& key) {
  const fs::path root = cache_root();
  ensure_private_directory(root);
  return root / hex_key(key);
}

// Makes the cache entry dir hold a sound artifact ("solve", the compiled solver, or "tape"),
// locked (cache.hpp: held until the program this process becomes ends) and marked as used: kept
// when it is sound, else reported when damaged and made by build(), which returns 0 or the exit
// status to end with (returned). After a build the cache is brought within its limit.
template <class Build>
int ensure_entry(const fs::path& dir, const std::string& artifact, const std::string& model_file,
                 std::optional<EntryLock>& lock, Build&& build) {
  const std::string noun = artifact == "solve" ? "solver" : artifact;
  std::string why;
  lock = EntryLock::shared(dir);
  if (lock && sound_artifact(dir, artifact, why)) {
    touch_entry(dir);
    return 0;
  }
  lock.reset();
  if (!why.empty()) {
    std::cerr << "mbsgen run: the cached " << noun << " " << dir.string() << " is damaged (" << why << "): rebuilding it\n";
    discard_entry(dir);
  }
  const auto t0 = std::chrono::steady_clock::now();
  if (const int status = build()) return status;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (::isatty(STDERR_FILENO))
    std::cerr << "mbsgen run: " << (artifact == "solve" ? "built" : "generated") << " the " << noun << " of "
              << model_file << " in " << std::setprecision(3) << seconds << " s\n";
  why.clear();
  // Locked from its birth (make_entry), or another run's entry that won the race.
  if (!lock) lock = EntryLock::shared(dir);
  if (!lock || !sound_artifact(dir, artifact, why))
    throw std::runtime_error("the " + noun + " just made in " + dir.string() + " is not sound (" +
                             (why.empty() ? "it was removed meanwhile" : why) + ")");
  enforce_cache_limit(dir);
  return 0;
}

// Replaces this process with program, given arguments first and then args; returns (1) only
// when it cannot.
int exec_program(const fs::path& program, std::string name, std::vector<std::string> given,
                 std::vector<std::string>& args) {
  std::vector<char*> argv{name.data()};
  for (auto& a : given) argv.push_back(a.data());
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  ::execv(program.c_str(), argv.data());
  std::cerr << "mbsgen run: error: cannot execute " << program.string() << ": " << std::strerror(errno) << "\n";
  return 1;
}

// Runs args on the model's tape (issue 40 §1: no compiler), generating and caching it first;
// nullopt when the model has no tape (closed loops): then a compiled solver answers.
// Makes sure model_file's tape is in its cache entry dir (generating it first; `command` names the
// progress line), the entry locked by `lock`; 0, or the build's exit status.
int ensure_tape(const std::string& model_file, const std::string& scene, const std::string& text, const char* command,
                fs::path& dir, std::optional<EntryLock>& lock) {
  dir = entry_dir(tape_key(text, scene));
  return ensure_entry(dir, "tape", model_file, lock, [&] {
    Progress progress(command);
    build_tape(model_file, scene, text, dir, lock, progress);
    return 0;
  });
}

// Whether the tape entry dir holds a tape: an empty one stands for a model with closed loops.
bool holds_tape(const fs::path& dir) {
  std::error_code ec;
  return !(fs::file_size(dir / "tape", ec) == 0 && !ec);
}

std::optional<int> run_tape(const std::string& model_file, const std::string& scene, std::vector<std::string>& args,
                            const std::string& text) {
  fs::path dir;
  std::optional<EntryLock> lock;
  if (const int status = ensure_tape(model_file, scene, text, "run", dir, lock)) return status;
  if (!holds_tape(dir)) return std::nullopt;  // closed loops
  const fs::path solver = tape_solver();
  return exec_program(solver, solver.string(), {(dir / "tape").string()}, args);
}

}  // namespace
#endif  // MBSGEN_RUN_AVAILABLE

int tape_main(const std::string& model_file, const std::string& scene) {
#ifndef MBSGEN_RUN_AVAILABLE
  (void)model_file, (void)scene;
  std::cerr << "mbsgen tape: this mbsgen was built without the runtime (MBSGEN_BUILD_RUNTIME=OFF)\n";
  return 1;
#else
  const std::string text = read_model_text(model_file);  // throws: reported by the caller, exit 1
  cache_limit();
  fs::path dir;
  std::optional<EntryLock> lock;
  if (const int status = ensure_tape(model_file, scene, text, "tape", dir, lock)) return status;
  if (!holds_tape(dir)) {
    std::cerr << "mbsgen tape: " << model_file << " has closed loops, whose kernels only compiled code evaluates: no tape\n";
    return 3;
  }
  std::cout << (dir / "tape").string() << "\n";
  return 0;
#endif
}

int kernels_main(const std::string& model_file, const std::string& scene) {
#ifndef MBSGEN_RUN_AVAILABLE
  (void)model_file, (void)scene;
  std::cerr << "mbsgen kernels: this mbsgen was built without the runtime (MBSGEN_BUILD_RUNTIME=OFF)\n";
  return 1;
#else
  const std::string text = read_model_text(model_file);  // throws: reported by the caller, exit 1
  cache_limit();
  const Toolchain tc = toolchain();
  const fs::path dir = entry_dir(solver_key(text, scene, false, false, std::nullopt, tc) + '\0' + "shared kernels");
  std::optional<EntryLock> lock;
  if (const int status = ensure_entry(dir, "kernels", model_file, lock, [&] {
        try {
          TerminationGuard guard;
          Progress progress("kernels");
          return build_kernels(model_file, scene, text, tc, dir, lock, progress) ? 0 : 1;
        } catch (const Terminated& t) {
          std::cerr << "mbsgen kernels: " << t.what() << "; the kernels were not built\n";
          return 128 + t.signal;
        }
      }))
    return status;
  std::cout << (dir / "kernels").string() << "\n";
  return 0;
#endif
}

int run_main(const std::string& model_file, const std::string& scene, std::vector<std::string> args, bool compiled,
             bool debug) {
#ifndef MBSGEN_RUN_AVAILABLE
  (void)model_file, (void)scene, (void)args, (void)compiled, (void)debug;
  std::cerr << "mbsgen run: this mbsgen was built without the runtime (MBSGEN_BUILD_RUNTIME=OFF)\n";
  return 1;
#else
  const std::string text = read_model_text(model_file);  // throws: reported by the caller, exit 1
  cache_limit();  // a malformed MBSGEN_CACHE_MAX_SIZE is reported before any work
  const std::optional<std::vector<std::string>> sensitivity = sensitivity_request(scene, args);
  if (sensitivity && !sensitivity->empty()) {  // an unknown name is a usage error, as the solver's
    try {
      read_model_file(model_file).request_sensitivity(*sensitivity);
    } catch (const std::invalid_argument& e) {
      std::cerr << "mbsgen run: " << args[0] << " --" << e.what() << "\n";
      return 2;
    }
  }
  // The tape answers a one-off analysis; a compiled solver what runs the kernels many times
  // (simulate, study) and what is asked for with --compiled.
  const bool many_calls = !args.empty() && (args[0] == "simulate" || args[0] == "study");
  if (!compiled && !debug && !many_calls) {
    if (const std::optional<int> status = run_tape(model_file, scene, args, text)) return *status;
  }
  const Toolchain tc = toolchain();
  // `simulate` needs the kernels of a time step (EmitOptions::dynamics: the dynamics Jacobian);
  // the other commands' solver is built without them, as they cost compile time.
  const bool dynamics = !args.empty() && args[0] == "simulate" && scene == "full";
  const fs::path dir = entry_dir(solver_key(text, scene, dynamics, debug, sensitivity, tc));
  std::optional<EntryLock> lock;
  if (const int status = ensure_entry(dir, "solve", model_file, lock, [&] {
        try {
          TerminationGuard guard;
          Progress progress("run");  // on a terminal, after 2 s: the stage, and files compiled
          return build_solver(model_file, scene, dynamics, sensitivity, debug, text, tc, dir, lock, progress) ? 0 : 1;
        } catch (const Terminated& t) {  // the children stopped, the build directory removed
          std::cerr << "mbsgen run: " << t.what() << "; the solver was not built\n";
          return 128 + t.signal;
        }
      }))
    return status;
  return exec_program(dir / "solve", entry_id(dir, model_file) + "-solve", {}, args);
#endif
}

}  // namespace mbsgen::tool
