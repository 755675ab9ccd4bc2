// Parameter studies of a generated model (issue 20 §2): the linear model at each point of a
// design of experiments (study_design.hpp), its lowest modes and its frequency response, on every
// core; and the statistics of the results: percentile bands and Sobol' indices.
//
// Each evaluation depends only on its index and the design's seed, so a study split over
// threads or MPI ranks (evaluate() on a range of indices each, gathered in index order) gives the
// same numbers, bit for bit, as one process. An evaluation that fails (a singular system, a failed
// equilibrium, a non-finite kernel value, fewer modes than asked) keeps NaN values and is
// reported with its parameter values and the error, never dropped.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "mbsgen/runtime/model/generated_model.hpp"
#include "mbsgen/runtime/study/study_design.hpp"

namespace mbsgen {

/// What each evaluation records.
struct StudyQuantities {
  /// The lowest `modes` modes (finite eigenvalues, one per complex-conjugate pair, by natural
  /// frequency): f_n [Hz] and ζ of each.
  int modes = 0;
  /// A frequency response |ẑ_output/û_input| (the output's units per the input's) at each of
  /// `sweep_hz` (for bands) and, in dB re 1 of those units, at each of `at_hz` (scalar quantities
  /// for statistics and Sobol' indices). Input and output by name; empty: no response.
  std::string input, output;
  std::vector<double> sweep_hz, at_hz;
  /// The frequency-response method (FrfMethod as text, "auto" by default).
  std::string method = "auto";
};

/// One failed evaluation.
struct StudyFailure {
  std::size_t index = 0;
  std::vector<double> parameters;
  std::string message;
};

/// The results of evaluations first … first + count − 1 (or of a whole study).
struct StudyResults {
  std::size_t first = 0, count = 0;
  /// Names of the scalar quantities: f1_hz, zeta1, …, then L_<f>Hz_dB per at_hz.
  std::vector<std::string> scalar_names;
  std::vector<double> scalars;  ///< count × scalar_names.size(), row per evaluation; NaN where failed
  std::vector<double> sweep;    ///< count × sweep_hz.size(), row per evaluation; NaN where failed
  std::vector<StudyFailure> failures;  ///< in index order
  /// Seconds spent, summed over threads: kernels (operating point and linear model), modes
  /// (QZ), response (factorizations and the sweeps).
  double seconds_kernels = 0, seconds_modes = 0, seconds_response = 0;
};

/// The names of the scalar quantities that q records.
std::vector<std::string> scalar_names(const StudyQuantities& q);

/// Evaluates design points first … first + count − 1 of `design` on `model` (its parameters not
/// in the design keep their values), with `threads` threads (0: std::thread::hardware_concurrency).
/// progress(done) is called now and then from the calling thread (may be empty). Sets OpenBLAS,
/// when it is the BLAS, to one thread (its results depend on its thread count). Throws NameError
/// for a design parameter, input or output the model does not have, Error for a descriptor model
/// with modes or responses, DimensionError for a range beyond the design.
StudyResults evaluate(const GeneratedModel& model, const StudyDesign& design, const StudyQuantities& quantities,
                      std::size_t first, std::size_t count, int threads = 0,
                      const std::function<void(std::size_t)>& progress = {});

/// Appends b (the evaluations right after a's) to a: results gathered from parts of a study.
void append(StudyResults& a, const StudyResults& b);

/// Percentiles (type 7) of each sweep frequency's values over the evaluations that did not fail.
/// bands[k][i]: percentile qs[k] at sweep frequency i.
std::vector<std::vector<double>> percentile_bands(const StudyResults& results, std::size_t n_sweep,
                                                  const std::vector<double>& qs);

}  // namespace mbsgen
