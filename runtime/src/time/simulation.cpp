// simulate(): SUNDIALS CVODE, or our Radau IIA (radau.hpp), on x' = (v, −M(y)⁻¹ (k − q)(y, v, u(t))),
// x = (y, v) (simulation.hpp).
#include "mbsgen/runtime/time/simulation.hpp"

#include "time/block_cholesky.hpp"
#include "time/radau.hpp"
#include "time/second_order_newton.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <set>
#include <sstream>

namespace mbsgen {

namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// Internal steps allowed between two output samples before the run is reported as stuck.
constexpr long kMaxStepsPerSample = 200000;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// The most values (samples × (coordinates, rates, inputs, outputs)) a run keeps: 400 MB.
constexpr double kMaxValues = 5e7;

std::string short_number(double v) {
  std::ostringstream s;
  s.precision(3);
  s << v;
  return s.str();
}

std::string at_time(double t) {
  std::ostringstream s;
  s.precision(10);
  s << "at t = " << t << " s";
  return s.str();
}

// The SUNDIALS objects of one run, released in reverse order.
struct Cvode {
  SUNContext context = nullptr;
  N_Vector x = nullptr;
  SUNMatrix A = nullptr;
  SUNLinearSolver solver = nullptr;
  SUNNonlinearSolver fixed_point = nullptr;
  void* mem = nullptr;
  Cvode(const Cvode&) = delete;
  Cvode& operator=(const Cvode&) = delete;
  // `reduced`: BDF's Newton systems in n unknowns from the Jacobian kernel (second_order_newton.hpp).
  Cvode(sunindextype size, IntegrationMethod method, bool reduced) {
    try {
      create(size, method, reduced);
    } catch (...) {
      release();
      throw;
    }
  }
  ~Cvode() { release(); }

 private:
  void create(sunindextype size, IntegrationMethod method, bool reduced) {
    if (SUNContext_Create(nullptr, &context) != 0) throw Error("simulate: SUNContext_Create failed");
    x = N_VNew_Serial(size, context);
    mem = CVodeCreate(method == IntegrationMethod::adams ? CV_ADAMS : CV_BDF, context);
    if (!x || !mem) throw Error("simulate: out of memory for the integrator");
    if (method == IntegrationMethod::adams) {
      fixed_point = SUNNonlinSol_FixedPoint(x, 0, context);
      if (!fixed_point) throw Error("simulate: SUNNonlinSol_FixedPoint failed");
    } else if (reduced) {
      A = detail::new_second_order_matrix(size / 2, context);
      solver = A ? detail::new_second_order_solver(size / 2, context) : nullptr;
      if (!solver) throw Error("simulate: out of memory for the integrator's linear solver");
    } else {
      A = SUNDenseMatrix(size, size, context);
      solver = A ? SUNLinSol_Dense(x, A, context) : nullptr;
      if (!solver) throw Error("simulate: SUNLinSol_Dense failed");
    }
  }
  void release() {
    if (mem) CVodeFree(&mem);
    if (fixed_point) SUNNonlinSolFree(fixed_point);
    if (solver) SUNLinSolFree(solver);
    if (A) SUNMatDestroy(A);
    if (x) N_VDestroy(x);
    if (context) SUNContext_Free(&context);
  }
};

// The model's equations at a state, through the generated kernels: M and k − q, the
// accelerations ÿ = −M⁻¹ (k − q), and the Jacobian kernel.
class Equations : public detail::SecondOrderSystem {
 public:
  Equations(const GeneratedModel& model, const SimulationOptions& o)
      : k_(model.kernels()), p_(model.parameters()), n_(k_.n_coordinates), options_(o),
        M_(n_, n_), r_(n_), u_(k_.n_inputs), a_(n_), scale_(n_), scaled_r_(n_), scaled_(n_, n_), cholesky_factors_(n_), lu_(n_) {}

  // Closed loops, followed through any range: the tree's coordinates at the last accepted step
  // (`anchor_`), from which every evaluation closes the loops again (assemble_from).
  bool follows_loops() const {
    return k_.n_constraints > 0 && k_.assemble && k_.assemble_from && k_.dynamics_full && k_.constraints &&
           (k_.n_outputs == 0 || (k_.outputs_general ? k_.outputs_general_full != nullptr : k_.outputs_full != nullptr));
  }
  // The initial closed configuration: from the operating point's (yi0) to yi's by continuation
  // in the independent coordinates (32 steps, halved where Newton fails), so that the loops close
  // on the operating point's branch. False when they cannot be closed.
  bool close_initial(const VectorXd& yi0, const VectorXd& yi) {
    anchor_.assign(static_cast<std::size_t>(k_.n_tree_coordinates), 0.0);
    if (k_.assemble(yi0.data(), p_.data(), anchor_.data()) != 0) return false;
    double done = 0, step = 1.0 / 32;
    std::vector<double> trial;
    while (done < 1) {
      const double to = std::min(1.0, done + step);
      const VectorXd at = yi0 + to * (yi - yi0);
      trial = anchor_;
      if (k_.assemble_from(at.data(), p_.data(), trial.data()) == 0) {
        anchor_.swap(trial);
        done = to;
      } else if ((step /= 2) < 1.0 / 4096) {
        return false;
      }
    }
    return true;
  }
  // After an accepted step to y: the loops closed there become the start of the next ones.
  void advance(const double* y) {
    std::vector<double>& trial = tree_;
    trial = anchor_;
    if (k_.assemble_from(y, p_.data(), trial.data()) == 0) anchor_.swap(trial);
  }
  // The closed configuration at y (independent coordinates), from the anchor; null on failure.
  const double* closed(const double* y) {
    tree_ = anchor_;
    return k_.assemble_from(y, p_.data(), tree_.data()) == 0 ? tree_.data() : nullptr;
  }

