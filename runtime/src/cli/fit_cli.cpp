// The command `fit` (issue 42; docs/fitting.md): `mbsgen run MODEL fit …` and `mbsgen-fit TAPE
// fit …`. Reads measured data, fits named parameters (runtime/fit), prints the estimates and
// what the data identify, and writes JSON/CSV and a plot of data, start and fit with residuals.
#include "cli/fit_cli.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <thread>

#include "cli/bode_plot.hpp"
#include "cli/cli_files.hpp"
#include "cli/cli_output.hpp"
#include "cli/study_cluster.hpp"
#include "mbsgen/runtime/model/tape.hpp"
#include "mbsgen/runtime/spectral/sensitivity.hpp"

namespace mbsgen::cli {

namespace {

constexpr const char* kMarker = "mbsgen fit";
constexpr double kPi = 3.14159265358979323846;

void write_table(std::ostream& out, const ModelKernels& k, const FitResult& f) {
  out << "# fit of model '" << k.model << "' (scene '" << k.scene << "'): " << f.residuals << " residuals, "
      << f.names.size() << " parameters, " << (f.converged ? "converged" : "NOT CONVERGED") << " (" << f.termination
      << "), " << f.iterations << " iterations, " << f.evaluations << " evaluations, " << fixed(f.seconds, "%.3g") << " s\n"
      << "# cost 1/2 sum r^2: " << short_num(f.initial_cost) << " at the start, " << short_num(f.cost) << " at the fit (data "
      << short_num(f.data_cost) << "); s^2 = " << short_num(f.residual_variance)
      << (f.weighted ? " (the data's standard deviations)\n" : " (estimated from the residuals: the data carry no standard deviations)\n");
  out << pad("parameter", 20) << pad("start", 15) << pad("estimate", 15) << pad("std.error", 15) << pad("95% lower", 15)
      << pad("95% upper", 15) << "  space   bound\n";
  for (std::size_t j = 0; j < f.names.size(); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    out << pad(f.names[j], 20) << pad(short_num(f.start[i]), 15) << pad(short_num(f.values[i]), 15)
        << pad(short_num(f.standard_error[i]), 15) << pad(short_num(f.lower95[i]), 15) << pad(short_num(f.upper95[i]), 15)
        << "  " << (f.log_space[j] ? "log   " : "linear") << "  " << (f.at_bound[j].empty() ? "-" : f.at_bound[j]) << "\n";
  }
  out << "# identifiability (Fisher information of the data, relative coordinates; weakest first):\n";
  std::string said;  // the directions of zero eigenvalue share one description: printed once
  for (const FisherDirection& d : f.fisher) {
    if (d.description == said) continue;
    said = d.description;
    out << "#   " << d.verdict << ": sigma " << short_num(d.sigma) << ": " << d.description << "\n";
  }
  if (f.minima.size() > 1) {
    out << "# distinct local minima (cost, starts ending there):\n";
    for (const LocalMinimum& m : f.minima) out << "#   " << short_num(m.cost) << "  " << m.starts << "\n";
  }
  for (const Profile& p : f.profiles)
    out << "# profile likelihood of " << p.parameter << ": 95 % interval [" << short_num(p.lower) << ", "
        << short_num(p.upper) << "] (" << p.points.size() << " points; '-': not reached within the range)\n";
  for (const std::string& w : f.warnings) out << "# warning: " << w << "\n";
}

std::string json_vector(const Eigen::VectorXd& v) {
  std::string s = "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) s += (i ? ", " : "") + num(v[i], true);
  return s + "]";
}

std::string json_matrix(const Eigen::MatrixXd& m) {
  std::string s = "[";
  for (Eigen::Index i = 0; i < m.rows(); ++i) s += (i ? ", " : "") + json_vector(m.row(i).transpose());
  return s + "]";
}

std::string json_result(const ModelKernels& k, const FitResult& f) {
  std::ostringstream s;
  s << "{\"generator\": \"" << kMarker << "\", \"model\": " << json_string(k.model) << ", \"scene\": " << json_string(k.scene)
    << ",\n \"converged\": " << (f.converged ? "true" : "false") << ", \"termination\": " << json_string(f.termination)
    << ", \"iterations\": " << f.iterations << ", \"evaluations\": " << f.evaluations << ", \"seconds\": " << num(f.seconds, true)
    << ",\n \"initial_cost\": " << num(f.initial_cost, true) << ", \"cost\": " << num(f.cost, true)
    << ", \"data_cost\": " << num(f.data_cost, true) << ", \"residuals\": " << f.residuals
    << ", \"degrees_of_freedom\": " << f.degrees_of_freedom << ", \"residual_variance\": " << num(f.residual_variance, true)
    << ", \"weighted\": " << (f.weighted ? "true" : "false") << ",\n \"parameters\": [";
  for (std::size_t j = 0; j < f.names.size(); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    s << (j ? ",\n  " : "\n  ") << "{\"name\": " << json_string(f.names[j]) << ", \"start\": " << num(f.start[i], true)
      << ", \"estimate\": " << num(f.values[i], true) << ", \"standard_error\": " << num(f.standard_error[i], true)
      << ", \"lower95\": " << num(f.lower95[i], true) << ", \"upper95\": " << num(f.upper95[i], true)
      << ", \"at_bound\": " << json_string(f.at_bound[j]) << "}";
  }
  s << "],\n \"covariance_theta\": " << json_matrix(f.covariance) << ",\n \"correlation\": " << json_matrix(f.correlation)
    << ",\n \"fisher\": [";
  for (std::size_t d = 0; d < f.fisher.size(); ++d)
    s << (d ? ",\n  " : "\n  ") << "{\"eigenvalue\": " << num(f.fisher[d].eigenvalue, true) << ", \"sigma\": "
      << num(f.fisher[d].sigma, true) << ", \"verdict\": " << json_string(f.fisher[d].verdict)
      << ", \"description\": " << json_string(f.fisher[d].description) << ", \"direction\": " << json_vector(f.fisher[d].direction) << "}";
  s << "],\n \"minima\": [";
  for (std::size_t m = 0; m < f.minima.size(); ++m)
    s << (m ? ", " : "") << "{\"cost\": " << num(f.minima[m].cost, true) << ", \"starts\": " << f.minima[m].starts
      << ", \"converged\": " << (f.minima[m].converged ? "true" : "false") << ", \"values\": " << json_vector(f.minima[m].values) << "}";
  s << "],\n \"profiles\": [";
  for (std::size_t q = 0; q < f.profiles.size(); ++q) {
    const Profile& p = f.profiles[q];
    s << (q ? ", " : "") << "{\"parameter\": " << json_string(p.parameter) << ", \"lower95\": " << num(p.lower, true)
      << ", \"upper95\": " << num(p.upper, true) << ", \"points\": [";
    for (std::size_t i = 0; i < p.points.size(); ++i)
      s << (i ? ", " : "") << "[" << num(p.points[i].value, true) << ", " << num(p.points[i].cost, true) << "]";
    s << "]}";
  }
  s << "],\n \"warnings\": [";
  for (std::size_t w = 0; w < f.warnings.size(); ++w) s << (w ? ", " : "") << json_string(f.warnings[w]);
  s << "]}\n";
  return s.str();
}

// Every data point: data, the model at the start and at the fit, the weighted residuals.
std::string points_csv(const ModelKernels& k, const FitResult& f) {
  std::ostringstream s;
  s << "# " << kMarker << ": model " << csv_field(k.model) << ", the data points with the model at the start and the fit\n"
    << "source,line,set,kind,input,output,frequency_hz_or_mode,data_re,data_im,initial_re,initial_im,fitted_re,fitted_im,"
       "residual_magnitude,residual_phase\n";
  for (const FitResult::Point& p : f.points)
    s << csv_field(p.source) << "," << p.line << "," << csv_field(p.set) << "," << p.kind << "," << csv_field(p.input) << ","
      << csv_field(p.output) << "," << num(p.hz, false) << "," << num(p.data.real(), false) << "," << num(p.data.imag(), false)
      << "," << num(p.initial.real(), false) << "," << num(p.initial.imag(), false) << "," << num(p.fitted.real(), false)
      << "," << num(p.fitted.imag(), false) << "," << num(p.residual_magnitude, false) << ","
      << num(p.residual_phase, false) << "\n";
  return s.str();
}

// The estimates, and the identifiability directions, as CSV (JSON has them too).
std::string estimates_csv(const ModelKernels& k, const FitResult& f) {
  std::ostringstream s;
  s << "# " << kMarker << ": model " << csv_field(k.model) << ", the estimates (" << (f.converged ? "converged" : "NOT CONVERGED")
    << ", cost " << num(f.cost, false) << ") and 95 % intervals; correlations in fit.json\n"
    << "parameter,space,start,estimate,standard_error,lower95,upper95,at_bound\n";
  for (std::size_t j = 0; j < f.names.size(); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    s << csv_field(f.names[j]) << "," << (f.log_space[j] ? "log" : "linear") << "," << num(f.start[i], false) << ","
      << num(f.values[i], false) << "," << num(f.standard_error[i], false) << "," << num(f.lower95[i], false) << ","
      << num(f.upper95[i], false) << "," << f.at_bound[j] << "\n";
  }
  s << "\n# identifiability: directions of the Fisher information (relative coordinates), weakest first\n"
    << "eigenvalue,sigma,verdict,description";
  for (const std::string& n : f.names) s << "," << csv_field("v_" + n);
  s << "\n";
  for (const FisherDirection& d : f.fisher) {
    s << num(d.eigenvalue, false) << "," << num(d.sigma, false) << "," << csv_field(d.verdict) << "," << csv_field(d.description);
    for (Eigen::Index i = 0; i < d.direction.size(); ++i) s << "," << num(d.direction[i], false);
    s << "\n";
  }
  return s.str();
}

// The plot: per input/output pair the model at the start and at the fit on 200 frequencies over
// its data's range, and per data set its points with their residuals.
void plot_fit(const std::string& path, const GeneratedModel& model0, const FitResult& f, const MeasuredData& data,
              const FitPlot& plot) {
  GeneratedModel model = model0;
  std::vector<FitPlotCurve> curves;
  std::vector<FitPlotPoints> points;
  std::vector<std::pair<std::string, std::string>> io;
  const auto unit_of = [](const char* const* units, Eigen::Index i) {
    return units && units[i] && *units[i] ? std::string(units[i]) : std::string("-");
  };
  for (const FrfData& d : data.responses) {
    const std::pair<std::string, std::string> key{d.input, d.output};
    auto it = std::find(io.begin(), io.end(), key);
    const double lo = *std::min_element(d.hz.begin(), d.hz.end()), hi = *std::max_element(d.hz.begin(), d.hz.end());
    if (it == io.end()) {
      io.push_back(key);
      it = io.end() - 1;
      const Eigen::Index in = model.input_index(d.input), out = model.output_index(d.output);
      curves.push_back({d.output + "/" + d.input + " [" + unit_of(model.kernels().output_units, out) + "/" +
                            unit_of(model.kernels().input_units, in) + "]",
                        {lo, hi}, {}, {}});
    }
    FitPlotCurve& c = curves[static_cast<std::size_t>(it - io.begin())];
    c.hz = {std::min(c.hz.front(), lo), std::max(c.hz.back(), hi)};
    FitPlotPoints x;
    x.label = d.set.empty() ? d.output + "/" + d.input : d.set;
    x.curve = static_cast<std::size_t>(it - io.begin());
    for (const FitResult::Point& p : f.points)
      if (p.kind == "frf" && p.set == d.set && p.input == d.input && p.output == d.output && p.source == d.source) {
        x.hz.push_back(p.hz);
        x.data.push_back(p.data);
        x.has_magnitude.push_back(!std::isnan(p.residual_magnitude));
        x.has_phase.push_back(!std::isnan(p.residual_phase));
        x.residual_magnitude.push_back(p.residual_magnitude);
        x.residual_phase.push_back(p.residual_phase);
      }
    points.push_back(std::move(x));
  }
  for (std::size_t k = 0; k < curves.size(); ++k) {
    FitPlotCurve& c = curves[k];
    const double lo = c.hz.front(), hi = c.hz.back();
    c.hz.clear();
    for (int i = 0; i < 200; ++i) c.hz.push_back(hi > lo ? lo * std::pow(hi / lo, i / 199.0) : lo);
    for (int at = 0; at < 2; ++at) {
      const Eigen::VectorXd& p = at == 0 ? f.start : f.values;
      for (std::size_t j = 0; j < f.names.size(); ++j) model.set(f.names[j], p[static_cast<Eigen::Index>(j)]);
      const auto s = frequency_response_sensitivity(model.linear_model(), {}, c.hz);
      const Eigen::Index in = model.input_index(io[k].first), out = model.output_index(io[k].second);
      for (const auto& m : s.response) (at == 0 ? c.initial : c.fitted).push_back(m(out, in));
    }
  }
  write_fit_plot(path, curves, points, plot);
}

}  // namespace

CLI::App* add_fit(CLI::App& app, FitCliOptions& o) {
  CLI::App* fit = app.add_subcommand("fit", "fit parameters to measured frequency responses and modal data (docs/fitting.md)");
  fit->add_option("--data", o.data, "measured data (CSV: frequency_hz with re,im or magnitude[,phase_deg]; or mode,frequency_hz,damping_ratio); repeatable")
      ->required();
  fit->add_option("--parameter", o.parameters, "a fitted parameter NAME=LO:HI[:xF | :+-W][:lin]; repeatable")->required();
  fit->add_option("--input", o.input, "the input of data files without an input column");
  fit->add_option("--output", o.output, "the output of data files without an output column");
  fit->add_option("--set", o.set, "set a parameter, NAME=VALUE (SI units): the start and the priors' centre; repeatable");
  fit->add_option("--starts", o.starts, "starting points: the start, then a Latin hypercube within the bounds")
      ->check(CLI::Range(1, 100000));
  fit->add_option("--threads", o.threads, "threads for the starts (default: every core)")->check(CLI::Range(0, 1024));
  fit->add_option("--seed", o.seed, "seed of the starts' Latin hypercube")->check(seed_value());
  fit->add_option("--max-iterations", o.max_iterations, "Levenberg-Marquardt steps per start")->check(CLI::Range(1, 100000));
  fit->add_option("--profile", o.profile, "trace the profile likelihood of these parameters")->delimiter(',');
  fit->add_option("--profile-points", o.profile_points, "points of each profile")->check(CLI::Range(3, 1001));
  fit->add_flag("--no-fit", o.no_fit, "no optimization: the statistics and identifiability at the start");
  fit->add_option("--format", o.format, "output format")->check(CLI::IsMember({"table", "json"}));
  fit->add_option("--out", o.out_dir,
                  "write fit.json, fit_estimates.csv, fit_points.csv (and fit_profile_NAME.csv) into this directory");
  fit->add_option("--plot", o.plot, "write data, start and fit with the residuals (FILE.svg or FILE.png)");
  return fit;
}

namespace {

// What a fit reads and where it writes, checked before any work (the files: not after the fit).
struct FitInputs {
  MeasuredData data;
  std::vector<FitParameter> params;
  std::vector<OutputFile> files;
};

FitInputs prepare(const FitCliOptions& o, GeneratedModel& model, bool writes) {
  FitInputs in;
  for (const std::string& a : o.set) model.set(a);
  for (const std::string& file : o.data) {
    MeasuredData d = read_measured_data_file(file, o.input, o.output);
    for (auto& r : d.responses) in.data.responses.push_back(std::move(r));
    for (auto& m : d.modal) in.data.modal.push_back(std::move(m));
  }
  for (const std::string& p : o.parameters) in.params.push_back(parse_fit_parameter(p));
  for (const std::string& name : o.profile)
    for (char c : name)
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_'))
        throw NameError("fit --profile '" + name + "': not a parameter name (letters, digits and '_')");
  if (!o.out_dir.empty()) {
    in.files.push_back({std::filesystem::path(o.out_dir) / "fit.json", ""});
    in.files.push_back({std::filesystem::path(o.out_dir) / "fit_points.csv", ""});
    in.files.push_back({std::filesystem::path(o.out_dir) / "fit_estimates.csv", ""});
    for (const std::string& name : o.profile)
      in.files.push_back({std::filesystem::path(o.out_dir) / ("fit_profile_" + name + ".csv"), ""});
  }
  if (!writes) return in;  // the files are rank 0's
  if (!o.out_dir.empty()) {
    refuse_non_directory(o.out_dir, "fit --out");
    std::vector<std::filesystem::path> paths;
    for (const auto& f : in.files) paths.push_back(f.path);
    refuse_foreign_files(paths, kMarker, "fit");
  }
  if (!o.plot.empty()) refuse_special_file(o.plot, "fit --plot");
  return in;
}

void write_outputs(const ModelKernels& k, const FitCliOptions& o, const GeneratedModel& model, FitInputs& in,
                   const FitResult& f, std::ostream& out) {
  if (o.format == "json")
    out << json_result(k, f);
  else
    write_table(out, k, f);
  if (!in.files.empty()) {
    in.files[0].content = json_result(k, f);
    in.files[1].content = points_csv(k, f);
    in.files[2].content = estimates_csv(k, f);
    for (std::size_t q = 0; q < f.profiles.size(); ++q) {
      std::ostringstream s;
      s << "# " << kMarker << ": model " << csv_field(k.model) << ", profile likelihood of " << f.profiles[q].parameter
        << " (cost: 1/2 sum r^2 with the others optimized; 95 %: 2 (cost - " << num(f.cost, false) << ")/s^2 = 3.84)\n"
        << f.profiles[q].parameter << ",cost,converged\n";
      for (const ProfilePoint& p : f.profiles[q].points)
        s << num(p.value, false) << "," << num(p.cost, false) << "," << (p.converged ? 1 : 0) << "\n";
      in.files[3 + q].content = s.str();
    }
    write_all_or_nothing(in.files, kMarker, "fit");
  }
  if (!o.plot.empty() && !in.data.responses.empty()) {
    FitPlot plot;
    plot.title = "fit of '" + std::string(k.model) + "': data, start (cost " + short_num(f.initial_cost) + ") and fit (cost " +
                 short_num(f.cost) + (f.converged ? ")" : ", NOT CONVERGED)");
    plot_fit(o.plot, model, f, in.data, plot);
  }
}

}  // namespace

int run_fit(const ModelKernels& k, const FitCliOptions& o, std::ostream& out, std::ostream& err) {
  // Under mpirun the ranks share the starts (FitOptions::share); every rank checks the same input
  // and all stop together when one cannot go on (as a study does: no rank left waiting).
  Cluster cluster;
  GeneratedModel model(k);
  FitInputs in;
  std::exception_ptr problem;
  try {
    in = prepare(o, model, cluster.rank() == 0);
  } catch (...) {
    problem = std::current_exception();
  }
  if (cluster.any(problem != nullptr)) {
    if (problem) std::rethrow_exception(problem);
    return 1;
  }
  FitOptions opt;
  opt.starts = o.starts;
  opt.threads = o.threads > 0 ? o.threads
                              : std::max(1, static_cast<int>(std::thread::hardware_concurrency()) / cluster.local_size());
  opt.seed = o.seed;
  opt.max_iterations = o.max_iterations;
  opt.optimize = !o.no_fit;
  opt.profile = o.profile;
  opt.profile_points = o.profile_points;
  opt.rank = cluster.rank();
  opt.ranks = cluster.size();
  opt.share = [&cluster](const std::vector<double>& v) { return cluster.all_gather(v); };
  const FitResult f = fit(model, in.data, in.params, opt);
  if (cluster.rank() != 0) return f.converged ? 0 : 3;
  if (cluster.size() > 1) out << "# the starts on " << cluster.description() << "\n";
  write_outputs(k, o, model, in, f, out);
  if (!f.converged) {
    err << "fit: the fit did not converge (" << f.termination << "): the values printed are where it stopped, not a minimum\n";
    return 3;
  }
  return 0;
}

}  // namespace mbsgen::cli

