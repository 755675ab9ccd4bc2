// The mbsgen command: check, info and generate a model; `mbsgen linear` analyses raw matrices.
// Exit codes: 0 success, 1 a bad model or failed analysis, 2 a usage error.
#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/codegen/emit_api.hpp"
#include "mbsgen/generator/codegen/emit_tape.hpp"
#include "mbsgen/generator/codegen/output_files.hpp"
#include "mbsgen/generator/linear/operating_point_check.hpp"
#include "mbsgen/generator/model/scene.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include <CLI/CLI.hpp>

#include "cache.hpp"
#include "progress.hpp"
#include "run.hpp"
#include "run_key.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#ifdef MBSGEN_HAVE_LINEAR_CLI
namespace mbsgen::cli {
int linear_main(int argc, char** argv);
}
#endif

namespace {

// `model` is the scene's pruned model; `scenes` the scenes of the model file.
// Closed loops: the constraint equations kept and dropped, and the independent coordinates.
void print_loops(const mbsgen::Model& model, const mbsgen::LoopClosure& loops) {
  if (!loops.active) return;
  auto names = [&](const std::vector<std::size_t>& v) {
    std::string s;
    for (std::size_t k : v) s += " " + model.coordinates()[k].name;
    return s;
  };
  std::cout << "closed loops: " << loops.equations.size() << " constraint equations in "
            << model.coordinates().size() << " coordinates\n";
  std::cout << "  independent coordinates (" << (loops.chosen ? "chosen by mbsgen: column-pivoted QR of the "
                                                              "constraint Jacobian at the operating point"
                                                            : "listed in the model")
            << "):" << names(loops.independent) << "\n  dependent coordinates:" << names(loops.dependent) << "\n";
  std::cout << "  equations:";
  for (const auto& e : loops.equations) std::cout << " " << e.constraint << (e.component.empty() ? "" : "." + e.component);
  std::cout << "\n";
  for (const auto& [e, why] : loops.dropped)
    std::cout << "  dropped " << e.constraint << (e.component.empty() ? "" : "." + e.component) << ": " << why << "\n";
  if (loops.redundant) std::cout << "  the reaction forces are not unique (redundant constraints)\n";
}

// Nonholonomic constraints (rolling wheels, velocity constraints): their equations, the
// independent speeds and those that follow, and the reduced second-order form's coordinates.
void print_nonholonomic(const mbsgen::Model& model, const mbsgen::Nonholonomic& nh, const mbsgen::LinearEquations& lin) {
  if (!nh.active) return;
  auto names = [&](const std::vector<std::size_t>& v) {
    std::string s;
    for (std::size_t k : v) s += " " + model.coordinates()[k].name + "_dot";
    return s.empty() ? std::string(" (none)") : s;
  };
  std::cout << "nonholonomic constraints: " << nh.equations.size() << " velocity equations\n  equations:";
  for (const auto& e : nh.equations) std::cout << " " << e.constraint << (e.component.empty() ? "" : "." + e.component);
  std::cout << "\n  independent speeds ("
            << (nh.chosen ? "chosen by mbsgen: column-pivoted QR of the constraints' speed matrix at the operating point"
                          : "listed in the model")
            << "):" << names(nh.speeds) << "\n  dependent speeds:" << names(nh.dependent_speeds) << "\n";
  if (!lin.descriptor) return;
  std::cout << "  linear model: descriptor E x' = A x in (independent coordinates, independent speeds)\n";
  std::cout << "  reduced second-order form: ";
  if (!lin.reduced.exists) {
    std::cout << "none (the coordinates are coupled to the speeds beyond a closed block)\n";
    return;
  }
  std::cout << lin.reduced.coordinates.size() << " coordinates:";
  for (std::size_t k : lin.reduced.coordinates) std::cout << " " << model.coordinates()[k].name;
  std::cout << "\n";
}

int print_info(const mbsgen::Model& model, const std::vector<mbsgen::Scene>& scenes,
               const mbsgen::Equations& eq, const mbsgen::LinearEquations& lin, const mbsgen::GeneratedCode& code,
               double seconds) {
  const mbsgen::SceneSelection& scene = model.selection();
  std::cout << "model " << model.name() << "\n";
  std::cout << "scenes: full (implicit)";
  for (const auto& s : scenes) std::cout << ", " << s.name;
  std::cout << "\nscene " << scene.name << (scene.description.empty() ? "" : ": " + scene.description)
            << "\n  analyses:";
  for (auto a : scene.analyses) std::cout << " " << mbsgen::to_string(a);
  std::cout << "\n  effects:\n";
  for (const auto& e : scene.effects)
    std::cout << "    " << (e.active ? "on  " : "off ") << e.name << " (" << e.category << ")"
              << (e.note.empty() ? "" : ": " + e.note) << "\n";
  std::cout << "  structure: D " << (lin.D_zero ? "zero" : "nonzero") << ", G "
            << (lin.G_zero ? "zero" : "nonzero") << ", N " << (lin.N_zero ? "zero" : "nonzero") << "\n";
  std::cout << "  exact zeros: " << lin.zeros.everywhere << " everywhere, " << lin.zeros.at_operating_point
            << " at the operating point, " << lin.zeros.unproved << " candidates unproved (manifest: sparsity)\n";
  std::cout << "bodies (" << model.bodies().size() << "):";
  for (const auto& b : model.bodies()) std::cout << " " << b.name << "<-" << b.parent;
  std::cout << "\ncoordinates (" << model.coordinates().size() << "):";
  for (const auto& c : model.coordinates()) std::cout << " " << c.name;
  std::cout << "\n";
  print_loops(model, eq.loops);
  print_nonholonomic(model, eq.nonholonomic, lin);
  std::cout << "inputs (" << model.inputs().size() << "):";
  for (const auto& i : model.inputs()) std::cout << " " << i.name << (i.motion ? " (motion)" : "");
  std::cout << "\noutputs (" << model.outputs().size() << "):";
  for (const auto& o : model.outputs()) std::cout << " " << o.name;
  std::cout << "\nparameters (" << model.parameters().size() << ")\n";
  std::cout << "kernels (operations, bytes of C++):\n";
  for (const auto& k : code.kernels) std::cout << "  " << k.name << " " << k.operations << " " << k.bytes << "\n";
  // What this scene could have but was not asked for (issue 40 §2: kernels on demand).
  std::vector<std::string> absent;
  for (const char* k : {"dynamics", "dynamics_jacobian", "sensitivity"})
    if (std::none_of(code.kernels.begin(), code.kernels.end(), [&](const auto& x) { return x.name == k; }))
      absent.push_back(k);
  if (model.selection().full && !absent.empty()) {
    std::cout << "not emitted unless asked for:";
    for (const auto& k : absent)
      std::cout << " " << k << (k == "sensitivity" ? " (--sensitivity; a tape derives it by forward mode)" : " (--dynamics)");
    std::cout << "\n";
  }
  std::cout << "generation time: " << seconds << " s\n";
  return 0;
}

// mbsgen run MODEL [--scene NAME] [-- ARGS...]
int run_command(int argc, char** argv) {
  const char* usage =
      "usage: mbsgen run MODEL [--scene NAME] [--compiled] [--debug] -- "
      "info|modes|frf|static|sweep|matrices|simulate|study|outputs|fit [ARGS...]\n"
      "  generates and caches the model's kernels, then runs the solver with ARGS: info, modes, frf, static,\n"
      "  sweep, matrices, outputs and fit evaluate the kernels from a tape, without a compiler; simulate, study, a\n"
      "  model with closed loops and --compiled compile and cache the solver first (--debug: with the\n"
      "  runtime's debug information, for a debugger)\n"
      "  (the solver's options: mbsgen run MODEL -- --help; the cache: mbsgen cache --help)\n";
  const mbsgen::tool::RunRequest r = mbsgen::tool::parse_run(argc, argv);
  if (r.help) {
    std::cout << usage;
    return 0;
  }
  if (!r.error.empty()) {
    std::cerr << "mbsgen run: " << r.error << "\n" << usage;
    return 2;
  }
  try {
    return mbsgen::tool::run_main(r.model_file, r.scene, r.args, r.compiled, r.debug);
  } catch (const mbsgen::ModelError& e) {
    std::cerr << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "mbsgen run: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) try {
#ifdef MBSGEN_HAVE_LINEAR_CLI
  if (argc >= 2 && std::strcmp(argv[1], "linear") == 0) return mbsgen::cli::linear_main(argc - 1, argv + 1);
#endif
  if (argc >= 2 && std::strcmp(argv[1], "run") == 0) return run_command(argc, argv);
  CLI::App app{"mbsgen: symbolic-to-numeric code generator for multibody systems"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("mbsgen ") + mbsgen::kGeneratorVersion, "print the version and exit");
  std::string model_file, out_dir, scene = "full", id;
  bool no_cse = false, dynamics = false, sensitivity = false, tape = false;
  std::vector<std::string> sensitivity_parameters;
  std::size_t parts = 0;
  std::size_t part_operations = 5000;
  auto* check = app.add_subcommand("check", "read and validate a model file (and its operating point)");
  check->add_option("MODEL", model_file, "model file (YAML)")->required();
  auto* info = app.add_subcommand("info", "scenes, effects, kernels and operation counts");
  info->add_option("MODEL", model_file, "model file (YAML)")->required();
  info->add_option("--scene", scene, "scene to describe (default: the full model)");
  auto* generate = app.add_subcommand("generate", "emit C++ kernels and a JSON manifest");
  generate->add_option("MODEL", model_file, "model file (YAML)")->required();
  generate->add_option("--out", out_dir, "output directory")->required();
  generate->add_option("--scene", scene, "scene to generate (default: the full model)");
  generate->add_option("--id", id, "C identifier prefix of the kernels (default: the model name, "
                                   "MODEL_SCENE for a scene)");
  generate->add_flag("--no-cse", no_cse, "skip common-subexpression elimination");
  generate->add_flag("--dynamics", dynamics,
                     "also emit the kernels of a time step (the solver's simulate): dynamics(y, yd, u, p, M, r), "
                     "M and k - q in one kernel sharing their work, and dynamics_jacobian(y, yd, ydd, u, p, Ky, Kv)");
  generate->add_flag("--sensitivity", sensitivity,
                     "also emit the sensitivity kernel of the full model: the derivatives of the linear matrices by "
                     "every parameter (what modes/frf --sensitivity need; a scene asks with its analyses)");
  generate->add_option("--sensitivity-parameters", sensitivity_parameters,
                       "the sensitivity kernel by these parameters only (comma-separated; implies --sensitivity)")
      ->delimiter(',');
  generate->add_flag("--tape", tape,
                     "also write ID.tape, the kernels as a tape that a program evaluates without a compiler "
                     "(mbsgen::TapeModel; not for a model with closed loops)");
  generate->add_option("--parts", parts,
                       "also write ID_part1.cpp … ID_partN.cpp holding the long kernels' parts, to compile in "
                       "parallel (default 0: all in ID.cpp)")
      ->check(CLI::Range(0, 64));
  generate->add_option("--part-operations", part_operations,
                       "operations per part of a long kernel, one longer than 4 times this (default 5000; 0: no kernel is cut, as before issue 17)")
      ->check(CLI::Range(std::size_t{0}, std::size_t{10000000}));
  auto* tape_cmd = app.add_subcommand("tape", "make sure a model's tape is cached (as mbsgen run makes it) and print its path");
  tape_cmd->add_option("MODEL", model_file, "model file (YAML)")->required();
  tape_cmd->add_option("--scene", scene, "scene (default: the full model)");
  auto* kernels_cmd = app.add_subcommand("kernels", "make sure a model's kernels are cached, compiled as a shared library, and print its path");
  kernels_cmd->add_option("MODEL", model_file, "model file (YAML)")->required();
  kernels_cmd->add_option("--scene", scene, "scene (default: the full model)");
  app.add_subcommand("linear", "modes and frequency responses of raw matrices (mbsgen linear --help)");
  app.add_subcommand("run", "generate, compile, cache and run a model's solver (mbsgen run --help)");
  auto* cache = app.add_subcommand("cache", "list, describe or clean the cache of mbsgen run");
  cache->require_subcommand(1);
  auto* cache_list = cache->add_subcommand("list", "every entry: kind, size, last use, model, scene, options");
  auto* cache_info = cache->add_subcommand("info", "where the cache is, its entries, size and limit");
  auto* cache_clean = cache->add_subcommand(
      "clean", "remove entries not in use: all of them, or those chosen by --older-than and --max-size");
  std::string older_than, max_size;
  bool dry_run = false;
  cache_clean->add_option("--older-than", older_than, "entries last used longer ago than this (30d, 12h, 90m, 45s, 2w)");
  cache_clean->add_option("--max-size", max_size,
                          "then the least recently used until the cache is within this size (500M, 2G; binary units)");
  cache_clean->add_flag("--dry-run", dry_run, "say what would be removed, remove nothing");
  (void)cache_list;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (*tape_cmd || *kernels_cmd) {
    try {
      return *tape_cmd ? mbsgen::tool::tape_main(model_file, scene) : mbsgen::tool::kernels_main(model_file, scene);
    } catch (const mbsgen::ModelError& e) {
      std::cerr << e.what() << "\n";
      return 1;
    } catch (const std::exception& e) {
      std::cerr << "mbsgen " << (*tape_cmd ? "tape" : "kernels") << ": error: " << e.what() << "\n";
      return 1;
    }
  }
  if (*cache) {
    if (*cache_info) return mbsgen::tool::cache_info();
    if (!*cache_clean) return mbsgen::tool::cache_list();
    std::optional<double> age;
    std::optional<std::uintmax_t> size;
    try {
      if (!older_than.empty()) age = mbsgen::tool::parse_duration(older_than, "--older-than");
      if (!max_size.empty()) size = mbsgen::tool::parse_size(max_size, "--max-size");
    } catch (const std::invalid_argument& e) {
      std::cerr << "mbsgen cache clean: " << e.what() << "\n";
      return 2;
    }
    return mbsgen::tool::cache_clean(age, size, dry_run);
  }
  if (*generate && !id.empty() && !mbsgen::id_problem(id).empty()) {
    std::cerr << "mbsgen generate: --id '" << id << "' " << mbsgen::id_problem(id) << "\n";
    return 2;
  }
  try {
    auto t0 = std::chrono::steady_clock::now();
    mbsgen::tool::Progress progress(*check ? "check" : *info ? "info" : "generate");
    mbsgen::Model model = mbsgen::read_model_file(model_file);
    mbsgen::Model pruned = mbsgen::apply_scene(model, scene);
    if (sensitivity || !sensitivity_parameters.empty()) pruned.request_sensitivity(sensitivity_parameters);
    mbsgen::EmitOptions options;
    options.cse = !no_cse;
    options.dynamics = dynamics;
    options.parts = parts;
    options.chunk_operations = part_operations;
    options.source_file = model_file;
    options.id = id;
    // The kernels that need only the derivation, on the second core while this one linearizes.
    mbsgen::KernelsAhead ahead;
    if (!*check) ahead = progress.paused([&] { return mbsgen::emit_ahead(pruned, options); });
    progress.stage("deriving the equations");
    mbsgen::Equations& eq = mbsgen::tool::kept_until_exit<mbsgen::Equations>([&] { return mbsgen::derive(pruned); });
    for (const auto& [e, why] : eq.loops.dropped)
      if (eq.loops.redundant && why.rfind("redundant", 0) == 0)
        std::cerr << "mbsgen: warning: constraint '" << e.constraint << "'"
                  << (e.component.empty() ? "" : " (" + e.component + ")") << " dropped: " << why << "\n";
    progress.stage("linearizing");
    mbsgen::LinearEquations& lin =
        mbsgen::tool::kept_until_exit<mbsgen::LinearEquations>([&] { return mbsgen::linearize(eq); });
    progress.stage("checking the operating point");
    mbsgen::check_operating_point(eq, lin);
    progress.stage("emitting the kernels");
    if (*check) {
      progress.stop();
      std::cout << model_file << ": ok (" << model.bodies().size() << " bodies, "
                << model.coordinates().size() << " coordinates)\n";
      return 0;
    }
    mbsgen::GeneratedCode code = mbsgen::emit(pruned, eq, lin, options, &ahead);
    progress.stop();
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (*info) return print_info(pruned, model.scenes(), eq, lin, code, seconds);
    const auto& range = pruned.selection().frequency_range;
    const double from = range ? range->from_hz : 0.0, to = range ? range->to_hz : 0.0;
    const int points = range ? range->points : 0;
    const bool linear_spacing = range ? !range->logarithmic : false;
    std::vector<mbsgen::OutputFile> files = mbsgen::generated_files(code, out_dir);
    for (auto& f : mbsgen::api_files(mbsgen::emit_api(pruned, lin, code, scene, from, to, points, linear_spacing), out_dir))
      files.push_back(std::move(f));
    if (tape) {
      std::string text = mbsgen::emit_tape(pruned, lin, code, scene, from, to, points, linear_spacing);
      if (text.empty()) {
        std::cerr << "mbsgen generate: --tape: model '" << model.name()
                  << "' has closed loops, whose kernels only compiled code evaluates; nothing was written\n";
        return 2;
      }
      files.push_back({std::filesystem::path(out_dir) / (code.id + ".tape"), std::move(text)});
    }
    mbsgen::write_files(files);
    std::cerr << "mbsgen: wrote " << out_dir << "/" << code.id << (tape ? "{.hpp,.cpp,.json,.tape,_model.hpp,_model.cpp}" : "{.hpp,.cpp,.json,_model.hpp,_model.cpp}")
              << (code.parts.empty() ? "" : " and " + std::to_string(code.parts.size()) + " part files") << " in " << seconds
              << " s\n";
    return 0;
  } catch (const mbsgen::ModelError& e) {
    std::cerr << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "mbsgen: error: " << e.what() << "\n";
    return 1;
  }
} catch (const std::exception& e) {  // anywhere else, `mbsgen linear` and `mbsgen run` included
  std::cerr << "mbsgen: error: " << e.what() << "\n";
  return 1;
}