  Index size() const { return n_; }
  const ModelKernels& kernels() const { return k_; }
  bool analytic_jacobian() const {
    return options_.method != IntegrationMethod::adams && k_.dynamics_jacobian && !options_.difference_quotients;
  }

  // The inputs at t; at the start of a segment (t = 0, or a breakpoint where the integrator
  // restarted) their value just after it, so that a step at the start acts from the start.
  const VectorXd& inputs(double t) {
    return inputs_at(t <= segment_start_ ? std::nextafter(segment_start_, kInfinity) : t);
  }
  const VectorXd& inputs_at(double t) {  // the signals' own values (left-continuous at a step)
    for (Index i = 0; i < u_.size(); ++i)
      u_[i] = options_.inputs.empty() ? 0.0 : options_.inputs[static_cast<std::size_t>(i)](t);
    return u_;
  }
  void start_segment(double t) { segment_start_ = t; }
  // M, k − q and ÿ at (y, ẏ, u(t)); false (with the reason kept) when a kernel fails or M is
  // singular. ÿ by refinement on the last Cholesky factors where M is near them (to the backward
  // error of a stable solve: block_cholesky.hpp), else from M's own factors, whose singularity is
  // judged (factor_mass()): at the Jacobian's state (factor_next()), where refinement does not
  // converge fast, and at least every kRefinedEvaluations evaluations.
  // `signal_values`: with the signals' own values at t (a sample's, which it stores), not those
  // just after a restart at t.
  bool evaluate(double t, const double* y, const double* yd, bool signal_values = false) {
    if (signal_values) inputs_at(t); else inputs(t);
    if (!kernels(t, y, yd)) return false;
    const bool refined = cholesky_ && !factor_next_ && refined_ < kRefinedEvaluations &&
                         cholesky_factors_.solve_refined(M_, r_, a_);
    factor_next_ = false;
    refined_ = refined ? refined_ + 1 : 0;
    if (!refined) {
      if (!factor_mass()) return fail(t, Failure::singular_mass);
      if (cholesky_) {  // ÿ = −M⁻¹ (k − q)
        cholesky_factors_.solve_negated(r_, a_);
      } else {  // ÿ = −S (S M S)⁻¹ S (k − q)
        scaled_r_ = r_.cwiseProduct(scale_);
        a_.noalias() = lu_.solve(scaled_r_);
        a_.array() *= -scale_.array();
      }
    }
    if (!a_.allFinite()) return fail(t, Failure::non_finite);
    return true;
  }
  // The next evaluate() factors M afresh (its singularity judged again), rather than refining
  // on the last factors: at the Jacobian's state.
  void factor_next() { factor_next_ = true; }
  // The factors of M, judged by those of the equilibrated S M S, S = diag(|M_ii|)^(-1/2) (whose
  // pivots do not depend on the units: kg against kg m²). A mass matrix is symmetric positive
  // definite: Cholesky's factors first, of M itself, since S M S = (S L)(S L)ᵀ and Cholesky's
  // rounding errors are bounded by S M S's condition, not M's (Demmel 1989; Higham, Accuracy and
  // Stability of Numerical Algorithms, 2nd ed., Thm. 10.7). Eigen's are unblocked below 32
  // coordinates and a third of the LU's work: half the time of an evaluation of the middle ear
  // was its blocked LU. Block by block where M is block diagonal (block_cholesky.hpp: the middle
  // ear's three bodies). The equilibrated LU's where they fail. False when M is singular to
  // working precision: the ratio of the pivots (s_i² L_ii² of Cholesky's) bounds the reciprocal
  // condition number of S M S from above (Eigen's rcond() estimate is 1 for an exactly singular
  // matrix), and where it is below 1e-8 the condition estimate decides (a few solves more, so not
  // at every evaluation of a well-conditioned M).
  bool factor_mass() {
    const double singular = static_cast<double>(n_) * std::numeric_limits<double>::epsilon();
    // Cholesky reads one triangle: only for an M symmetric to rounding in its equilibrated units
    // (the generator's is, by construction; anything else takes the LU, which reads all of it).
    // Symmetry is a property of the kernels, not of the state: judged at the first evaluation,
    // not at every one.
    if (!symmetry_known_) {
      detail::mass_scale(M_, scale_);
      double asymmetry = 0;
      for (Index j = 0; j < n_; ++j)
        for (Index i = j + 1; i < n_; ++i)
          asymmetry = std::max(asymmetry, std::abs(M_(i, j) - M_(j, i)) * scale_[i] * scale_[j]);
      symmetric_ = asymmetry <= 1e-10;
      symmetry_known_ = true;
    }
    if (symmetric_ && cholesky_factors_.compute(M_)) {
      // The squared pivots of S M S, s_i² L_ii² = L_ii² / |M_ii| (non-finite: singular).
      double smallest = n_ > 0 ? kInfinity : 1.0, largest = n_ > 0 ? 0.0 : 1.0;
      for (Index i = 0; i < n_; ++i) {
        const double L = cholesky_factors_.diagonal()[i], d = L * L / std::abs(M_(i, i));
        if (!std::isfinite(d)) smallest = 0;
        smallest = std::min(smallest, d);
        largest = std::max(largest, d);
      }
      rcond_ = smallest / largest;
      if (rcond_ > singular && rcond_ < 1e-8) {
        scaled_ = M_;
        detail::equilibrate(M_, scale_, scaled_);
        rcond_ = std::min(rcond_, Eigen::LLT<MatrixXd>(scaled_).rcond());
      }
      if ((cholesky_ = rcond_ > singular)) return true;
    }
    cholesky_ = false;
    scaled_ = M_;
    detail::equilibrate(M_, scale_, scaled_);
    lu_.compute(scaled_);
    rcond_ = detail::pivot_ratio(lu_);
    if (rcond_ > singular && rcond_ < 1e-8) rcond_ = std::min(rcond_, lu_.rcond());
    return rcond_ > singular;
  }
  // M, K_y(y, ẏ, ÿ) and K_v after evaluate() at the same state: the Jacobian's parts
  // (second_order_newton.hpp).
  bool jacobian(double t, const double* y, const double* yd, detail::SecondOrderMatrix& J) {
    J.c = 1;
    J.d = 0;
    return jacobian_kernel(t, y, yd, J.M, J.Ky, J.Kv);
  }
  const VectorXd& accelerations() const { return a_; }
  const std::vector<double>& parameters() const { return p_; }

