#include "mbsgen/runtime/model/generated_model.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <limits>

#include <cerrno>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "mbsgen/runtime/model/static_equilibrium.hpp"

namespace mbsgen {

namespace {

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
  return s.empty() ? "(none)" : s;
}

Eigen::Index find(const std::vector<std::string>& list, const std::string& name,
                  const std::string& what, const std::string& model) {
  for (std::size_t i = 0; i < list.size(); ++i)
    if (list[i] == name) return static_cast<Eigen::Index>(i);
  throw NameError("unknown " + what + " '" + name + "' of model '" + model + "'; known: " + join(list));
}

void check_status(int status, const char* kernel, const std::string& model) {
  // Status 2: a model with closed loops whose dependent coordinates could not be found
  // (docs/generated-abi.md): Newton's method on the constraints failed from the operating point.
  if (status == 2)
    throw Error(std::string("kernel ") + kernel + " of model '" + model +
                "' could not close the kinematic loops there: the constraints have no solution near the "
                "operating point for these coordinates and parameters, or their Jacobian is singular (a dead "
                "point)");
  if (status != 0)
    throw NonFiniteError(std::string("kernel ") + kernel + " of model '" + model +
                         "' returned a non-finite value (check the parameters)");
}

// %.6g: a value in a message.
std::string g6(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

// Why a body's mass m and inertia tensor (Ixx, Iyy, Izz, Ixy, Ixz, Iyz at v) are no mass
// distribution's, or "". The conditions of the model file's check (generator model.cpp,
// inertia_problem): m >= 0; the principal moments A <= B <= C >= 0 with A + B >= C (equality for a
// flat body), within 32 ε max|d| for the rounding of the entries and of the eigensolver; a zero
// mass with a zero tensor.
std::string body_problem(const double* v) {
  if (v[0] < 0) return "has mass " + g6(v[0]) + " kg; a mass must be >= 0";
  Eigen::Matrix3d J;
  J << v[1], v[4], v[5], v[4], v[2], v[6], v[5], v[6], v[3];
  if (v[0] == 0 && !J.isZero(0)) return "has zero mass but a nonzero inertia tensor (give it a mass, or zero inertia)";
  const Eigen::Vector3d d = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(J, Eigen::EigenvaluesOnly).eigenvalues();
  const double tol = 32 * std::numeric_limits<double>::epsilon() * d.cwiseAbs().maxCoeff();
  const std::string moments = "principal moments " + g6(d(0)) + ", " + g6(d(1)) + ", " + g6(d(2)) + " kg m^2";
  if (d(0) < -tol) return "has an inertia tensor that is not positive semi-definite (" + moments + ")";
  if (d(0) + d(1) - d(2) < -2 * tol)
    return "has an inertia tensor that violates the triangle inequality (" + moments +
           ": A + B < C, which no mass distribution gives)";
  return "";
}

}  // namespace

void GeneratedModel::check_parameters() const {
  if (!k_.physical || k_.n_checks <= 0) return;
  std::size_t count = 0;
  for (int c = 0; c < k_.n_checks; ++c) count += std::string(k_.check_kinds[c]) == "body" ? 7 : 1;
  std::vector<double> v(count);
  check_status(k_.physical(p_.data(), v.data()), "physical", k_.model);
  const double* x = v.data();
  for (int c = 0; c < k_.n_checks; ++c) {
    const std::string kind = k_.check_kinds[c], label = k_.check_labels[c];
    std::string problem;
    if (kind == "body") {
      problem = body_problem(x);
      x += 7;
    } else {
      const bool positive = kind == "positive";
      const double value = *x++;
      const std::string unit = k_.check_units && k_.check_units[c] && *k_.check_units[c] ? std::string(" ") + k_.check_units[c] : "";
      if (positive ? !(value > 0) : !(value >= 0))
        problem = "is " + g6(value) + unit + "; it must be " + (positive ? "> 0" : ">= 0");
    }
    if (problem.empty()) continue;
    // The parameters it depends on, with their values.
    std::string values, names = k_.check_parameters[c];
    for (std::size_t start = 0; start <= names.size();) {
      const std::size_t end = std::min(names.find(',', start), names.size());
      const std::string name = names.substr(start, end - start);
      for (std::size_t i = 0; i < parameter_names_.size(); ++i)
        if (parameter_names_[i] == name) values += (values.empty() ? "" : ", ") + name + " = " + g6(p_[i]);
      start = end + 1;
    }
    throw ParameterError("model '" + std::string(k_.model) + "': with these parameter values (" + values + ") " +
                         label + " " + problem);
  }
}

std::vector<std::string> name_list(const char* const* list, int n) {
  std::vector<std::string> v;
  for (int i = 0; i < n; ++i) v.emplace_back(list && list[i] ? list[i] : "");
  return v;
}

GeneratedModel::GeneratedModel(const ModelKernels& kernels) : k_(kernels) {
  if (k_.abi_version != kKernelAbiVersion)
    throw Error("GeneratedModel: model '" + std::string(k_.id) + "' has kernel ABI version " +
                std::to_string(k_.abi_version) + ", this runtime expects " +
                std::to_string(kKernelAbiVersion) + "; regenerate it");
  if (!k_.operating_point || (!k_.linear && !k_.descriptor && !k_.dynamics))
    throw Error("GeneratedModel: model '" + std::string(k_.id) +
                "' lacks the operating_point kernel, or has neither the linear kernel nor those of a time step");
  parameter_names_ = name_list(k_.parameter_names, k_.n_parameters);
  p_.assign(k_.parameter_defaults, k_.parameter_defaults + k_.n_parameters);
}

void GeneratedModel::set(const std::string& name, double value) {
  const Eigen::Index i = find(parameter_names_, name, "parameter", k_.model);
  if (!std::isfinite(value))
    throw NonFiniteError("parameter '" + name + "' set to a non-finite value");
  p_[static_cast<std::size_t>(i)] = value;
}

void GeneratedModel::set_parameters(const std::vector<double>& values) {
  if (values.size() != p_.size())
    throw DimensionError("GeneratedModel::set_parameters: " + std::to_string(values.size()) +
                         " values for " + std::to_string(p_.size()) + " parameters of model '" +
                         k_.model + "'");
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!std::isfinite(values[i]))
      throw NonFiniteError("parameter '" + parameter_names_[i] + "' set to a non-finite value");
  p_ = values;
}

