// FrequencyResponse's public API (to_string, parse_frf_method, automatic_frf_method, the class's
// constructor, compute() and its sweep over the frequencies) and the members of
// FrequencyResponse::Impl that all methods share (output selection and combination). Each method's
// own members are in frf_direct.cpp, frf_banded.cpp, frf_hessenberg.cpp, frf_modal.cpp and
// frf_real.cpp; Impl is declared in frequency_response_impl.hpp.
#include "mbsgen/runtime/spectral/frequency_response.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "spectral/frequency_response_impl.hpp"

namespace mbsgen {

namespace {
constexpr double kTwoPi = 6.283185307179586476925286766559;

std::string hz(double omega) {
  std::ostringstream s;
  s << omega << " rad/s (" << omega / kTwoPi << " Hz)";
  return s.str();
}

/// compute()'s checks of its arguments: `input` a column of B, `outputs` (empty: all) rows of
/// C_y, the frequencies finite and non-negative; throws DimensionError or NonFiniteError.
/// Returns the output rows.
std::vector<Index> checked_rows(const LinearModel& model, const Eigen::VectorXd& omega, Index input,
                                const std::vector<Index>& outputs) {
  const Index n = model.size();
  if (input < 0 || input >= model.num_inputs()) {
    std::ostringstream s;
    s << "FrequencyResponse::compute: input index " << input << " out of range (B is " << n
      << "x" << model.num_inputs() << ")";
    throw DimensionError(s.str());
  }
  std::vector<Index> rows = outputs;
  if (rows.empty())
    for (Index i = 0; i < model.num_outputs(); ++i) rows.push_back(i);
  for (Index r : rows)
    if (r < 0 || r >= model.num_outputs()) {
      std::ostringstream s;
      s << "FrequencyResponse::compute: output index " << r << " out of range (C_y is "
        << model.num_outputs() << "x" << n << ")";
      throw DimensionError(s.str());
    }
  for (Index k = 0; k < omega.size(); ++k)
    if (!std::isfinite(omega[k]) || omega[k] < 0) {
      std::ostringstream s;
      s << "FrequencyResponse::compute: frequency " << k << " is " << omega[k]
        << " rad/s; frequencies must be finite and non-negative";
      throw NonFiniteError(s.str());
    }
  return rows;
}

}  // namespace

const char* to_string(FrfMethod method) {
  switch (method) {
    case FrfMethod::automatic: return "automatic";
    case FrfMethod::direct: return "direct";
    case FrfMethod::banded: return "banded";
    case FrfMethod::hessenberg: return "hessenberg";
    case FrfMethod::modal: return "modal";
    case FrfMethod::real: return "real";
  }
  return "?";
}

FrfMethod parse_frf_method(const std::string& name) {
  if (name == "auto" || name == "automatic") return FrfMethod::automatic;
  if (name == "direct") return FrfMethod::direct;
  if (name == "banded") return FrfMethod::banded;
  if (name == "hessenberg") return FrfMethod::hessenberg;
  if (name == "modal") return FrfMethod::modal;
  if (name == "real") return FrfMethod::real;
  throw Error("parse_frf_method: unknown method '" + name +
              "' (expected auto, direct, banded, hessenberg, modal, real)");
}

// The rule follows docs/accuracy-vs-time.md §5 (the recommendation table; measured by
// bench/frf_accuracy.cpp, checked by tests/runtime/test_auto_method.cpp): banded wherever the
// band is narrow (faster than the dense methods on every chain and in the sweep up to b = n/4,
// where it ties with hessenberg; as accurate as direct); dense and below 12 coordinates direct,
// the backward-stable reference, since every method costs microseconds there (the rotor:
// hessenberg 3× faster, 1000× less accurate); among the dense methods hessenberg once its
// one-time reduction is paid back (break-even from about 8 frequencies at f = 12 to about 25–35
// from f = 100 on), unless the first-order form is badly conditioned: its error grows like
// u·κ(M̃)κ(K̃) (speaker_box: 4e-8 against direct's 3e-10), so above 1e8 — or with M or K
// singular — direct.
FrfMethod automatic_frf_method(const LinearModel& model, Index frequencies) {
  const Index n = model.size(), b = model.bandwidth();
  if (4 * b <= n && b * b <= 16 * n) return FrfMethod::banded;
  if (n < 12) return FrfMethod::direct;
  if (frequencies < std::min<Index>(30, std::max<Index>(8, n / 2))) return FrfMethod::direct;
  // κ₁ of M and K scaled to unit diagonal of M (the coordinates' units divided out).
  const Eigen::VectorXd d = model.M().diagonal();
  if (!(d.minCoeff() > 0)) return FrfMethod::direct;
  const Eigen::VectorXd s = d.cwiseSqrt().cwiseInverse();
  const double rc_M = Eigen::PartialPivLU<Eigen::MatrixXd>(s.asDiagonal() * model.M() * s.asDiagonal()).rcond();
  const double rc_K = Eigen::PartialPivLU<Eigen::MatrixXd>(s.asDiagonal() * model.K() * s.asDiagonal()).rcond();
  return rc_M * rc_K >= 1e-8 ? FrfMethod::hessenberg : FrfMethod::direct;
}

const char* to_string(FrfFlag flag) {
  switch (flag) {
    case FrfFlag::ok: return "ok";
    case FrfFlag::ill_conditioned: return "ill_conditioned";
    case FrfFlag::pole: return "pole";
    case FrfFlag::overflow: return "overflow";
  }
  return "?";
}

double frf_scaled_rcond(const Eigen::MatrixXd& X2, const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X0,
                        double omega) {
  using ld = long double;  // 64-bit mantissa, exponent to ±4932 on x86-64 and AArch64
  const Index n = X0.rows();
  const ld w = omega;
  auto largest = [](const Eigen::MatrixXd& X) { return X.size() ? static_cast<ld>(X.cwiseAbs().maxCoeff()) : 0.0L; };
  const ld s = std::max({w * w * largest(X2), w * largest(X1), largest(X0)});
  if (!(s > 0)) return 0.0;
  Eigen::MatrixXcd G(n, n);
  for (Index j = 0; j < n; ++j)
    for (Index i = 0; i < n; ++i) {
      const ld re = (X2.size() ? -w * w * X2(i, j) : 0.0L) + X0(i, j);
      const ld im = w * X1(i, j);
      G(i, j) = cd(static_cast<double>(re / s), static_cast<double>(im / s));
    }
  return Eigen::PartialPivLU<Eigen::MatrixXcd>(G).rcond();
}

// ---- FrequencyResponse::Impl: the members every method shares ----

/// Selects input column `input` and the output `rows` (validated by the caller): b, the rows
/// Cy, Cv (and their real parts), acc_row, feed and combine. Without C_a and D (or with zero
/// rows) exactly the old rows and no combination step.
void FrequencyResponse::Impl::select_outputs(const std::vector<Index>& rows, Index input) {
  const Index p = static_cast<Index>(rows.size());
  b = model.B().col(input);
  acc_row.assign(rows.size(), -1);
  feed.setZero(p);
  Index q = 0;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    if (model.has_output_accelerations() && (model.C_a().row(rows[r]).array() != 0.0).any())
      acc_row[r] = p + q++;
    if (model.has_feedthrough()) feed[static_cast<Index>(r)] = model.D()(rows[r], input);
  }
  combine = q > 0 || (feed.array() != 0.0).any();
  Cy.resize(p + q, n);
  Cv.resize(p + q, n);
  for (Index r = 0; r < p; ++r) {
    const Index row = rows[static_cast<std::size_t>(r)];
    Cy.row(r) = model.C_y().row(row).cast<cd>();
    Cv.row(r) = model.C_v().row(row).cast<cd>();
    const Index a = acc_row[static_cast<std::size_t>(r)];
    if (a >= 0) {
      Cy.row(a) = model.C_a().row(row).cast<cd>();
      Cv.row(a).setZero();
    }
  }
  z.resize(p + q);
  Cy_re = Cy.real();
  Cv_re = Cv.real();
}

