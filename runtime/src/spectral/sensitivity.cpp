#include "mbsgen/runtime/spectral/sensitivity.hpp"

#include <Eigen/LU>

#include <array>
#include <cmath>
#include <limits>

namespace mbsgen {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A, or a zero matrix of the given size when A is stored empty (a zero part of a LinearModel or
// a derivative the model does not have). DimensionError for any other size.
Eigen::MatrixXd part(const Eigen::MatrixXd& A, Eigen::Index rows, Eigen::Index cols, const char* what,
                     const std::string& parameter) {
  if (A.size() == 0) return Eigen::MatrixXd::Zero(rows, cols);
  if (A.rows() != rows || A.cols() != cols)
    throw DimensionError(std::string("sensitivity: d") + what + "/d" + parameter + " is " + std::to_string(A.rows()) +
                         "×" + std::to_string(A.cols()) + ", the model's " + what + " is " + std::to_string(rows) +
                         "×" + std::to_string(cols));
  return A;
}

// Whether the data separate mode k from every other finite mode: |λ_k − λ_j| above the sum of
// their error bounds (and above rounding, 8u·|λ|, for bounds that are 0).
bool separated(const std::vector<Mode>& modes, std::size_t k) {
  const double u = std::numeric_limits<double>::epsilon();
  for (std::size_t j = 0; j < modes.size(); ++j) {
    // A mode whose own bound is infinite (defective) is flagged itself; it separates nothing.
    if (j == k || modes[j].kind != EigenvalueKind::finite || !std::isfinite(modes[j].error_bound)) continue;
    const double gap = std::abs(modes[k].lambda - modes[j].lambda);
    const double scale = std::max(std::abs(modes[k].lambda), std::abs(modes[j].lambda));
    if (gap <= modes[k].error_bound + modes[j].error_bound + 8 * u * scale) return false;
  }
  return true;
}

EigenvalueSensitivity undefined(const char* why) {
  EigenvalueSensitivity s;
  s.note = why;
  s.dlambda = s.relative = {kNaN, kNaN};
  s.dfrequency_hz = s.relative_frequency = s.ddamping_ratio = kNaN;
  return s;
}

}  // namespace

std::vector<std::vector<EigenvalueSensitivity>> eigenvalue_sensitivities(
    const LinearModel& model, const std::vector<Mode>& modes, const std::vector<MatrixSensitivity>& sensitivities) {
  const Eigen::Index f = model.size();
  std::vector<std::array<Eigen::MatrixXd, 3>> d;  // dM, dQ, dK per parameter
  for (const auto& s : sensitivities)
    d.push_back({part(s.M, f, f, "M", s.parameter), part(s.Q, f, f, "Q", s.parameter), part(s.K, f, f, "K", s.parameter)});
  std::vector<std::vector<EigenvalueSensitivity>> out(modes.size());
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const Mode& mode = modes[k];
    const char* why = mode.kind == EigenvalueKind::zero || mode.zero_within_bound ? "zero"
                      : mode.kind == EigenvalueKind::infinite ? "infinite"
                      : mode.defective                         ? "defective"
                      : !separated(modes, k)                   ? "repeated"
                                                               : nullptr;
    const std::complex<double> lambda = mode.lambda;
    const Eigen::VectorXcd& x = mode.shape;
    const Eigen::VectorXcd& y = mode.left_shape;
    std::complex<double> denominator;
    if (!why) {
      denominator = y.dot((2.0 * lambda * model.M() + model.Q()) * x);  // yᴴ(2λM + Q)x
      if (!(std::abs(denominator) > 0) || !std::isfinite(mode.condition)) why = "defective";
    }
    for (std::size_t j = 0; j < sensitivities.size(); ++j) {
      if (why) {
        out[k].push_back(undefined(why));
        continue;
      }
      EigenvalueSensitivity s;
      s.defined = true;
      const Eigen::VectorXcd dPx = (lambda * lambda * d[j][0] + lambda * d[j][1] + d[j][2].cast<std::complex<double>>()) * x;
      s.dlambda = -y.dot(dPx) / denominator;
      const double p = sensitivities[j].value, r = std::abs(lambda);
      s.relative = p / lambda * s.dlambda;
      // |λ|' = Re(conj(λ) λ')/|λ|;  ζ = −Re λ/|λ|  ⇒  ζ' = −(Re λ' |λ| − Re λ |λ|')/|λ|².
      const double dr = std::real(std::conj(lambda) * s.dlambda) / r;
      s.dfrequency_hz = dr / (2 * M_PI);
      s.relative_frequency = p * dr / r;
      s.ddamping_ratio = -(s.dlambda.real() * r - lambda.real() * dr) / (r * r);
      out[k].push_back(s);
    }
  }
  return out;
}

