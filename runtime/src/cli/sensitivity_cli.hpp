// `modes --sensitivity` and `frf --sensitivity` of the solvers (issue 20 §1; docs/cli.md).
#pragma once

#include <Eigen/Core>

#include <ostream>
#include <string>
#include <vector>

#include "mbsgen/runtime/model/generated_model.hpp"

namespace mbsgen::cli {

/// The sensitivities of the eigenvalues (one per conjugate pair unless all) to the parameters
/// (all of the kernel's when empty): a row per (mode, parameter) with dλ/dp, the relative
/// sensitivity of the natural frequency (p/f_n) df_n/dp and dζ/dp; format table, csv or json.
void write_modes_sensitivity(std::ostream& out, const GeneratedModel& model, const std::vector<std::string>& parameters,
                             const std::string& format, bool all);

/// The frequency response of one output to one input and its sensitivities at the frequencies
/// hz: per parameter the relative magnitude sensitivity d ln|ẑ|/d ln p = Re((p/ẑ) dẑ/dp), the
/// phase sensitivity d arg ẑ/d ln p = Im((p/ẑ) dẑ/dp) (rad) and dẑ/dp itself (csv, json; the
/// table gives the relative magnitude sensitivities only).
void write_frf_sensitivity(std::ostream& out, const GeneratedModel& model, Eigen::Index input, Eigen::Index output,
                           const Eigen::VectorXd& hz, const std::vector<std::string>& parameters,
                           const std::string& format);

}  // namespace mbsgen::cli
