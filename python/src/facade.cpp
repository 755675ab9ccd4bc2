// The Python package's C++ side (facade.hpp).
#include "facade.hpp"

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/model/descriptor_model.hpp"
#include "mbsgen/runtime/model/generated_model.hpp"
#include "mbsgen/runtime/model/tape.hpp"
#include "mbsgen/runtime/spectral/descriptor_eigen.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"
#include "mbsgen/runtime/spectral/parameter_sweep.hpp"
#include "mbsgen/runtime/spectral/sensitivity.hpp"
#include "mbsgen/runtime/study/study.hpp"
#include "mbsgen/runtime/study/study_design.hpp"
#include "mbsgen/runtime/time/simulation.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <fstream>
#include <atomic>
#include <cmath>
#include <exception>
#include <limits>
#include <thread>

// OpenBLAS's own threads would compete with the batch's (and its results depend on their count):
// one thread, as the study sets it, when OpenBLAS is the BLAS.
extern "C" void openblas_set_num_threads(int) __attribute__((weak));

namespace mbsgen::python {

namespace {

constexpr double kTwoPi = 6.283185307179586;

std::vector<std::string> names(const char* const* list, int n) { return n > 0 && list ? name_list(list, n) : std::vector<std::string>(); }

// A GeneratedModel over the kernels with the parameters p (every one, in order).
GeneratedModel configured(const ModelKernels& kernels, const ConstVectorRef& p) {
  GeneratedModel model(kernels);
  model.set_parameters(std::vector<double>(p.data(), p.data() + p.size()));
  return model;
}

Modes modes_from(const std::vector<Mode>& modes, Stability stability, std::string method, Eigen::Index f) {
  Modes r;
  const Eigen::Index n = static_cast<Eigen::Index>(modes.size());
  r.eigenvalues.resize(n);
  r.natural_frequency_hz.resize(n);
  r.damped_frequency_hz.resize(n);
  r.damping_ratio.resize(n);
  r.backward_error.resize(n);
  r.error_bound.resize(n);
  r.shapes.resize(f, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const Mode& m = modes[static_cast<std::size_t>(k)];
    r.eigenvalues[k] = m.lambda;
    r.natural_frequency_hz[k] = m.natural_frequency_hz;
    r.damped_frequency_hz[k] = m.damped_frequency_hz;
    r.damping_ratio[k] = m.damping_ratio;
    r.backward_error[k] = m.backward_error;
    r.error_bound[k] = m.error_bound;
    r.kinds.emplace_back(kind_label(m));
    if (m.shape.size() == f) r.shapes.col(k) = m.shape;
    else r.shapes.col(k).setConstant(std::complex<double>(std::nan(""), std::nan("")));
  }
  r.stability = to_string(stability);
  r.method = std::move(method);
  return r;
}

Modes quadratic_modes(const LinearModel& lin, bool all) {
  QuadraticEigenOptions opt;
  opt.one_per_conjugate_pair = !all;
  QuadraticEigenSolver solver(lin.size(), opt);
  solver.compute(lin);
  return modes_from(solver.modes(), solver.stability(), solver.method(), lin.size());
}

Response second_order_response(const LinearModel& lin, Eigen::Index input, Eigen::Index output, const ConstVectorRef& hz,
                               const std::string& method) {
  FrfOptions opt;
  opt.method = parse_frf_method(method);
  FrequencyResponse frf(lin, opt);
  frf.compute(Eigen::VectorXd(hz) * kTwoPi, input, {output});
  Response r;
  r.values = frf.response().row(0).transpose();
  r.rcond = frf.rcond();
  for (FrfFlag f : frf.flags()) r.flags.emplace_back(to_string(f));
  r.warnings = frf.warnings();
  r.method = to_string(frf.method());
  return r;
}

}  // namespace

Model::Model(const std::string& path) {
  char magic[4] = {};
  std::ifstream(path, std::ios::binary).read(magic, 4);
  if (std::string(magic, 4) != "\x7f" "ELF") {
    tape_ = TapeModel::load(path);
    kernels_ = &tape_->kernels();
    return;
  }
  void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) throw Error(std::string("cannot load the compiled kernels ") + path + ": " + ::dlerror());
  library_ = std::shared_ptr<void>(handle, [](void* h) { ::dlclose(h); });
  using Entry = const ModelKernels* (*)();
  const auto entry = reinterpret_cast<Entry>(::dlsym(handle, "mbsgen_model_kernels"));
  if (!entry) throw Error(path + " is not a library of compiled kernels (no mbsgen_model_kernels; made by `mbsgen kernels`)");
  kernels_ = entry();
  GeneratedModel check(*kernels_);  // throws for kernels of another ABI version
}
Model::~Model() = default;

