#include "mbsgen/runtime/solver_cli.hpp"

#include <CLI/CLI.hpp>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "bode_plot.hpp"
#include "cli_output.hpp"
#include "mbsgen/runtime/frequency_response.hpp"
#include "mbsgen/runtime/matrix_market.hpp"
#include "mbsgen/runtime/quadratic_eigen.hpp"

namespace mbsgen::cli {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

std::string unit_or(const char* const* units, Eigen::Index i, const char* fallback) {
  if (!units || !units[i] || !*units[i]) return fallback;
  return units[i];
}

struct Options {
  std::vector<std::string> set;
  std::string format = "table";
  bool shapes = false, all = false;
  std::string input, output, method = "auto", spacing = "log", on_pole = "flag", plot, out_dir;
  long points = 200;
  double from = 0, to = 0;
};

GeneratedModel configured(const ModelKernels& k, const Options& o) {
  GeneratedModel model(k);
  for (const auto& a : o.set) model.set(a);
  return model;
}

int run_info(const ModelKernels& k, const Options& o, std::ostream& out) {
  GeneratedModel model = configured(k, o);
  out << "model " << k.model << ", scene " << k.scene << " (kernels " << k.id << ", ABI "
      << k.abi_version << ")\n";
  out << "coordinates (" << k.n_coordinates << "):";
  for (int i = 0; i < k.n_coordinates; ++i) out << " " << k.coordinate_names[i];
  out << "\ninputs (" << k.n_inputs << "):";
  for (int i = 0; i < k.n_inputs; ++i) out << " " << k.input_names[i] << " [" << unit_or(k.input_units, i, "-") << "]";
  out << "\noutputs (" << k.n_outputs << "):";
  for (int i = 0; i < k.n_outputs; ++i) out << " " << k.output_names[i] << " [" << unit_or(k.output_units, i, "-") << "]";
  out << "\noperating point: " << (k.equilibrium ? "static equilibrium" : "given")
      << (k.at_rest ? ", at rest" : ", steady motion") << "\nparameters (" << k.n_parameters << "):\n";
  for (int i = 0; i < k.n_parameters; ++i)
    out << "  " << pad(k.parameter_names[i], 0) << " = " << num(model.parameters()[static_cast<std::size_t>(i)], false)
        << " " << unit_or(k.parameter_units, i, "") << "\n";
  return 0;
}

int run_modes(const ModelKernels& k, const Options& o, std::ostream& out) {
  GeneratedModel model = configured(k, o);
  const LinearModel lin = model.linear_model();
  QuadraticEigenOptions opt;
  opt.one_per_conjugate_pair = !o.all;
  QuadraticEigenSolver solver(lin.size(), opt);
  solver.compute(lin);
  ModesFormat f;
  f.format = o.format;
  f.shapes = o.shapes;
  f.coordinate_names = lin.coordinate_names();
  write_modes(out, solver, lin.size(), f);
  return 0;
}

int run_frf(const ModelKernels& k, const Options& o, std::ostream& out, std::ostream& err) {
  GeneratedModel model = configured(k, o);
  const Eigen::Index input = model.input_index(o.input), output = model.output_index(o.output);
  const LinearModel lin = model.linear_model();
  Eigen::VectorXd hz(o.points);
  for (long i = 0; i < o.points; ++i) {
    const double t = o.points == 1 ? 0.0 : static_cast<double>(i) / static_cast<double>(o.points - 1);
    hz[i] = o.spacing == "log" ? o.from * std::pow(o.to / o.from, t) : o.from + (o.to - o.from) * t;
  }
  hz[o.points - 1] = o.to;
  FrfOptions opt;
  opt.method = parse_frf_method(o.method);
  opt.on_pole = o.on_pole == "error" ? PoleHandling::raise : PoleHandling::flag;
  FrequencyResponse frf(lin, opt);
  // Progress on a terminal for long sweeps; quiet when stderr is a file or a pipe. The sweep
  // runs in chunks (the factorizations a method needs are made once, on the first chunk).
  const bool progress = o.points >= 2000 && ::isatty(STDERR_FILENO);
  FrfResult r{hz, Eigen::VectorXcd(o.points), Eigen::VectorXd(o.points), {}, FrfMethod::automatic};
  const long chunk = progress ? (o.points + 49) / 50 : o.points;
  for (long first = 0; first < o.points; first += chunk) {
    const long n = std::min(chunk, o.points - first);
    frf.compute(hz.segment(first, n) * kTwoPi, input, {output});
    r.g.segment(first, n) = frf.response().row(0).transpose();
    r.rcond.segment(first, n) = frf.rcond();
    r.flags.insert(r.flags.end(), frf.flags().begin(), frf.flags().end());
    if (progress) err << "\rfrf: " << (first + n) * 100 / o.points << " %" << std::flush;
  }
  if (progress) err << "\r          \r";
  r.method = frf.method();
  for (const auto& w : frf.warnings()) err << "warning: " << w << "\n";
  FrfTable t;
  t.format = o.format;
  t.input_json = json_string(o.input);
  t.output_json = json_string(o.output);
  t.input_label = o.input;
  t.output_label = o.output;
  write_frf(out, r, t);
  if (!o.plot.empty()) {
    BodePlot plot;
    plot.title = std::string(k.model) + " (" + k.scene + "): " + o.output + " / " + o.input;
    const std::string uo = unit_or(k.output_units, output, "1"), ui = unit_or(k.input_units, input, "1");
    plot.amplitude_label = "|" + o.output + " / " + o.input + "| [(" + uo + ")/(" + ui + ")]";
    write_bode_plot(o.plot, hz, r.g, plot);
    err << "wrote " << o.plot << "\n";
  }
  return 0;
}

int run_static(const ModelKernels& k, const Options& o, std::ostream& out) {
  GeneratedModel model = configured(k, o);
  const OperatingPoint op = model.operating_point();
  const auto names = name_list(k.coordinate_names, k.n_coordinates);
  if (o.format == "json") {
    out << "{\"equilibrium\":" << (op.equilibrium ? "true" : "false")
        << ",\"iterations\":" << op.iterations << ",\"residual_norm\":" << num(op.residual_norm, true)
        << ",\"report\":" << json_string(op.report) << ",\"coordinates\":{";
    for (std::size_t i = 0; i < names.size(); ++i)
      out << (i ? "," : "") << json_string(names[i]) << ":" << num(op.y0[static_cast<Eigen::Index>(i)], true);
    out << "},\"rates\":{";
    for (std::size_t i = 0; i < names.size(); ++i)
      out << (i ? "," : "") << json_string(names[i]) << ":" << num(op.yd0[static_cast<Eigen::Index>(i)], true);
    out << "}}\n";
    return 0;
  }
  out << pad("coordinate", 16) << pad("y0", 26) << pad("yd0", 26) << "  unit\n";
  for (std::size_t i = 0; i < names.size(); ++i)
    out << pad(names[i], 16) << pad(num(op.y0[static_cast<Eigen::Index>(i)], false), 26)
        << pad(num(op.yd0[static_cast<Eigen::Index>(i)], false), 26) << "  "
        << unit_or(k.coordinate_units, static_cast<Eigen::Index>(i), "-") << "\n";
  out << "# " << (op.equilibrium ? "static equilibrium, " : "operating point given by the model, ")
      << "residual norm " << short_num(op.residual_norm) << ", Newton iterations " << op.iterations << "\n";
  return 0;
}

void json_matrix(std::ostream& out, const Eigen::MatrixXd& A) {
  out << "[";
  for (Eigen::Index i = 0; i < A.rows(); ++i) {
    out << (i ? ",[" : "[");
    for (Eigen::Index j = 0; j < A.cols(); ++j) out << (j ? "," : "") << num(A(i, j), true);
    out << "]";
  }
  out << "]";
}

void json_names(std::ostream& out, const std::vector<std::string>& v) {
  out << "[";
  for (std::size_t i = 0; i < v.size(); ++i) out << (i ? "," : "") << json_string(v[i]);
  out << "]";
}

int run_matrices(const ModelKernels& k, const Options& o, std::ostream& out, std::ostream& err) {
  GeneratedModel model = configured(k, o);
  const LinearModel lin = model.linear_model();
  const std::pair<const char*, const Eigen::MatrixXd*> mats[] = {
      {"M", &lin.M()}, {"Q", &lin.Q()}, {"K", &lin.K()}, {"B", &lin.B()}, {"C_y", &lin.C_y()}, {"C_v", &lin.C_v()}};
  if (o.format == "mtx") {
    namespace fs = std::filesystem;
    const fs::path dir = o.out_dir.empty() ? fs::path(".") : fs::path(o.out_dir);
    fs::create_directories(dir);
    for (const auto& [name, A] : mats) {
      const fs::path target = dir / (std::string(name) + ".mtx");
      const fs::path tmp = dir / ("." + std::string(name) + ".mtx.tmp");
      write_matrix_market(tmp.string(), *A, MatrixMarketFormat::array, std::string(k.model) + " " + name);
      fs::rename(tmp, target);
      err << "wrote " << target.string() << "\n";
    }
    return 0;
  }
  out << "{\"coordinates\":";
  json_names(out, lin.coordinate_names());
  out << ",\n\"inputs\":";
  json_names(out, lin.input_names());
  out << ",\n\"outputs\":";
  json_names(out, lin.output_names());
  for (const auto& [name, A] : mats) {
    out << ",\n\"" << name << "\":";
    json_matrix(out, *A);
  }
  out << "}\n";
  return 0;
}

}  // namespace

