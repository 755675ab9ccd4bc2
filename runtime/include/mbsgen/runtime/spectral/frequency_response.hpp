// Frequency response of  M ÿ + Q ẏ + K y = B u,  z = C_y y + C_v ẏ + C_a ÿ + D u  (seed eqs.
// 3.18-3.23, docs/design.md, "Linearization"): for u_j = e_j cos(Ωt − φ_j) the stationary output is z = Re(ẑ e^{iΩt})
//     (K − Ω²M + iΩQ) ŷ = b_j,   ẑ = (C_y + iΩ C_v − Ω² C_a) ŷ + d_j
// (b_j, d_j: column j of B and D, per unit input; C_a and D are zero unless the model has them,
// e.g. joint loads, issue 15 §3).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <complex>
#include <memory>
#include <string>
#include <vector>

#include "mbsgen/runtime/model/linear_model.hpp"

namespace mbsgen {

/// How FrequencyResponse solves for each frequency.
enum class FrfMethod {
  automatic,   ///< banded, hessenberg or direct by size and conditioning: automatic_frf_method
  direct,      ///< complex LU (zgetrf) of K − Ω²M + iΩQ per frequency, O(f³) each: the reference
  banded,      ///< complex band LU of the same matrix, O(f·b²) each (chains, FE models)
  hessenberg,  ///< one-time Hessenberg(-triangular) reduction, then O(f²) per frequency (Laub 1981)
  modal,       ///< superposition of the modes with static correction (needs M nonsingular)
  real         ///< docs/design.md's corrected real formulation (Ω²E + A²)g = −A b, −Ω b (comparison)
};

/// "automatic", "direct", "banded", "hessenberg", "modal", "real".
const char* to_string(FrfMethod method);
/// Inverse of to_string (also accepts "auto"); throws mbsgen::Error for an unknown name.
FrfMethod parse_frf_method(const std::string& name);

/// The method FrfMethod::automatic uses for `model` (f coordinates, half-bandwidth b) and a call
/// with `frequencies` frequencies (docs/accuracy-vs-time.md §5): banded when 4b ≤ f and
/// b² ≤ 16f; otherwise direct when f < 12; hessenberg when frequencies ≥ min(30, max(8, f/2)) and
/// rcond₁(M̃)·rcond₁(K̃) ≥ 1e-8, with M̃, K̃ = S M S, S K S and S = diag(M)^(−1/2) (M or K
/// singular fails the test); otherwise direct. Costs two LU factorizations of f×f matrices when
/// it gets to the conditioning test, nothing otherwise. This is the rule before the solve:
/// FrequencyResponse with FrfMethod::automatic also takes direct when hessenberg's a-posteriori
/// backward-error check fails (FrfOptions::hessenberg_backward_error_bar), or when its forward
/// error at the probe frequencies, in ŷ or in a selected output, exceeds 10× direct's
/// (estimated by one step of iterative refinement of direct's solution; floor 10·f·u) — no
/// method auto picks is more than 10× less accurate than direct (issue 14).
FrfMethod automatic_frf_method(const LinearModel& model, Eigen::Index frequencies);

/// What to do at (or numerically at) a pole of an undamped system.
enum class PoleHandling {
  flag,  ///< mark the point FrfFlag::pole and set its response to NaN
  raise  ///< throw SingularSystemError naming the frequency
};

/// Per-frequency status.
enum class FrfFlag : unsigned char {
  ok,               ///< rcond ≥ FrfOptions::ill_conditioned_rcond
  /// pole_rcond < rcond < ill_conditioned_rcond: value kept, few digits; for `real`, any rcond
  /// below ill_conditioned_rcond (the real 2f×2f system Ω²E + A² squares the condition number:
  /// its rcond says how well that solve is conditioned, not that Ω is a pole)
  ill_conditioned,
  /// exactly singular (zero pivot), a non-finite value, or (except `real`) rcond ≤ pole_rcond:
  /// no correct digits; value NaN
  pole,
  /// the range of double was exceeded at this frequency: an entry of the dynamic stiffness
  /// −Ω²M + iΩQ + K (iΩE − A) overflows, or the solve or an output (or its modulus) does although
  /// the system is not singular; value NaN. Not a pole: rescale the model's units.
  overflow
};
/// "ok", "ill_conditioned", "pole", "overflow".
/// The reciprocal condition (1-norm estimate) of −Ω²X2 + iΩX1 + X0 (X2 may be empty) assembled in
/// extended range and scaled by its largest term's size to unit norm before the LU, so that data
/// near the ends of the range of double (entries of 1e308 or 1e-307) neither overflow nor make the
/// estimate underflow: what tells a pole (≈ 0) from a point whose value only overflows.
double frf_scaled_rcond(const Eigen::MatrixXd& X2, const Eigen::MatrixXd& X1, const Eigen::MatrixXd& X0,
                        double omega);
const char* to_string(FrfFlag flag);

/// Options of FrequencyResponse.
struct FrfOptions {
  FrfMethod method = FrfMethod::automatic;
  PoleHandling on_pole = PoleHandling::flag;
  /// Below this reciprocal condition number a point is flagged ill_conditioned. The forward
  /// error bound of a backward-stable solve is about f·u/rcond, so 1e-8 means "fewer than about
  /// 7 correct digits may remain".
  double ill_conditioned_rcond = 1e-8;
  /// At or below this rcond a point is a pole; 0 means the default f·u, where the error bound
  /// f·u/rcond reaches 1 (no correct digit).
  double pole_rcond = 0.0;
  /// modal: keep only the k lowest (by |λ|) eigenvalue pairs; 0 keeps all 2f eigenvalues.
  Eigen::Index modal_modes = 0;
  /// modal with truncation: add the static (residual) correction K⁻¹b − Σ_kept (needs K regular).
  bool static_correction = true;
  /// modal: refuse (IllConditionedError) when the 1-norm condition estimate κ of the
  /// column-normalized eigenvector matrix [x_k; (λ_k/γ)x_k] of the linearization (γ the
  /// eigenvalue scaling of QuadraticEigenSolver) exceeds this, unless
  /// modal_allow_ill_conditioned.
  /// The modal sum loses about log10(κ) digits; 1e6 keeps about 10 (a defective pair, split by
  /// O(√u) in floating point, has κ ≈ 1e8).
  double modal_max_condition = 1e6;
  bool modal_allow_ill_conditioned = false;  ///< then only a warning is recorded
  /// hessenberg: use the standard form A = [[0, E], [−M⁻¹K, −M⁻¹Q]] (via an LU of M, never
  /// M⁻¹ itself; dgebal + dgehrd, blocked and fast) when rcond₁(M) ≥ this; otherwise the
  /// pencil (diag(E, M), [[0, E], [−K, −Q]]) (dggbal + dgghrd).
  double hessenberg_mass_rcond = 1e-6;
  /// hessenberg: balance before the reduction, chosen a posteriori: permute and scale (LAPACK
  /// xGEBAL/xGGBAL job 'B'), and when the largest normwise backward error of the solution at up
  /// to five probe frequencies (the smallest, the quartiles and the largest of the first
  /// compute(), for its input; O(f²) each) exceeds hessenberg_backward_error_bar, permute only ('P'),
  /// keeping whichever has the smaller backward error. Without scaling the ear-scaled chain
  /// loses 6-7 digits (issue 3); with it, rounding noise where M, Q, K have exact zeros can steer
  /// the scaling to lose all of them (issue 14). false: neither ('N'), for the benchmarks and
  /// tests that show it.
  bool balance = true;
  /// hessenberg: the bar of the a-posteriori check above, on the normwise backward error of ŷ
  /// in the second-order system scaled to unit coordinates, ‖S(b − Dŷ)‖∞/(‖SDS‖∞‖S⁻¹ŷ‖∞ +
  /// ‖Sb‖∞), D = K − Ω²M + iΩQ, S = diag(|K_ii| + Ω²|M_ii| + Ω|Q_ii|)^(−1/2); 0 means the
  /// default 10·f·u, within an order of magnitude of what direct (LU with partial pivoting)
  /// achieves. When no balancing meets it, FrfMethod::automatic uses direct instead and an
  /// explicit hessenberg records a warning.
  double hessenberg_backward_error_bar = 0.0;
};

/// Frequency response for one input column and selected output rows, shaped like an Eigen
/// decomposition. The model must outlive the object. Per-method setup (factorizations,
/// reductions, modes) happens once, on the first compute() with that method; the loop over
/// frequencies does not allocate.
///
/// Every frequency carries a reciprocal condition estimate rcond (1-norm) of the matrix actually
/// solved: K − Ω²M + iΩQ (direct, banded: LAPACK xGECON/xGBCON, Higham's estimator), the reduced
/// Hessenberg matrix iΩT − H of the balanced first-order system (hessenberg: the two-solve
/// LINPACK estimator of Cline, Moler, Stewart & Wilkinson 1979), Ω²E + A² equilibrated by
/// dgeequb (real: dgecon);
/// for modal min(min_k |iΩ − λ_k|/max(|λ_k|, Ω), ‖ẑ‖/Σ_k‖term_k‖)/κ: the relative distance to
/// the nearest pole and the cancellation in the modal sum, divided by the eigenvector condition κ. Amplitude |ẑ| and phase lag Ψ = −arg ẑ = atan2(−Im ẑ, Re ẑ), so that
/// z(t) = |ẑ| cos(Ωt − Ψ) (eqs. 3.21-3.23 with the quadrant kept).
class FrequencyResponse {
 public:
  /// Keeps a reference to `model` (f coordinates) and the options; allocates nothing large yet.
  explicit FrequencyResponse(const LinearModel& model, FrfOptions options = {});
  /// Refused at compile time: the reference would dangle once the temporary is gone
  /// (`FrequencyResponse frf(model.linear_model())` crashed in compute()).
  explicit FrequencyResponse(LinearModel&& model, FrfOptions options = {}) = delete;
  ~FrequencyResponse();  ///< defined where Impl is complete
  FrequencyResponse(const FrequencyResponse&) = delete;
  FrequencyResponse& operator=(const FrequencyResponse&) = delete;

