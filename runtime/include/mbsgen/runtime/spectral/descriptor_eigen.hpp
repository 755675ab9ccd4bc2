// The modes and the frequency response of a descriptor model E ẋ = A x + B u, z = C x + D u
// (model/descriptor_model.hpp). Everything here accepts a general square E; a singular E gives
// infinite eigenvalues (EigenvalueKind::infinite).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/model/descriptor_model.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

namespace mbsgen {

/// Options of DescriptorEigenSolver.
struct DescriptorEigenOptions {
  /// Relative normwise data uncertainty η_floor below which a backward error does not lower
  /// Mode::error_bound; 0 means the default 100·n·u (as QuadraticEigenOptions); negative: no floor.
  double backward_error_floor = 0.0;
  /// Report each complex-conjugate pair once (the member with Im λ > 0).
  bool one_per_conjugate_pair = false;
};

/// Solver for the n eigenpairs of the pencil λE − A, shaped like an Eigen decomposition.
///
/// 1. Exact zeros: every exactly zero column k of A (an ignorable coordinate) gives λ = 0 exactly,
///    eigenvector e_k. They are deflated orthogonally (det(λE − A) = λ^|Z| det([E_Z, (λE − A)_R])
///    for the zero columns Z and the rest R; with E_Z P = [Q1 Q2][R; 0] the remaining eigenvalues
///    are those of (Q2ᵀE_R, Q2ᵀA_R)) and reported as EigenvalueKind::zero with λ = 0, α = 0,
///    β = 1, error_bound 0. When each column of E_Z has a single nonzero, in distinct rows (the
///    usual E = blkdiag(I, M_r)), Q is a permutation: the reduced pencil is a submatrix bit for
///    bit, and the test is repeated on it (soundly: a zero column there is exactly zero in the
///    data outside the removed rows). Zeros found so are Jordan chains at 0 through the earlier
///    ones (e.g. the lateral position y and yaw ψ of a rolling wheel with ẏ = vψ); their shape is
///    the chain's head and both members are marked defective. Otherwise one Householder QR
///    (LAPACK dgeqp3) deflates them, and the test is not repeated (after rounding an exact zero
///    is no structural fact). Throws SingularSystemError naming the states when E_Z is rank
///    deficient (det(λE − A) ≡ 0, e.g. a column that is zero in both E and A).
/// 2. The rest by LAPACK dggevx with left and right eigenvectors. Balancing: permutation ('P');
///    permutation and scaling ('B') when the largest normwise backward error exceeds 10·n·u
///    (kept if smaller, QuadraticEigenSolver's rule) or the largest componentwise one does and
///    'B' lowers it without raising the normwise one above 10·n·u — never after a Householder
///    deflation. Each eigenvalue carries the backward error η = ‖(βA − αE)x‖/((|β|‖A‖ +
///    |α|‖E‖)‖x‖) and the absolute condition κ = (‖A‖ + |λ|‖E‖)‖x‖‖y‖/|yᴴEx| (Higham & Higham
///    1998), error_bound = κ·max(η, η_floor) (+∞ when yᴴEx = 0), zero_within_bound when
///    |λ| ≤ error_bound, condition = κ/|λ|, condition_homogeneous (Dedieu & Tisseur 2003).
///    An eigenvalue is infinite (kind infinite, λ = +∞, not counted for stability, error_bound 0,
///    α and β as computed) when |α|‖E‖ ≥ |β|‖A‖ and μ = β/α is zero within its own bound, the
///    same test on the reversed pencil E − μA: |μ| ≤ (‖E‖ + |μ|‖A‖)‖x‖‖y‖/|yᴴAx|·max(η, η_floor).
///    This includes β = 0 exactly (QZ sets β to 0 below u‖E‖) and rounding-split Jordan chains
///    at ∞ (higher-index descriptor systems).
///    After exact deflations (permutations only) the bound is structured: κ, η and the infinite
///    test are those of the reduced pencil, whose eigenvalues are the full pencil's other than
///    the deflated zeros for every perturbation that keeps the deflated exact zeros zero. (The
///    full pencil's normwise bound of a reduced eigenvalue that is coupled to an ignorable
///    coordinate's Jordan chain — a rolling disk's steady turn and its heading — is 1e20.)
/// 3. Structural zeros: when the reduced A (exact deflations) has structural rank m − k, λ = 0 is
///    an eigenvalue at least k times for every value of the data; the k finite eigenvalues of
///    least modulus, each zero within its bound, are reported as kind zero (λ = 0, bound 0).
/// 4. Symmetric spectra: when a signature R makes R E R = E and R A R = −A on the reduced pencil's
///    sign pattern (exact deflations; an undamped system, even positions and odd speeds), its
///    spectrum is symmetric about the imaginary axis for every value of the data, so a finite
///    eigenvalue within its bound of the axis whose error disk meets no other eigenvalue's is on
///    the axis exactly: its real part is reported as 0 (a marginal verdict, not undecided).
/// Norms are ‖·‖₂ lower estimates (so η errs on the large side). Cost: O(n³), about 66n³ flops
/// for QZ with both eigenvector sets, twice when 'B' is tried.
class DescriptorEigenSolver {
 public:
  explicit DescriptorEigenSolver(DescriptorEigenOptions options = {});

