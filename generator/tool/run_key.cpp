// The keys of `mbsgen run`'s cache entries (run_key.hpp).
#include "run_key.hpp"

#include "cache.hpp"
#include "mbsgen/generator/codegen/version.hpp"
#include "mbsgen_build_config.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <system_error>

namespace mbsgen::tool {

namespace {

std::uint64_t fnv1a(const std::string& s, std::uint64_t h = 1469598103934665603ULL) {
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ULL;
  return h;
}

// Words of a build-configuration string (flags and paths without spaces, as CMake wrote them).
std::vector<std::string> words(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

fs::path running_program() {
  std::error_code ec;
  return fs::read_symlink("/proc/self/exe", ec);
}

// The part of a key that names the generator: mbsgen-core's path, size and time of modification
// (a generator rebuilt in place makes new entries).
std::string generator_identity() {
  const fs::path core = core_program();
  std::string key = std::string(1, '\0') + core.string();
  std::error_code ec;
  const auto size = fs::file_size(core, ec);
  const auto time = fs::last_write_time(core, ec);
  if (!ec) key += '\0' + std::to_string(size) + '\0' + std::to_string(time.time_since_epoch().count());
  return key;
}

}  // namespace

#ifdef MBSGEN_RUN_AVAILABLE
Toolchain toolchain() {
  Toolchain t;
  t.compiler = MBSGEN_CXX_COMPILER;
  const fs::path exe = running_program();
  const fs::path prefix = exe.empty() ? fs::path() : exe.parent_path().parent_path();
  const fs::path installed_solver = prefix / MBSGEN_INSTALL_LIBDIR / MBSGEN_SOLVER_LIBRARY_NAME;
  std::error_code ec;
  if (!prefix.empty() && fs::exists(installed_solver, ec) &&
      fs::exists(prefix / "include/mbsgen/runtime/cli/solver_cli.hpp", ec)) {
    t.includes = {"-I" + (prefix / "include").string()};
    t.libraries = {installed_solver.string(),
                   (prefix / MBSGEN_INSTALL_LIBDIR / MBSGEN_RUNTIME_LIBRARY_NAME).string()};
  } else {
    t.includes = {std::string("-I") + MBSGEN_BUILD_RUNTIME_INCLUDE};
    t.libraries = {MBSGEN_BUILD_SOLVER_LIBRARY, MBSGEN_BUILD_RUNTIME_LIBRARY};
  }
  for (auto& w : words(MBSGEN_EXTRA_INCLUDES)) t.includes.push_back(w);
  for (auto& w : words(MBSGEN_EXTRA_LIBRARIES)) t.libraries.push_back(w);
  return t;
}

fs::path tape_solver() {
  std::error_code ec;
  fs::path solver = running_program().parent_path() / MBSGEN_TAPE_SOLVER_NAME;
  if (!fs::is_regular_file(solver, ec)) solver = MBSGEN_BUILD_TAPE_SOLVER;
  return solver;
}
#endif

RunRequest parse_run(int argc, char** argv) {
  RunRequest r;
  int i = 2;
  for (; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--") {
      ++i;
      break;
    }
    if (a == "-h" || a == "--help") {
      r.help = true;
      return r;
    }
    if (a == "--compiled") {
      r.compiled = true;
    } else if (a == "--debug") {
      r.debug = true;
    } else if (a == "--scene" && i + 1 < argc) {
      r.scene = argv[++i];
    } else if (a.rfind("--scene=", 0) == 0) {
      r.scene = a.substr(8);
    } else if (!a.empty() && a[0] != '-' && r.model_file.empty()) {
      r.model_file = a;
    } else {
      r.error = "unexpected argument '" + a + "'";
      return r;
    }
  }
  r.args.assign(argv + i, argv + argc);
  if (r.model_file.empty()) r.error = "missing MODEL";
  return r;
}

fs::path core_program() { return running_program().parent_path() / "mbsgen-core"; }

std::optional<std::vector<std::string>> sensitivity_request(const std::string& scene,
                                                            const std::vector<std::string>& args) {
  if (scene != "full" || args.empty() || (args[0] != "modes" && args[0] != "frf")) return std::nullopt;
  for (std::size_t i = 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a != "--sensitivity" && a.rfind("--sensitivity=", 0) != 0) continue;
    std::vector<std::string> names;
    auto add = [&names](const std::string& text) {
      std::stringstream list(text);
      for (std::string name; std::getline(list, name, ',');)
        if (!name.empty()) names.push_back(name);
    };
    if (a.size() > 13) add(a.substr(14));
    else
      for (std::size_t j = i + 1; j < args.size() && (args[j].empty() || args[j][0] != '-'); ++j) add(args[j]);
    std::sort(names.begin(), names.end());  // one cache entry per set of parameters
    names.erase(std::unique(names.begin(), names.end()), names.end());
    return names;
  }
  return std::nullopt;
}

std::string tape_key(const std::string& text, const std::string& scene) {
  return text + '\0' + scene + '\0' + kGeneratorVersion + '\0' + "tape" + generator_identity();
}

std::string solver_key(const std::string& text, const std::string& scene, bool dynamics, bool debug,
                       const std::optional<std::vector<std::string>>& sensitivity, const Toolchain& tc) {
  std::string key = text + '\0' + scene + '\0' + kGeneratorVersion + '\0' + tc.compiler;
  if (dynamics) key += std::string(1, '\0') + "dynamics";
  if (debug) key += std::string(1, '\0') + "debug";
  if (sensitivity) {
    key += std::string(1, '\0') + "sensitivity";
    for (const auto& name : *sensitivity) key += ',' + name;
  }
  for (const auto& a : tc.includes) key += '\0' + a;
  // A library or generator rebuilt in place (a developer's build tree) makes a new key: their size
  // and time of modification are part of it, so a solver is never linked against an older runtime
  // nor built from kernels an older generator wrote.
  for (const auto& a : tc.libraries) {
    key += '\0' + a;
    std::error_code ec;
    const auto size = fs::file_size(a, ec);
    const auto time = fs::last_write_time(a, ec);
    if (!ec) key += '\0' + std::to_string(size) + '\0' + std::to_string(time.time_since_epoch().count());
  }
  return key + '\0' + std::string("/proc/self/exe") + generator_identity();
}

std::string hex_key(const std::string& key) {
  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(fnv1a(key)));
  return hash;
}

std::string entry_id(const fs::path& dir, const std::string& model_file) {
  std::string id = fs::path(model_file).stem().string();
  if (std::error_code ec; fs::is_regular_file(dir / "id", ec)) {
    const std::string recorded = read_file(dir / "id");
    if (!recorded.empty() && recorded.size() < 256) id = recorded;
  }
  return id;
}

}  // namespace mbsgen::tool
