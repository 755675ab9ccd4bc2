// simulate(): SUNDIALS IDA on F(t, x, x') = [y' − v; M(y) v' + (k − q)(y, v, u(t))] (simulation.hpp).
#include "mbsgen/runtime/simulation.hpp"

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

namespace mbsgen {

namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// Internal steps allowed between two output samples before the run is reported as stuck.
constexpr long kMaxStepsPerSample = 200000;

std::string at_time(double t) {
  std::ostringstream s;
  s.precision(10);
  s << "at t = " << t << " s";
  return s.str();
}

// The SUNDIALS objects of one run, released in reverse order.
struct Ida {
  SUNContext context = nullptr;
  N_Vector x = nullptr, xp = nullptr;
  SUNMatrix A = nullptr;
  SUNLinearSolver solver = nullptr;
  void* mem = nullptr;
  Ida(const Ida&) = delete;
  Ida& operator=(const Ida&) = delete;
  explicit Ida(sunindextype size) {
    if (SUNContext_Create(nullptr, &context) != 0) throw Error("simulate: SUNContext_Create failed");
    x = N_VNew_Serial(size, context);
    xp = N_VNew_Serial(size, context);
    A = SUNDenseMatrix(size, size, context);
    mem = IDACreate(context);
    if (!x || !xp || !A || !mem) throw Error("simulate: out of memory for the integrator");
    solver = SUNLinSol_Dense(x, A, context);
    if (!solver) throw Error("simulate: SUNLinSol_Dense failed");
  }
  ~Ida() {
    if (mem) IDAFree(&mem);
    if (solver) SUNLinSolFree(solver);
    if (A) SUNMatDestroy(A);
    if (xp) N_VDestroy(xp);
    if (x) N_VDestroy(x);
    if (context) SUNContext_Free(&context);
  }
};

// The model's equations at a state, through the generated kernels.
class Equations {
 public:
  Equations(const GeneratedModel& model, const SimulationOptions& o)
      : k_(model.kernels()), p_(model.parameters()), n_(k_.n_coordinates), options_(o),
        M_(n_, n_), r_(n_), u_(k_.n_inputs), Ky_(n_, n_), Kv_(n_, n_) {}

  Index size() const { return n_; }
  const ModelKernels& kernels() const { return k_; }
  bool analytic_jacobian() const { return k_.dynamics_jacobian && !options_.difference_quotients; }

  const VectorXd& inputs(double t) {
    for (Index i = 0; i < u_.size(); ++i)
      u_[i] = options_.inputs.empty() ? 0.0 : options_.inputs[static_cast<std::size_t>(i)](t);
    return u_;
  }
  // M and k − q at (y, ẏ, u(t)); the kernel's status (0 success, 1 non-finite, 2 loops not closed).
  int evaluate(double t, const double* y, const double* yd) {
    inputs(t);
    if (k_.dynamics) return k_.dynamics(y, yd, u_.data(), p_.data(), M_.data(), r_.data());
    const int s = k_.mass_matrix(y, p_.data(), M_.data());
    return s ? s : k_.residual(y, yd, u_.data(), p_.data(), r_.data());
  }
  int jacobian(const double* y, const double* yd, const double* ydd) {
    return k_.dynamics_jacobian(y, yd, ydd, u_.data(), p_.data(), Ky_.data(), Kv_.data());
  }
  // ÿ = −M⁻¹ (k − q) at the last evaluate(), or a SimulationError when M is singular there.
  VectorXd accelerations(double t) const {
    const Eigen::PartialPivLU<MatrixXd> lu(M_);
    const double rcond = n_ ? lu.rcond() : 1.0;
    if (!(rcond > static_cast<double>(n_) * std::numeric_limits<double>::epsilon()))
      throw SimulationError("simulate: the mass matrix is singular " + at_time(t) + " (reciprocal condition number " +
                                std::to_string(rcond) + "): no unique accelerations there",
                            t);
    return lu.solve(-r_);
  }
  const MatrixXd& M() const { return M_; }
  const VectorXd& r() const { return r_; }
  const MatrixXd& Ky() const { return Ky_; }
  const MatrixXd& Kv() const { return Kv_; }
  const std::vector<double>& parameters() const { return p_; }

  int failed_status = 0;  // the last kernel status that was not 0, for the error message
  double failed_time = 0;

