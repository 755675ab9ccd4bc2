// Modes of  M ÿ + Q ẏ + K y = 0: the quadratic eigenvalue problem (λ²M + λQ + K) x = 0
// (seed eqs. 3.12-3.17).
#pragma once

#include <Eigen/Core>
#include <complex>
#include <string>
#include <vector>

#include "mbsgen/runtime/model/linear_model.hpp"

namespace mbsgen {

/// How an eigenvalue was classified.
enum class EigenvalueKind {
  finite,   ///< ordinary eigenvalue
  zero,     ///< λ = 0 (rigid-body mode; K numerically singular)
  infinite  ///< λ = ∞ (massless coordinate; M numerically singular)
};

/// "finite", "zero" or "infinite".
const char* to_string(EigenvalueKind kind);

/// Verdict on the linear stability of M ÿ + Q ẏ + K y = 0 that takes each eigenvalue's
/// error_bound into account (QuadraticEigenSolver::stability()). Infinite eigenvalues (massless
/// coordinates, constraints) carry no motion and are not counted.
enum class Stability {
  stable,     ///< every finite eigenvalue has Re λ < −error_bound, and there is no zero one
  unstable,   ///< some eigenvalue has Re λ > error_bound (and is not zero within its bound)
  marginal,   ///< not unstable, and the eigenvalues not decided stable are exactly on the
              ///< imaginary axis: deflated zeros (rigid-body modes) or Re λ = 0 exactly (the
              ///< symmetric undamped path); growth then depends on Jordan structure and on
              ///< nonlinear terms, which the linear analysis does not decide
  undecided   ///< not unstable, but some eigenvalue is zero within its bound or has
              ///< 0 < |Re λ| ≤ error_bound: perturbations of the data of the size behind the
              ///< bound can move it to either half-plane
};

/// "stable", "unstable", "marginal" or "undecided".
const char* to_string(Stability verdict);

struct Mode;
/// The verdict of Stability from modes' kinds and error bounds (infinite eigenvalues do not
/// count): what QuadraticEigenSolver::stability() and DescriptorEigenSolver::stability() report.
Stability stability_of(const std::vector<Mode>& modes);

/// One eigenpair of λ²M + λQ + K.
struct Mode {
  /// Reported eigenvalue λ (1/s): exactly 0 for kind zero, +∞ (real part) for kind infinite.
  std::complex<double> lambda;
  /// The homogeneous pair (α, β) with λ = α/β, unscaled, normalized |α|²+β² = 1, β ≥ 0: as
  /// computed by QZ for finite eigenvalues; exactly (0, 1) for kind zero and (1, 0) for kind
  /// infinite, which are deflated before QZ and never computed as numbers.
  std::complex<double> alpha;
  double beta = 0.0;
  EigenvalueKind kind = EigenvalueKind::finite;
  double natural_frequency_hz = 0.0;  ///< |λ|/2π (Hz); 0 for zero, +∞ for infinite
  double damped_frequency_hz = 0.0;   ///< Im λ/2π (Hz)
  /// −Re λ/|λ| (dimensionless); NaN (undefined) for zero eigenvalues and for those zero within
  /// their error bound, 0 for infinite ones.
  double damping_ratio = 0.0;
  /// Right eigenvector x (f), normalized to ‖x‖₂ = 1 with its largest-modulus entry real positive.
  Eigen::VectorXcd shape;
  /// Left eigenvector y (f), yᴴ(λ²M + λQ + K) = 0, same normalization.
  Eigen::VectorXcd left_shape;
  /// Normwise backward error (Tisseur 2000, eq. 2.3, homogeneous form):
  /// ‖(α²M + αβQ + β²K)x‖ / ((|α|²‖M‖ + |α|β‖Q‖ + β²‖K‖)‖x‖), with ‖·‖₂ lower estimates of the
  /// coefficient norms (so the value errs on the large side).
  double backward_error = 0.0;
  /// Relative condition number of λ (Tisseur 2000, Thm. 5):
  /// (|λ|²‖M‖ + |λ|‖Q‖ + ‖K‖)‖x‖‖y‖ / (|λ| |yᴴ(2λM + Q)x|); +∞ for zero and infinite kinds.
  double condition = 0.0;
  /// Homogeneous (chordal) condition number of (α, β) (Dedieu & Tisseur 2003), finite also for
  /// zero and infinite eigenvalues.
  double condition_homogeneous = 0.0;
  /// True for a zero or infinite eigenvalue in a Jordan chain (algebraic multiplicity above the
  /// geometric one, e.g. the double λ = 0 of an undamped rigid-body mode): it has one eigenvector
  /// per chain, `shape` is that eigenvector (the chain's head), and both condition numbers are +∞.
  bool defective = false;
  /// Absolute first-order error bound on λ (1/s): κ_abs(λ)·max(η, η_floor), with η =
  /// backward_error, η_floor = QuadraticEigenOptions::backward_error_floor and the absolute
  /// condition number κ_abs = (|λ|²‖M‖ + |λ|‖Q‖ + ‖K‖)‖x‖‖y‖ / |yᴴ(2λM + Q)x| (Tisseur 2000,
  /// Thm. 5, = |λ|·condition). The exact eigenvalue of a problem within relative normwise distance
  /// max(η, η_floor) of the data lies within error_bound of λ to first order. +∞ when
  /// yᴴ(2λM + Q)x = 0 (a defective eigenvalue); 0 for the deflated zero and infinite kinds, whose
  /// values are exact for the data perturbed by backward_error.
  double error_bound = 0.0;
  /// True for a finite eigenvalue with |λ| ≤ error_bound: the data do not separate it from 0
  /// (e.g. a Jordan block at 0 with rounding noise, which QZ splits into ±√noise). λ is still
  /// reported, but damping_ratio is NaN and the mode is neither stable nor unstable.
  bool zero_within_bound = false;
};

/// "zero_within_bound" for a mode with zero_within_bound set, else to_string(kind).
const char* kind_label(const Mode& mode);

/// Options of QuadraticEigenSolver.
struct QuadraticEigenOptions {
  enum class Scaling {
    automatic,           ///< Fan-Lin-Van Dooren if τ = ‖Q‖/√(‖M‖‖K‖) < 10, else tropical
    none,                ///< no scaling
    fan_lin_van_dooren,  ///< λ = γμ, γ = √(‖K‖/‖M‖), δ = 2/(‖K‖ + γ‖Q‖)  (Fan, Lin & Van Dooren 2004)
    tropical             ///< two QZ runs with the tropical roots (Gaubert & Sharify; quadeig)
  };
  Scaling scaling = Scaling::automatic;
  /// Balance the linearization in dggevx: by permutation ('P'); when the largest backward error
  /// then exceeds 10·f·u, once more with permutation and scaling ('B', Ward's algorithm, which is
  /// not normwise safe on these pencils) keeping the better run. false: neither ('N').
  bool balance = true;
  bool symmetric_fast_path = true;   ///< dsygvd when Q = 0, M = Mᵀ > 0, K = Kᵀ
  /// Rank tolerance tol of the deflation of zero and infinite eigenvalues; 0 means the default
  /// f·u (u = 2⁻⁵³). Two kinds of rank decision use it:
  ///  - M and K: a pivot |R_ii| ≤ tol·|R_00| of the column-pivoted QR (LAPACK dgeqp3) of Mᵀ
  ///    (Kᵀ) counts as zero; its null vectors are the eigenvectors of the f − rank(M) infinite
  ///    (f − rank(K) zero) eigenvalues deflated first, so their backward error is ≤ ‖R₂₂‖/‖M‖;
  ///  - further members of Jordan chains at 0 or ∞ (e.g. a rigid-body mode without damping, a
  ///    massless coordinate without a damper, constraints): a pivot ≤ 2·tol·‖A‖_F (‖B‖_F) of the
  ///    column-pivoted QR of the remaining block of the scaled linearization A − μB.
  /// An eigenvalue is deflated only if a perturbation of that relative size makes it exactly 0 or
  /// ∞: a small but nonzero eigenvalue (a soft spring, a weak damper to ground) stays finite.
  double rank_tolerance = 0.0;
  /// Relative normwise data uncertainty η_floor below which a backward error does not lower
  /// Mode::error_bound; 0 means the default 100·f·u, the backward-error level the solver is
  /// tested to (a matrix of f×f entries evaluated in floating point carries relative errors of
  /// order f·u, with room for cancellation in generated kernels). Negative: no floor (the bound
  /// then reflects the computed backward error alone).
  double backward_error_floor = 0.0;
  /// Unused since zero and infinite eigenvalues are deflated exactly (see rank_tolerance); kept so
  /// that code setting it still compiles.
  double classification_tolerance = 1e-6;
  /// Report each complex-conjugate pair once (the member with Im λ > 0), and a double zero
  /// eigenvalue of a rigid-body mode once.
  bool one_per_conjugate_pair = false;
};

/// Solver for all 2f eigenpairs of λ²M + λQ + K, shaped like an Eigen decomposition.
///
/// General path: the first companion linearization
///     μ [[E, 0], [0, M̃]] − [[0, E], [−K̃, −Q̃]],   z = [x; μx],
/// of the scaled problem M̃ = γ²δM, Q̃ = γδQ, K̃ = δK, λ = γμ. When M or K is rank deficient
/// (QuadraticEigenOptions::rank_tolerance) the zero and infinite eigenvalues are first deflated
/// exactly, as quadeig does (Hammarling, Munro & Tisseur 2013, §4-5): orthogonal transformations
/// split off a triangular pencil whose eigenvalues are exactly 0 and ∞ — one per null vector of K
/// (M), then, by a staircase of rank-revealing QRs (Van Dooren 1979), the further members of
/// Jordan chains — and the remaining pencil, whose eigenvalues are all finite and nonzero, is
/// solved by LAPACK dggevx with balancing. x is taken from the block of z that gives the smaller
/// backward error (as in quadeig). The symmetric undamped fast path uses dsygvd (Cholesky of M
/// inside LAPACK; M⁻¹ is never formed), on the M-orthogonal complement of the null space of K
/// when K is singular. Throws SingularSystemError when det(λ²M + λQ + K) vanishes identically.
/// Cost: O(f³), about 10·(2f)³ flops for QZ; the deflation adds O(f³) only when M or K is
/// singular.
class QuadraticEigenSolver {
 public:
  /// Preallocates for f coordinates.
  explicit QuadraticEigenSolver(Eigen::Index f = 0, QuadraticEigenOptions options = {});

