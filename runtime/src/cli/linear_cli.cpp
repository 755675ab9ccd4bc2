#include "mbsgen/runtime/cli/linear_cli.hpp"

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <new>
#include <string>
#include <vector>

#include "cli/cli_output.hpp"
#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/model/generated_model.hpp"
#include "mbsgen/runtime/model/linear_model.hpp"
#include "mbsgen/runtime/model/matrix_market.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"
#include "mbsgen/runtime/version.hpp"

namespace mbsgen::cli {
namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

struct Common {
  std::string M, K, Q, format = "table";
};

LinearModel load(const Common& c, const std::string& Bf, const std::string& Cf,
                 const std::string& Cvf, const std::string& Caf = "", const std::string& Df = "") {
  Eigen::MatrixXd M = read_matrix_market(c.M);
  Eigen::MatrixXd K = read_matrix_market(c.K);
  Eigen::MatrixXd Q = c.Q.empty() ? Eigen::MatrixXd() : read_matrix_market(c.Q);
  Eigen::MatrixXd B = Bf.empty() ? Eigen::MatrixXd::Identity(M.rows(), M.rows())
                                 : read_matrix_market(Bf);
  Eigen::MatrixXd Cy = Cf.empty() ? Eigen::MatrixXd() : read_matrix_market(Cf);
  Eigen::MatrixXd Cv = Cvf.empty() ? Eigen::MatrixXd() : read_matrix_market(Cvf);
  LinearModel model(std::move(M), std::move(Q), std::move(K), std::move(B), std::move(Cy),
                    std::move(Cv));
  if (Caf.empty() && Df.empty()) return model;
  Eigen::MatrixXd Ca = Caf.empty() ? Eigen::MatrixXd() : read_matrix_market(Caf);
  Eigen::MatrixXd D = Df.empty() ? Eigen::MatrixXd() : read_matrix_market(Df);
  return model.with_output_terms(std::move(Ca), std::move(D));
}

int run_modes(const Common& c, bool all, std::ostream& out) {
  const LinearModel model = load(c, "", "", "");
  QuadraticEigenOptions opt;
  opt.one_per_conjugate_pair = !all;
  QuadraticEigenSolver solver(model.size(), opt);
  solver.compute(model);
  ModesFormat f;
  f.format = c.format;
  write_modes(out, solver, model.size(), f);
  return 0;
}

struct FrfArgs {
  std::string B, C, Cv, Ca, D, B1, B2, D1, method = "auto", spacing = "log", on_pole = "flag";
  long input = 1, output = 1, points = 200;
  double from = 1.0, to = 1000.0;
};

// The model of `frf`, with a moving support's B1, B2, D1 when given (prescribed motion).
LinearModel load_frf(const Common& c, const FrfArgs& a) {
  const LinearModel model = load(c, a.B, a.C, a.Cv, a.Ca, a.D);
  if (a.B1.empty() && a.B2.empty() && a.D1.empty()) return model;
  auto read = [](const std::string& f) { return f.empty() ? Eigen::MatrixXd() : read_matrix_market(f); };
  return model.with_input_rates(read(a.B1), read(a.B2), read(a.D1));
}

int run_frf(const Common& c, const FrfArgs& a, std::ostream& out, std::ostream& err) {
  const LinearModel model = load_frf(c, a);
  // Out of the model's range: a usage error (exit status 2), like an unknown name for a solver.
  if (a.input < 1 || a.input > model.num_inputs())
    throw NameError("--input " + std::to_string(a.input) + " out of range 1.." +
                    std::to_string(model.num_inputs()) + " (the columns of B)");
  if (a.output < 1 || a.output > model.num_outputs())
    throw NameError("--output " + std::to_string(a.output) + " out of range 1.." +
                    std::to_string(model.num_outputs()) + " (the rows of C)");
  const Eigen::VectorXd hz = sweep_hz(a.from, a.to, a.points, a.spacing == "log");
  FrfOptions opt;
  opt.method = parse_frf_method(a.method);
  opt.on_pole = a.on_pole == "error" ? PoleHandling::raise : PoleHandling::flag;
  FrequencyResponse frf(model, opt);
  frf.compute(hz * kTwoPi, a.input - 1, {a.output - 1});
  for (const auto& w : frf.warnings()) err << "mbsgen linear frf: warning: " << w << "\n";
  FrfTable t;
  t.format = c.format;
  t.input_json = t.input_label = std::to_string(a.input);
  t.output_json = t.output_label = std::to_string(a.output);
  write_frf(out, {hz, frf.response().row(0).transpose(), frf.rcond(), frf.flags(), frf.method()}, t);
  return 0;
}

}  // namespace

