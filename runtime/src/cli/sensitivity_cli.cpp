#include "cli/sensitivity_cli.hpp"

#include <cmath>
#include <complex>

#include "cli/cli_output.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"
#include "mbsgen/runtime/spectral/sensitivity.hpp"

namespace mbsgen::cli {


void write_modes_sensitivity(std::ostream& out, const GeneratedModel& model, const std::vector<std::string>& parameters,
                             const std::string& format, bool all) {
  const OperatingPoint op = model.operating_point();
  const LinearModel lin = model.linear_model(op);
  const std::vector<MatrixSensitivity> d = model.linear_sensitivities(op, parameters);
  QuadraticEigenOptions opt;
  opt.one_per_conjugate_pair = false;  // the separation test needs every eigenvalue
  QuadraticEigenSolver solver(lin.size(), opt);
  solver.compute(lin);
  const std::vector<Mode>& modes = solver.modes();
  const auto s = eigenvalue_sensitivities(lin, modes, d);
  // The modes as `modes` lists them (one per conjugate pair, a rigid-body double zero once,
  // unless --all), each with its place in the full list: the same numbering as `modes`.
  opt.one_per_conjugate_pair = !all;
  QuadraticEigenSolver listed(lin.size(), opt);
  listed.compute(lin);
  std::vector<std::size_t> order;
  std::vector<bool> used(modes.size(), false);
  for (const Mode& m : listed.modes())
    for (std::size_t k = 0; k < modes.size(); ++k)
      if (!used[k] && modes[k].kind == m.kind && modes[k].lambda == m.lambda) {
        used[k] = true;
        order.push_back(k);
        break;
      }
  const bool json = format == "json";
  if (json) out << "{\"model\": " << json_string(model.kernels().model) << ", \"modes\": [";
  else if (format == "csv")
    out << "mode,lambda_re,lambda_im,frequency_hz,damping_ratio,parameter,value,dlambda_re,dlambda_im,"
           "relative_frequency,dfrequency_hz,ddamping_ratio,relative_re,relative_im,note\n";
  else
    out << pad("mode", 5) << pad("f_n [Hz]", 14) << pad("parameter", 22) << pad("(p/f) df/dp", 15)
        << pad("d zeta/dp", 15) << pad("Re dlambda/dp", 15) << pad("Im dlambda/dp", 15) << "note\n";
  int index = 0;
  bool first_mode = true;
  for (std::size_t k : order) {
    const Mode& m = modes[k];
    ++index;
    if (json)
      out << (first_mode ? "" : ",") << "\n  {\"mode\": " << index << ", \"lambda\": [" << num(m.lambda.real(), true)
          << ", " << num(m.lambda.imag(), true) << "], \"frequency_hz\": " << num(m.natural_frequency_hz, true)
          << ", \"damping_ratio\": " << num(m.damping_ratio, true) << ", \"kind\": " << json_string(kind_label(m))
          << ", \"sensitivities\": [";
    first_mode = false;
    for (std::size_t j = 0; j < d.size(); ++j) {
      const EigenvalueSensitivity& e = s[k][j];
      if (json) {
        out << (j ? ", " : "") << "\n    {\"parameter\": " << json_string(d[j].parameter) << ", \"value\": "
            << num(d[j].value, true) << ", \"dlambda\": [" << num(e.dlambda.real(), true) << ", "
            << num(e.dlambda.imag(), true) << "], \"relative_frequency\": " << num(e.relative_frequency, true)
            << ", \"dfrequency_hz\": " << num(e.dfrequency_hz, true) << ", \"ddamping_ratio\": "
            << num(e.ddamping_ratio, true) << ", \"relative\": [" << num(e.relative.real(), true) << ", "
            << num(e.relative.imag(), true) << "], \"defined\": " << (e.defined ? "true" : "false")
            << ", \"note\": " << json_string(e.note) << "}";
      } else if (format == "csv") {
        out << index << "," << num(m.lambda.real(), false) << "," << num(m.lambda.imag(), false) << ","
            << num(m.natural_frequency_hz, false) << "," << num(m.damping_ratio, false) << ","
            << csv_field(d[j].parameter) << "," << num(d[j].value, false) << "," << num(e.dlambda.real(), false) << ","
            << num(e.dlambda.imag(), false) << "," << num(e.relative_frequency, false) << ","
            << num(e.dfrequency_hz, false) << "," << num(e.ddamping_ratio, false) << "," << num(e.relative.real(), false)
            << "," << num(e.relative.imag(), false) << "," << e.note << "\n";
      } else {
        out << pad(std::to_string(index), 5) << pad(short_num(m.natural_frequency_hz), 14) << pad(d[j].parameter, 22)
            << pad(short_num(e.relative_frequency), 15) << pad(short_num(e.ddamping_ratio), 15)
            << pad(short_num(e.dlambda.real()), 15) << pad(short_num(e.dlambda.imag()), 15) << e.note << "\n";
      }
    }
    if (json) out << "]}";
  }
  if (json) out << "\n]}\n";
}

void write_frf_sensitivity(std::ostream& out, const GeneratedModel& model, Eigen::Index input, Eigen::Index output,
                           const Eigen::VectorXd& hz, const std::vector<std::string>& parameters,
                           const std::string& format) {
  const OperatingPoint op = model.operating_point();
  const LinearModel lin = model.linear_model(op);
  // The one input and output asked for (LinearModel::select): one right-hand side per frequency.
  std::vector<MatrixSensitivity> d = model.linear_sensitivities(op, parameters);
  for (MatrixSensitivity& x : d) x = select(x, {input}, {output});
  const FrequencyResponseSensitivity r = frequency_response_sensitivity(
      lin.select({input}, {output}), d, std::vector<double>(hz.data(), hz.data() + hz.size()));
  const bool json = format == "json";
  if (json) {
    out << "{\"model\": " << json_string(model.kernels().model) << ", \"input\": "
        << json_string(model.kernels().input_names[input]) << ", \"output\": "
        << json_string(model.kernels().output_names[output]) << ", \"parameters\": [";
    for (std::size_t j = 0; j < d.size(); ++j)
      out << (j ? ", " : "") << "{\"name\": " << json_string(d[j].parameter) << ", \"value\": " << num(d[j].value, true) << "}";
    out << "], \"points\": [";
  } else if (format == "csv") {
    out << "frequency_hz,re,im,magnitude,phase_rad";
    for (const auto& x : d) {
      const std::string n = x.parameter;
      out << "," << csv_field("dlnmag/dlnp:" + n) << "," << csv_field("dphase/dlnp:" + n) << "," << csv_field("dre/dp:" + n)
          << "," << csv_field("dim/dp:" + n);
    }
    out << "\n";
  } else {
    out << pad("f [Hz]", 14) << pad("|z|", 14) << "relative magnitude sensitivity d ln|z|/d ln p per parameter:";
    for (const auto& x : d) out << " " << x.parameter;
    out << "\n";
  }
  for (std::size_t i = 0; i < r.frequencies_hz.size(); ++i) {
    const std::complex<double> z = r.response[i](0, 0);
    if (json) out << (i ? "," : "") << "\n  {\"frequency_hz\": " << num(hz[static_cast<Eigen::Index>(i)], true)
                  << ", \"response\": [" << num(z.real(), true) << ", " << num(z.imag(), true) << "], \"sensitivities\": [";
    else if (format == "csv")
      out << num(hz[static_cast<Eigen::Index>(i)], false) << "," << num(z.real(), false) << "," << num(z.imag(), false)
          << "," << num(std::abs(z), false) << "," << num(std::arg(z), false);
    else
      out << pad(short_num(hz[static_cast<Eigen::Index>(i)]), 14) << pad(short_num(std::abs(z)), 14);
    for (std::size_t j = 0; j < d.size(); ++j) {
      const std::complex<double> dz = r.derivative[j][i](0, 0);
      const std::complex<double> rel = d[j].value * dz / z;  // NaN where z = 0
      if (json)
        out << (j ? ", " : "") << "{\"dlnmag_dlnp\": " << num(rel.real(), true) << ", \"dphase_dlnp\": "
            << num(rel.imag(), true) << ", \"dz_dp\": [" << num(dz.real(), true) << ", " << num(dz.imag(), true) << "]}";
      else if (format == "csv")
        out << "," << num(rel.real(), false) << "," << num(rel.imag(), false) << "," << num(dz.real(), false) << ","
            << num(dz.imag(), false);
      else
        out << " " << short_num(rel.real());
    }
    if (json) out << "]}";
    else out << "\n";
  }
  if (json) out << "\n]}\n";
}

}  // namespace mbsgen::cli