  /// Eigenpairs of the model's λE − A; the model's state names label SingularSystemError.
  DescriptorEigenSolver& compute(const DescriptorModel& model);
  /// Same for raw n×n matrices (validated as DescriptorModel does; states named "x1"..).
  DescriptorEigenSolver& compute(const Eigen::MatrixXd& E, const Eigen::MatrixXd& A);

  /// Eigen::Success after a successful compute().
  Eigen::ComputationInfo info() const { return info_; }
  /// Eigenpairs sorted as QuadraticEigenSolver sorts them: zero kind first, then finite by
  /// increasing |λ| (Im λ ≥ 0 first within a conjugate pair), then infinite. shape is the right
  /// eigenvector x (n), (λE − A)x = 0; left_shape y, yᴴ(λE − A) = 0; both ‖·‖₂ = 1 with the
  /// largest-modulus entry real positive. For the deflated zeros, in increasing column order,
  /// shape is exactly e_k (the chain's head for a defective one) and left_shape a left null
  /// vector of A, biorthogonal to the other zeros' shapes (yⱼᴴE x_k = 0 for j ≠ k) when there is
  /// no Jordan chain and that is well conditioned; otherwise an orthonormal basis vector of the
  /// left null space, and condition_homogeneous is +∞.
  const std::vector<Mode>& modes() const { return modes_; }
  /// Number of exactly zero eigenvalues (deflated zero columns of A and of the exactly reduced
  /// pencils, and the structural zeros of the reduced pencil, see num_structural_zero()).
  Eigen::Index num_zero() const { return num_zero_; }
  /// Of num_zero(), those from the structural rank of the reduced A (item 3 of the class
  /// comment): zero for every value of the data, found by QZ within their error bounds.
  Eigen::Index num_structural_zero() const { return num_structural_zero_; }
  /// Number of eigenvalues classified infinite (counted also when one_per_conjugate_pair).
  Eigen::Index num_infinite() const { return num_infinite_; }
  /// Stability verdict with the rules of QuadraticEigenSolver (see Stability).
  Stability stability() const { return stability_; }
  /// Largest backward error over all eigenpairs (the deflated zeros have 0).
  double max_backward_error() const;
  /// The state indices (0-based) of the deflated zero columns, in increasing order (the order
  /// of the zero modes).
  const std::vector<Eigen::Index>& zero_columns() const { return zero_columns_; }

 private:
  DescriptorEigenSolver& compute_named(const Eigen::MatrixXd& E, const Eigen::MatrixXd& A,
                                       const std::vector<std::string>& names);

  DescriptorEigenOptions options_;
  Eigen::ComputationInfo info_ = Eigen::InvalidInput;
  std::vector<Mode> modes_;
  std::vector<Eigen::Index> zero_columns_;
  Eigen::Index num_zero_ = 0, num_infinite_ = 0, num_structural_zero_ = 0;
  Stability stability_ = Stability::undecided;
};

/// Frequency response of a descriptor model for one input column.
struct DescriptorFrf {
  Eigen::VectorXd omega;       ///< F angular frequencies (rad/s), as given
  Eigen::MatrixXcd response;   ///< p×F: row r is output outputs[r], column k frequency omega[k]
  std::vector<FrfFlag> flags;  ///< F flags (FrfFlag)
  Eigen::VectorXd rcond;       ///< F reciprocal 1-norm condition estimates of iΩE − A (zgecon)
};

/// ẑ(Ω) = (C (iΩE − A)⁻¹ B + D)(:, input) on the selected output rows (empty: all), for the
/// frequencies omega (rad/s, finite, ≥ 0): for u = e_input cos(Ωt) the stationary output is
/// z = Re(ẑ e^{iΩt}). Each frequency takes a complex LU with partial pivoting (LAPACK zgetrf) and
/// Higham's 1-norm condition estimate (zgecon); a point is FrfFlag::pole when the LU meets an
/// exactly zero pivot, rcond ≤ n·u or the result is not finite (response NaN, or
/// SingularSystemError when on_pole == raise), ill_conditioned when rcond < 1e-8. Throws
/// DimensionError for an input or output index out of range, NonFiniteError for a bad frequency.
DescriptorFrf descriptor_frequency_response(const DescriptorModel& model,
                                            const Eigen::VectorXd& omega, Eigen::Index input,
                                            const std::vector<Eigen::Index>& outputs = {},
                                            PoleHandling on_pole = PoleHandling::flag);

}  // namespace mbsgen
