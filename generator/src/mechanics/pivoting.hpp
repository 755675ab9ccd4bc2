// Pivot choices at the operating point for the symbolic eliminations of the constraint stages
// (loop_closure.cpp, nonholonomic.cpp). Internal to the generator.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace mbsgen {

/// The row order of partial pivoting of a square matrix.
std::vector<std::size_t> partial_pivoting_rows(Eigen::MatrixXd A);

/// The columns that a column-pivoted QR of a wide matrix J picks first (rank(J) of them,
/// ascending): the dependent ones.
std::vector<std::size_t> pivoted_qr_columns(const Eigen::MatrixXd& J);

}  // namespace mbsgen
