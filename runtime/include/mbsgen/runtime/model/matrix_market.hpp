// Matrix Market exchange format (NIST, Boisvert, Pozo & Remington 1996), real matrices only:
// "array" (dense, column-major) and "coordinate" (sparse triplets), with the symmetry kinds
// general, symmetric and skew-symmetric; "integer" fields are read as real.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <iosfwd>
#include <string>

namespace mbsgen {

/// Limits of the reader: matrices are read into dense storage, so a matrix may have at most
/// kMatrixMarketMaxEntries entries (rows x columns, 200 MB of doubles; 5000 x 5000), checked
/// against the size line before anything is allocated.
inline constexpr long long kMatrixMarketMaxEntries = 25'000'000;
/// The format's limit on the length of a line (characters, without the end of line).
inline constexpr std::size_t kMatrixMarketMaxLine = 1024;
/// At most this many blank or comment lines in a file, so that no input is read without end.
inline constexpr long kMatrixMarketMaxBlankLines = 10'000;

/// Reads a real Matrix Market matrix from a file. Throws ParseError with "file:line: reason" and
/// NonFiniteError for NaN/Inf entries or values beyond double's range. Rules (docs/runtime.md):
/// banner `%%MatrixMarket matrix array|coordinate real|integer general|symmetric|skew-symmetric`;
/// comments only between the banner and the size line; one entry per line and nothing after it;
/// `symmetric` stores the lower triangle (row >= column), `skew-symmetric` the strictly lower one
/// (no diagonal); coordinate entries: 1-based indices within the size, each position at most once,
/// exactly as many as declared (at most what the symmetry stores); integer fields hold integers.
/// Lines are at most kMatrixMarketMaxLine characters, with no NUL byte; at most
/// kMatrixMarketMaxBlankLines blank or comment lines. Memory and time are bounded by the size
/// line: an endless or binary input ends in a ParseError.
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