void GeneratedModel::set(const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == assignment.size())
    throw NameError("malformed assignment '" + assignment + "': expected NAME=VALUE");
  const std::string name = assignment.substr(0, eq), text = assignment.substr(eq + 1);
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0')
    throw NameError("malformed value '" + text + "' for parameter '" + name + "': expected a number");
  if (errno == ERANGE)  // beyond ±1.8e308, or below 2.2e-308 where strtod loses digits or all
    throw NonFiniteError("value '" + text + "' for parameter '" + name +
                         "' is outside the range of double (magnitudes 2.2e-308 to 1.8e308, or 0)");
  set(name, value);
}

Eigen::Index GeneratedModel::input_index(const std::string& name) const {
  return find(name_list(k_.input_names, k_.n_inputs), name, "input", k_.model);
}

Eigen::Index GeneratedModel::output_index(const std::string& name) const {
  return find(name_list(k_.output_names, k_.n_outputs), name, "output", k_.model);
}

Eigen::VectorXd GeneratedModel::residual(const Eigen::VectorXd& y, const Eigen::VectorXd& yd) const {
  Eigen::VectorXd r(size());
  std::vector<double> u(static_cast<std::size_t>(std::max(k_.n_inputs, 1)), 0.0);
  check_status(k_.residual(y.data(), yd.data(), u.data(), p_.data(), r.data()), "residual", k_.model);
  return r;
}

