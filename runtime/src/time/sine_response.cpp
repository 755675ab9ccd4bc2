// sine_response(): the nonlinear steady state under a tone (simulation.hpp).
#include <Eigen/Dense>

#include <cmath>
#include <complex>
#include <string>

#include "mbsgen/runtime/time/simulation.hpp"

namespace mbsgen {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

// ŷ = (K − Ω²M + iΩQ)⁻¹ B_input A: the linear model's steady state.
Eigen::VectorXcd linear_steady_state(const LinearModel& lin, Eigen::Index input, double w, double amplitude) {
  using C = std::complex<double>;
  const Eigen::MatrixXcd D = lin.K().cast<C>() - w * w * lin.M().cast<C>() +
                             (lin.Q().size() ? Eigen::MatrixXcd(C(0, w) * lin.Q().cast<C>())
                                             : Eigen::MatrixXcd::Zero(lin.size(), lin.size()));
  const Eigen::PartialPivLU<Eigen::MatrixXcd> lu(D);
  const Eigen::VectorXd pivots = lu.matrixLU().diagonal().cwiseAbs();
  if (!(pivots.minCoeff() > 1e-14 * pivots.maxCoeff()))
    throw SingularSystemError("sine_response: K − Ω²M + iΩQ is singular at " + std::to_string(w / kTwoPi) +
                              " Hz (a resonance of an undamped mode): no steady state");
  return lu.solve(amplitude * lin.B().col(input).cast<C>());
}

}  // namespace

SineResponse sine_response(const GeneratedModel& model, const OperatingPoint& op, Eigen::Index input, double hz,
                           double amplitude, const SineResponseOptions& o) {
  const ModelKernels& k = model.kernels();
  if (input < 0 || input >= k.n_inputs)
    throw DimensionError("sine_response: input " + std::to_string(input) + " of " + std::to_string(k.n_inputs));
  if (!(hz > 0) || !(amplitude > 0) || !std::isfinite(hz) || !std::isfinite(amplitude))
    throw Error("sine_response: the frequency and the amplitude must be finite and > 0");
  if (o.periods < 1 || o.fit_periods < 1 || o.fit_periods > o.periods || o.samples_per_period < 8)
    throw Error("sine_response: need 1 <= fit_periods <= periods and samples_per_period >= 8");
  if (!k.outputs && !k.outputs_general) throw Error("sine_response: the kernels give no outputs");
  const double w = kTwoPi * hz;
  const Eigen::VectorXcd yhat = linear_steady_state(model.linear_model(op), input, w, amplitude);
  SimulationOptions s;
  s.method = o.method;
  s.duration = o.periods / hz;
  s.step = 1 / (hz * o.samples_per_period);
  s.rtol = o.rtol;
  s.atol = o.rtol * o.atol_fraction * yhat.cwiseAbs().maxCoeff();
  if (!(s.atol > 0)) s.atol = 1e-300;  // the input does not move the model
  const auto names = name_list(k.coordinate_names, k.n_coordinates);
  for (std::size_t c = 0; c < names.size(); ++c) {
    const auto i = static_cast<Eigen::Index>(c);
    s.initial.emplace_back(names[c], op.y0[i] + yhat[i].imag());
    s.initial.emplace_back(names[c] + "_dot", op.yd0[i] + w * yhat[i].real());
  }
  s.inputs.resize(static_cast<std::size_t>(k.n_inputs));
  s.inputs[static_cast<std::size_t>(input)] = InputSignal::sine(amplitude, hz);
  const SimulationResult r = simulate(model, op, s);
  if (r.z.rows() != k.n_outputs)
    throw Error("sine_response: model '" + std::string(k.model) + "' gives no outputs in a simulation");

  const Eigen::Index first = r.t.size() - 1 - static_cast<Eigen::Index>(o.fit_periods) * o.samples_per_period;
  const Eigen::Index rows = r.t.size() - first;
  Eigen::MatrixXd X(rows, 3);
  for (Eigen::Index j = 0; j < rows; ++j) X.row(j) << std::sin(w * r.t[first + j]), std::cos(w * r.t[first + j]), 1.0;
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
  SineResponse out;
  out.fundamental.resize(k.n_outputs);
  out.offset.resize(k.n_outputs);
  out.distortion.resize(k.n_outputs);
  for (Eigen::Index i = 0; i < k.n_outputs; ++i) {
    const Eigen::VectorXd z = r.z.row(i).segment(first, rows).transpose();
    const Eigen::Vector3d abc = qr.solve(z);
    out.fundamental[i] = {abc[0], abc[1]};
    out.offset[i] = abc[2];
    const double rms = std::sqrt((z - X * abc).squaredNorm() / static_cast<double>(rows));
    out.distortion[i] = rms / std::abs(out.fundamental[i]);
  }
  out.steps = r.steps;
  return out;
}

}  // namespace mbsgen
