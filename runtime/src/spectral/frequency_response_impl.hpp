// Private to FrequencyResponse: `struct FrequencyResponse::Impl` (the per-method workspaces and
// steps; the shared members are defined in frequency_response.cpp, each method's in its own unit:
// frf_direct.cpp, frf_banded.cpp, frf_hessenberg.cpp, frf_modal.cpp, frf_real.cpp), the helper
// structs it holds by value (HessenbergSolver, BandSolver, PermutedDiagonal), and the aliases,
// constants and complex helpers these units share.
#pragma once

#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <string>
#include <vector>

#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"
#include "spectral/dense_linear_algebra.hpp"

namespace mbsgen {

using Eigen::Index;

namespace detail {

using cd = std::complex<double>;
using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMatrixXcd = Eigen::Matrix<cd, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

inline constexpr double kU = std::numeric_limits<double>::epsilon() / 2;
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// Column j of a permuted-diagonal matrix X has its single nonzero val[j] in row row[j];
/// X is obtained by applying LAPACK's xGEBAK/xGGBAK to the identity.
struct PermutedDiagonal {
  std::vector<Index> row;
  Eigen::VectorXd val;
  /// row and val from the dense X (the largest entry of each column; frf_hessenberg.cpp).
  void from_dense(const Eigen::MatrixXd& X);
  /// (Xᵀ v)_j = val_j · v_{row_j}
  template <class V>
  Eigen::VectorXd transpose_times(const V& v) const {
    Eigen::VectorXd out(val.size());
    for (Index j = 0; j < val.size(); ++j) out[j] = val[j] * v[row[static_cast<std::size_t>(j)]];
    return out;
  }
};

/// 1/(c + id) by Smith's (1962) algorithm, inline: std::complex division calls libgcc's
/// __divdc3 (C99 Annex G), which dominated the O(n) band solve.
inline cd reciprocal(double c, double d) {
  if (std::abs(c) >= std::abs(d)) {
    const double r = d / c, den = c + d * r;
    return {1.0 / den, -r / den};
  }
  const double r = c / d, den = c * r + d;
  return {r / den, -1.0 / den};
}
/// a·b by the textbook formula, inline (std::complex multiplication calls __muldc3).
inline cd mul(cd a, cd b) {
  return {a.real() * b.real() - a.imag() * b.imag(), a.real() * b.imag() + a.imag() * b.real()};
}

/// Solver for (iΩT − H) x = b with H upper Hessenberg and T upper triangular (or T = E), real,
/// of order N, in O(N²) per frequency (Laub 1981): Gaussian elimination with adjacent-row
/// partial pivoting, fused so that the matrix is streamed twice per frequency — once to form and
/// factorize W = iΩT − H (also accumulating ‖W‖₁, eliminating the right-hand side and running the
/// first half of the condition estimate), once for the back substitution of two right-hand
/// sides. W is kept as separate row-major real and imaginary planes so the inner loops are plain
/// real arithmetic the compiler vectorizes (std::complex products would call __muldc3 for C99
/// Annex G Inf/NaN semantics; a non-finite result is caught by the caller's check). The
/// condition estimate follows Cline, Moler, Stewart & Wilkinson (1979, LINPACK): solve Wᴴy = e
/// choosing |e_j| = 1 during the substitution with Uᴴ so that y grows, then z = W⁻¹y, and
/// ‖z‖₁/‖y‖₁ ≤ ‖W⁻¹‖₁ (in practice within a small factor). Workspaces are allocated once.
/// Defined in frf_hessenberg.cpp.
struct HessenbergSolver {
  RowMatrixXd Wr, Wi;              // U after factorization
  Eigen::VectorXd lr, li;          // multipliers l_k (row k+1 −= l_k·row k)
  std::vector<unsigned char> swapped;
  Eigen::VectorXd er, ei;          // estimator vector
  Eigen::VectorXd colH, colT;      // column sums of |H| and |T| (set by the owner)
  Eigen::VectorXcd rpiv;           // 1/U_kk
  Index N = 0;
  /// Allocates the workspaces for order n (colH, colT zero).
  void resize(Index n);