OperatingPoint GeneratedModel::operating_point() const {
  const Eigen::Index f = size();
  OperatingPoint op;
  op.y0.setZero(f);
  op.yd0.setZero(f);
  check_parameters();
  check_status(k_.operating_point(p_.data(), op.y0.data(), op.yd0.data()), "operating_point", k_.model);
  if (!k_.residual) {
    op.report = "given by the model";
    op.residual_norm = std::nan("");
    return op;
  }
  const Eigen::VectorXd yd0 = op.yd0;
  if (!k_.equilibrium) {
    op.residual_norm = residual(op.y0, yd0).norm();
    op.report = "given by the model";
    return op;
  }
  const Eigen::Index m = k_.n_inputs, r = k_.n_outputs;
  Eigen::MatrixXd M(f, f), Q(f, f), B(f, std::max<Eigen::Index>(m, 1)), Cy(std::max<Eigen::Index>(r, 1), f),
      Cv(std::max<Eigen::Index>(r, 1), f);
  if (!k_.linear && !k_.dynamics_jacobian)
    throw Error("operating_point: model '" + std::string(k_.model) + "' (scene '" + k_.scene +
                "') has an equilibrium operating point but neither the linear nor the dynamics_jacobian kernel");
  const Eigen::VectorXd ydd0 = Eigen::VectorXd::Zero(f);
  const std::vector<double> u0(static_cast<std::size_t>(std::max<Eigen::Index>(m, 1)), 0.0);
  StaticEquilibrium newton(f);
  bool at_guess = true;
  newton.compute(
      [&](const Eigen::VectorXd& y, Eigen::VectorXd& res) {
        // At the guess a kernel that cannot evaluate is the model's error (its message stands); at a
        // trial point of the line search it is a step too far: a non-finite residual, which the
        // search halves (a full Newton step from a nearly singular K can leave where the kernels
        // are finite).
        if (at_guess) {
          at_guess = false;
          res = residual(y, yd0);
          return;
        }
        try {
          res = residual(y, yd0);
        } catch (const NonFiniteError&) {
          res = Eigen::VectorXd::Constant(f, std::numeric_limits<double>::quiet_NaN());
        }
      },
      [&](const Eigen::VectorXd& y, Eigen::MatrixXd& J) {
        J.resize(f, f);
        if (k_.linear) {
          check_status(k_.linear(y.data(), yd0.data(), p_.data(), M.data(), Q.data(), J.data(), B.data(), Cy.data(),
                                 Cv.data()),
                       "linear", k_.model);
        } else {  // a scene that only simulates: K = ∂(k − q)/∂y = K_y at ÿ = 0, u = 0
          check_status(k_.dynamics_jacobian(y.data(), yd0.data(), ydd0.data(), u0.data(), p_.data(), J.data(), Q.data()),
                       "dynamics_jacobian", k_.model);
        }
      },
      op.y0);
  newton.throw_if_failed();
  op.y0 = newton.solution();
  op.equilibrium = true;
  op.iterations = newton.iterations();
  op.residual_norm = newton.residual_norm();
  op.report = newton.report();
  return op;
}

Eigen::VectorXd GeneratedModel::outputs(const OperatingPoint& op) const {
  if (!k_.outputs) return {};
  if (op.y0.size() != size() || op.yd0.size() != size())
    throw DimensionError("GeneratedModel::outputs: operating point of size " + std::to_string(op.y0.size()) + "/" +
                         std::to_string(op.yd0.size()) + " for a model with " + std::to_string(size()) +
                         " coordinates");
  Eigen::VectorXd z(std::max<Eigen::Index>(k_.n_outputs, 1));
  check_status(k_.outputs(op.y0.data(), op.yd0.data(), p_.data(), z.data()), "outputs", k_.model);
  z.conservativeResize(k_.n_outputs);
  return z;
}