 private:
  const ModelKernels& k_;
  std::vector<double> p_;
  Index n_;
  const SimulationOptions& options_;
  MatrixXd M_;
  VectorXd r_, u_;
  MatrixXd Ky_, Kv_;
};

int residual_function(realtype t, N_Vector x, N_Vector xp, N_Vector F, void* data) {
  auto& eq = *static_cast<Equations*>(data);
  const Index n = eq.size();
  const double* xs = N_VGetArrayPointer(x);
  const double* xps = N_VGetArrayPointer(xp);
  double* f = N_VGetArrayPointer(F);
  const int status = eq.evaluate(t, xs, xs + n);
  if (status != 0) {
    eq.failed_status = status;
    eq.failed_time = t;
    return 1;  // recoverable: IDA retries with a smaller step
  }
  Eigen::Map<VectorXd>(f, n) = Eigen::Map<const VectorXd>(xps, n) - Eigen::Map<const VectorXd>(xs + n, n);
  Eigen::Map<VectorXd>(f + n, n) = eq.M() * Eigen::Map<const VectorXd>(xps + n, n) + eq.r();
  return 0;
}

// ∂F/∂x + c_j ∂F/∂x' = [c_j I, −I; K_y, c_j M + K_v].
int jacobian_function(realtype t, realtype cj, N_Vector x, N_Vector xp, N_Vector, SUNMatrix J, void* data, N_Vector,
                      N_Vector, N_Vector) {
  auto& eq = *static_cast<Equations*>(data);
  const Index n = eq.size();
  const double* xs = N_VGetArrayPointer(x);
  const double* xps = N_VGetArrayPointer(xp);
  int status = eq.evaluate(t, xs, xs + n);
  if (status == 0) status = eq.jacobian(xs, xs + n, xps + n);
  if (status != 0) {
    eq.failed_status = status;
    eq.failed_time = t;
    return 1;
  }
  Eigen::Map<MatrixXd> A(SM_DATA_D(J), 2 * n, 2 * n);
  A.setZero();
  A.topLeftCorner(n, n).diagonal().setConstant(cj);
  A.topRightCorner(n, n).diagonal().setConstant(-1.0);
  A.bottomLeftCorner(n, n) = eq.Ky();
  A.bottomRightCorner(n, n) = cj * eq.M() + eq.Kv();
  return 0;
}

void error_handler(int, const char*, const char*, char* message, void* data) {
  *static_cast<std::string*>(data) = message ? message : "";
}

// ---------------------------------------------------------------------------------------------

// The initial state: the operating point with options.initial applied.
void initial_state(const GeneratedModel& model, const OperatingPoint& op, const SimulationOptions& o, VectorXd& y,
                   VectorXd& yd) {
  const ModelKernels& k = model.kernels();
  y = op.y0;
  yd = op.yd0;
  const std::vector<std::string> names = name_list(k.coordinate_names, k.n_coordinates);
  for (const auto& [name, value] : o.initial) {
    if (!std::isfinite(value)) throw NonFiniteError("simulate: the initial value of '" + name + "' is not finite");
    bool found = false;
    for (std::size_t i = 0; i < names.size() && !found; ++i) {
      if (name == names[i]) y[static_cast<Index>(i)] = value, found = true;
      if (name == names[i] + "_dot") yd[static_cast<Index>(i)] = value, found = true;
    }
    if (!found) {
      std::string known;
      for (const auto& c : names) known += " " + c + " " + c + "_dot";
      throw NameError("simulate: no coordinate or rate '" + name + "' (known:" + known + ")");
    }
  }
}

void check_options(const GeneratedModel& model, const SimulationOptions& o) {
  const ModelKernels& k = model.kernels();
  if (!k.mass_matrix || !k.residual)
    throw Error("simulate: model '" + std::string(k.model) + "' (scene '" + k.scene +
                "') has no second-order kernels mass_matrix and residual (a model with rolling constraints, or a "
                "scene without them)");
  auto positive = [](double v, const char* what) {
    if (!(std::isfinite(v) && v > 0))
      throw Error(std::string("simulate: ") + what + " must be a finite number > 0, got " + std::to_string(v));
  };
  positive(o.duration, "the duration");
  positive(o.step, "the output step");
  positive(o.rtol, "rtol");
  positive(o.atol, "atol");
  if (o.duration / o.step > 1e8) throw Error("simulate: more than 10^8 output samples (duration / step)");
  if (!o.inputs.empty() && o.inputs.size() != static_cast<std::size_t>(k.n_inputs))
    throw DimensionError("simulate: " + std::to_string(o.inputs.size()) + " input signals for " +
                         std::to_string(k.n_inputs) + " inputs");
}

// The reason an IDASolve flag gives, and the time: for a failed Newton iteration or matrix
// factorization, a singular mass matrix there is named as the cause.
[[noreturn]] void integration_failed(int flag, Ida& ida, Equations& eq, const std::string& message) {
  double t = 0;
  IDAGetCurrentTime(ida.mem, &t);
  const Index n = eq.size();
  const double* x = N_VGetArrayPointer(ida.x);
  std::string why;
  switch (flag) {
    case IDA_TOO_MUCH_WORK:
      why = "more than " + std::to_string(kMaxStepsPerSample) +
            " internal steps between two samples (the tolerance cannot be met at a reasonable cost, or the "
            "motion is too fast for the output step)";
      break;
    case IDA_TOO_MUCH_ACC:
      why = "the tolerances ask for more accuracy than double precision gives (loosen --rtol/--atol)";
      break;
    case IDA_ERR_FAIL:
      why = "the error test failed repeatedly: the integrator cannot meet the tolerance";
      break;
    case IDA_RES_FAIL:
    case IDA_REP_RES_ERR:
    case IDA_FIRST_RES_FAIL:
      t = eq.failed_time;
      why = eq.failed_status == 2 ? "the kinematic loops could not be closed (a dead point, or far from the operating point)"
                                  : "the kernels returned non-finite values (the state or a parameter left the model's range)";
      break;
    default:
      if (eq.evaluate(t, x, x + n) == 0) eq.accelerations(t);  // throws when M is singular there
      why = flag == IDA_CONV_FAIL ? "Newton's iteration failed to converge repeatedly"
                                  : "the iteration matrix could not be factorized or solved";
  }
  throw SimulationError("simulate: the integration stopped " + at_time(t) + ": " + why +
                            (message.empty() ? "" : " [IDA: " + message + "]"),
                        t);
}

// Consistent derivatives at t: y' = v and v' = −M⁻¹ (k − q) with the inputs just after t.
void consistent_rates(Ida& ida, Equations& eq, double t) {
  const Index n = eq.size();
  const double* x = N_VGetArrayPointer(ida.x);
  double* xp = N_VGetArrayPointer(ida.xp);
  const double after = std::nextafter(t, std::numeric_limits<double>::infinity());
  if (eq.evaluate(after, x, x + n) != 0)
    throw SimulationError("simulate: the kernels returned non-finite values " + at_time(t) +
                              " (the initial state or a parameter is outside the model's range)",
                          t);
  Eigen::Map<VectorXd>(xp, n) = Eigen::Map<const VectorXd>(x + n, n);
  Eigen::Map<VectorXd>(xp + n, n) = eq.accelerations(t);
}

void configure(Ida& ida, Equations& eq, const SimulationOptions& o, std::string& message) {
  auto check = [](int flag, const char* what) {
    if (flag != 0) throw Error(std::string("simulate: ") + what + " failed (" + std::to_string(flag) + ")");
  };
  check(IDAInit(ida.mem, residual_function, 0.0, ida.x, ida.xp), "IDAInit");
  check(IDASStolerances(ida.mem, o.rtol, o.atol), "IDASStolerances");
  check(IDASetUserData(ida.mem, &eq), "IDASetUserData");
  check(IDASetErrHandlerFn(ida.mem, error_handler, &message), "IDASetErrHandlerFn");
  check(IDASetLinearSolver(ida.mem, ida.solver, ida.A), "IDASetLinearSolver");
  if (eq.analytic_jacobian()) check(IDASetJacFn(ida.mem, jacobian_function), "IDASetJacFn");
  check(IDASetMaxNumSteps(ida.mem, kMaxStepsPerSample), "IDASetMaxNumSteps");
}

// Stores sample j: the state, the inputs and the outputs at t.
void record(SimulationResult& r, Index j, double t, Ida& ida, Equations& eq) {
  const ModelKernels& k = eq.kernels();
  const Index n = eq.size();
  const double* x = N_VGetArrayPointer(ida.x);
  r.t[j] = t;
  r.y.col(j) = Eigen::Map<const VectorXd>(x, n);
  r.yd.col(j) = Eigen::Map<const VectorXd>(x + n, n);
  if (!r.y.col(j).allFinite() || !r.yd.col(j).allFinite())
    throw SimulationError("simulate: the state is not finite " + at_time(t), t);
  r.u.col(j) = eq.inputs(t);
  if (r.z.size() == 0) return;
  const std::vector<double>& p = eq.parameters();
  int status = 0;
  if (k.outputs_general) {
    if (eq.evaluate(t, x, x + n) != 0) throw SimulationError("simulate: non-finite kernel values " + at_time(t), t);
    const VectorXd ydd = eq.accelerations(t), u = r.u.col(j);
    status = k.outputs_general(x, x + n, ydd.data(), u.data(), p.data(), r.z.col(j).data());
  } else {
    status = k.outputs(x, x + n, p.data(), r.z.col(j).data());
  }
  if (status != 0) throw SimulationError("simulate: the outputs are not finite " + at_time(t), t);
}

// The breakpoints of the inputs inside (0, duration).
std::vector<double> breakpoints(const SimulationOptions& o) {
  std::set<double> b;
  for (const InputSignal& s : o.inputs)
    for (double t : s.breakpoints())
      if (t > 0 && t < o.duration) b.insert(t);
  return {b.begin(), b.end()};
}

void statistics(Ida& ida, SimulationResult& r) {
  long v = 0;
  IDAGetNumSteps(ida.mem, &v), r.steps += v;
  IDAGetNumResEvals(ida.mem, &v), r.residual_evaluations += v;
  IDAGetNumJacEvals(ida.mem, &v), r.jacobian_evaluations += v;
  IDAGetNumErrTestFails(ida.mem, &v), r.error_test_failures += v;
  IDAGetNumNonlinSolvConvFails(ida.mem, &v), r.nonlinear_failures += v;
}

}  // namespace

