#include "cli/simulate_cli.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "cli/bode_plot.hpp"
#include "cli/cli_files.hpp"
#include "cli/cli_output.hpp"
#include "mbsgen/runtime/time/simulation.hpp"

namespace mbsgen::cli {

namespace {

// "NAME=VALUE" → (NAME, VALUE text); NameError naming the option otherwise.
std::pair<std::string, std::string> assignment(const std::string& text, const char* option) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw NameError(std::string(option) + " '" + text + "': expected NAME=VALUE");
  return {text.substr(0, eq), text.substr(eq + 1)};
}

SimulationOptions simulation_options(const GeneratedModel& model, const SimulateOptions& o) {
  SimulationOptions s;
  s.duration = o.duration;
  s.step = o.step > 0 ? o.step : o.duration / 1000;
  s.rtol = o.rtol;
  s.atol = o.atol;
  s.difference_quotients = o.difference_quotients;
  s.method = o.method == "adams"   ? IntegrationMethod::adams
             : o.method == "radau" ? IntegrationMethod::radau
             : o.method == "radau9" ? IntegrationMethod::radau9
                                   : IntegrationMethod::bdf;
  for (const std::string& a : o.initial) {
    const auto [name, text] = assignment(a, "--initial");
    s.initial.emplace_back(name, finite_number(text, "--initial '" + a + "'"));
  }
  for (const std::string& a : o.atol_of) {
    const auto [name, text] = assignment(a, "--atol-of");
    const double atol = finite_number(text, "--atol-of '" + a + "'");
    if (!(atol > 0)) throw NameError("--atol-of '" + a + "': an absolute tolerance must be > 0");
    s.atol_of.emplace_back(name, atol);
  }
  // The samples kept in memory, as simulate() counts them (5e7 values), a usage error here: 1e300
  // seconds sampled every 1e-300 s was a run failure that printed "inf samples".
  const double per_sample = 2.0 * model.size() + model.kernels().n_inputs + model.kernels().n_outputs;
  if (!(s.duration / s.step + 1 <= 5e7 / per_sample))
    throw NameError("simulate: --duration " + fixed(s.duration, "%.6g") + " sampled every " + fixed(s.step, "%.6g") +
                    " s gives more than " + std::to_string(static_cast<long>(5e7 / per_sample)) + " samples of " +
                    std::to_string(static_cast<long>(per_sample)) +
                    " values (400 MB): sample less often (--step) or simulate less time");
  if (!o.inputs.empty()) s.inputs.resize(static_cast<std::size_t>(model.kernels().n_inputs));
  for (const std::string& a : o.inputs) {
    const auto [name, spec] = assignment(a, "--input");
    s.inputs[static_cast<std::size_t>(model.input_index(name))] = InputSignal::parse(spec, o.duration);
  }
  return s;
}

// The series' names: the coordinates, their rates, the outputs (when the kernels give them).
std::vector<std::string> series_names(const ModelKernels& k) {
  std::vector<std::string> names = name_list(k.coordinate_names, k.n_coordinates);
  for (int i = 0; i < k.n_coordinates; ++i) names.push_back(names[static_cast<std::size_t>(i)] + "_dot");
  if (simulates_outputs(k))
    for (const auto& z : name_list(k.output_names, k.n_outputs)) names.push_back(z);
  return names;
}

Eigen::MatrixXd series_values(const SimulationResult& r) {
  Eigen::MatrixXd v(r.y.rows() + r.yd.rows() + r.z.rows(), r.t.size());
  v << r.y, r.yd, r.z;
  return v;
}

void write_csv(std::ostream& out, const std::vector<std::string>& names, const Eigen::VectorXd& t,
               const Eigen::MatrixXd& v) {
  out << "t";
  for (const auto& n : names) out << "," << n;
  out << "\n";
  for (Eigen::Index j = 0; j < t.size(); ++j) {
    out << num(t[j], false);
    for (Eigen::Index i = 0; i < v.rows(); ++i) out << "," << num(v(i, j), false);
    out << "\n";
  }
}

void write_json(std::ostream& out, const ModelKernels& k, const SimulateOptions& o, const SimulationResult& r,
                const std::vector<std::string>& names, const Eigen::MatrixXd& v) {
  auto row = [&out](auto&& values, Eigen::Index size) {
    out << "[";
    for (Eigen::Index j = 0; j < size; ++j) out << (j ? "," : "") << num(values(j), true);
    out << "]";
  };
  out << "{\"model\":" << json_string(k.model) << ",\"scene\":" << json_string(k.scene)
      << ",\"method\":" << json_string(o.method) << ",\"jacobian\":"
      << json_string(o.method == "adams" ? "none" : r.analytic_jacobian ? "kernels" : "difference quotients")
      << ",\"restarts\":" << r.restarts;
  if (k.n_constraints > 0) out << ",\"constraint_drift\":" << num(r.constraint_drift, true);
  if (o.statistics)  // counts that vary with the SUNDIALS version and the libm: asked for only
    out << ",\"statistics\":{\"steps\":" << r.steps << ",\"rhs_evaluations\":" << r.rhs_evaluations
        << ",\"jacobian_evaluations\":" << r.jacobian_evaluations << ",\"error_test_failures\":" << r.error_test_failures
        << ",\"nonlinear_failures\":" << r.nonlinear_failures << "}";
  out << ",\"t\":";
  row([&](Eigen::Index j) { return r.t[j]; }, r.t.size());
  out << ",\"series\":{";
  for (std::size_t i = 0; i < names.size(); ++i) {
    out << (i ? "," : "") << json_string(names[i]) << ":";
    row([&](Eigen::Index j) { return v(static_cast<Eigen::Index>(i), j); }, v.cols());
  }
  out << "}}\n";
}

// The series --show names (default: the outputs, or the coordinates when there are none).
std::vector<Eigen::Index> shown(const std::vector<std::string>& names, const SimulateOptions& o, const ModelKernels& k) {
  std::vector<Eigen::Index> rows;
  for (const std::string& s : o.show) {
    const auto it = std::find(names.begin(), names.end(), s);
    if (it == names.end()) {
      std::string known;
      for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
      throw NameError("--show '" + s + "': no such series; known: " + known);
    }
    rows.push_back(it - names.begin());
  }
  if (rows.empty()) {
    const bool outputs = simulates_outputs(k) && k.n_outputs > 0;
    const Eigen::Index first = outputs ? 2 * k.n_coordinates : 0;
    const Eigen::Index count = outputs ? k.n_outputs : k.n_coordinates;
    for (Eigen::Index i = 0; i < std::min(count, kMaxTimePanels); ++i) rows.push_back(first + i);
  }
  if (static_cast<Eigen::Index>(rows.size()) > kMaxTimePanels)
    throw NameError("--show: at most " + std::to_string(kMaxTimePanels) + " series in one plot");
  return rows;
}

void plot(const SimulateOptions& o, const ModelKernels& k, const SimulationResult& r,
          const std::vector<std::string>& names, const std::vector<Eigen::Index>& rows, const Eigen::MatrixXd& v) {
  TimePlot p;
  p.title = std::string(k.model) + " (" + k.scene + "): simulation";
  Eigen::MatrixXd values(static_cast<Eigen::Index>(rows.size()), v.cols());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    values.row(static_cast<Eigen::Index>(i)) = v.row(rows[i]);
    const Eigen::Index row = rows[i], n = k.n_coordinates;
    const char* unit = row < 2 * n ? k.coordinate_units[row % n] : k.output_units[row - 2 * n];
    std::string label = names[static_cast<std::size_t>(row)];
    if (unit && *unit) label += " [" + std::string(unit) + (row >= n && row < 2 * n ? "/s" : "") + "]";
    p.labels.push_back(label);
  }
  write_time_plot(o.plot, r.t, values, p);
}

