#include "mbsgen/generator/codegen/emit_tape.hpp"

#include "mbsgen/generator/model/escape.hpp"

#include <sstream>

namespace mbsgen {

namespace {

std::string tape_string(const std::string& s) { return json_string_literal(s); }

// `list NAME COUNT`, then one line per row of fields.
void list(std::ostringstream& t, const char* name, const std::vector<std::vector<std::string>>& rows) {
  t << "list " << name << " " << rows.size() << "\n";
  for (const auto& row : rows) {
    for (std::size_t i = 0; i < row.size(); ++i) t << (i ? " " : "") << row[i];
    t << "\n";
  }
}

}  // namespace

std::string emit_tape(const Model& model, const LinearEquations& lin, const GeneratedCode& code,
                      const std::string& scene, double from_hz, double to_hz, int points, bool linear_spacing) {
  if (code.tape.empty()) return "";
  std::ostringstream t;
  t << "mbsgen-tape 1\n";
  t << "abi " << kAbiVersion << "\ngenerator " << tape_string(kGeneratorVersion) << "\nid " << tape_string(code.id)
    << "\nmodel " << tape_string(model.name()) << "\nscene " << tape_string(scene) << "\n";
  t << "operating-point " << (lin.at_rest ? 1 : 0) << " " << (lin.equilibrium ? 1 : 0) << "\n";
  t << "frequencies " << format_double(from_hz) << " " << format_double(to_hz) << " " << points << " "
    << (linear_spacing ? 1 : 0) << "\n";
  std::vector<std::vector<std::string>> rows;
  for (const auto& c : model.coordinates()) rows.push_back({tape_string(c.name), tape_string(c.unit)});
  list(t, "coordinates", rows);
  rows.clear();
  for (const auto& p : model.parameters()) rows.push_back({tape_string(p.name), tape_string(p.unit), format_double(p.value)});
  list(t, "parameters", rows);
  rows.clear();
  for (const auto& i : model.inputs()) rows.push_back({tape_string(i.name), tape_string(i.unit), tape_string(std::string(i.motion ? "motion" : "force"))});
  list(t, "inputs", rows);
  rows.clear();
  for (const auto& o : model.outputs()) rows.push_back({tape_string(o.name), tape_string(o.unit)});
  list(t, "outputs", rows);
  auto names = [&](const char* what, const std::vector<std::size_t>& coordinates) {
    rows.clear();
    for (std::size_t k : coordinates) rows.push_back({tape_string(model.coordinates()[k].name)});
    list(t, what, rows);
  };
  if (lin.descriptor) {
    names("speeds", lin.speeds);
    names("reduced-coordinates", lin.reduced.coordinates);
    rows.clear();
    for (const auto& part : model.reduced_coefficients()) rows.push_back({tape_string(part.name)});
    list(t, "reduced-parts", rows);
  }
  if (code.tape.find("kernel sensitivity ") != std::string::npos) {
    rows.clear();
    for (const auto& name : sensitivity_parameter_names(model)) rows.push_back({tape_string(name)});
    list(t, "sensitivity-parameters", rows);
  }
  if (code.tape.find("kernel physical ") != std::string::npos) {
    rows.clear();
    for (const PhysicalCheck& c : model.physical_checks()) {
      std::string parameters;
      for (const auto& name : c.parameters) parameters += (parameters.empty() ? "" : ",") + name;
      const std::string kind = to_string(c.kind);
      rows.push_back({tape_string(kind), tape_string(c.label), tape_string(c.unit), tape_string(parameters)});
    }
    list(t, "checks", rows);
  }
  t << code.tape;
  return t.str();
}

}  // namespace mbsgen