  // For Radau IIA (radau.hpp).
  bool accelerations(double t, const double* y, const double* yd, VectorXd& a) override {
    if (!evaluate(t, y, yd)) return false;
    a = a_;
    return true;
  }
  bool jacobian_mass(double t, const double* y, const double* yd, MatrixXd& M, VectorXd& a) override {
    factor_next();
    if (!evaluate(t, y, yd)) return false;
    M = M_;
    a = a_;
    return true;
  }
  bool has_jacobian() const override { return analytic_jacobian(); }
  bool jacobian(double t, const double* y, const double* yd, MatrixXd& M, MatrixXd& Ky, MatrixXd& Kv) override {
    factor_next();
    return evaluate(t, y, yd) && jacobian_kernel(t, y, yd, M, Ky, Kv);
  }

  enum class Failure { none, non_finite, loops, singular_mass, exception };
  Failure failure = Failure::none;  // the last failure in the current CVode call, for the message
  double failed_time = 0;
  std::string reason() const {
    switch (failure) {
      case Failure::non_finite:
        return "the kernels returned non-finite values (the state or a parameter left the model's range)";
      case Failure::loops:
        return follows_loops() ? "the kinematic loops could not be closed (a dead point of the independent coordinates, "
                                 "or a step too large to close them from the last one)"
                               : "the kinematic loops could not be closed (a dead point, or far from the operating point)";
      case Failure::singular_mass:
        return "the mass matrix is singular (reciprocal condition number " + short_number(rcond_) +
               "): no unique accelerations";
      case Failure::exception:
        return "out of memory in the right-hand side or its Jacobian";
      case Failure::none:
        break;
    }
    return "";
  }

 private:
  // M, K_y and K_v from the Jacobian kernel, after evaluate() at the same state.
  bool jacobian_kernel(double t, const double* y, const double* yd, MatrixXd& M, MatrixXd& Ky, MatrixXd& Kv) {
    if (k_.dynamics_jacobian(y, yd, a_.data(), u_.data(), p_.data(), Ky.data(), Kv.data()) != 0)
      return fail(t, Failure::non_finite);
    M = M_;
    return Ky.allFinite() && Kv.allFinite() ? true : fail(t, Failure::non_finite);
  }
  // M and k − q at (y, ẏ) and the inputs u_.
  bool kernels(double t, const double* y, const double* yd) {
    int s = 0;
    if (follows_loops()) {
      const double* tree = closed(y);
      s = tree ? k_.dynamics_full(tree, yd, u_.data(), p_.data(), M_.data(), r_.data()) : 2;
    } else if (k_.dynamics) {
      s = k_.dynamics(y, yd, u_.data(), p_.data(), M_.data(), r_.data());
    } else {
      s = k_.mass_matrix(y, p_.data(), M_.data());
      if (s == 0) s = k_.residual(y, yd, u_.data(), p_.data(), r_.data());
    }
    return s == 0 ? true : fail(t, s == 2 ? Failure::loops : Failure::non_finite);
  }
  bool fail(double t, Failure f) {
    failure = f;
    failed_time = t;
    return false;
  }
  const ModelKernels& k_;
  std::vector<double> p_;
  Index n_;
  const SimulationOptions& options_;
  MatrixXd M_;
  VectorXd r_, u_, a_, scale_, scaled_r_;
  MatrixXd scaled_;
  std::vector<double> anchor_, tree_;
  detail::BlockCholesky cholesky_factors_;  // M's, block by block where it is block diagonal
  Eigen::PartialPivLU<MatrixXd> lu_;
  bool cholesky_ = false;  // the last factor_mass() kept cholesky_factors_
  bool factor_next_ = false;  // factor_next()
  // Evaluations since M's singularity was last judged: refined solves in a row, at most
  // kRefinedEvaluations (every CVODE evaluation between two Jacobians, or Adams without one,
  // could refine). A fresh factorization costs about four refined solves in the middle ear.
  static constexpr int kRefinedEvaluations = 64;
  int refined_ = 0;
  bool symmetry_known_ = false, symmetric_ = false;  // of M (factor_mass())
  double rcond_ = 0, segment_start_ = 0;
};

// x' = (v, ÿ(y, v, u(t))).
int rhs_function(realtype t, N_Vector x, N_Vector xp, void* data) noexcept {
  auto& eq = *static_cast<Equations*>(data);
  try {
    const Index n = eq.size();
    const double* xs = N_VGetArrayPointer(x);
    double* f = N_VGetArrayPointer(xp);
    if (!eq.evaluate(t, xs, xs + n)) return 1;  // recoverable: CVODE retries with a smaller step
    Eigen::Map<VectorXd>(f, n) = Eigen::Map<const VectorXd>(xs + n, n);
    Eigen::Map<VectorXd>(f + n, n) = eq.accelerations();
    return 0;
  } catch (...) {  // nothing may unwind through CVODE's C frames
    eq.failure = Equations::Failure::exception;
    eq.failed_time = t;
    return -1;
  }
}

// ∂x'/∂x = [0, I; −M⁻¹ K_y, −M⁻¹ K_v] as its parts M, K_y, K_v (second_order_newton.hpp), with
// K_y at the accelerations of the state (evaluated again for M and ÿ there).
int jacobian_function(realtype t, N_Vector x, N_Vector, SUNMatrix J, void* data, N_Vector, N_Vector,
                      N_Vector) noexcept {
  auto& eq = *static_cast<Equations*>(data);
  try {
    const Index n = eq.size();
    const double* xs = N_VGetArrayPointer(x);
    eq.factor_next();
    if (!eq.evaluate(t, xs, xs + n)) return 1;
    return eq.jacobian(t, xs, xs + n, detail::parts(J)) ? 0 : 1;
  } catch (...) {
    eq.failure = Equations::Failure::exception;
    eq.failed_time = t;
    return -1;
  }
}

void error_handler(int, const char*, const char*, char* message, void* data) noexcept {
  try {
    *static_cast<std::string*>(data) = message ? message : "";
  } catch (...) {  // out of memory for the message: report without it
  }
}

// ---------------------------------------------------------------------------------------------

// The position of state `name` in x = (y, ẏ): a coordinate `phi` at its index, a rate `phi_dot`
// at n + its index; NameError naming the known states otherwise (`what`: for the message).
Index state_index(const ModelKernels& k, const std::string& name, const std::string& what) {
  const std::vector<std::string> names = name_list(k.coordinate_names, k.n_coordinates);
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (name == names[i]) return static_cast<Index>(i);
    if (name == names[i] + "_dot") return k.n_coordinates + static_cast<Index>(i);
  }
  std::string known;
  for (const auto& c : names) known += (known.empty() ? "" : ", ") + c + ", " + c + "_dot";
  throw NameError("simulate: no coordinate or rate '" + name + "'" + what + "; known: " + known);
}