/// The right-hand side b and the feedthrough d(rows) of one part of a moving support's
/// excitation (FrequencyResponse::compute): B1's or B2's column and D1's or none.
void FrequencyResponse::Impl::select_part(const Eigen::MatrixXd& part_B,
                                          const Eigen::MatrixXd* part_D,
                                          const std::vector<Index>& rows, Index input) {
  if (part_B.size() != 0) b = part_B.col(input);
  else b.setZero(n);
  feed.setZero(static_cast<Index>(rows.size()));
  if (part_D && part_D->size() != 0)
    for (std::size_t r = 0; r < rows.size(); ++r) feed[static_cast<Index>(r)] = (*part_D)(rows[r], input);
  bool acc = false;
  for (Index a : acc_row) acc = acc || a >= 0;
  combine = acc || (feed.array() != 0.0).any();
}

/// ẑ_r = (C_y + iΩC_v)_r ŷ − Ω²(C_a ŷ)_r + D(r, input) for the p outputs, in place in z's
/// first p entries (the pseudo-rows are read before being overwritten: their index is ≥ p).
void FrequencyResponse::Impl::combine_outputs(double om) {
  const double om2 = om * om;
  for (std::size_t r = 0; r < acc_row.size(); ++r) {
    const Index i = static_cast<Index>(r);
    if (acc_row[r] >= 0) z[i] -= om2 * z[acc_row[r]];
    if (feed[i] != 0.0) z[i] += feed[i];
  }
}