  /// Computes the eigenpairs of the model's λ²M + λQ + K. Throws LapackError if QZ fails.
  QuadraticEigenSolver& compute(const LinearModel& model);
  /// Same for raw f×f matrices (validated as LinearModel does).
  QuadraticEigenSolver& compute(const Eigen::MatrixXd& M, const Eigen::MatrixXd& Q,
                                const Eigen::MatrixXd& K);

  /// Eigen::Success after a successful compute().
  Eigen::ComputationInfo info() const { return info_; }
  /// Eigenpairs sorted: zero kind first, then finite by increasing |λ| (Im λ ≥ 0 first within a
  /// conjugate pair), then infinite.
  const std::vector<Mode>& modes() const { return modes_; }

  Eigen::Index rank_M() const { return rank_M_; }  ///< numerical rank of M
  Eigen::Index rank_K() const { return rank_K_; }  ///< numerical rank of K
  /// Number of eigenvalues deflated as exactly zero (algebraic multiplicity of λ = 0; each
  /// counts once in modes() even when one_per_conjugate_pair lists a Jordan chain once).
  Eigen::Index num_zero() const { return num_zero_; }
  /// Number of eigenvalues deflated as infinite (algebraic multiplicity of λ = ∞).
  Eigen::Index num_infinite() const { return num_infinite_; }
  /// f×(f − rank K) orthonormal basis of the numerical null space of K (rigid-body modes).
  const Eigen::MatrixXd& null_space_K() const { return null_K_; }
  /// f×(f − rank M) orthonormal basis of the numerical null space of M (massless coordinates).
  const Eigen::MatrixXd& null_space_M() const { return null_M_; }
  double tau() const { return tau_; }              ///< ‖Q‖/√(‖M‖‖K‖) (Frobenius norms)
  double gamma() const { return gamma_; }          ///< eigenvalue scaling γ (1/s)
  /// "symmetric", "fan_lin_van_dooren", "tropical" or "none": what compute() used.
  const std::string& method() const { return method_; }
  /// Largest backward error over all eigenpairs.
  double max_backward_error() const;
  /// Stability verdict of the spectrum, each eigenvalue taken with its error_bound (see
  /// Stability). With one_per_conjugate_pair the omitted members have the same real parts.
  Stability stability() const { return stability_; }
  /// The backward-error floor η_floor used for the error bounds (see backward_error_floor).
  double backward_error_floor() const { return floor_; }