std::string Model::name() const { return (*kernels_).model; }
std::string Model::scene() const { return (*kernels_).scene; }
std::string Model::evaluation() const {
  const char* e = (*kernels_).evaluation;
  return e ? e : "compiled";
}
std::vector<std::string> Model::parameter_names() const {
  const ModelKernels& k = (*kernels_);
  return names(k.parameter_names, k.n_parameters);
}
std::vector<std::string> Model::parameter_units() const {
  const ModelKernels& k = (*kernels_);
  return names(k.parameter_units, k.n_parameters);
}
Vector Model::parameter_defaults() const {
  const ModelKernels& k = (*kernels_);
  return Eigen::Map<const Vector>(k.parameter_defaults, k.n_parameters);
}
std::vector<std::string> Model::coordinate_names() const {
  const ModelKernels& k = (*kernels_);
  return names(k.coordinate_names, k.n_coordinates);
}
std::vector<std::string> Model::coordinate_units() const {
  const ModelKernels& k = (*kernels_);
  return names(k.coordinate_units, k.n_coordinates);
}
std::vector<std::string> Model::input_names() const {
  const ModelKernels& k = (*kernels_);
  return names(k.input_names, k.n_inputs);
}
std::vector<std::string> Model::input_units() const {
  const ModelKernels& k = (*kernels_);
  return names(k.input_units, k.n_inputs);
}
std::vector<std::string> Model::output_names() const {
  const ModelKernels& k = (*kernels_);
  return names(k.output_names, k.n_outputs);
}
std::vector<std::string> Model::output_units() const {
  const ModelKernels& k = (*kernels_);
  return names(k.output_units, k.n_outputs);
}
bool Model::descriptor() const { return (*kernels_).descriptor != nullptr; }
double Model::default_from_hz() const { return (*kernels_).default_from_hz; }
double Model::default_to_hz() const { return (*kernels_).default_to_hz; }
int Model::default_points() const { return (*kernels_).default_points; }

OperatingPoint Model::operating_point(const ConstVectorRef& p) const {
  const mbsgen::OperatingPoint op = configured(*kernels_, p).operating_point();
  return {op.y0, op.yd0, op.equilibrium, op.iterations, op.residual_norm, op.report};
}

Linear Model::linear(const ConstVectorRef& p) const {
  const GeneratedModel model = configured(*kernels_, p);
  Linear r;
  if (model.is_descriptor()) {
    const DescriptorModel d = model.descriptor_model();
    r.descriptor = true;
    r.E = d.E(), r.A = d.A(), r.B = d.B(), r.C = d.C(), r.D = d.D();
    r.state_names = d.state_names();
    return r;
  }
  const LinearModel lin = model.linear_model();
  r.M = lin.M(), r.Q = lin.Q(), r.K = lin.K(), r.B = lin.B(), r.C_y = lin.C_y(), r.C_v = lin.C_v();
  r.C_a = lin.C_a(), r.D = lin.D(), r.B1 = lin.B1(), r.B2 = lin.B2(), r.D1 = lin.D1();
  return r;
}

