#include "cli/outputs_cli.hpp"

#include <Eigen/Core>

#include <set>

#include "cli/cli_output.hpp"
#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/time/simulation.hpp"  // finite_number

namespace mbsgen::cli {

namespace {

std::vector<std::string> names_of(const char* const* names, int n) {
  std::vector<std::string> v;
  for (int i = 0; i < n; ++i) v.emplace_back(names[i]);
  return v;
}

std::string known_names(const std::vector<std::string>& coordinates, const std::vector<std::string>& inputs) {
  std::string s;
  for (const auto& c : coordinates) s += (s.empty() ? "" : ", ") + c + ", " + c + "_dot, " + c + "_ddot";
  for (const auto& u : inputs) s += ", " + u;
  return s;
}

// Sets the entry of the state that NAME=VALUE names.
void apply(const std::string& entry, const std::vector<std::string>& coordinates, const std::vector<std::string>& inputs,
           Eigen::VectorXd& y, Eigen::VectorXd& yd, Eigen::VectorXd& ydd, Eigen::VectorXd& u, std::set<std::string>& seen) {
  const auto eq = entry.find('=');
  if (eq == std::string::npos || eq == 0)
    throw NameError("outputs: --state '" + entry + "': expected NAME=VALUE");
  const std::string name = entry.substr(0, eq);
  if (!seen.insert(name).second) throw NameError("outputs: --state: '" + name + "' is given twice");
  const double value = finite_number(entry.substr(eq + 1), "outputs: --state " + name);
  auto index_of = [](const std::vector<std::string>& list, const std::string& n) {
    for (std::size_t i = 0; i < list.size(); ++i)
      if (list[i] == n) return static_cast<Eigen::Index>(i);
    return Eigen::Index{-1};
  };
  auto ends_with = [&](const std::string& suffix) {
    return name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  Eigen::Index i = -1;
  if ((i = index_of(coordinates, name)) >= 0) {
    y[i] = value;
  } else if (ends_with("_ddot") && (i = index_of(coordinates, name.substr(0, name.size() - 5))) >= 0) {
    ydd[i] = value;
  } else if (ends_with("_dot") && (i = index_of(coordinates, name.substr(0, name.size() - 4))) >= 0) {
    yd[i] = value;
  } else if ((i = index_of(inputs, name)) >= 0) {
    u[i] = value;
  } else {
    throw NameError("outputs: --state: unknown name '" + name + "' (known: " + known_names(coordinates, inputs) + ")");
  }
}

}  // namespace

CLI::App* add_outputs(CLI::App& app, OutputsOptions& o) {
  CLI::App* s = app.add_subcommand("outputs", "every output (joint loads included) at any state");
  s->add_option("--set", o.set, "set a parameter, NAME=VALUE (SI units); repeatable");
  s->add_option("--state", o.state,
                "a coordinate, rate, acceleration or input of the state: NAME=VALUE, NAME_dot=VALUE, NAME_ddot=VALUE or "
                "INPUT=VALUE; repeatable (default: the operating point, no acceleration, no input)");
  s->add_option("--format", o.format, "output format")->check(CLI::IsMember({"table", "json"}));
  return s;
}

int run_outputs(const ModelKernels& k, const OutputsOptions& o, std::ostream& out) {
  GeneratedModel model(k);
  for (const auto& a : o.set) model.set(a);
  const auto coordinates = names_of(k.coordinate_names, k.n_coordinates);
  const auto inputs = names_of(k.input_names, k.n_inputs);
  const OperatingPoint op = model.operating_point();
  Eigen::VectorXd y = op.y0, yd = op.yd0, ydd = Eigen::VectorXd::Zero(k.n_coordinates), u = Eigen::VectorXd::Zero(k.n_inputs);
  std::set<std::string> seen;
  for (const auto& entry : o.state) apply(entry, coordinates, inputs, y, yd, ydd, u, seen);
  const Eigen::VectorXd z = model.outputs_at(y, yd, ydd, u);
  const auto outputs = names_of(k.output_names, k.n_outputs);
  if (o.format == "json") {
    out << "{\"outputs\":{";
    for (Eigen::Index i = 0; i < z.size(); ++i)
      out << (i ? "," : "") << json_string(outputs[static_cast<std::size_t>(i)]) << ":" << num(z[i], true);
    out << "}}\n";
    return 0;
  }
  out << pad("output", 16) << pad("value", 26) << "  unit\n";
  for (Eigen::Index i = 0; i < z.size(); ++i)
    out << pad(outputs[static_cast<std::size_t>(i)], 16) << pad(num(z[i], false), 26) << "  "
        << (k.output_units && k.output_units[i] && *k.output_units[i] ? k.output_units[i] : "-") << "\n";
  if (z.size() == 0) out << "# the model has no outputs\n";
  return 0;
}

}  // namespace mbsgen::cli
