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

FrequencyResponseSensitivity frequency_response_sensitivity(const LinearModel& model,
                                                            const std::vector<MatrixSensitivity>& sensitivities,
                                                            const std::vector<double>& frequencies_hz) {
  using C = std::complex<double>;
  using CM = Eigen::MatrixXcd;
  const Eigen::Index f = model.size(), m = model.num_inputs(), r = model.num_outputs();
  struct Parts {
    Eigen::MatrixXd M, Q, K, B, Cy, Cv, Ca, D, B1, B2, D1;
  };
  auto parts = [&](const MatrixSensitivity& s, const std::string& name) {
    return Parts{part(s.M, f, f, "M", name),   part(s.Q, f, f, "Q", name),   part(s.K, f, f, "K", name),
                 part(s.B, f, m, "B", name),   part(s.C_y, r, f, "C_y", name), part(s.C_v, r, f, "C_v", name),
                 part(s.C_a, r, f, "C_a", name), part(s.D, r, m, "D", name), part(s.B1, f, m, "B1", name),
                 part(s.B2, f, m, "B2", name), part(s.D1, r, m, "D1", name)};
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
  for (double hz : frequencies_hz) {
    if (!std::isfinite(hz)) throw NonFiniteError("frequency_response_sensitivity: frequency " + std::to_string(hz) + " Hz");
    const double w = 2 * M_PI * hz;
    const C iw(0, w);
    auto A_of = [&](const Parts& X) -> CM { return X.K.cast<C>() + iw * X.Q.cast<C>() - w * w * X.M.cast<C>(); };
    auto B_of = [&](const Parts& X) -> CM { return X.B.cast<C>() + iw * X.B1.cast<C>() - w * w * X.B2.cast<C>(); };
    auto C_of = [&](const Parts& X) -> CM { return X.Cy.cast<C>() + iw * X.Cv.cast<C>() - w * w * X.Ca.cast<C>(); };
    auto D_of = [&](const Parts& X) -> CM { return X.D.cast<C>() + iw * X.D1.cast<C>(); };
    const Eigen::PartialPivLU<CM> lu(A_of(P));
    const double rc = f ? lu.rcond() : 1.0;
    out.rcond.push_back(rc);
    const bool singular = !(rc > u);
    const CM X = lu.solve(B_of(P)), Cw = C_of(P);
    CM Z = Cw * X + D_of(P);
    if (singular) Z.setConstant(C(kNaN, kNaN));
    out.response.push_back(Z);
    for (std::size_t j = 0; j < dP.size(); ++j) {
      CM dZ = C_of(dP[j]) * X + Cw * lu.solve(B_of(dP[j]) - A_of(dP[j]) * X) + D_of(dP[j]);
      if (singular) dZ.setConstant(C(kNaN, kNaN));
      out.derivative[j].push_back(std::move(dZ));
    }
  }
  return out;
}

}  // namespace mbsgen