// The initial state: the operating point with options.initial applied.
void initial_state(const GeneratedModel& model, const OperatingPoint& op, const SimulationOptions& o, VectorXd& y,
                   VectorXd& yd) {
  const ModelKernels& k = model.kernels();
  y = op.y0;
  yd = op.yd0;
  for (const auto& [name, value] : o.initial) {
    if (!std::isfinite(value)) throw NonFiniteError("simulate: the initial value of '" + name + "' is not finite");
    const Index i = state_index(k, name, "");
    (i < k.n_coordinates ? y[i] : yd[i - k.n_coordinates]) = value;
  }
}

// The absolute tolerance of each state (coordinates, then rates): atol, or atol_of by name.
VectorXd absolute_tolerances(const ModelKernels& k, const SimulationOptions& o) {
  VectorXd atol = VectorXd::Constant(2 * k.n_coordinates, o.atol);
  for (const auto& [name, value] : o.atol_of) {
    if (!(std::isfinite(value) && value > 0))
      throw Error("simulate: the absolute tolerance of '" + name + "' must be a finite number > 0, got " +
                  std::to_string(value));
    atol[state_index(k, name, " for an absolute tolerance")] = value;
  }
  return atol;
}

void check_options(const GeneratedModel& model, const SimulationOptions& o) {
  const ModelKernels& k = model.kernels();
  if (!k.mass_matrix || !k.residual)
    throw Error("simulate: model '" + std::string(k.model) + "' (scene '" + k.scene +
                "') has no second-order kernels mass_matrix and residual: " +
                (k.descriptor ? "its kernels are the descriptor form of a model with rolling constraints"
                              : "the scene does not ask for simulate (add it to its analyses)"));
  auto positive = [](double v, const char* what) {
    if (!(std::isfinite(v) && v > 0))
      throw Error(std::string("simulate: ") + what + " must be a finite number > 0, got " + std::to_string(v));
  };
  positive(o.duration, "the duration");
  positive(o.step, "the output step");
  positive(o.rtol, "rtol");
  const bool radau = o.method == IntegrationMethod::radau || o.method == IntegrationMethod::radau9;
  if (radau && o.rtol < 100 * std::numeric_limits<double>::epsilon())
    throw Error(std::string("simulate: --method ") + (o.method == IntegrationMethod::radau ? "radau" : "radau9") +
                " needs rtol of at least 100 ε = 2.2e-14 (its Newton iteration stops at "
                "10 ε / rtol of the tolerance), got " + std::to_string(o.rtol));
  positive(o.atol, "atol");
  absolute_tolerances(k, o);  // the names and values of atol_of
  const double values = (o.duration / o.step + 1) * (2.0 * k.n_coordinates + k.n_inputs + k.n_outputs);
  if (values > kMaxValues)
    throw Error("simulate: " + short_number(o.duration / o.step + 1) + " samples of " +
                std::to_string(2 * k.n_coordinates + k.n_inputs + k.n_outputs) + " values each are more than " +
                short_number(kMaxValues) + " values (400 MB): sample less often (--step) or simulate less time");
  if (!o.inputs.empty() && o.inputs.size() != static_cast<std::size_t>(k.n_inputs))
    throw DimensionError("simulate: " + std::to_string(o.inputs.size()) + " input signals for " +
                         std::to_string(k.n_inputs) + " inputs");
  // The kernels hold a moving support at rest (prescribed_motion.hpp): a signal on a motion
  // input would be silently lost.
  for (std::size_t j = 0; j < o.inputs.size(); ++j)
    if (is_motion_input(k, static_cast<int>(j)) && !o.inputs[j].is_zero())
      throw Error("simulate: input '" + std::string(k.input_names[j]) +
                  "' prescribes motion; a moving support is taken by the frequency response (frf), "
                  "not yet by simulate");
}