int solver_main(const ModelKernels& k, int argc, char** argv, std::ostream& out, std::ostream& err) {
  const std::string program = argc > 0 && argv[0] ? argv[0] : std::string(k.id) + "-solve";
  CLI::App app{std::string("solver for model '") + k.model + "', scene '" + k.scene +
               "': modes, frequency responses, static equilibrium and matrices"};
  app.name(program);
  app.require_subcommand(1);
  Options o;
  auto add_set = [&o](CLI::App* s) {
    s->add_option("--set", o.set, "set a parameter, NAME=VALUE (SI units); repeatable");
  };
  CLI::App* info = app.add_subcommand("info", "coordinates, inputs, outputs and parameters");
  add_set(info);
  CLI::App* modes = app.add_subcommand("modes", "eigenvalues, frequencies, damping ratios (and shapes)");
  add_set(modes);
  modes->add_option("--format", o.format, "output format")->check(CLI::IsMember({"table", "json", "csv"}));
  modes->add_flag("--shapes", o.shapes, "print the mode shapes");
  modes->add_flag("--all", o.all, "both members of each complex-conjugate pair");
  CLI::App* frf = app.add_subcommand("frf", "frequency response of one output to one input");
  add_set(frf);
  frf->add_option("--input", o.input, "input name")->required();
  frf->add_option("--output", o.output, "output name")->required();
  frf->add_option("--from", o.from, "first frequency [Hz]")->check(frequency_hz());
  frf->add_option("--to", o.to, "last frequency [Hz]")->check(frequency_hz());
  frf->add_option("--points", o.points, "number of frequencies")->check(CLI::Range(1L, 100000000L));
  frf->add_option("--spacing", o.spacing, "frequency spacing")->check(CLI::IsMember({"log", "linear"}));
  frf->add_option("--method", o.method, "solution method")
      ->check(CLI::IsMember({"auto", "direct", "banded", "hessenberg", "modal", "real"}));
  frf->add_option("--on-pole", o.on_pole, "at a pole of an undamped system: flag the point or fail")
      ->check(CLI::IsMember({"flag", "error"}));
  frf->add_option("--format", o.format, "output format")->check(CLI::IsMember({"table", "json", "csv"}));
  frf->add_option("--plot", o.plot, "write a Bode plot (FILE.svg or FILE.png)");
  CLI::App* stat = app.add_subcommand("static", "the operating point: equilibrium, residual, iterations");
  add_set(stat);
  stat->add_option("--format", o.format, "output format")->check(CLI::IsMember({"table", "json"}));
  CLI::App* matrices = app.add_subcommand("matrices", "M, Q, K, B, C_y, C_v at the operating point");
  add_set(matrices);
  matrices->add_option("--format", o.format, "json (standard output) or mtx (files in --out)")
      ->check(CLI::IsMember({"json", "mtx"}));
  matrices->add_option("--out", o.out_dir, "directory of the .mtx files (default: current)");
  o.format = "table";
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {
      out << (app.get_subcommands().empty() ? app.help() : app.get_subcommands().front()->help());
      return 0;
    }
    err << program << ": " << e.what() << "\nRun with --help for more information.\n";
    return 2;
  }
  if (matrices->parsed() && o.format == "table") o.format = "json";
  if (frf->parsed()) {
    if (o.from == 0 && o.to == 0) {
      o.from = k.default_from_hz > 0 ? k.default_from_hz : 1.0;
      o.to = k.default_to_hz > 0 ? k.default_to_hz : 1000.0;
    }
    if (o.spacing == "log" && (o.from <= 0 || o.to <= 0)) {
      err << program << ": frf: --spacing log needs --from and --to > 0 (got " << o.from << ", " << o.to << ")\n";
      return 2;
    }
    if (o.to < o.from || (o.points > 1 && o.to == o.from)) {
      err << program << ": frf: empty range --from " << o.from << " --to " << o.to << "\n";
      return 2;
    }
  }
  try {
    if (info->parsed()) return run_info(k, o, out);
    if (modes->parsed()) return run_modes(k, o, out);
    if (frf->parsed()) return run_frf(k, o, out, err);
    if (stat->parsed()) return run_static(k, o, out);
    return run_matrices(k, o, out, err);
  } catch (const NameError& e) {
    err << program << ": " << e.what() << "\n";
    return 2;
  } catch (const Error& e) {
    err << program << ": error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    err << program << ": error: " << e.what() << "\n";
    return 1;
  }
}

int solver_main(const ModelKernels& kernels, int argc, char** argv) {
  return solver_main(kernels, argc, argv, std::cout, std::cerr);
}

}  // namespace mbsgen::cli
