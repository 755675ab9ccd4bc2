// Matrix Market exchange format (NIST, Boisvert, Pozo & Remington 1996), real matrices only:
// "array" (dense, column-major) and "coordinate" (sparse triplets), with the symmetry kinds
// general, symmetric and skew-symmetric; "integer" fields are read as real.
#pragma once

#include <Eigen/Core>
#include <iosfwd>
#include <string>

namespace mbsgen {

/// Reads a real Matrix Market matrix from a file. Throws ParseError with "file:line: reason"
/// (unsupported field such as complex or pattern, malformed line, index out of range, wrong
/// entry count) and NonFiniteError for NaN/Inf entries. Duplicate coordinate entries are summed.
Eigen::MatrixXd read_matrix_market(const std::string& path);
/// Same from a stream; `name` is used in error messages.
Eigen::MatrixXd read_matrix_market(std::istream& in, const std::string& name);

/// Storage format for writing.
enum class MatrixMarketFormat {
  array,      ///< dense, every entry, column-major
  coordinate  ///< nonzero entries only
};

/// Writes A with 17 significant digits (lossless for double), `general` symmetry, an optional
/// comment line. Throws Error if the file cannot be written.
void write_matrix_market(const std::string& path, const Eigen::MatrixXd& A,
                         MatrixMarketFormat format = MatrixMarketFormat::array,
                         const std::string& comment = {});
/// Same to a stream.
void write_matrix_market(std::ostream& out, const Eigen::MatrixXd& A,
                         MatrixMarketFormat format = MatrixMarketFormat::array,
                         const std::string& comment = {});

}  // namespace mbsgen