namespace mbsgen::cli {

int fit_main(const std::string& tape_file, int argc, char** argv) {
  std::unique_ptr<TapeModel> tape;
  try {
    tape = TapeModel::load(tape_file);
  } catch (const Error& e) {
    std::cerr << "mbsgen-fit: " << e.what() << "\n";
    return 1;
  }
  const ModelKernels& k = tape->kernels();
  const std::string program = std::string(k.model) + "-solve";
  CLI::App app{"fit parameters of model '" + std::string(k.model) + "' to measured data"};
  app.name(program);
  app.require_subcommand(1);
  FitCliOptions o;
  CLI::App* fit = add_fit(app, o);
  try {
    std::vector<std::string> args;
    for (int i = argc - 1; i >= 1; --i) args.emplace_back(argv[i]);
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {
      std::cout << fit->help();
      return 0;
    }
    std::cerr << program << ": " << e.what() << "\nRun with --help for more information.\n";
    return 2;
  }
  try {
    return run_fit(k, o, std::cout, std::cerr);
  } catch (const NameError& e) {
    std::cerr << program << ": fit: " << e.what() << "\n";
    return 2;
  } catch (const Error& e) {
    std::cerr << program << ": fit: error: " << e.what() << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << program << ": fit: error: out of memory\n";
    return 1;
  }
}

}  // namespace mbsgen::cli