void check_mass_semidefinite(const Eigen::MatrixXd& M, const std::string& what) {
  const Eigen::Index f = M.rows();
  if (f == 0) return;
  // The symmetric part: a mass matrix is symmetric up to the rounding of its kernel.
  const Eigen::MatrixXd S = (M + M.transpose()) / 2;
  const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(S, Eigen::EigenvaluesOnly).eigenvalues();
  const double norm = lambda.cwiseAbs().maxCoeff();
  // Rounding moves eigenvalues of a symmetric matrix by O(n·u·‖M‖); a margin of 1e-12·n·‖M‖.
  if (lambda(0) < -1e-12 * static_cast<double>(f) * norm) {
    char range[80];
    std::snprintf(range, sizeof range, "%.3g to %.3g", lambda(0), lambda(f - 1));
    throw Error(what + " is not positive semi-definite with these parameter values (eigenvalues " + range +
                "): a negative mass or inertia?");
  }
}

Eigen::VectorXd GeneratedModel::outputs_at(const Eigen::VectorXd& y, const Eigen::VectorXd& yd,
                                           const Eigen::VectorXd& ydd, const Eigen::VectorXd& u) const {
  const char* who = "GeneratedModel::outputs_at";
  if (k_.descriptor)
    throw Error(std::string(who) + ": model '" + k_.model + "' has nonholonomic constraints: its coordinate rates "
                "are not free, and a state that violates the velocity constraints would give outputs that mean "
                "nothing (the outputs at the operating point: outputs(operating_point()))");
  check_parameters();
  const Eigen::Index f = size(), m = k_.n_inputs;
  if (y.size() != f || yd.size() != f || ydd.size() != f || u.size() != m)
    throw DimensionError(std::string(who) + ": y, yd, ydd, u of sizes " + std::to_string(y.size()) + "/" +
                         std::to_string(yd.size()) + "/" + std::to_string(ydd.size()) + "/" + std::to_string(u.size()) +
                         " for a model with " + std::to_string(f) + " coordinates and " + std::to_string(m) + " inputs");
  if (!y.allFinite() || !yd.allFinite() || !ydd.allFinite() || !u.allFinite())
    throw NonFiniteError(std::string(who) + ": the state has a non-finite entry");
  if (!k_.outputs || k_.n_outputs == 0) return {};
  Eigen::VectorXd z(k_.n_outputs);
  if (k_.outputs_general) {
    double no_input[1] = {0.0};  // kernels read no u of a model without inputs; a valid pointer anyway
    check_status(k_.outputs_general(y.data(), yd.data(), ydd.data(), u.size() ? u.data() : no_input, p_.data(), z.data()),
                 "outputs_general", k_.model);
  } else if (k_.output_terms && !k_.input_kinds) {
    // Kernels from before outputs_general: their `outputs` give static loads whatever ÿ and u.
    throw Error(std::string(who) + ": the kernels of model '" + k_.model + "' give its loads only at rest (generated "
                "before outputs at any state existed): regenerate them");
  } else {
    // No output depends on ÿ, nor on a force input; a model with motion inputs has its
    // outputs with the support at rest at its reference position (as a simulation holds it), so
    // a nonzero motion input is refused rather than ignored.
    for (Eigen::Index i = 0; i < m; ++i)
      if (u[i] != 0.0 && k_.input_kinds && std::string(k_.input_kinds[i]) == "motion")
        throw Error(std::string(who) + ": input '" + k_.input_names[i] + "' of model '" + k_.model +
                    "' prescribes motion: its outputs are computed with the support at its reference position; "
                    "give the state relative to it (a nonzero motion input is not supported here)");
    check_status(k_.outputs(y.data(), yd.data(), p_.data(), z.data()), "outputs", k_.model);
  }
  return z;
}