  /// Solves (iΩT − H)x = b for real b given in xr (xi must be zero on entry); T == nullptr
  /// means T = E. Returns false at an exact zero pivot; rc receives the reciprocal condition
  /// estimate 1/(‖W‖₁·est‖W⁻¹‖₁).
  bool solve(const RowMatrixXd& H, const RowMatrixXd* T, double om, Eigen::VectorXd& xr,
             Eigen::VectorXd& xi, double& rc);
  /// solve's first pass: forms, factorizes and eliminates (xr, xi), with the first half of the
  /// estimate (er, ei zero on entry); false at an exact zero pivot.
  bool factorize(const RowMatrixXd& H, const RowMatrixXd* T, double om, Eigen::VectorXd& xr,
                 Eigen::VectorXd& xi);
};

/// Solver for a complex band matrix W (kl = ku = b) given column by column, in the layout of
/// LAPACK xGBTRF (row kv + i − j of column j holds W(i, j), kv = 2b, room for the fill-in of
/// partial pivoting) but with separate real and imaginary planes: Gaussian elimination with
/// partial pivoting as in xGBTF2, the right-hand side eliminated on the fly, and the two-solve
/// LINPACK condition estimate (Cline, Moler, Stewart & Wilkinson 1979) fused into the back
/// substitution. O(f·b²) per frequency; replaces zgbtrf + zgbcon, whose estimator (zlacn2 with
/// zlatbs) cost several times the factorization on chains. Defined in frf_banded.cpp.
struct BandSolver {
  Index n = 0, b = 0, kv = 0, ld = 0;
  Eigen::MatrixXd Ar, Ai;  // ld × n, ld = 3b + 1
  std::vector<Index> piv;
  Eigen::VectorXd er, ei;
  Eigen::VectorXcd rpiv;  // 1/U_jj
  /// Allocates the workspaces for order n_ and half-bandwidth b_.
  void resize(Index n_, Index b_);
  double& re(Index i, Index j) { return Ar(kv + i - j, j); }
  double& im(Index i, Index j) { return Ai(kv + i - j, j); }

  /// Factorizes (the matrix must already be stored, fill-in rows zero) and solves for the real
  /// right-hand side in xr (xi zero on entry). anorm = ‖W‖₁. Returns false at a zero pivot.
  bool solve(double anorm, Eigen::VectorXd& xr, Eigen::VectorXd& xi, double& rc);
};

}  // namespace detail

// Only the frequency-response units include this header: these names enter mbsgen there alone.
using detail::cd;
using detail::kInf;
using detail::kNaN;
using detail::kU;
using detail::RowMatrixXcd;
using detail::RowMatrixXd;

// ---------------------------------------------------------------------------------------------
struct FrequencyResponse::Impl {
  const LinearModel& model;
  Index n;
  // selected input/outputs for the current compute()
  Eigen::VectorXd b;
  // The rows every method computes, ẑ_r = (C_y + iΩC_v)_r ŷ: the p selected outputs, then one
  // pseudo-row per selected output with a nonzero row of C_a (C_y := that row, C_v := 0), so
  // that the methods need not know C_a; combine_outputs() adds −Ω²·(C_a ŷ) and D(:, input).
  Eigen::MatrixXcd Cy, Cv;  // (p + q)×n, complex copies so that products do not allocate
  Eigen::MatrixXd Cy_re, Cv_re;  // (p + q)×n real
  Eigen::VectorXcd z;       // p + q
  std::vector<Index> acc_row;  // per output r < p: its pseudo-row in z, or −1
  Eigen::VectorXd feed;        // per output r < p: D(row, input), 0 without D
  bool combine = false;        // some pseudo-row or nonzero feedthrough: combine_outputs needed

  explicit Impl(const LinearModel& m) : model(m), n(m.size()) {}

  // ---- shared by all methods (frequency_response.cpp) ----
  /// Selects input column `input` and the output `rows`: b, Cy/Cv, acc_row, feed and combine.
  void select_outputs(const std::vector<Index>& rows, Index input);
  /// b and feed of one part (B1 or B2) of a moving support's excitation.
  void select_part(const Eigen::MatrixXd& part_B, const Eigen::MatrixXd* part_D,
                   const std::vector<Index>& rows, Index input);
  /// Adds −Ω²·(C_a ŷ) and the feedthrough to z's first p entries.
  void combine_outputs(double om);

  // ---- direct (frf_direct.cpp) ----
  bool direct_ready = false;
  Eigen::MatrixXcd D;
  Eigen::VectorXcd y;
  std::vector<lapack_int> ipiv;
  Eigen::VectorXcd zwork;
  Eigen::VectorXd rwork;
  /// Allocates the workspaces of direct (once).
  void prepare_direct();
  /// One frequency by zgetrf/zgecon/zgetrs; false for an exactly singular matrix.
  bool point_direct(double om, double& rc);

  // ---- banded (frf_banded.cpp) ----
  bool banded_ready = false;
  detail::BandSolver band;
  Eigen::VectorXd bxr, bxi;
  Eigen::MatrixXd Bm, Bq, Bk;  // the bands of M, Q, K: row b + i − j of column j holds (i, j)
  /// Copies the bands of M, Q, K and allocates the band solver (once).
  void prepare_banded();
  /// One frequency by the band solver; false at a zero pivot.
  bool point_banded(double om, double& rc);
  /// The requested output rows of C_y and C_v in compressed-row form.
  struct SparseRows {
    std::vector<std::size_t> start;
    std::vector<Index> col;
    std::vector<double> val;
    /// The nonzeros of C, row by row.
    void assign(const Eigen::MatrixXd& C);
  };
  SparseRows out_y, out_v;
  /// out_y, out_v for the selected outputs.
  void select_banded();