  /// Computes ẑ(Ω) for the angular frequencies omega (rad/s, any order, ≥ 0), input column
  /// `input` (0-based) of B and the output rows `outputs` (0-based rows of C_y, C_v; empty means
  /// all). Every method gives ẑ = (C_y + iΩC_v − Ω²C_a) ŷ + D(:, input): an output with a
  /// nonzero row of C_a is computed as two rows, C_y + iΩC_v and C_a (a pseudo-row the method
  /// solves like any output), combined after each frequency; rcond and the flags are those of
  /// the solve for ŷ (the combination, like C_y ŷ, is an ordinary sum rounded to about
  /// u·(|(C_y + iΩC_v)ŷ| + Ω²|C_a ŷ| + |d|), which may cancel: an output that is exactly zero
  /// by the equations of motion comes out at that rounding level). A model without C_a and D
  /// takes the path it took before they existed. Throws DimensionError for bad indices, SingularSystemError at a pole when
  /// on_pole == raise, IllConditionedError/SingularSystemError when modal cannot be used.
  FrequencyResponse& compute(const Eigen::VectorXd& omega, Eigen::Index input,
                             const std::vector<Eigen::Index>& outputs = {});

  /// Eigen::Success after a completed compute() (flagged points included).
  Eigen::ComputationInfo info() const { return info_; }
  /// The method used (never automatic after compute()).
  FrfMethod method() const { return used_; }
  /// p×F matrix: row r is output outputs[r], column k is frequency omega[k] (output unit per
  /// input unit).
  const Eigen::MatrixXcd& response() const { return response_; }
  /// F reciprocal condition estimates (see class comment).
  const Eigen::VectorXd& rcond() const { return rcond_; }
  /// F flags.
  const std::vector<FrfFlag>& flags() const { return flags_; }
  /// hessenberg: the balancing the a-posteriori check kept, 'B' (permute and scale), 'P'
  /// (permute) or 'N' (none); '\0' before the method has been set up.
  char hessenberg_balancing() const;
  /// hessenberg: the largest normwise backward error of the probe solves of that check
  /// (FrfOptions::balance); 0 before the method has been set up.
  double hessenberg_backward_error() const;
  /// Warnings recorded by the last compute() (e.g. modal without static correction).
  const std::vector<std::string>& warnings() const { return warnings_; }
  /// Why FrfMethod::automatic replaced hessenberg by direct after its a-posteriori checks (not
  /// warnings: the result has direct's accuracy; method() names the method used).
  const std::vector<std::string>& notes() const { return notes_; }