void print_statistics(std::ostream& err, const SimulateOptions& o, const SimulationResult& r) {
  err << "simulate: " << r.t.size() << " samples, " << o.method << ", " << r.steps << " steps, " << r.rhs_evaluations
      << " right-hand sides";
  if (o.method != "adams")
    err << ", " << r.jacobian_evaluations << " Jacobians (" << (r.analytic_jacobian ? "kernels" : "difference quotients")
        << ")";
  err << ", " << r.error_test_failures << " error test failures, " << r.nonlinear_failures
      << " corrector failures, " << r.restarts << " restarts";
  if (r.constraint_drift > 0) err << ", largest |Phi| " << short_num(r.constraint_drift);
  err << "\n";
}

}  // namespace

CLI::App* add_simulate(CLI::App& app, SimulateOptions& o) {
  CLI::App* s = app.add_subcommand("simulate", "integrate the nonlinear equations of motion in time");
  s->add_option("--set", o.set, "set a parameter, NAME=VALUE (SI units); repeatable");
  s->add_option("--duration", o.duration, "simulated time [s]")->required()->check(
      finite_in(0, 1e300, true, "a duration in seconds (a finite number > 0)"));
  s->add_option("--step", o.step, "output sampling [s] (default: duration / 1000)")
      ->check(finite_in(0, 1e300, true, "a time step in seconds (a finite number > 0)"));
  s->add_option("--initial", o.initial, "initial coordinate or rate, NAME=VALUE or NAME_dot=VALUE; repeatable "
                                        "(default: the operating point)");
  s->add_option("--input", o.inputs, "an input against time, NAME=VALUE, NAME=sine:AMPLITUDE,HZ[,PHASE_DEG[,OFFSET]], "
                                     "NAME=step:AMPLITUDE[,TIME[,BEFORE]], NAME=chirp:AMPLITUDE,F0,F1[,DURATION] or "
                                     "NAME=table:FILE.csv (t,value lines); repeatable (default: 0)");
  // 100 ε: below it no integrator here can meet the tolerance (Radau's Newton iteration stops at
  // 10 ε / rtol; BDF reports "too much accuracy requested" after a long run).
  s->add_option("--rtol", o.rtol, "relative tolerance, in [2.2e-14, 1]")
      ->check(finite_in(2.2e-14, 1.0, false, "a relative tolerance in [2.2e-14, 1] (100 machine epsilons to 1)"));
  s->add_option("--atol", o.atol, "absolute tolerance")
      ->check(finite_in(0, 1e300, true, "an absolute tolerance (a finite number > 0)"));
  s->add_option("--atol-of", o.atol_of, "the absolute tolerance of one coordinate or rate, NAME=VALUE or "
                                        "NAME_dot=VALUE, in its units (states of different sizes); repeatable");
  s->add_option("--method", o.method, "bdf (stiff models; the default), radau (Radau IIA of order 5: stiff and "
                                     "oscillating models, tighter tolerances), radau9 (Radau IIA of order 9: the "
                                     "same, fewer and longer steps on smooth motion) or adams (non-stiff motion: "
                                     "fewer, more accurate steps)")
      ->check(CLI::IsMember({"bdf", "radau", "radau9", "adams"}));
  s->add_option("--format", o.format, "output format")->check(CLI::IsMember({"csv", "json"}));
  s->add_option("--plot", o.plot, "plot chosen series against time (FILE.svg or FILE.png)");
  s->add_option("--show", o.show, "the series to plot (default: the outputs); repeatable");
  s->add_flag("--statistics", o.statistics, "print the integrator's statistics on standard error");
  s->add_flag("--difference-quotients", o.difference_quotients,
              "iteration matrices from difference quotients even where the kernels give the Jacobian");
  return s;
}