// The reason a CVode flag gives, and the time.
// `reached`: the last time the integrator stood at (a lost step control can leave CVODE's own
// time, or the time of a failed evaluation, not finite).
[[noreturn]] void integration_failed(int flag, Cvode& cv, const Equations& eq, const std::string& message, double reached) {
  double t = 0;
  CVodeGetCurrentTime(cv.mem, &t);
  if (!std::isfinite(t)) t = reached;
  std::string why;
  switch (flag) {
    case CV_TOO_MUCH_WORK:
      why = "more than " + std::to_string(kMaxStepsPerSample) +
            " internal steps between two samples (the tolerance cannot be met at a reasonable cost, the problem is "
            "stiff for --method adams, or the motion is too fast for the output step)";
      break;
    case CV_TOO_MUCH_ACC:
      why = "the tolerances ask for more accuracy than double precision gives (loosen --rtol/--atol)";
      break;
    case CV_ERR_FAILURE:
      why = "the error test failed repeatedly: the integrator cannot meet the tolerance";
      break;
    case CV_CONV_FAILURE:
      why = "the corrector iteration failed to converge repeatedly";
      break;
    default: {
      double last = 0, next = 0;
      CVodeGetLastStep(cv.mem, &last);
      CVodeGetCurrentStep(cv.mem, &next);
      const double h = last != 0 ? last : next;
      const bool stuck = h != 0 && std::abs(h) <= 4 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(t));
      const bool lost = flag == CV_BAD_T || flag == CV_ILL_INPUT;  // from its interpolation, or a time not finite
      why = stuck ? "the integrator cannot advance (step size " + short_number(h) +
                        " s): the motion is too fast there (forces or parameters far out of range?)"
            : lost ? "the integrator lost control of its step size (step " + short_number(h) +
                         " s): the forces or parameters are far out of range?"
                  : "the integrator failed (CVODE flag " + std::to_string(flag) + ")";
    }
  }
  // The cause the kernels or M gave, where the failure is theirs (not for a tolerance that cannot
  // be met: a failed evaluation CVODE recovered from may be recorded before it).
  const bool theirs = flag == CV_RHSFUNC_FAIL || flag == CV_FIRST_RHSFUNC_ERR || flag == CV_REPTD_RHSFUNC_ERR ||
                      flag == CV_UNREC_RHSFUNC_ERR || flag == CV_LSETUP_FAIL || flag == CV_CONV_FAILURE;
  if (theirs && eq.failure != Equations::Failure::none && !std::isfinite(eq.failed_time)) {
    why = "the integrator lost control of its step size (its time is no longer finite): the forces or parameters "
          "are far out of range?";
  } else if (theirs && eq.failure != Equations::Failure::none) {
    t = eq.failed_time;
    why = eq.reason();
  } else if (eq.failure != Equations::Failure::none && std::isfinite(eq.failed_time)) {  // a likely cause: say so, as such
    why += "; the last evaluation that failed on the way, at t = " + short_number(eq.failed_time) + " s: " + eq.reason();
  }
  throw SimulationError("simulate: the integration stopped " + at_time(t) + ": " + why +
                            (message.empty() ? "" : " [CVODE: " + message + "]"),
                        t);
}

void configure(Cvode& cv, Equations& eq, const SimulationOptions& o, std::string& message) {
  auto check = [](int flag, const char* what) {
    if (flag != 0) throw Error(std::string("simulate: ") + what + " failed (" + std::to_string(flag) + ")");
  };
  check(CVodeInit(cv.mem, rhs_function, 0.0, cv.x), "CVodeInit");
  if (o.atol_of.empty()) {
    check(CVodeSStolerances(cv.mem, o.rtol, o.atol), "CVodeSStolerances");
  } else {  // CVODE copies the vector
    VectorXd atol = absolute_tolerances(eq.kernels(), o);
    N_Vector v = N_VMake_Serial(atol.size(), atol.data(), cv.context);
    if (!v) throw Error("simulate: out of memory for the tolerances");
    const int flag = CVodeSVtolerances(cv.mem, o.rtol, v);
    N_VDestroy(v);
    check(flag, "CVodeSVtolerances");
  }
  check(CVodeSetUserData(cv.mem, &eq), "CVodeSetUserData");
  check(CVodeSetErrHandlerFn(cv.mem, error_handler, &message), "CVodeSetErrHandlerFn");
  if (cv.fixed_point) {
    check(CVodeSetNonlinearSolver(cv.mem, cv.fixed_point), "CVodeSetNonlinearSolver");
  } else {
    check(CVodeSetLinearSolver(cv.mem, cv.solver, cv.A), "CVodeSetLinearSolver");
    if (eq.analytic_jacobian()) check(CVodeSetJacFn(cv.mem, jacobian_function), "CVodeSetJacFn");
  }
  check(CVodeSetMaxNumSteps(cv.mem, kMaxStepsPerSample), "CVodeSetMaxNumSteps");
  check(CVodeSetMaxHnilWarns(cv.mem, -1), "CVodeSetMaxHnilWarns");  // no messages on stderr
}