DescriptorModel GeneratedModel::descriptor_model(const OperatingPoint& op) const {
  if (!k_.descriptor)
    throw Error("GeneratedModel::descriptor_model: model '" + std::string(k_.model) +
                "' has no nonholonomic constraints; its linear model is second order (linear_model)");
  const Eigen::Index f = size(), s = k_.n_speeds, n = f + s, m = k_.n_inputs, r = k_.n_outputs;
  if (op.y0.size() != f || op.yd0.size() != f)
    throw DimensionError("GeneratedModel::descriptor_model: operating point of size " + std::to_string(op.y0.size()) +
                         "/" + std::to_string(op.yd0.size()) + " for a model with " + std::to_string(f) + " coordinates");
  Eigen::MatrixXd E(n, n), A(n, n), B(n, m), C(r, n);
  double dummy[1];
  auto data = [&](Eigen::MatrixXd& X) { return X.size() ? X.data() : dummy; };
  check_status(k_.descriptor(op.y0.data(), op.yd0.data(), p_.data(), E.data(), A.data(), data(B), data(C)),
               "descriptor", k_.model);
  // The speeds' rows of E are the mass matrix in the independent speeds (Tᵀ M T): semi-definite
  // for any physical parameters, so a negative mass shows here as it does in linear_model.
  check_mass_semidefinite(E.bottomRightCorner(s, s), "GeneratedModel::descriptor_model: the mass matrix (in the independent "
                                                      "speeds) of model '" + std::string(k_.model) + "'");
  std::vector<std::string> states = name_list(k_.coordinate_names, k_.n_coordinates);
  for (const auto& speed : name_list(k_.speed_names, k_.n_speeds)) states.push_back(speed + "_dot");
  // An equation that vanishes in both E and A makes det(λE − A) ≡ 0. The model file's values
  // never do that (the generator checks them), so run-time parameter values did: name the ones
  // whose model-file value alone restores the equation (a wheel radius r = 0), not only the
  // equation.
  for (Eigen::Index i = 0; i < n; ++i)
    if ((E.row(i).array() == 0.0).all() && (A.row(i).array() == 0.0).all()) {
      // A parameter is named when its model-file value alone makes the equation come back.
      std::string suspects;
      const auto names = name_list(k_.parameter_names, k_.n_parameters);
      for (std::size_t j = 0; j < names.size(); ++j) {
        if (p_[j] == k_.parameter_defaults[j]) continue;
        std::vector<double> q = p_;
        q[j] = k_.parameter_defaults[j];
        Eigen::MatrixXd E2(n, n), A2(n, n), B2(n, m), C2(r, n);
        if (k_.descriptor(op.y0.data(), op.yd0.data(), q.data(), E2.data(), A2.data(), data(B2), data(C2)) != 0) continue;
        if (!(E2.row(i).array() == 0.0).all() || !(A2.row(i).array() == 0.0).all()) {
          std::ostringstream v;
          v.precision(17);
          v << names[j] << " = " << p_[j];
          suspects += (suspects.empty() ? "" : ", ") + v.str();
        }
      }
      throw SingularSystemError("GeneratedModel::descriptor_model: with these parameter values the equation of state '" +
                                states[static_cast<std::size_t>(i)] + "' of model '" + k_.model +
                                "' vanishes in both E and A, so det(λE − A) ≡ 0" +
                                (suspects.empty() ? std::string()
                                                  : "; the parameter value that does it: " + suspects +
                                                        " (its model-file value does not)"));
    }
  return DescriptorModel(E, A, B, C, {}, states, name_list(k_.input_names, k_.n_inputs),
                         name_list(k_.output_names, k_.n_outputs), name_list(k_.input_units, k_.n_inputs),
                         name_list(k_.output_units, k_.n_outputs));
}