  // ---- hessenberg (Laub 1981; SLICOT TB05AD; frf_hessenberg.cpp) ----
  bool hess_ready = false;
  bool hess_standard = false;
  Index N = 0;
  RowMatrixXd H, T;                  // reduced pencil (T unused in the standard form)
  Eigen::MatrixXd reflectors;        // dgehrd output (standard form)
  Eigen::VectorXd hess_tau;          // dgehrd tau
  lapack_int hilo = 1, hihi = 1;
  Eigen::PartialPivLU<Eigen::MatrixXd> Mlu;  // standard form: LU of M
  Eigen::MatrixXd Qleft, Zright;     // pencil form: Qᵀ(balanced) Z, both N×N
  Eigen::MatrixXd qr_E;              // pencil form: QR factors of the balanced E
  Eigen::VectorXd qr_tau;
  detail::PermutedDiagonal Xl, Xr;   // balancing: Ã = Xlᵀ A Xr, x = Xr x̃
  detail::HessenbergSolver hsolver;
  Eigen::MatrixXd Chat_re;           // p×N reduced outputs (real)
  std::string hess_form;
  /// Balancing job of the current reduction: 'B' (permute and scale), 'P' (permute) or 'N'.
  char hess_job = 'N';
  /// Largest backward error of the probe solves of the kept reduction (hessenberg_check), and
  /// whether it met the bar.
  double hess_backward_error = 0.0, hess_bar = 0.0, hess_forward_ratio = 0.0;
  Eigen::VectorXd rhs_reduced;
  Eigen::VectorXd xr_ws, xi_ws, zr_ws, zi_ws;

  /// LU of M exists and its rcond is at least `threshold` (hessenberg and real;
  /// frequency_response.cpp).
  bool mass_is_regular(double threshold) const;
  /// Reduces the first-order form with balancing `job`: standard form or pencil.
  void reduce_hessenberg(double mass_rcond, char job);
  /// Standard form: dgebal, dgehrd.
  void reduce_standard(Eigen::MatrixXd&& A, char job);
  /// Pencil: dggbal, QR of E, dgghrd.
  void reduce_pencil(char job);
  /// ŷ at Ω by the Hessenberg reduction, undone; false at an exact zero pivot.
  bool hessenberg_solution(double om, Eigen::VectorXcd& yh);
  /// Scaling of the coordinates to unit size at Ω.
  Eigen::VectorXd unit_scaling(double om) const;
  /// Forward errors at Ω of direct and hessenberg, in ŷ and in the selected outputs.
  std::array<double, 4> forward_errors(double om);
  /// FrfMethod::automatic's accuracy check of hessenberg against direct at the probes.
  bool hessenberg_as_accurate_as_direct(const Eigen::VectorXd& omega, double& worst_ratio);
  /// Unit-scaled normwise backward error of the Hessenberg solution at Ω.
  double hessenberg_backward_error(double om);
  /// Largest hessenberg_backward_error over the probe frequencies.
  double hessenberg_check(const Eigen::VectorXd& omega);
  /// Up to five probe frequencies: the smallest, the quartiles and the largest of omega.
  std::vector<double> probe_frequencies(const Eigen::VectorXd& omega) const;
  /// The reduction with its balancing chosen a posteriori (once).
  void prepare_hessenberg(const FrfOptions& opt, const Eigen::VectorXd& omega);
  /// The right-hand side of the first-order form, balanced and reduced.
  Eigen::VectorXd reduced_rhs() const;
  /// Reduced right-hand side and outputs for the current input/outputs.
  void select_hessenberg();
  /// One frequency by the Hessenberg solver; false at an exact zero pivot.
  bool point_hessenberg(double om, double& rc);

  // ---- modal (frf_modal.cpp) ----
  bool modal_ready = false;
  std::vector<Mode> modes;
  double eigvec_condition = 0.0;
  Eigen::VectorXcd lam, coef;  // kept eigenvalues; y_kᴴ b / (y_kᴴ P'(λ_k) x_k)
  Eigen::MatrixXcd CX, CVX;    // p×k: C_y x_k, C_v x_k
  Eigen::VectorXcd zstatic_y, zstatic_v;  // C_y r0, C_v r0 (static correction)
  Eigen::VectorXcd dk;
  /// The modes and the eigenvector condition (once); refuses or warns when ill-conditioned.
  void prepare_modal(const FrfOptions& opt, std::vector<std::string>& warnings);
  /// The kept modes' coefficients and outputs, and the static correction.
  void select_modal(const FrfOptions& opt, std::vector<std::string>& warnings);
  /// One frequency by the modal sum; false at an eigenvalue.
  bool point_modal(double om, double& rc);

  // ---- real formulation (docs/design.md, "Linearization"; frf_real.cpp) ----
  bool real_ready = false;
  Eigen::MatrixXd A1, A2, S, G;
  Eigen::VectorXd req, ceq;  // equilibration of Ω²E + A² (dgeequb)
  Eigen::VectorXd Ab;
  std::vector<lapack_int> ipiv_r;
  Eigen::VectorXd dwork;
  std::vector<lapack_int> iwork;
  Eigen::MatrixXcd Cxc;
  Eigen::VectorXcd gc;
  /// A and A² of the standard first-order form, and the workspaces (once).
  void prepare_real();
  /// The right-hand sides −A b and b of the real system, and the outputs.
  void select_real();
  /// One frequency by the equilibrated real LU of Ω²E + A²; false when singular.
  bool point_real(double om, double& rc);
};

}  // namespace mbsgen
