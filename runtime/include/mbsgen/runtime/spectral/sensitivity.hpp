// Parameter sensitivities of a linear model (issue 20 §1): of its eigenvalues and of its
// frequency responses, from the derivatives of its matrices (the generated `sensitivity` kernel,
// GeneratedModel::linear_sensitivities).
//
// Eigenvalues. For a simple eigenvalue λ of P(λ) = λ²M + λQ + K with right and left eigenvectors
// x, y (P(λ)x = 0, yᴴP(λ) = 0), differentiating P(λ(p))x(p) = 0 and multiplying by yᴴ gives
//
//     dλ/dp = −yᴴ(λ² dM + λ dQ + dK)x / yᴴ(2λM + Q)x
//
// (Tisseur 2000, Thm. 5, the same quantities as the condition number). It exists only for a
// simple eigenvalue: a defective one (the denominator vanishes), one that the data do not
// separate from another (|λ_i − λ_j| within the sum of their error bounds: a repeated eigenvalue,
// whose derivative is not a number but the eigenvalues of a matrix), and a deflated zero or
// infinite one are flagged, with NaN, never a wrong number.
//
// Frequency responses. With A(Ω) = K + iΩQ − Ω²M, B(Ω) = B + iΩB1 − Ω²B2,
// C(Ω) = C_y + iΩC_v − Ω²C_a and D(Ω) = D + iΩD1, ẑ = C(Ω)X + D(Ω), X = A⁻¹B(Ω), and
//
//     dẑ/dp = dC(Ω) X + C(Ω) A⁻¹(dB(Ω) − dA(Ω) X) + dD(Ω):
//
// one more solve per parameter with the LU of A(Ω) in hand (Eigen's partial-pivoting LU).
#pragma once

#include <Eigen/Core>

#include <complex>
#include <string>
#include <vector>

#include "mbsgen/runtime/model/linear_model.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

namespace mbsgen {

/// dλ/dp of one eigenvalue for one parameter.
struct EigenvalueSensitivity {
  bool defined = false;         ///< false: the eigenvalue is not simple (see note); values NaN
  std::string note;             ///< why not defined: "defective", "repeated", "zero" (also zero
                                ///< within its error bound), "infinite"
  std::complex<double> dlambda; ///< dλ/dp (1/s per unit of p)
  std::complex<double> relative;///< (p/λ) dλ/dp
  double dfrequency_hz = 0;     ///< d(|λ|/2π)/dp
  double relative_frequency = 0;///< (p/f_n) df_n/dp
  double ddamping_ratio = 0;    ///< dζ/dp, ζ = −Re λ/|λ|
};

/// The sensitivities of every mode's eigenvalue (as the solver reports them: modes[k]) to every
/// parameter: result[k][j] for modes[k] and sensitivities[j]. DimensionError when a derivative's
/// size differs from the model's.
std::vector<std::vector<EigenvalueSensitivity>> eigenvalue_sensitivities(
    const LinearModel& model, const std::vector<Mode>& modes, const std::vector<MatrixSensitivity>& sensitivities);

/// The frequency response ẑ(Ω) (outputs × inputs) and its derivatives at each frequency.
struct FrequencyResponseSensitivity {
  std::vector<double> frequencies_hz;
  std::vector<Eigen::MatrixXcd> response;                ///< [frequency]: r×m
  std::vector<std::vector<Eigen::MatrixXcd>> derivative; ///< [parameter][frequency]: r×m
  std::vector<double> rcond;  ///< reciprocal condition estimate of A(Ω) per frequency; NaN results below u
};

/// ẑ and dẑ/dp at the frequencies (Hz), by the direct method. Throws DimensionError for a
/// derivative of the wrong size, NonFiniteError for a non-finite frequency; at a frequency where
/// A(Ω) is singular to working precision (rcond ≤ u) the response and derivatives are NaN.
FrequencyResponseSensitivity frequency_response_sensitivity(const LinearModel& model,
                                                            const std::vector<MatrixSensitivity>& sensitivities,
                                                            const std::vector<double>& frequencies_hz);

}  // namespace mbsgen