SimulationResult simulate(const GeneratedModel& model, const OperatingPoint& op, const SimulationOptions& o) {
  check_options(model, o);
  const ModelKernels& k = model.kernels();
  const Index n = k.n_coordinates;
  VectorXd y, yd;
  initial_state(model, op, o, y, yd);
  Equations eq(model, o);
  Ida ida(2 * n);
  std::string message;
  Eigen::Map<VectorXd>(N_VGetArrayPointer(ida.x), n) = y;
  Eigen::Map<VectorXd>(N_VGetArrayPointer(ida.x) + n, n) = yd;
  consistent_rates(ida, eq, 0.0);
  configure(ida, eq, o, message);

  const auto samples = static_cast<Index>(std::ceil(o.duration / o.step * (1 - 1e-12))) + 1;
  SimulationResult r;
  r.analytic_jacobian = eq.analytic_jacobian();
  r.t.resize(samples);
  r.y.resize(n, samples);
  r.yd.resize(n, samples);
  r.u.resize(k.n_inputs, samples);
  if (k.outputs || k.outputs_general) r.z.resize(k.n_outputs, samples);
  record(r, 0, 0.0, ida, eq);
  const std::vector<double> breaks = breakpoints(o);
  auto next_break = breaks.begin();
  double t = 0;
  for (Index j = 1; j < samples; ++j) {
    const double tout = j + 1 == samples ? o.duration : std::min(o.duration, static_cast<double>(j) * o.step);
    while (t < tout) {
      const bool at_break = next_break != breaks.end() && *next_break <= tout;
      const double stop = at_break ? *next_break : o.duration;
      IDASetStopTime(ida.mem, stop);
      double reached = t;
      const int flag = IDASolve(ida.mem, std::min(tout, stop), &reached, ida.x, ida.xp, IDA_NORMAL);
      if (flag < 0) integration_failed(flag, ida, eq, message);
      t = reached;
      if (at_break && t >= stop) {  // restart after the jump with consistent derivatives
        statistics(ida, r);
        consistent_rates(ida, eq, stop);
        IDAReInit(ida.mem, stop, ida.x, ida.xp);
        ++r.restarts, ++next_break;
      }
    }
    record(r, j, tout, ida, eq);
    if (o.progress) o.progress(tout);
  }
  statistics(ida, r);
  return r;
}

}  // namespace mbsgen