Modes Model::modes(const ConstVectorRef& p, bool all) const {
  const GeneratedModel model = configured(*kernels_, p);
  if (model.is_descriptor()) {
    const DescriptorModel d = model.descriptor_model();
    DescriptorEigenOptions opt;
    opt.one_per_conjugate_pair = !all;
    DescriptorEigenSolver solver(opt);
    solver.compute(d);
    return modes_from(solver.modes(), solver.stability(), "descriptor", d.size());
  }
  return quadratic_modes(model.linear_model(), all);
}

Response Model::frf(const ConstVectorRef& p, const std::string& input, const std::string& output,
                    const ConstVectorRef& hz, const std::string& method) const {
  const GeneratedModel model = configured(*kernels_, p);
  const Eigen::Index in = model.input_index(input), out = model.output_index(output);
  if (model.is_descriptor()) {
    const DescriptorFrf d = descriptor_frequency_response(model.descriptor_model(), Eigen::VectorXd(hz) * kTwoPi, in, {out});
    Response r;
    r.values = d.response.row(0).transpose();
    r.rcond = d.rcond;
    for (FrfFlag f : d.flags) r.flags.emplace_back(to_string(f));
    r.method = "direct";
    return r;
  }
  const LinearModel lin = model.linear_model();
  return second_order_response(lin, in, out, hz, method);
}

namespace {

void refuse_descriptor(const GeneratedModel& model, const char* what) {
  if (model.is_descriptor())
    throw Error(std::string(what) + ": model '" + model.kernels().model +
                "' has rolling constraints; sensitivities are not available for it");
}

}  // namespace

ModeSensitivities Model::modes_sensitivity(const ConstVectorRef& p, const std::vector<std::string>& names) const {
  const GeneratedModel model = configured(*kernels_, p);
  refuse_descriptor(model, "modes_sensitivity");
  const mbsgen::OperatingPoint op = model.operating_point();
  const LinearModel lin = model.linear_model(op);
  const std::vector<MatrixSensitivity> d = model.linear_sensitivities(op, names);
  QuadraticEigenOptions opt;
  opt.one_per_conjugate_pair = false;  // the separation test needs every eigenvalue
  QuadraticEigenSolver solver(lin.size(), opt);
  solver.compute(lin);
  const auto s = eigenvalue_sensitivities(lin, solver.modes(), d);
  ModeSensitivities r;
  r.modes = modes_from(solver.modes(), solver.stability(), solver.method(), lin.size());
  const Eigen::Index n = static_cast<Eigen::Index>(s.size()), q = static_cast<Eigen::Index>(d.size());
  r.parameter_values.resize(q);
  for (Eigen::Index j = 0; j < q; ++j) {
    r.parameters.push_back(d[static_cast<std::size_t>(j)].parameter);
    r.parameter_values[j] = d[static_cast<std::size_t>(j)].value;
  }
  r.dlambda.resize(n, q);
  r.dfrequency_hz.resize(n, q);
  r.relative_frequency.resize(n, q);
  r.ddamping_ratio.resize(n, q);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (Eigen::Index k = 0; k < n; ++k) {
    std::string note;
    for (Eigen::Index j = 0; j < q; ++j) {
      const EigenvalueSensitivity& e = s[static_cast<std::size_t>(k)][static_cast<std::size_t>(j)];
      r.dlambda(k, j) = e.defined ? e.dlambda : std::complex<double>(nan, nan);
      r.dfrequency_hz(k, j) = e.defined ? e.dfrequency_hz : nan;
      r.relative_frequency(k, j) = e.defined ? e.relative_frequency : nan;
      r.ddamping_ratio(k, j) = e.defined ? e.ddamping_ratio : nan;
      if (!e.defined) note = e.note;
    }
    r.notes.push_back(note);
  }
  return r;
}