 private:
  void compute_symmetric(const Eigen::MatrixXd& M, const Eigen::MatrixXd& K, bool& ok);
  void compute_general(const Eigen::MatrixXd& M, const Eigen::MatrixXd& Q,
                       const Eigen::MatrixXd& K);
  void finish(const Eigen::MatrixXd& M, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& K);

  QuadraticEigenOptions options_;
  Eigen::ComputationInfo info_ = Eigen::InvalidInput;
  std::vector<Mode> modes_;
  Eigen::Index rank_M_ = 0, rank_K_ = 0, num_zero_ = 0, num_infinite_ = 0;
  Eigen::MatrixXd null_M_, null_K_;
  double tau_ = 0.0, gamma_ = 1.0, floor_ = 0.0;
  Stability stability_ = Stability::undecided;
  double norm_M_ = 0.0, norm_Q_ = 0.0, norm_K_ = 0.0;  // ‖·‖₂ lower estimates
  std::string method_;
  // Workspaces of the linearization (2f×2f) reused across compute() calls.
  Eigen::MatrixXd A_, B_, VL_, VR_;
  Eigen::VectorXd alphar_, alphai_, beta_;
};

/// Backward error of an approximate eigenpair (α, β, x) of λ²M + λQ + K in the homogeneous form
/// of Tisseur (2000) with given coefficient norms (any consistent norm; the solver uses ‖·‖₂).
double quadratic_backward_error(const Eigen::MatrixXd& M, const Eigen::MatrixXd& Q,
                                const Eigen::MatrixXd& K, std::complex<double> alpha, double beta,
                                const Eigen::VectorXcd& x, double norm_M, double norm_Q,
                                double norm_K);

}  // namespace mbsgen
