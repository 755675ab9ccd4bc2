// FrfMethod::modal: superposition of the modes of QuadraticEigenSolver with static correction —
// FrequencyResponse::Impl's prepare_modal, select_modal and point_modal.
#include "spectral/frequency_response_impl.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace mbsgen {

void FrequencyResponse::Impl::prepare_modal(const FrfOptions& opt,
                                            std::vector<std::string>& warnings) {
  if (!modal_ready) {
    QuadraticEigenOptions eo;
    QuadraticEigenSolver es(n, eo);
    es.compute(model);
    for (const Mode& m : es.modes())
      if (m.kind != EigenvalueKind::finite)
        throw SingularSystemError(
            std::string("FrequencyResponse (modal): the model has ") + to_string(m.kind) +
            " eigenvalues (singular " + (m.kind == EigenvalueKind::zero ? "K" : "M") +
            "); modal superposition needs all 2f eigenvalues finite and nonzero: use direct");
    modes = es.modes();
    const Index nm = static_cast<Index>(modes.size());
    Eigen::MatrixXcd V(2 * n, nm);
    dk.resize(nm);
    const Eigen::MatrixXcd Mc = model.M().cast<cd>(), Qc = model.Q().cast<cd>();
    // Eigenvector matrix of the linearization in the scaled variable μ = λ/γ, so that the
    // estimate measures near-defectiveness rather than the spread of |λ|.
    const double gamma = es.gamma();
    for (Index k = 0; k < nm; ++k) {
      const Mode& m = modes[static_cast<std::size_t>(k)];
      V.col(k) << m.shape, (m.lambda / gamma) * m.shape;
      V.col(k).normalize();
      dk[k] = m.left_shape.dot(2.0 * m.lambda * (Mc * m.shape) + Qc * m.shape);
    }
    const double rc = Eigen::PartialPivLU<Eigen::MatrixXcd>(V).rcond();
    eigvec_condition = rc > 0 ? 1.0 / rc : std::numeric_limits<double>::infinity();
    modal_ready = true;
  }
  if (!(eigvec_condition <= opt.modal_max_condition)) {
    std::ostringstream s;
    s << "FrequencyResponse (modal): eigenvector matrix condition estimate " << eigvec_condition
      << " exceeds " << opt.modal_max_condition
      << " (ill-conditioned eigenvectors, e.g. near-defective eigenvalues); the modal sum is unreliable: use direct";
    if (!opt.modal_allow_ill_conditioned) throw IllConditionedError(s.str());
    warnings.push_back(s.str());
  }
}

void FrequencyResponse::Impl::select_modal(const FrfOptions& opt,
                                           std::vector<std::string>& warnings) {
  const Index nm = static_cast<Index>(modes.size());
  Index keep = nm;
  if (opt.modal_modes > 0 && 2 * opt.modal_modes < nm) {
    keep = 2 * opt.modal_modes;
    const auto& a = modes[static_cast<std::size_t>(keep - 1)].lambda;
    const auto& c = modes[static_cast<std::size_t>(keep)].lambda;
    if (a.imag() != 0 && c == std::conj(a)) ++keep;  // do not split a conjugate pair
  }
  const Index p = Cy.rows();
  lam.resize(keep);
  coef.resize(keep);
  CX.resize(p, keep);
  CVX.resize(p, keep);
  Eigen::VectorXcd y0 = Eigen::VectorXcd::Zero(n);
  for (Index k = 0; k < keep; ++k) {
    const Mode& m = modes[static_cast<std::size_t>(k)];
    lam[k] = m.lambda;
    coef[k] = m.left_shape.dot(b.cast<cd>()) / dk[k];
    CX.col(k) = Cy * m.shape;
    CVX.col(k) = Cv * m.shape;
    y0 += m.shape * (coef[k] / (-m.lambda));
  }
  zstatic_y = Eigen::VectorXcd::Zero(p);
  zstatic_v = Eigen::VectorXcd::Zero(p);
  if (keep < nm) {
    if (!opt.static_correction) {
      warnings.push_back("FrequencyResponse (modal): truncated without static correction");
    } else {
      Eigen::FullPivLU<Eigen::MatrixXd> Klu(model.K());
      if (!Klu.isInvertible()) {
        warnings.push_back("FrequencyResponse (modal): K singular, no static correction");
      } else {
        const Eigen::VectorXcd r0 = Klu.solve(b).cast<cd>() - y0;
        zstatic_y = Cy * r0;
        zstatic_v = Cv * r0;
      }
    }
  }
}

bool FrequencyResponse::Impl::point_modal(double om, double& rc) {
  const cd s(0.0, om);
  z = zstatic_y + s * zstatic_v;
  double dmin = std::numeric_limits<double>::infinity();
  double terms = z.norm();
  for (Index k = 0; k < lam.size(); ++k) {
    const cd d = s - lam[k];
    dmin = std::min(dmin, std::abs(d) / std::max(std::abs(lam[k]), om));
    if (d == cd(0.0)) {
      rc = 0.0;
      return false;
    }
    const cd w = coef[k] / d;
    z += w * (CX.col(k) + s * CVX.col(k));
    terms += std::abs(w) * (CX.col(k) + s * CVX.col(k)).norm();
  }
  // Relative distance to the nearest pole (eigenvalues carry errors ~u|λ|) and cancellation in
  // the sum (rounding errors of the terms relative to the result), whichever is worse, divided
  // by the eigenvector condition (errors of the computed eigenvectors).
  const double cancellation = terms > 0 ? z.norm() / terms : 1.0;
  rc = std::min(dmin, cancellation) / std::max(1.0, eigvec_condition);
  return true;
}

}  // namespace mbsgen
