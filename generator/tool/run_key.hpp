// The keys of `mbsgen run`'s cache entries and what they are made of (the toolchain, the
// generator's identity, the sensitivity asked for). Shared by the `mbsgen` launcher, which starts
// a cached solver without loading the generator, and by mbsgen-core, which builds the entries:
// both must compute the same key from the same request. No GiNaC here.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace mbsgen::tool {

namespace fs = std::filesystem;

/// The compiler and where the runtime's headers and libraries are: beside an installed mbsgen
/// (<prefix>/bin, <prefix>/lib, <prefix>/include), otherwise in the build tree it was built in.
/// Each entry is one argument of the compiler: nothing passes through a shell.
struct Toolchain {
  std::string compiler;
  std::vector<std::string> includes, libraries;
};
Toolchain toolchain();

/// `mbsgen run MODEL [--scene NAME] [--compiled] [--debug] [-- ARGS...]` (argv[1] is "run").
struct RunRequest {
  std::string model_file, scene = "full";
  bool compiled = false, debug = false, help = false;
  std::vector<std::string> args;  // the solver's
  std::string error;              // a usage error, when not empty
};
RunRequest parse_run(int argc, char** argv);

/// The program that generates and builds (mbsgen-core), beside the running one.
fs::path core_program();
/// The generic tape solver: mbsgen-tape beside the running program (installed), else the one of
/// the build tree.
fs::path tape_solver();

/// `modes|frf --sensitivity [NAME,…]` of the full model: the parameters asked for (empty: all),
/// for a solver with the sensitivity kernel by exactly those (issue 40 §2: made only when asked,
/// and cached as its own entry); nullopt when no sensitivity is asked for, or for a scene (whose
/// analyses say whether it has them).
std::optional<std::vector<std::string>> sensitivity_request(const std::string& scene,
                                                            const std::vector<std::string>& args);

/// The key of a model's tape (the model file's text, the scene, the generator).
std::string tape_key(const std::string& text, const std::string& scene);
/// The key of a model's compiled solver: also the compiler, the runtime's headers and libraries
/// (with their size and time: a library rebuilt in place makes a new key) and the options.
std::string solver_key(const std::string& text, const std::string& scene, bool dynamics, bool debug,
                       const std::optional<std::vector<std::string>>& sensitivity, const Toolchain& tc);
/// The name of a key's entry directory: its FNV-1a hash in 16 hexadecimal digits.
std::string hex_key(const std::string& key);

/// The model's id from a cache entry (an entry written before ids were recorded: the file's stem).
std::string entry_id(const fs::path& dir, const std::string& model_file);

}  // namespace mbsgen::tool
