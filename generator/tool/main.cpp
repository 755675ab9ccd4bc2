// The mbsgen command: check, info and generate a model; `mbsgen linear` analyses raw matrices.
// Exit codes: 0 success, 1 a bad model or failed analysis, 2 a usage error.
#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/codegen/emit_api.hpp"
#include "mbsgen/generator/codegen/emit_tape.hpp"
#include "mbsgen/generator/codegen/output_files.hpp"
#include "mbsgen/generator/linear/operating_point_check.hpp"
#include "mbsgen/generator/model/scene.hpp"
#include "mbsgen/generator/model/urdf_import.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include <CLI/CLI.hpp>

#include "cache.hpp"
#include "progress.hpp"
#include "run.hpp"
#include "run_key.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
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

// `mbsgen import FILE.urdf [--out MODEL.yaml] [options]`: the URDF as a model file (docs/urdf.md).
struct ImportRequest {
  std::string file, out, base = "fixed";
  std::vector<std::string> elastic, pose, outputs;
  std::vector<double> gravity{0, 0, -9.81};
  double stiffness = 1e4, damping = 10;
  bool no_inputs = false;
};

void add_import_options(CLI::App& app, ImportRequest& r) {
  app.add_option("URDF", r.file, "the robot description (.urdf)")->required();
  app.add_option("--out", r.out, "write the model here (all or nothing; never over a file mbsgen did not write); "
                                 "default: standard output");
  app.add_option("--base", r.base, "the root link fixed to the world (default, as URDF means it) or floating "
                                   "(six coordinates)")
      ->check(CLI::IsMember({"fixed", "floating"}));
  app.add_option("--gravity", r.gravity, "gravity in the world frame, m/s^2 (default 0 0 -9.81)")->expected(3);
  app.add_option("--elastic", r.elastic, "joints with a joint spring and damper (series elastic), comma-separated, "
                                         "or all")
      ->delimiter(',');
  app.add_option("--stiffness", r.stiffness, "each elastic joint's stiffness, N m/rad or N/m (default 1e4)");
  app.add_option("--damping", r.damping, "each elastic joint's damping, N m s/rad or N s/m (default 10)");
  app.add_option("--output", r.outputs, "links whose origins' position and velocity are outputs, comma-separated "
                                        "(default: the leaf links)")
      ->delimiter(',');
  app.add_option("--pose", r.pose, "joint values JOINT=VALUE,... of the pose: the operating point's guess and "
                                   "the springs' rest (default 0)")
      ->delimiter(',');
  app.add_flag("--no-inputs", r.no_inputs, "no torque (force) inputs at the joints");
}

// CLI11 splits the lists at commas; empty items ("a,,b") are dropped.
std::vector<std::string> nonempty(std::vector<std::string> v) {
  v.erase(std::remove(v.begin(), v.end(), std::string()), v.end());
  return v;
}

int import_command(const ImportRequest& r) {
  mbsgen::UrdfImportOptions o;
  o.floating_base = r.base == "floating";
  for (int k = 0; k < 3; ++k) o.gravity[k] = r.gravity[k];
  o.elastic = nonempty(r.elastic);
  o.stiffness = r.stiffness;
  o.damping = r.damping;
  o.outputs = nonempty(r.outputs);
  o.inputs = !r.no_inputs;
  for (const auto& item : nonempty(r.pose)) {
    const auto eq = item.find('=');
    std::size_t used = 0;
    double v = 0;
    try {
      if (eq == std::string::npos) throw std::invalid_argument("");
      v = std::stod(item.substr(eq + 1), &used);
    } catch (const std::exception&) {
      used = std::string::npos;
    }
    if (used != item.size() - eq - 1 || !std::isfinite(v)) {
      std::cerr << "mbsgen import: --pose: '" << item << "' is not JOINT=VALUE\n";
      return 2;
    }
    o.pose[item.substr(0, eq)] = v;
  }
  mbsgen::UrdfImport imported = mbsgen::import_urdf_file(r.file, o);
  // What the import wrote must be a model: read it as `check` would, before a byte is written.
  (void)mbsgen::read_model_string(imported.yaml, r.file + " (as imported)");
  for (const auto& n : imported.notes) std::cerr << "mbsgen import: note: " << n << "\n";
  if (r.out.empty()) {
    std::cout << imported.yaml;
    return 0;
  }
  // A model file this command wrote may have been edited since (it is meant to be read and kept):
  // replaced only when its checksum says it was not.
  std::error_code ec;
  if (std::filesystem::is_regular_file(r.out, ec)) {
    std::ifstream in(r.out, std::ios::binary);
    std::string old((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::size_t last = old.rfind("# mbsgen import checksum ");
    const bool ours = last != std::string::npos && old.compare(0, 24, "# Generated by mbsgen im") == 0;
    if (ours && mbsgen::urdf_import_checksum(old.substr(0, last)) != old.substr(last)) {
      std::cerr << "mbsgen import: refusing to overwrite " << r.out
                << ": it was edited after mbsgen import wrote it (remove it, or give another --out)\n";
      return 1;
    }
  }
  mbsgen::write_files({{r.out, imported.yaml}});
  std::cerr << "mbsgen import: wrote " << r.out << "\n";
  return 0;
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
  check->add_option("MODEL", model_file, "model file (YAML, or a robot's .urdf)")->required();
  auto* info = app.add_subcommand("info", "scenes, effects, kernels and operation counts");
  info->add_option("MODEL", model_file, "model file (YAML, or a robot's .urdf)")->required();
  info->add_option("--scene", scene, "scene to describe (default: the full model)");
  auto* generate = app.add_subcommand("generate", "emit C++ kernels and a JSON manifest");
  generate->add_option("MODEL", model_file, "model file (YAML, or a robot's .urdf)")->required();
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
  tape_cmd->add_option("MODEL", model_file, "model file (YAML, or a robot's .urdf)")->required();
  tape_cmd->add_option("--scene", scene, "scene (default: the full model)");
  auto* kernels_cmd = app.add_subcommand("kernels", "make sure a model's kernels are cached, compiled as a shared library, and print its path");
  kernels_cmd->add_option("MODEL", model_file, "model file (YAML, or a robot's .urdf)")->required();
  kernels_cmd->add_option("--scene", scene, "scene (default: the full model)");
  auto* import_cmd = app.add_subcommand("import", "a URDF robot description as an mbsgen model file (docs/urdf.md)");
  ImportRequest import_request;
  add_import_options(*import_cmd, import_request);
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
  if (*import_cmd) {
    try {
      return import_command(import_request);
    } catch (const mbsgen::UrdfOptionError& e) {
      std::cerr << "mbsgen import: " << e.what() << "\n";
      return 2;
    } catch (const mbsgen::ModelError& e) {
      std::cerr << e.what() << "\n";
      return 1;
    } catch (const std::exception& e) {
      std::cerr << "mbsgen import: error: " << e.what() << "\n";
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
    if ((*check || *info) && mbsgen::is_urdf_path(model_file))
      for (const auto& n : mbsgen::import_urdf_file(model_file).notes) std::cerr << "mbsgen: note: " << n << "\n";
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