int linear_main(int argc, char** argv, std::ostream& out, std::ostream& err) try {
  CLI::App app{"mbsgen linear: modes and frequency responses of M y'' + Q y' + K y = B u, "
               "z = C y + Cv y' + Ca y'' + D u, from Matrix Market files"};
  app.name("mbsgen linear");
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("mbsgen linear ") + kRuntimeVersion, "print the version and exit");
  Common c;
  bool all = false;
  FrfArgs a;
  auto add_common = [&c](CLI::App* s) {
    s->add_option("--M", c.M, "mass matrix M (f x f), Matrix Market")->required()
;
    s->add_option("--K", c.K, "stiffness matrix K (f x f)")->required();
    s->add_option("--Q", c.Q, "velocity (damping + gyroscopic) matrix Q (f x f); default 0")
;
    s->add_option("--format", c.format, "output format")
        ->check(CLI::IsMember({"table", "json", "csv"}));
  };
  CLI::App* modes = app.add_subcommand("modes", "eigenvalues and modes of λ²M + λQ + K");
  add_common(modes);
  modes->add_flag("--all", all, "report both members of each complex-conjugate pair");
  CLI::App* frf = app.add_subcommand("frf", "frequency response z/u of one input and one output");
  add_common(frf);
  frf->add_option("--B", a.B, "input matrix B (f x m); default identity (unit force per coordinate)")
;
  frf->add_option("--C", a.C, "output matrix C_y (p x f); default identity (outputs = coordinates)")
;
  frf->add_option("--Cv", a.Cv, "velocity output matrix C_v (p x f); default 0")
;
  frf->add_option("--Ca", a.Ca, "acceleration output matrix C_a (p x f); default 0");
  frf->add_option("--D", a.D, "feedthrough matrix D (p x m), z += D u; default 0");
  frf->add_option("--B1", a.B1, "a moving support's rate matrix B1 (f x m), h += B1 u'; default 0");
  frf->add_option("--B2", a.B2, "a moving support's acceleration matrix B2 (f x m), h += B2 u''; default 0");
  frf->add_option("--D1", a.D1, "feedthrough of the input's rate D1 (p x m), z += D1 u'; default 0");
  frf->add_option("--input", a.input, "input: column of B, 1-based")->check(CLI::Range(1L, 1000000000L));
  frf->add_option("--output", a.output, "output: row of C, 1-based")->check(CLI::Range(1L, 1000000000L));
  frf->add_option("--from", a.from, "first frequency [Hz]")->check(frequency_hz());
  frf->add_option("--to", a.to, "last frequency [Hz]")->check(frequency_hz());
  frf->add_option("--points", a.points, "number of frequencies")->check(CLI::Range(1L, kMaxFrequencyPoints));
  frf->add_option("--spacing", a.spacing, "frequency spacing")
      ->check(CLI::IsMember({"log", "linear"}));
  frf->add_option("--method", a.method, "solution method")
      ->check(CLI::IsMember({"auto", "direct", "banded", "hessenberg", "modal", "real"}));
  frf->add_option("--on-pole", a.on_pole,
                  "at a pole of an undamped system: flag the point, or fail with exit code 1")
      ->check(CLI::IsMember({"flag", "error"}));
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    out << app.help();
    return 0;
  } catch (const CLI::CallForVersion& e) {
    out << e.what() << "\n";
    return 0;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {
      out << app.help();
      return 0;
    }
    err << "mbsgen linear: " << e.what() << "\n";
    return 2;
  }
  if (frf->parsed()) {
    const std::string problem = sweep_problem(a.from, a.to, a.points, a.spacing == "log");
    if (!problem.empty()) {
      err << "mbsgen linear frf: " << problem << "\n";
      return 2;
    }
  }
  try {
    if (modes->parsed()) return run_modes(c, all, out);
    return run_frf(c, a, out, err);
  } catch (const NameError& e) {
    err << "mbsgen linear: " << e.what() << "\n";
    return 2;
  } catch (const std::bad_alloc&) {
    err << "mbsgen linear: error: out of memory\n";
    return 1;
  } catch (const std::exception& e) {
    err << "mbsgen linear: error: " << e.what() << "\n";
    return 1;
  }
} catch (const std::exception& e) {  // while setting up or parsing the command line
  err << "mbsgen linear: error: " << e.what() << "\n";
  return 1;
}

int linear_main(int argc, char** argv) { return linear_main(argc, argv, std::cout, std::cerr); }

}  // namespace mbsgen::cli