// Stores sample j: the state x, the inputs and the outputs at t.
void record(SimulationResult& r, Index j, double t, const double* x, Equations& eq) {
  const ModelKernels& k = eq.kernels();
  const Index n = eq.size();
  r.t[j] = t;
  r.y.col(j) = Eigen::Map<const VectorXd>(x, n);
  r.yd.col(j) = Eigen::Map<const VectorXd>(x + n, n);
  if (!r.y.col(j).allFinite() || !r.yd.col(j).allFinite())
    throw SimulationError("simulate: the state is not finite " + at_time(t), t);
  r.u.col(j) = eq.inputs_at(t);
  const std::vector<double>& p = eq.parameters();
  const double* tree = nullptr;  // closed loops followed: the tree's coordinates at the sample
  if (eq.follows_loops() && !(tree = eq.closed(x)))
    throw SimulationError("simulate: the kinematic loops could not be closed " + at_time(t), t);
  if (k.assemble && k.constraints && k.n_constraints > 0) {  // closed loops: Φ at the sample
    std::vector<double> own(static_cast<std::size_t>(k.n_tree_coordinates)), phi(static_cast<std::size_t>(k.n_constraints));
    if (!tree && k.assemble(x, p.data(), own.data()) != 0)
      throw SimulationError("simulate: the kinematic loops could not be closed " + at_time(t), t);
    if (k.constraints(tree ? tree : own.data(), p.data(), phi.data()) != 0)
      throw SimulationError("simulate: the constraints are not finite " + at_time(t), t);
    for (double v : phi) r.constraint_drift = std::max(r.constraint_drift, std::abs(v));
  }
  if (r.z.rows() == 0) return;
  int status = 0;
  if (k.outputs_general) {
    // The accelerations under the inputs the sample stores (before a jump at t, whether or not
    // the integrator has restarted there yet).
    if (!eq.evaluate(t, x, x + n, true)) throw SimulationError("simulate: " + eq.reason() + " " + at_time(t), t);
    const VectorXd u = r.u.col(j);
    const double* ydd = eq.accelerations().data();
    if (tree && !(tree = eq.closed(x)))  // again: evaluate() closed the loops in the same buffer
      throw SimulationError("simulate: the kinematic loops could not be closed " + at_time(t), t);
    status = tree ? k.outputs_general_full(tree, x + n, ydd, u.data(), p.data(), r.z.col(j).data())
                  : k.outputs_general(x, x + n, ydd, u.data(), p.data(), r.z.col(j).data());
  } else {
    status = tree ? k.outputs_full(tree, x + n, p.data(), r.z.col(j).data()) : k.outputs(x, x + n, p.data(), r.z.col(j).data());
  }
  if (status != 0) throw SimulationError("simulate: the outputs are not finite " + at_time(t), t);
}

SimulationResult allocated(const ModelKernels& k, Index samples, bool outputs) {
  SimulationResult r;
  r.t.resize(samples);
  r.y.resize(k.n_coordinates, samples);
  r.yd.resize(k.n_coordinates, samples);
  r.u.resize(k.n_inputs, samples);
  r.z.resize(outputs && simulates_outputs(k) ? k.n_outputs : 0, samples);
  return r;
}

// Where the integrator stops: at every input step (restarting there, as its history holds the
// old input) and at every knot of an input table (so that no knot is stepped over).
struct Stop {
  double t;
  bool restart;
};

// Times closer than this are one: a millionth of the output step, or a few ulps of t.
double window(const SimulationOptions& o, double t) {
  return std::max(1e-9 * o.step, 16 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(t)));
}

std::vector<Stop> stop_times(const SimulationOptions& o) {
  std::vector<Stop> all;
  for (const InputSignal& s : o.inputs) {
    for (double t : s.breakpoints()) all.push_back({t, true});
    for (double t : s.knots()) all.push_back({t, false});
  }
  std::sort(all.begin(), all.end(), [](const Stop& a, const Stop& b) { return a.t < b.t; });
  std::vector<Stop> stops;
  for (const Stop& s : all) {
    if (!(s.t > window(o, 0)) || s.t >= o.duration - window(o, o.duration)) continue;  // inside (0, duration)
    if (!stops.empty() && s.t - stops.back().t <= window(o, s.t))
      stops.back().restart = stops.back().restart || s.restart;
    else
      stops.push_back(s);
  }
  return stops;
}

// A time integrator as the sampling loop drives it: one step at a time, restarts where an input
// jumps, and the state between steps from its interpolant.
class Integrator {
 public:
  virtual ~Integrator() = default;
  // One step towards tout, not past stop; the time reached. SimulationError when it fails.
  virtual double step(double tout, double stop) = 0;
  // After a jump of an input at t (the new segment's inputs are those just after t).
  virtual void restart(double t, SimulationResult& r) = 0;
  virtual const double* state() = 0;  // at the time reached
  virtual void interpolate(double t, double* x) = 0;
  [[noreturn]] virtual void too_much_work(double t) = 0;
  virtual void add_statistics(SimulationResult& r) = 0;
};