 private:
  struct Impl;  // per-method workspaces (frequency_response.cpp)
  /// One pass over the frequencies with the selected right-hand side: `out` (p×F), rcond_ and
  /// flags_ (the same for every right-hand side of one input).
  void sweep(const Eigen::VectorXd& omega, FrfMethod m, Eigen::Index p, Eigen::MatrixXcd& out);
  const LinearModel& model_;
  FrfOptions options_;
  std::unique_ptr<Impl> impl_;
  Eigen::ComputationInfo info_ = Eigen::InvalidInput;
  FrfMethod used_ = FrfMethod::automatic;
  Eigen::MatrixXcd response_;
  Eigen::VectorXd rcond_;
  std::vector<FrfFlag> flags_;
  std::vector<std::string> warnings_;
  std::vector<std::string> notes_;
};

/// Amplitude |g| (eq. 3.22).
inline double amplitude(std::complex<double> g) { return std::abs(g); }
/// Phase lag Ψ = −arg g = atan2(−Im g, Re g) in radians, in (−π, π] (eq. 3.23 with atan2).
inline double phase_lag(std::complex<double> g) {
  const double p = std::atan2(-g.imag(), g.real());
  return p <= -3.141592653589793 ? 3.141592653589793 : p + 0.0;  // (−π, π], no −0
}

}  // namespace mbsgen