LinearModel GeneratedModel::reduced_model(const OperatingPoint& op) const {
  if (!k_.reduced)
    throw Error("GeneratedModel::reduced_model: model '" + std::string(k_.model) + "' has no reduced second-order form");
  const Eigen::Index f = size(), n = k_.n_reduced, m = k_.n_inputs;
  if (op.y0.size() != f || op.yd0.size() != f)
    throw DimensionError("GeneratedModel::reduced_model: operating point of size " + std::to_string(op.y0.size()) + "/" +
                         std::to_string(op.yd0.size()) + " for a model with " + std::to_string(f) + " coordinates");
  Eigen::MatrixXd M(n, n), Q(n, n), K(n, n), B(n, m);
  double dummy[1];
  check_status(k_.reduced(op.y0.data(), op.yd0.data(), p_.data(), M.data(), Q.data(), K.data(), B.size() ? B.data() : dummy),
               "reduced", k_.model);
  return LinearModel(M, Q, K, B, Eigen::MatrixXd(), Eigen::MatrixXd(), name_list(k_.reduced_coordinate_names, k_.n_reduced),
                     name_list(k_.input_names, k_.n_inputs));
}

std::vector<std::pair<std::string, Eigen::MatrixXd>> GeneratedModel::reduced_parts(const OperatingPoint& op) const {
  std::vector<std::pair<std::string, Eigen::MatrixXd>> out;
  if (!k_.reduced_parts || k_.n_reduced_parts == 0) return out;
  const Eigen::Index n = k_.n_reduced;
  if (op.y0.size() != size())
    throw DimensionError("GeneratedModel::reduced_parts: operating point of size " + std::to_string(op.y0.size()) +
                         " for a model with " + std::to_string(size()) + " coordinates");
  std::vector<double> C(static_cast<std::size_t>(k_.n_reduced_parts * n * n));
  check_status(k_.reduced_parts(op.y0.data(), p_.data(), C.data()), "reduced_parts", k_.model);
  const auto names = name_list(k_.reduced_part_names, k_.n_reduced_parts);
  for (int i = 0; i < k_.n_reduced_parts; ++i)
    out.emplace_back(names[static_cast<std::size_t>(i)], Eigen::Map<const Eigen::MatrixXd>(C.data() + i * n * n, n, n));
  return out;
}

LinearModel GeneratedModel::linear_model(const OperatingPoint& op) const {
  if (!k_.linear && k_.descriptor)
    throw Error("model '" + std::string(k_.model) + "' has nonholonomic constraints: its linear model is first order, "
                "E x' = A x + B u (GeneratedModel::descriptor_model)");
  if (!k_.linear)
    throw Error("model '" + std::string(k_.model) + "', scene '" + k_.scene +
                "': no linear kernel (the scene asks for no linear analysis: modes, frf or static)");
  const Eigen::Index f = size(), m = k_.n_inputs, r = k_.n_outputs;
  if (op.y0.size() != f || op.yd0.size() != f)
    throw DimensionError("GeneratedModel::linear_model: operating point of size " +
                         std::to_string(op.y0.size()) + "/" + std::to_string(op.yd0.size()) +
                         " for a model with " + std::to_string(f) + " coordinates");
  Eigen::MatrixXd M(f, f), Q(f, f), K(f, f), B(f, m), Cy(r, f), Cv(r, f);
  // Kernels write nothing into zero-sized buffers; give them valid pointers anyway.
  double dummy[1];
  auto ptr = [&dummy](Eigen::MatrixXd& A) { return A.size() ? A.data() : dummy; };
  check_status(k_.linear(op.y0.data(), op.yd0.data(), p_.data(), ptr(M), ptr(Q), ptr(K), ptr(B),
                         ptr(Cy), ptr(Cv)),
               "linear", k_.model);
  check_mass_semidefinite(M, "GeneratedModel::linear_model: the mass matrix of model '" + std::string(k_.model) + "'");
  LinearModel lin(std::move(M), std::move(Q), std::move(K), std::move(B), std::move(Cy),
                  std::move(Cv), name_list(k_.coordinate_names, k_.n_coordinates),
                  name_list(k_.input_names, k_.n_inputs), name_list(k_.output_names, k_.n_outputs),
                  name_list(k_.coordinate_units, k_.n_coordinates),
                  name_list(k_.input_units, k_.n_inputs), name_list(k_.output_units, k_.n_outputs));
  if (k_.output_terms) {
    Eigen::MatrixXd Ca(r, f), D(r, m);
    check_status(k_.output_terms(op.y0.data(), op.yd0.data(), p_.data(), ptr(Ca), ptr(D)),
                 "output_terms", k_.model);
    lin = lin.with_output_terms(std::move(Ca), std::move(D));
  }
  if (k_.excitation) {
    Eigen::MatrixXd B1(f, m), B2(f, m), D1(r, m);
    check_status(k_.excitation(op.y0.data(), op.yd0.data(), p_.data(), ptr(B1), ptr(B2), ptr(D1)),
                 "excitation", k_.model);
    lin = lin.with_input_rates(std::move(B1), std::move(B2), std::move(D1));
  }
  return lin;
}

}  // namespace mbsgen