namespace {

// One matrix of a model or derivative with its shape checked (part()), and whether it is exactly
// zero: a derivative by a stiffness has dM = dQ = 0, and its terms are skipped.
struct Part {
  Eigen::MatrixXd a;
  bool zero = true;
};

struct Parts {
  Part M, Q, K, B, Cy, Cv, Ca, D, B1, B2, D1;
};

Part make_part(Eigen::MatrixXd a) {
  Part p;
  p.zero = a.size() == 0 || (a.array() == 0.0).all();
  p.a = std::move(a);
  return p;
}

using CM = Eigen::MatrixXcd;
using Cx = std::complex<double>;

// x0 + iw x1 − w² x2 of three real matrices into `out` (sized rows × cols), skipping zero parts.
void combine(CM& out, Eigen::Index rows, Eigen::Index cols, const Part& x0, const Part& x1, const Part& x2, double w) {
  out.resize(rows, cols);
  out.setZero();
  if (!x0.zero) out.real() += x0.a;
  if (!x1.zero) out.imag() += w * x1.a;
  if (!x2.zero) out.real() -= (w * w) * x2.a;
}

// (x0 + iw x1 − w² x2) X for real x0, x1, x2 and complex X = Xr + i Xi (its parts split once per
// frequency by the caller): real products, zero parts skipped.
void apply(CM& out, const Part& x0, const Part& x1, const Part& x2, double w, const Eigen::MatrixXd& Xr,
           const Eigen::MatrixXd& Xi, Eigen::Index rows) {
  out.setZero(rows, Xr.cols());
  const auto add = [&](const Part& x, Cx factor) {
    if (x.zero) return;
    const Eigen::MatrixXd re = x.a * Xr, im = x.a * Xi;
    out.real() += factor.real() * re - factor.imag() * im;
    out.imag() += factor.real() * im + factor.imag() * re;
  };
  add(x0, 1.0);
  add(x1, Cx(0, w));
  add(x2, -w * w);
}

}  // namespace

FrequencyResponseSensitivity frequency_response_sensitivity(const LinearModel& model,
                                                            const std::vector<MatrixSensitivity>& sensitivities,
                                                            const std::vector<double>& frequencies_hz) {
  const Eigen::Index f = model.size(), m = model.num_inputs(), r = model.num_outputs();
  auto parts = [&](const MatrixSensitivity& s, const std::string& name) {
    return Parts{make_part(part(s.M, f, f, "M", name)),     make_part(part(s.Q, f, f, "Q", name)),
                 make_part(part(s.K, f, f, "K", name)),     make_part(part(s.B, f, m, "B", name)),
                 make_part(part(s.C_y, r, f, "C_y", name)), make_part(part(s.C_v, r, f, "C_v", name)),
                 make_part(part(s.C_a, r, f, "C_a", name)), make_part(part(s.D, r, m, "D", name)),
                 make_part(part(s.B1, f, m, "B1", name)),   make_part(part(s.B2, f, m, "B2", name)),
                 make_part(part(s.D1, r, m, "D1", name))};
  };
  MatrixSensitivity own;  // the model's own matrices, in the same form
  own.M = model.M(), own.Q = model.Q(), own.K = model.K(), own.B = model.B(), own.C_y = model.C_y();
  own.C_v = model.C_v(), own.C_a = model.C_a(), own.D = model.D(), own.B1 = model.B1(), own.B2 = model.B2();
  own.D1 = model.D1();
  const Parts P = parts(own, "(the model)");
  std::vector<Parts> dP;
  for (const auto& s : sensitivities) dP.push_back(parts(s, s.parameter));

  FrequencyResponseSensitivity out;
  out.frequencies_hz = frequencies_hz;
  out.derivative.assign(sensitivities.size(), {});
  const double u = std::numeric_limits<double>::epsilon();
  // Work space reused over the frequencies (each analysis used to allocate its temporaries anew).
  CM A, Bw, Cw, X, Z, W, dAX, dBw, dCw, dZ;
  Eigen::MatrixXd Xr, Xi;
  Eigen::PartialPivLU<CM> lu(f);
  for (double hz : frequencies_hz) {
    if (!std::isfinite(hz)) throw NonFiniteError("frequency_response_sensitivity: frequency " + std::to_string(hz) + " Hz");
    const double w = 2 * M_PI * hz;
    combine(A, f, f, P.K, P.Q, P.M, w);
    lu.compute(A);
    const double rc = f ? lu.rcond() : 1.0;
    out.rcond.push_back(rc);
    const bool singular = !(rc > u);
    combine(Bw, f, m, P.B, P.B1, P.B2, w);
    combine(Cw, r, f, P.Cy, P.Cv, P.Ca, w);
    X = lu.solve(Bw);
    Z = Cw * X;
    if (!P.D.zero) Z.real() += P.D.a;
    if (!P.D1.zero) Z.imag() += w * P.D1.a;
    if (singular) Z.setConstant(Cx(kNaN, kNaN));
    out.response.push_back(Z);
    if (dP.empty()) continue;
    // dẑ = dC X + C(Ω) A⁻¹ (dB(Ω) − dA X) + dD.
    Xr = X.real();
    Xi = X.imag();
    for (std::size_t j = 0; j < dP.size(); ++j) {
      const Parts& d = dP[j];
      apply(dAX, d.K, d.Q, d.M, w, Xr, Xi, f);
      combine(dBw, f, m, d.B, d.B1, d.B2, w);
      dBw -= dAX;
      W = lu.solve(dBw);
      dZ.noalias() = Cw * W;
      if (!(d.Cy.zero && d.Cv.zero && d.Ca.zero)) {
        apply(dCw, d.Cy, d.Cv, d.Ca, w, Xr, Xi, r);
        dZ += dCw;
      }
      if (!d.D.zero) dZ.real() += d.D.a;
      if (!d.D1.zero) dZ.imag() += w * d.D1.a;
      if (singular) dZ.setConstant(Cx(kNaN, kNaN));
      out.derivative[j].push_back(dZ);
    }
  }
  return out;
}

}  // namespace mbsgen