ResponseSensitivity Model::frf_sensitivity(const ConstVectorRef& p, const std::string& input, const std::string& output,
                                           const ConstVectorRef& hz, const std::vector<std::string>& names) const {
  const GeneratedModel model = configured(*kernels_, p);
  refuse_descriptor(model, "frf_sensitivity");
  const Eigen::Index in = model.input_index(input), out = model.output_index(output);
  const mbsgen::OperatingPoint op = model.operating_point();
  const LinearModel lin = model.linear_model(op);
  std::vector<MatrixSensitivity> d = model.linear_sensitivities(op, names);
  for (MatrixSensitivity& x : d) x = select(x, {in}, {out});  // the one pair asked for, as the CLI
  const FrequencyResponseSensitivity s = frequency_response_sensitivity(
      lin.select({in}, {out}), d, std::vector<double>(hz.data(), hz.data() + hz.size()));
  ResponseSensitivity r;
  const Eigen::Index f = hz.size(), q = static_cast<Eigen::Index>(d.size());
  r.values.resize(f);
  r.rcond = Eigen::Map<const Vector>(s.rcond.data(), static_cast<Eigen::Index>(s.rcond.size()));
  r.derivatives.resize(q, f);
  for (Eigen::Index i = 0; i < f; ++i) {
    r.values[i] = s.response[static_cast<std::size_t>(i)](0, 0);
    for (Eigen::Index j = 0; j < q; ++j)
      r.derivatives(j, i) = s.derivative[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)](0, 0);
  }
  r.parameter_values.resize(q);
  for (Eigen::Index j = 0; j < q; ++j) {
    r.parameters.push_back(d[static_cast<std::size_t>(j)].parameter);
    r.parameter_values[j] = d[static_cast<std::size_t>(j)].value;
  }
  return r;
}