namespace mbsgen {

std::vector<std::string> GeneratedModel::sensitivity_parameters() const {
  return k_.sensitivity ? name_list(k_.sensitivity_parameter_names, k_.n_sensitivity_parameters)
                        : std::vector<std::string>{};
}

namespace {

// Column j of each derivative (s blocks of rows×cols one after the other), or 0×0 for an empty
// buffer.
Eigen::MatrixXd block(const std::vector<double>& buffer, Eigen::Index rows, Eigen::Index cols, Eigen::Index j) {
  if (buffer.empty() || rows * cols == 0) return Eigen::MatrixXd();
  return Eigen::Map<const Eigen::MatrixXd>(buffer.data() + j * rows * cols, rows, cols);
}

}  // namespace

std::vector<MatrixSensitivity> GeneratedModel::linear_sensitivities(const OperatingPoint& op,
                                                                    const std::vector<std::string>& names) const {
  if (!k_.sensitivity)
    throw Error("model '" + std::string(k_.model) + "', scene '" + k_.scene +
                "': no sensitivity kernel (it is made when asked: `mbsgen generate --sensitivity`, mbsgen_add_model's "
                "SENSITIVITY, or a scene with the analysis 'sensitivity'; `mbsgen run … -- modes --sensitivity` builds it "
                "itself; models with closed loops or rolling constraints have none)");
  const Eigen::Index f = size(), m = k_.n_inputs, r = k_.n_outputs, s = k_.n_sensitivity_parameters;
  if (op.y0.size() != f || op.yd0.size() != f)
    throw DimensionError("GeneratedModel::linear_sensitivities: operating point of size " + std::to_string(op.y0.size()) +
                         "/" + std::to_string(op.yd0.size()) + " for a model with " + std::to_string(f) + " coordinates");
  if (k_.equilibrium && !op.equilibrium)
    throw Error("GeneratedModel::linear_sensitivities: model '" + std::string(k_.model) +
                "' is linearized at a static equilibrium, and this operating point is not one (found by "
                "operating_point(): " + op.report + ")");
  const std::vector<std::string> known = sensitivity_parameters();
  std::vector<Eigen::Index> chosen;
  for (const auto& n : names) {
    const auto it = std::find(known.begin(), known.end(), n);
    if (it == known.end()) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw NameError("no sensitivity to '" + n + "' in model '" + std::string(k_.model) + "' (parameters: " + list + ")");
    }
    chosen.push_back(it - known.begin());
  }
  if (names.empty())
    for (Eigen::Index j = 0; j < s; ++j) chosen.push_back(j);
  // Along the chosen parameters only when the kernels offer it (a tape: a forward-mode pass per
  // parameter), else every parameter's derivatives, of which the chosen ones are kept.
  const bool along = !names.empty() && k_.sensitivity_along &&
                     (!k_.operating_point_sensitivity || k_.operating_point_sensitivity_along);
  const Eigen::Index c = along ? static_cast<Eigen::Index>(chosen.size()) : s;
  const std::vector<int> which(chosen.begin(), chosen.end());
  // The operating point's derivatives.
  Eigen::MatrixXd dy0 = Eigen::MatrixXd::Zero(f, c), dyd0 = Eigen::MatrixXd::Zero(f, c);
  if (k_.operating_point_sensitivity && f > 0 && c > 0) {
    check_status(along ? k_.operating_point_sensitivity_along(static_cast<int>(c), which.data(), op.y0.data(), op.yd0.data(),
                                                                p_.data(), dy0.data(), dyd0.data())
                       : k_.operating_point_sensitivity(op.y0.data(), op.yd0.data(), p_.data(), dy0.data(), dyd0.data()),
                 "operating_point_sensitivity", k_.model);
    if (k_.equilibrium) {  // dy0 holds dr: K dy0 = −dr
      const Eigen::PartialPivLU<Eigen::MatrixXd> lu(linear_model(op).K());
      if (!(lu.rcond() > std::numeric_limits<double>::epsilon()))
        throw SingularSystemError("GeneratedModel::linear_sensitivities: the stiffness matrix K of model '" +
                                  std::string(k_.model) + "' is singular at its equilibrium (rcond " +
                                  std::to_string(lu.rcond()) + "): the equilibrium does not move smoothly with the parameters");
      dy0 = -lu.solve(dy0);
    }
  }
  auto sized = [&](Eigen::Index rows, Eigen::Index cols) { return std::vector<double>(static_cast<std::size_t>(rows * cols * c)); };
  std::vector<double> dM = sized(f, f), dQ = sized(f, f), dK = sized(f, f), dB = sized(f, m), dCy = sized(r, f),
                      dCv = sized(r, f), dCa = sized(r, f), dD = sized(r, m), dB1 = sized(f, m), dB2 = sized(f, m),
                      dD1 = sized(r, m);
  double dummy[1] = {0};
  auto ptr = [&dummy](std::vector<double>& v) { return v.empty() ? dummy : v.data(); };
  const double* dy = dy0.size() ? dy0.data() : dummy;
  const double* dyd = dyd0.size() ? dyd0.data() : dummy;
  check_status(along ? k_.sensitivity_along(static_cast<int>(c), which.data(), op.y0.data(), op.yd0.data(), p_.data(), dy, dyd,
                                            ptr(dM), ptr(dQ), ptr(dK), ptr(dB), ptr(dCy), ptr(dCv), ptr(dCa), ptr(dD),
                                            ptr(dB1), ptr(dB2), ptr(dD1))
                     : k_.sensitivity(op.y0.data(), op.yd0.data(), p_.data(), dy, dyd, ptr(dM), ptr(dQ), ptr(dK), ptr(dB),
                                      ptr(dCy), ptr(dCv), ptr(dCa), ptr(dD), ptr(dB1), ptr(dB2), ptr(dD1)),
               "sensitivity", k_.model);
  const std::vector<std::string> all = name_list(k_.parameter_names, k_.n_parameters);
  std::vector<MatrixSensitivity> out;
  for (std::size_t q = 0; q < chosen.size(); ++q) {
    const Eigen::Index jj = chosen[q], j = along ? static_cast<Eigen::Index>(q) : jj;  // j: the block
    MatrixSensitivity d;
    d.parameter = known[static_cast<std::size_t>(jj)];
    d.value = p_[static_cast<std::size_t>(std::find(all.begin(), all.end(), d.parameter) - all.begin())];
    d.M = block(dM, f, f, j), d.Q = block(dQ, f, f, j), d.K = block(dK, f, f, j), d.B = block(dB, f, m, j);
    d.C_y = block(dCy, r, f, j), d.C_v = block(dCv, r, f, j);
    if (k_.output_terms) d.C_a = block(dCa, r, f, j), d.D = block(dD, r, m, j);
    if (k_.excitation) d.B1 = block(dB1, f, m, j), d.B2 = block(dB2, f, m, j), d.D1 = block(dD1, r, m, j);
    d.dy0 = dy0.col(j), d.dyd0 = dyd0.col(j);
    out.push_back(std::move(d));
  }
  return out;
}

}  // namespace mbsgen