// CVODE (BDF or Adams) in its one-step mode.
class CvodeIntegrator : public Integrator {
 public:
  CvodeIntegrator(Equations& eq, const SimulationOptions& o, const VectorXd& x0)
      : eq_(eq), cv_(x0.size(), o.method, eq.analytic_jacobian()) {
    Eigen::Map<VectorXd>(N_VGetArrayPointer(cv_.x), x0.size()) = x0;
    configure(cv_, eq, o, message_);
    sample_ = N_VNew_Serial(x0.size(), cv_.context);
    if (!sample_) throw Error("simulate: out of memory for the integrator");
  }
  ~CvodeIntegrator() override { N_VDestroy(sample_); }
  CvodeIntegrator(const CvodeIntegrator&) = delete;
  CvodeIntegrator& operator=(const CvodeIntegrator&) = delete;

  double step(double tout, double stop) override {
    if (CVodeSetStopTime(cv_.mem, stop) != CV_SUCCESS)
      throw SimulationError("simulate: cannot stop at t = " + short_number(stop) + " s (internal error)", reached_);
    double reached = reached_;
    const int flag = CVode(cv_.mem, std::min(tout, stop), cv_.x, &reached, CV_ONE_STEP);
    if (flag < 0 || !std::isfinite(reached)) integration_failed(flag < 0 ? flag : CV_BAD_T, cv_, eq_, message_, reached_);
    return reached_ = reached;
  }
  void restart(double t, SimulationResult& r) override {
    add_statistics(r);
    eq_.start_segment(t);
    if (CVodeReInit(cv_.mem, t, cv_.x) != CV_SUCCESS)
      throw SimulationError("simulate: cannot restart at t = " + short_number(t) + " s (internal error)", t);
  }
  const double* state() override { return N_VGetArrayPointer(cv_.x); }
  void interpolate(double t, double* x) override {
    if (CVodeGetDky(cv_.mem, t, 0, sample_) != CV_SUCCESS)
      throw SimulationError("simulate: cannot interpolate " + at_time(t) + " (internal error)", t);
    std::copy_n(N_VGetArrayPointer(sample_), N_VGetLength_Serial(sample_), x);
  }
  [[noreturn]] void too_much_work(double t) override { integration_failed(CV_TOO_MUCH_WORK, cv_, eq_, message_, t); }
  void add_statistics(SimulationResult& r) override {  // CVodeReInit sets CVODE's counters to 0
    long v = 0;
    CVodeGetNumSteps(cv_.mem, &v), r.steps += v;
    CVodeGetNumRhsEvals(cv_.mem, &v), r.rhs_evaluations += v;
    if (cv_.solver) {
      CVodeGetNumJacEvals(cv_.mem, &v), r.jacobian_evaluations += v;
      CVodeGetNumLinRhsEvals(cv_.mem, &v), r.rhs_evaluations += v;  // difference-quotient Jacobians
    }
    CVodeGetNumErrTestFails(cv_.mem, &v), r.error_test_failures += v;
    CVodeGetNumNonlinSolvConvFails(cv_.mem, &v), r.nonlinear_failures += v;
  }

 private:
  Equations& eq_;
  Cvode cv_;
  std::string message_;
  N_Vector sample_ = nullptr;
  double reached_ = 0;
};

// Radau IIA (radau.hpp).
class RadauIntegrator : public Integrator {
 public:
  RadauIntegrator(Equations& eq, const SimulationOptions& o, const VectorXd& x0)
      : eq_(eq),
        radau_(detail::Radau::make(eq, eq.size(), o.rtol, absolute_tolerances(eq.kernels(), o),
                                   o.method == IntegrationMethod::radau9 ? 5 : 3)) {
    start(0, x0);
  }
  double step(double, double stop) override {
    const auto status = radau_->step(stop);
    if (status == detail::Radau::Status::ok) return radau_->time();
    const double t = radau_->time();
    std::string why;
    if (status == detail::Radau::Status::failed) {
      why = "the Jacobian cannot be evaluated at the state reached";
    } else {
      why = "the integrator cannot advance (step size " + short_number(radau_->step_size()) +
            " s): its error test or Newton iteration keeps failing (the motion is too fast there, or the forces or "
            "parameters are far out of range?)";
    }
    // The cause the kernels or M gave, as a likely one: the step may have failed on its own.
    if (eq_.failure != Equations::Failure::none && std::isfinite(eq_.failed_time))
      why += "; the last evaluation that failed on the way, at t = " + short_number(eq_.failed_time) + " s: " + eq_.reason();
    throw SimulationError("simulate: the integration stopped " + at_time(t) + ": " + why, t);
  }
  void restart(double t, SimulationResult&) override {
    eq_.start_segment(t);
    start(t, radau_->state());
  }
  const double* state() override { return radau_->state().data(); }
  void interpolate(double t, double* x) override { radau_->interpolate(t, x); }
  [[noreturn]] void too_much_work(double t) override {
    throw SimulationError("simulate: the integration stopped " + at_time(t) + ": more than " +
                              std::to_string(kMaxStepsPerSample) +
                              " internal steps between two samples (the tolerance cannot be met at a reasonable "
                              "cost, or the motion is too fast for the output step)",
                          t);
  }
  void add_statistics(SimulationResult& r) override {
    const detail::RadauStatistics& s = radau_->statistics();
    r.steps += s.steps;
    r.rhs_evaluations += s.evaluations;
    r.jacobian_evaluations += s.jacobians;
    r.error_test_failures += s.rejected;
    r.nonlinear_failures += s.newton_failures;
  }

