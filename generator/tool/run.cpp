// `mbsgen run MODEL [--scene NAME] -- ARGS`: generate, compile and cache a model's solver, then
// run it with ARGS (docs/cli.md "Model solvers"). The solver is cached under a content hash of
// the model file, the scene, the generator version and the compile command, so a second run
// starts at once and any edit of the model rebuilds it. Nothing is written outside the cache.
#include "run.hpp"

#include "mbsgen/generator/check.hpp"
#include "mbsgen/generator/emit.hpp"
#include "mbsgen/generator/emit_api.hpp"
#include "mbsgen/generator/scene.hpp"
#include "mbsgen/generator/yaml_reader.hpp"
#include "mbsgen_build_config.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <system_error>

namespace mbsgen::tool {

namespace fs = std::filesystem;

#ifdef MBSGEN_RUN_AVAILABLE
namespace {

std::uint64_t fnv1a(const std::string& s, std::uint64_t h = 1469598103934665603ULL) {
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ULL;
  return h;
}

fs::path cache_root() {
  if (const char* d = std::getenv("MBSGEN_CACHE_DIR"); d && *d) return d;
  if (const char* d = std::getenv("XDG_CACHE_HOME"); d && *d) return fs::path(d) / "mbsgen";
  if (const char* d = std::getenv("HOME"); d && *d) return fs::path(d) / ".cache" / "mbsgen";
  return fs::temp_directory_path() / ("mbsgen-cache-" + std::to_string(::getuid()));
}

std::string shell_quote(const std::string& s) {
  std::string o = "'";
  for (char c : s) o += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return o + "'";
}

// Where the runtime's headers and libraries are: beside an installed mbsgen (<prefix>/bin,
// <prefix>/lib, <prefix>/include), otherwise in the build tree it was built in.
struct Toolchain {
  std::string compiler, includes, libraries;
};

Toolchain toolchain() {
  Toolchain t;
  t.compiler = MBSGEN_CXX_COMPILER;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  const fs::path prefix = ec ? fs::path() : exe.parent_path().parent_path();
  const fs::path installed_solver = prefix / MBSGEN_INSTALL_LIBDIR / MBSGEN_SOLVER_LIBRARY_NAME;
  if (!prefix.empty() && fs::exists(installed_solver) &&
      fs::exists(prefix / "include/mbsgen/runtime/solver_cli.hpp")) {
    t.includes = "-I" + shell_quote((prefix / "include").string());
    t.libraries = shell_quote(installed_solver.string()) + " " +
                  shell_quote((prefix / MBSGEN_INSTALL_LIBDIR / MBSGEN_RUNTIME_LIBRARY_NAME).string());
  } else {
    t.includes = "-I" + shell_quote(MBSGEN_BUILD_RUNTIME_INCLUDE);
    t.libraries = shell_quote(MBSGEN_BUILD_SOLVER_LIBRARY) + " " + shell_quote(MBSGEN_BUILD_RUNTIME_LIBRARY);
  }
  t.includes += " " MBSGEN_EXTRA_INCLUDES;
  t.libraries += " " MBSGEN_EXTRA_LIBRARIES;
  return t;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + p.string());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace
#endif  // MBSGEN_RUN_AVAILABLE

int run_main(const std::string& model_file, const std::string& scene, std::vector<std::string> args) {
#ifndef MBSGEN_RUN_AVAILABLE
  (void)model_file, (void)scene, (void)args;
  std::cerr << "mbsgen run: this mbsgen was built without the runtime (MBSGEN_BUILD_RUNTIME=OFF)\n";
  return 1;
#else
  const std::string text = read_file(model_file);  // throws: reported by the caller, exit 1
  const Toolchain tc = toolchain();
  const std::string command_base = tc.compiler + " -O2 -std=c++17 " + tc.includes;
  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx",
                static_cast<unsigned long long>(fnv1a(text + '\0' + scene + '\0' + kGeneratorVersion + '\0' +
                                                      command_base + '\0' + tc.libraries)));
  const fs::path dir = cache_root() / hash;
  const fs::path solver = dir / "solve";
  if (!fs::exists(solver)) {
    const bool terminal = ::isatty(STDERR_FILENO);
    if (terminal) std::cerr << "mbsgen run: generating and compiling the solver of " << model_file << " …" << std::flush;
    const auto t0 = std::chrono::steady_clock::now();
    const Model full = read_model_file(model_file);
    const Model model = apply_scene(full, scene);  // ModelError for a scene the file lacks
    Equations eq = derive(model);
    LinearEquations lin = linearize(eq);
    check_operating_point(eq, lin);
    EmitOptions options;
    options.scene = scene;
    options.source_file = model_file;
    options.id = "model";
    GeneratedCode code = emit(model, eq, lin, options);
    const auto& range = model.selection().frequency_range;
    GeneratedApi api = emit_api(model, lin, code, scene, range ? range->from_hz : 0.0, range ? range->to_hz : 0.0);
    // Build in a private directory, then rename: a concurrent or interrupted run never leaves
    // a half-built solver in the cache.
    fs::create_directories(dir.parent_path());
    const fs::path work = dir.parent_path() / (std::string(hash) + ".tmp-" + std::to_string(::getpid()));
    fs::remove_all(work);
    write_generated(code, work.string());
    write_api(api, work.string());
    {
      std::ofstream m(work / "main.cpp");
      m << "#include \"model_model.hpp\"\n#include \"mbsgen/runtime/solver_cli.hpp\"\n"
           "int main(int argc, char** argv) { return mbsgen::cli::solver_main(model::kernels(), argc, argv); }\n";
      std::ofstream s(work / "model.yaml");
      s << text;  // the model this solver was made from, for reference
    }
    const std::string command = command_base + " -I" + shell_quote(work.string()) + " " +
                                shell_quote((work / "model.cpp").string()) + " " +
                                shell_quote((work / "model_model.cpp").string()) + " " +
                                shell_quote((work / "main.cpp").string()) + " -o " +
                                shell_quote((work / "solve").string()) + " " + tc.libraries + " 2>" +
                                shell_quote((work / "compile.log").string());
    const int rc = std::system(command.c_str());
    if (rc != 0) {
      std::cerr << (terminal ? "\n" : "") << "mbsgen run: error: compiling the solver failed; see "
                << (work / "compile.log").string() << "\n";
      return 1;
    }
    std::error_code ec;
    fs::rename(work, dir, ec);  // fails if another run won the race: then use its solver
    if (ec) fs::remove_all(work, ec);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (terminal) std::cerr << " " << seconds << " s\n";
  }
  std::vector<char*> argv;
  std::string name = fs::path(model_file).stem().string() + "-solve";
  argv.push_back(name.data());
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  ::execv(solver.c_str(), argv.data());
  std::cerr << "mbsgen run: error: cannot execute " << solver.string() << "\n";
  return 1;
#endif
}

}  // namespace mbsgen::tool