/// LU of M exists (no zero pivot) and its 1-norm rcond estimate is at least `threshold`.
bool FrequencyResponse::Impl::mass_is_regular(double threshold) const {
  if (!(Mlu.matrixLU().diagonal().cwiseAbs().minCoeff() > 0.0)) return false;
  const double rc = Mlu.rcond();
  return std::isfinite(rc) && rc >= threshold;
}

FrequencyResponse::FrequencyResponse(const LinearModel& model, FrfOptions options)
    : model_(model), options_(options), impl_(std::make_unique<Impl>(model)) {}

FrequencyResponse::~FrequencyResponse() = default;

char FrequencyResponse::hessenberg_balancing() const {
  return impl_->hess_ready ? impl_->hess_job : '\0';
}

double FrequencyResponse::hessenberg_backward_error() const {
  return impl_->hess_ready ? impl_->hess_backward_error : 0.0;
}

FrequencyResponse& FrequencyResponse::compute(const Eigen::VectorXd& omega, Index input,
                                              const std::vector<Index>& outputs) {
  info_ = Eigen::InvalidInput;
  warnings_.clear();
  notes_.clear();
  Impl& im = *impl_;
  const std::vector<Index> rows = checked_rows(model_, omega, input, outputs);
  const Index p = static_cast<Index>(rows.size());
  im.select_outputs(rows, input);

  FrfMethod m = options_.method;
  if (m == FrfMethod::automatic) m = automatic_frf_method(model_, omega.size());
  used_ = m;
  switch (m) {
    case FrfMethod::direct: im.prepare_direct(); break;
    case FrfMethod::banded:
      im.prepare_banded();
      im.select_banded();
      break;
    case FrfMethod::hessenberg:
      im.prepare_hessenberg(options_, omega);
      if (options_.method == FrfMethod::automatic && im.hess_backward_error <= im.hess_bar &&
          !im.hessenberg_as_accurate_as_direct(omega, im.hess_forward_ratio)) {
        std::ostringstream s;
        s << "FrequencyResponse (hessenberg): forward error " << im.hess_forward_ratio
          << "x direct's at a probe frequency (bar 10x); automatic uses direct";
        notes_.push_back(s.str());
        used_ = m = FrfMethod::direct;
        im.prepare_direct();
      } else if (!(im.hess_backward_error <= im.hess_bar)) {
        std::ostringstream s;
        s << "FrequencyResponse (hessenberg): backward error " << im.hess_backward_error
          << " at the probe frequencies exceeds " << im.hess_bar << " (balancing '" << im.hess_job
          << "' kept)";
        if (options_.method == FrfMethod::automatic) {
          s << "; automatic uses direct";
          used_ = m = FrfMethod::direct;
          im.prepare_direct();
          notes_.push_back(s.str());
        } else {
          s << "; expect that many fewer correct digits than direct";
          im.select_hessenberg();
          warnings_.push_back(s.str());
        }
      } else {
        im.select_hessenberg();
      }
      break;
    case FrfMethod::modal:
      im.prepare_modal(options_, warnings_);
      im.select_modal(options_, warnings_);
      break;
    case FrfMethod::real:
      im.prepare_real();
      im.select_real();
      break;
    case FrfMethod::automatic: break;
  }

  sweep(omega, m, p, response_);
  // A moving support (LinearModel::B1): the response to B(Ω) = B + iΩB1 − Ω²B2 is, by
  // linearity, that to B plus iΩ times that to B1 (with D1) minus Ω² times that to B2: two more
  // sweeps, every method unchanged (those that factor per frequency factor again: three times the
  // cost for a motion input). A point's flag and rcond are the worst of the three sweeps (the
  // modal method's rcond depends on the right-hand side), and a pole in any makes it NaN.
  if (model_.input_has_rates(input)) {
    const std::vector<FrfFlag> flags = flags_;
    const Eigen::VectorXd rcond = rcond_;
    auto worst = [](FrfFlag a, FrfFlag b) {
      if (a == FrfFlag::overflow || b == FrfFlag::overflow) return FrfFlag::overflow;
      if (a == FrfFlag::pole || b == FrfFlag::pole) return FrfFlag::pole;
      return a == FrfFlag::ill_conditioned || b == FrfFlag::ill_conditioned ? FrfFlag::ill_conditioned : FrfFlag::ok;
    };
    std::vector<FrfFlag> merged = flags;
    Eigen::VectorXd merged_rcond = rcond;
    for (int part = 1; part <= 2; ++part) {
      im.select_part(part == 1 ? model_.B1() : model_.B2(), part == 1 ? &model_.D1() : nullptr, rows, input);
      switch (m) {
        case FrfMethod::banded: im.select_banded(); break;
        case FrfMethod::hessenberg: im.select_hessenberg(); break;
        case FrfMethod::modal: im.select_modal(options_, warnings_); break;
        case FrfMethod::real: im.select_real(); break;
        default: break;
      }
      Eigen::MatrixXcd z;
      sweep(omega, m, p, z);
      for (Index k = 0; k < omega.size(); ++k) {
        const auto K = static_cast<std::size_t>(k);
        merged[K] = worst(merged[K], flags_[K]);
        merged_rcond[k] = std::min(merged_rcond[k], rcond_[k]);
        const cd factor = part == 1 ? cd(0.0, omega[k]) : cd(-omega[k] * omega[k], 0.0);
        if (merged[K] == FrfFlag::pole || merged[K] == FrfFlag::overflow)
          response_.col(k).setConstant(cd(kNaN, kNaN));
        else
          response_.col(k) += factor * z.col(k);
      }
    }
    flags_ = merged;
    rcond_ = merged_rcond;
    // Each part's selection may say the same thing again (a modal truncation): once is enough.
    std::vector<std::string> once;
    for (const std::string& w : warnings_)
      if (std::find(once.begin(), once.end(), w) == once.end()) once.push_back(w);
    warnings_ = once;
  }
  info_ = Eigen::Success;
  return *this;
}