int run_simulate(const ModelKernels& k, const SimulateOptions& o, std::ostream& out, std::ostream& err) {
  GeneratedModel model(k);
  for (const auto& a : o.set) model.set(a);
  if (model.is_descriptor())
    throw Error("simulate: model '" + std::string(k.model) + "' has nonholonomic constraints; its kernels are the "
                "linearization's descriptor form, and time integration of such models is not available yet");
  SimulationOptions s = simulation_options(model, o);
  const std::vector<std::string> names = series_names(k);
  std::vector<Eigen::Index> rows;
  if (!o.plot.empty()) {  // before the run, not after
    refuse_special_file(o.plot, "--plot");
    rows = shown(names, o, k);
  }
  const bool terminal = ::isatty(STDERR_FILENO);
  const auto start = std::chrono::steady_clock::now();
  bool progress_shown = false;
  s.progress = [&](double t) {
    if (!terminal || std::chrono::steady_clock::now() - start < std::chrono::seconds(2)) return;
    err << "\rsimulate: t = " << short_num(t) << " s (" << static_cast<int>(100 * t / s.duration) << " %)" << std::flush;
    progress_shown = true;
  };
  if (o.method != "adams" && k.mass_matrix && k.residual && !k.dynamics_jacobian && !o.difference_quotients)
    err << "note: the kernels have no dynamics_jacobian ("
        << (k.n_constraints > 0 ? "not emitted for closed loops" : "generate with --dynamics")
        << "): iteration matrices from difference quotients\n";
  SimulationResult r;
  try {
    r = simulate(model, model.operating_point(), s);
  } catch (...) {
    if (progress_shown) err << "\r" << std::string(40, ' ') << "\r";
    throw;
  }
  if (progress_shown) err << "\r" << std::string(40, ' ') << "\r";
  const Eigen::MatrixXd v = series_values(r);
  if (!o.plot.empty()) plot(o, k, r, names, rows, v);
  if (o.format == "json")
    write_json(out, k, o, r, names, v);
  else
    write_csv(out, names, r.t, v);
  if (o.statistics) print_statistics(err, o, r);
  if (!o.plot.empty()) err << "wrote " << o.plot << "\n";
  return 0;
}

}  // namespace mbsgen::cli