BatchResponse Model::frf_batch(const ConstRowMajorRef& sets, const std::string& input, const std::string& output,
                               const ConstVectorRef& hz, const std::string& method, int threads,
                               const std::function<bool()>& stop) const {
  const Eigen::Index n = sets.rows();
  if (sets.cols() != (*kernels_).n_parameters)
    throw DimensionError("frf_batch: the parameter sets have " + std::to_string(sets.cols()) + " columns, the model " +
                         std::to_string((*kernels_).n_parameters) + " parameters");
  {  // names and the method checked once, before any thread starts
    const GeneratedModel model((*kernels_));
    (void)model.input_index(input);
    (void)model.output_index(output);
    parse_frf_method(method);
  }
  BatchResponse r;
  r.values.setConstant(n, hz.size(), std::complex<double>(std::nan(""), std::nan("")));
  std::vector<std::string> reason(static_cast<std::size_t>(n));
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int workers = static_cast<int>(std::min<Eigen::Index>(threads > 0 ? threads : cores, std::max<Eigen::Index>(n, 1)));
  if (openblas_set_num_threads) openblas_set_num_threads(1);
  std::atomic<Eigen::Index> next{0};
  std::atomic<bool> stopped{false};
  auto work = [&](bool asks) {
    for (Eigen::Index k = next++; k < n && !stopped; k = next++) {
      try {
        const Vector p = sets.row(k).transpose();
        r.values.row(k) = frf(p, input, output, hz, method).values.transpose();
      } catch (const std::exception& e) {
        r.values.row(k).setConstant(std::complex<double>(std::nan(""), std::nan("")));
        reason[static_cast<std::size_t>(k)] = e.what();
      }
      if (asks && stop && stop()) stopped = true;
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < workers; ++t) pool.emplace_back(work, false);
  work(true);
  for (std::thread& t : pool) t.join();
  if (stopped) throw Stopped();
  for (Eigen::Index k = 0; k < n; ++k)
    if (!reason[static_cast<std::size_t>(k)].empty()) {
      r.failed.push_back(static_cast<long>(k));
      r.reasons.push_back(std::move(reason[static_cast<std::size_t>(k)]));
    }
  return r;
}

Vector Model::outputs(const ConstVectorRef& p) const {
  const GeneratedModel model = configured(*kernels_, p);
  return model.outputs(model.operating_point());
}

namespace {

// The tree's own equations M ÿ + r = 0 are the model's only without loops or rolling constraints.
void require_explicit(const ModelKernels& k, const char* what) {
  if (k.n_constraints > 0 || k.descriptor)
    throw Error(std::string(what) + ": model '" + k.model + "' has " +
                (k.descriptor ? "rolling constraints" : "closed loops") +
                ": its equations of motion are not M(y) ÿ + r(y, ẏ, u) = 0 in its coordinates");
}

void require_size(const ConstVectorRef& v, Eigen::Index n, const char* what, const char* name) {
  if (v.size() != n)
    throw DimensionError(std::string(what) + ": " + name + " has " + std::to_string(v.size()) + " entries, the model " +
                         std::to_string(n));
}

void require_finite(const double* v, Eigen::Index n, const char* what, const char* kernel) {
  for (Eigen::Index i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) throw NonFiniteError(std::string(what) + ": the kernel " + kernel + " gave a value that is not finite");
}

}  // namespace

Matrix Model::mass_matrix(const ConstVectorRef& p, const ConstVectorRef& y) const {
  const ModelKernels& k = *kernels_;
  require_explicit(k, "mass_matrix");
  require_size(p, k.n_parameters, "mass_matrix", "p");
  require_size(y, k.n_coordinates, "mass_matrix", "y");
  Matrix M(k.n_coordinates, k.n_coordinates);
  k.mass_matrix(y.data(), p.data(), M.data());
  require_finite(M.data(), M.size(), "mass_matrix", "mass_matrix");
  return M;
}

Vector Model::accelerations(const ConstVectorRef& p, const ConstVectorRef& y, const ConstVectorRef& yd,
                            const ConstVectorRef& u) const {
  const ModelKernels& k = *kernels_;
  require_explicit(k, "accelerations");
  require_size(p, k.n_parameters, "accelerations", "p");
  require_size(y, k.n_coordinates, "accelerations", "y");
  require_size(yd, k.n_coordinates, "accelerations", "yd");
  require_size(u, k.n_inputs, "accelerations", "u");
  Matrix M(k.n_coordinates, k.n_coordinates);
  Vector r(k.n_coordinates);
  k.mass_matrix(y.data(), p.data(), M.data());
  k.residual(y.data(), yd.data(), u.data(), p.data(), r.data());
  require_finite(M.data(), M.size(), "accelerations", "mass_matrix");
  require_finite(r.data(), r.size(), "accelerations", "residual");
  const Eigen::PartialPivLU<Matrix> lu(M);
  const double rcond = lu.rcond();
  if (!(rcond > 1e-14))
    throw SingularSystemError("accelerations: M(y) is singular to working precision (reciprocal condition " +
                              std::to_string(rcond) + ")");
  return lu.solve(-r);
}

Sweep Model::sweep(const ConstVectorRef& p, const std::string& parameter, double from, double to, int points,
                   double relative_tolerance) const {
  GeneratedModel model = configured(*kernels_, p);
  SweepOptions o;
  o.relative_tolerance = relative_tolerance;
  const SweepResult r = sweep_parameter(model, parameter, from, to, points, o);
  Sweep s;
  const auto n = static_cast<Eigen::Index>(r.points.size());
  std::size_t widest = 0;
  for (const SweepPoint& q : r.points) widest = std::max(widest, q.eigenvalues.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  s.values.resize(n);
  s.abscissa.resize(n);
  s.eigenvalues.setConstant(n, static_cast<Eigen::Index>(widest), std::complex<double>(nan, nan));
  for (Eigen::Index i = 0; i < n; ++i) {
    const SweepPoint& q = r.points[static_cast<std::size_t>(i)];
    s.values[i] = q.value;
    s.abscissa[i] = q.abscissa;
    s.zeros.push_back(static_cast<long>(q.zeros));
    s.stability.emplace_back(to_string(q.stability));
    for (std::size_t k = 0; k < q.eigenvalues.size(); ++k) s.eigenvalues(i, static_cast<Eigen::Index>(k)) = q.eigenvalues[k];
  }
  const auto b = static_cast<Eigen::Index>(r.boundaries.size());
  s.boundary_values.resize(b);
  s.boundary_tolerances.resize(b);
  s.boundary_eigenvalues.resize(b);
  for (Eigen::Index i = 0; i < b; ++i) {
    const StabilityBoundary& q = r.boundaries[static_cast<std::size_t>(i)];
    s.boundary_values[i] = q.value;
    s.boundary_tolerances[i] = q.tolerance;
    s.boundary_eigenvalues[i] = q.eigenvalue;
    s.becomes_unstable.push_back(q.becomes_unstable ? 1 : 0);
    s.below.emplace_back(to_string(q.below));
    s.above.emplace_back(to_string(q.above));
  }
  return s;
}

Study Model::study(const ConstVectorRef& p, const StudyRequest& q) const {
  const GeneratedModel model = configured(*kernels_, p);
  std::vector<ParameterDistribution> distributions;
  for (const std::string& text : q.parameters) distributions.push_back(parse_distribution(text));
  if (q.samples < 1) throw DimensionError("study: samples must be at least 1, not " + std::to_string(q.samples));
  const StudyDesign design(parse_design(q.design), distributions, static_cast<std::size_t>(q.samples), q.seed);
  StudyQuantities quantities;
  quantities.modes = q.modes;
  quantities.input = q.input;
  quantities.output = q.output;
  quantities.sweep_hz.assign(q.sweep_hz.data(), q.sweep_hz.data() + q.sweep_hz.size());
  quantities.at_hz.assign(q.at_hz.data(), q.at_hz.data() + q.at_hz.size());
  quantities.method = q.method;
  const StudyResults r = evaluate(model, design, quantities, 0, design.size(), q.threads);
  Study s;
  const auto n = static_cast<Eigen::Index>(r.count), d = static_cast<Eigen::Index>(design.dimension());
  for (const ParameterDistribution& dist : distributions) s.parameter_names.push_back(dist.name);
  s.scalar_names = r.scalar_names;
  s.samples.resize(n, d);
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::vector<double> x = design.point(static_cast<std::size_t>(i));
    for (Eigen::Index k = 0; k < d; ++k) s.samples(i, k) = x[static_cast<std::size_t>(k)];
  }
  const auto nq = static_cast<Eigen::Index>(r.scalar_names.size()), nf = static_cast<Eigen::Index>(quantities.sweep_hz.size());
  s.scalars = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(r.scalars.data(), n, nq);
  s.sweep = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(r.sweep.data(), n, nf);
  for (const StudyFailure& f : r.failures) {
    s.failed.push_back(static_cast<long>(f.index));
    s.reasons.push_back(f.message);
  }
  if (design.design() == Design::saltelli) {
    for (Matrix* m : {&s.first, &s.first_low, &s.first_high, &s.total, &s.total_low, &s.total_high}) m->resize(nq, d);
    for (Eigen::Index j = 0; j < nq; ++j) {
      std::vector<double> f(static_cast<std::size_t>(n));
      for (Eigen::Index i = 0; i < n; ++i) f[static_cast<std::size_t>(i)] = s.scalars(i, j);
      const SobolResult so = sobol_indices(f, design.base_size(), design.dimension(),
                                           static_cast<std::size_t>(q.bootstrap), q.seed);
      for (Eigen::Index k = 0; k < d; ++k) {
        const SobolIndex& x = so.indices[static_cast<std::size_t>(k)];
        s.first(j, k) = x.first, s.first_low(j, k) = x.first_low, s.first_high(j, k) = x.first_high;
        s.total(j, k) = x.total, s.total_low(j, k) = x.total_low, s.total_high(j, k) = x.total_high;
      }
    }
  }
  return s;
}

Simulation Model::simulate(const ConstVectorRef& p, const SimulationRequest& q, const std::function<bool()>& stop) const {
  const GeneratedModel model = configured(*kernels_, p);
  const int m = kernels_->n_inputs;
  if (q.input_specs.size() != static_cast<std::size_t>(m) || q.table_times.size() != static_cast<std::size_t>(m) ||
      q.table_values.size() != static_cast<std::size_t>(m))
    throw DimensionError("simulate: " + std::to_string(q.input_specs.size()) + " input signals, the model has " +
                         std::to_string(m) + " inputs");
  if (q.initial_names.size() != q.initial_values.size())
    throw DimensionError("simulate: " + std::to_string(q.initial_names.size()) + " initial names and " +
                         std::to_string(q.initial_values.size()) + " values");
  SimulationOptions o;
  if (q.method == "bdf") o.method = IntegrationMethod::bdf;
  else if (q.method == "adams") o.method = IntegrationMethod::adams;
  else if (q.method == "radau") o.method = IntegrationMethod::radau;
  else if (q.method == "radau9") o.method = IntegrationMethod::radau9;
  else throw NameError("simulate: method '" + q.method + "' is none of bdf, adams, radau, radau9");
  o.duration = q.duration;
  o.step = q.step > 0 ? q.step : q.duration / 1000;
  o.rtol = q.rtol;
  o.atol = q.atol;
  for (std::size_t i = 0; i < q.initial_names.size(); ++i) o.initial.emplace_back(q.initial_names[i], q.initial_values[i]);
  bool any = false;
  for (int j = 0; j < m; ++j) {
    const auto J = static_cast<std::size_t>(j);
    if (q.table_times[J].size() > 0) {
      o.inputs.push_back(InputSignal::table(std::vector<double>(q.table_times[J].data(), q.table_times[J].data() + q.table_times[J].size()),
                                            std::vector<double>(q.table_values[J].data(), q.table_values[J].data() + q.table_values[J].size())));
    } else {
      o.inputs.push_back(q.input_specs[J].empty() ? InputSignal() : InputSignal::parse(q.input_specs[J], q.duration));
    }
    any = any || !o.inputs.back().is_zero();
  }
  if (!any) o.inputs.clear();
  o.outputs = q.outputs;
  if (stop) o.progress = [&stop](double) {
    if (stop()) throw Stopped();
  };
  const SimulationResult r = mbsgen::simulate(model, model.operating_point(), o);
  Simulation s;
  s.t = r.t, s.y = r.y, s.yd = r.yd, s.u = r.u, s.z = r.z;
  s.analytic_jacobian = r.analytic_jacobian;
  s.constraint_drift = r.constraint_drift;
  s.steps = r.steps, s.rhs_evaluations = r.rhs_evaluations, s.jacobian_evaluations = r.jacobian_evaluations;
  s.error_test_failures = r.error_test_failures, s.nonlinear_failures = r.nonlinear_failures;
  return s;
}

Modes modes_of(const ConstMatrixRef& M, const ConstMatrixRef& Q, const ConstMatrixRef& K, bool all) {
  const Eigen::Index f = M.rows();
  const LinearModel lin(M, Q.size() == 0 ? Matrix::Zero(f, f) : Matrix(Q), K);
  return quadratic_modes(lin, all);
}

Response frf_of(const ConstMatrixRef& M, const ConstMatrixRef& Q, const ConstMatrixRef& K, const ConstMatrixRef& B,
                const ConstMatrixRef& C_y, const ConstMatrixRef& C_v, Eigen::Index input, Eigen::Index output,
                const ConstVectorRef& hz, const std::string& method) {
  const LinearModel lin(M, Q, K, B, C_y, C_v);
  return second_order_response(lin, input, output, hz, method);
}

}  // namespace mbsgen::python