void FrequencyResponse::sweep(const Eigen::VectorXd& omega, FrfMethod m, Index p, Eigen::MatrixXcd& out) {
  Impl& im = *impl_;
  const Index n = model_.size();
  const Index F = omega.size();
  out.resize(p, F);
  rcond_.resize(F);
  flags_.assign(static_cast<std::size_t>(F), FrfFlag::ok);
  const double pole_rc =
      options_.pole_rcond > 0 ? options_.pole_rcond : static_cast<double>(n) * kU;
  for (Index k = 0; k < F; ++k) {
    const double om = omega[k];
    double rc = 0.0;
    bool ok = false;
    switch (m) {
      case FrfMethod::direct: ok = im.point_direct(om, rc); break;
      case FrfMethod::banded: ok = im.point_banded(om, rc); break;
      case FrfMethod::hessenberg: ok = im.point_hessenberg(om, rc); break;
      case FrfMethod::modal: ok = im.point_modal(om, rc); break;
      case FrfMethod::real: ok = im.point_real(om, rc); break;
      case FrfMethod::automatic: break;
    }
    if (ok && im.combine) im.combine_outputs(om);
    rcond_[k] = rc;
    FrfFlag flag = FrfFlag::ok;
    // `real` solves the squared system Ω²E + A², whose rcond is about the square of the complex
    // one's: a small rcond there says the real 2f×2f solve is ill-conditioned, not that Ω is a
    // pole; a pole is an exact zero pivot or a non-finite value.
    const bool finite = ok && im.z.allFinite();
    if (finite && !im.z.head(p).cwiseAbs().allFinite())  // |re + i im| beyond the range
      flag = FrfFlag::overflow;
    else if (!finite || (!(rc > pole_rc) && m != FrfMethod::real))
      // A pole, unless the system scaled to unit size is not singular: then the data or the
      // value left the range of double (an rcond of 3e-2 or 1 is no pole).
      flag = frf_scaled_rcond(model_.M(), model_.Q(), model_.K(), om) > pole_rc ? FrfFlag::overflow : FrfFlag::pole;
    else if (rc < options_.ill_conditioned_rcond)
      flag = FrfFlag::ill_conditioned;
    flags_[static_cast<std::size_t>(k)] = flag;
    if (flag == FrfFlag::overflow) {
      if (options_.on_pole == PoleHandling::raise) {
        std::ostringstream s;
        s << "FrequencyResponse::compute (" << to_string(m) << "): the range of double is exceeded at "
          << hz(om) << " (the dynamic stiffness, the solution or an output overflows): rescale the model's units";
        throw NonFiniteError(s.str());
      }
      out.col(k).setConstant(cd(kNaN, kNaN));
    } else if (flag == FrfFlag::pole) {
      if (options_.on_pole == PoleHandling::raise) {
        std::ostringstream s;
        s << "FrequencyResponse::compute (" << to_string(m) << "): the system is singular at "
          << hz(om) << ", rcond = " << rc << " (an undamped resonance?)";
        throw SingularSystemError(s.str());
      }
      out.col(k).setConstant(cd(kNaN, kNaN));
    } else {
      out.col(k) = im.z.head(p);
    }
  }
}

}  // namespace mbsgen