 private:
  void start(double t, const VectorXd& x) {
    eq_.failure = Equations::Failure::none;
    if (!radau_->start(t, x))
      throw SimulationError("simulate: the integration cannot start " + at_time(t) + ": " +
                                (eq_.failure != Equations::Failure::none
                                     ? eq_.reason()
                                     : "no first step fits the accelerations there (are the forces or parameters far "
                                       "out of range?)"),
                            t);
  }
  Equations& eq_;
  std::unique_ptr<detail::Radau> radau_;
};

// The integrator's steps, one at a time (each accepted step moves the closed loops' anchor), up
// to the stops and past the samples.
class Stepper {
 public:
  Stepper(Integrator& in, Equations& eq, SimulationResult& r, const SimulationOptions& o)
      : in_(in), eq_(eq), r_(r), o_(o), stops_(stop_times(o)), next_(stops_.begin()) {}

  // The sample time for `t`: a sample within rounding of the next stop is taken at the stop
  // (after a restart the integrator cannot start a step of a few ulps).
  double sample_time(double t) {
    t = std::min(o_.duration, t);
    if (next_ != stops_.end() && std::abs(next_->t - t) <= window(o_, t)) t = next_->t;
    if (t >= t_) pass_stops();  // not before the samples behind the integrator are taken
    return t;
  }
  // Steps until the integrator reaches tout or passes it; true when it stands at tout (the state
  // is in.state()), false when past it (interpolate). A restart at a stop waits until the
  // samples before it are taken from the old history.
  bool step_to(double tout) {
    long steps = 0;
    while (t_ < tout) {
      pass_stops();
      const double stop = next_ != stops_.end() ? next_->t : o_.duration;
      if (++steps > kMaxStepsPerSample) in_.too_much_work(t_);
      eq_.failure = Equations::Failure::none;
      t_ = in_.step(tout, stop);
      if (eq_.follows_loops()) eq_.advance(in_.state());
    }
    return t_ == tout;
  }

 private:
  void pass_stops() {
    for (; next_ != stops_.end() && t_ >= next_->t; ++next_)
      if (next_->restart) {
        in_.restart(next_->t, r_);
        ++r_.restarts;
      }
  }
  Integrator& in_;
  Equations& eq_;
  SimulationResult& r_;
  const SimulationOptions& o_;
  const std::vector<Stop> stops_;
  std::vector<Stop>::const_iterator next_;
  double t_ = 0;
};

Index sample_count(const SimulationOptions& o) { return static_cast<Index>(std::ceil(o.duration / o.step * (1 - 1e-12))) + 1; }

}  // namespace

// Kernels generated before `outputs_general` was in the descriptor have `output_terms` but not
// it: their `outputs` would give static loads as if dynamic, so there are no outputs then. A
// model with motion inputs (input_kinds) has output_terms for the support's motion only (no
// loads: Model::validate), which a simulation holds still: its `outputs` are exact.
bool simulates_outputs(const ModelKernels& k) {
  return k.outputs_general || (k.outputs && (!k.output_terms || k.input_kinds));
}

SimulationResult simulate(const GeneratedModel& model, const OperatingPoint& op, const SimulationOptions& o) {
  check_options(model, o);
  const ModelKernels& k = model.kernels();
  const Index n = k.n_coordinates;
  VectorXd y, yd;
  initial_state(model, op, o, y, yd);
  Equations eq(model, o);
  if (eq.follows_loops() && !eq.close_initial(op.y0, y))
    throw SimulationError("simulate: the kinematic loops cannot be closed at the initial state (from the operating "
                          "point's configuration by continuation)", 0.0);
  VectorXd x0(2 * n);
  x0 << y, yd;
  if (!eq.evaluate(0.0, y.data(), yd.data()))
    throw SimulationError("simulate: the initial state fails " + at_time(0) + ": " + eq.reason(), 0.0);
  // A negative mass or inertia given at run time: refused as linear_model refuses it (it
  // integrated before, issue 39 §1). M at the initial configuration, in the model's coordinates.
  if (k.mass_matrix && !eq.follows_loops()) {
    Eigen::MatrixXd M(n, n);
    if (n > 0 && k.mass_matrix(y.data(), model.parameters().data(), M.data()) == 0)
      check_mass_semidefinite(M, "simulate: the mass matrix of model '" + std::string(k.model) + "' at the initial state");
  }
  std::unique_ptr<Integrator> in;
  if (o.method == IntegrationMethod::radau || o.method == IntegrationMethod::radau9)
    in = std::make_unique<RadauIntegrator>(eq, o, x0);
  else
    in = std::make_unique<CvodeIntegrator>(eq, o, x0);

  const Index samples = sample_count(o);
  SimulationResult r = allocated(k, samples, o.outputs);
  r.analytic_jacobian = eq.analytic_jacobian();
  record(r, 0, 0.0, x0.data(), eq);
  Stepper stepper(*in, eq, r, o);
  VectorXd sample(2 * n);
  for (Index j = 1; j < samples; ++j) {
    const double tout = stepper.sample_time(j == samples - 1 ? o.duration : static_cast<double>(j) * o.step);
    if (stepper.step_to(tout)) {
      record(r, j, tout, in->state(), eq);
    } else {  // the last step went past the sample: the integrator's interpolant there
      in->interpolate(tout, sample.data());
      record(r, j, tout, sample.data(), eq);
    }
    if (o.progress) o.progress(tout);
  }
  in->add_statistics(r);
  return r;
}

}  // namespace mbsgen
