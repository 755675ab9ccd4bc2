// Descriptor models E ẋ = A x + B u, z = C x + D u: the validation of their matrices, names and
// units (their eigenpairs and frequency response: spectral/descriptor_eigen.cpp).
#include "mbsgen/runtime/model/descriptor_model.hpp"

#include <cmath>
#include <sstream>

#include "mbsgen/runtime/error.hpp"

namespace mbsgen {

using Eigen::Index;

namespace {
constexpr const char* kModel = "DescriptorModel";

std::string dims(const Eigen::MatrixXd& M) {
  std::ostringstream s;
  s << M.rows() << "x" << M.cols();
  return s.str();
}

void check_dims(const Eigen::MatrixXd& M, Index r, Index c, const char* name,
                const char* expected) {
  if (M.rows() != r || M.cols() != c) {
    std::ostringstream s;
    s << kModel << ": " << name << " is " << dims(M) << " but must be " << r << "x" << c << " ("
      << expected << ")";
    throw DimensionError(s.str());
  }
}

void check_finite(const Eigen::MatrixXd& M, const char* name) {
  for (Index j = 0; j < M.cols(); ++j)
    for (Index i = 0; i < M.rows(); ++i)
      if (!std::isfinite(M(i, j))) {
        std::ostringstream s;
        s << kModel << ": " << name << " (" << dims(M) << ") has a non-finite entry " << M(i, j)
          << " at (" << i + 1 << "," << j + 1 << ")";
        throw NonFiniteError(s.str());
      }
}

std::vector<std::string> names_or_default(std::vector<std::string> names, Index n,
                                          const char* prefix, const char* what) {
  if (names.empty()) {
    for (Index i = 0; i < n; ++i) names.push_back(prefix + std::to_string(i + 1));
    return names;
  }
  if (static_cast<Index>(names.size()) != n) {
    std::ostringstream s;
    s << kModel << ": " << names.size() << " " << what << " given for " << n << " entries";
    throw DimensionError(s.str());
  }
  return names;
}

std::vector<std::string> units_or_empty(std::vector<std::string> units, Index n,
                                        const char* what) {
  if (units.empty()) return std::vector<std::string>(static_cast<std::size_t>(n));
  return names_or_default(std::move(units), n, "", what);
}

}  // namespace

DescriptorModel::DescriptorModel(Eigen::MatrixXd E, Eigen::MatrixXd A, Eigen::MatrixXd B,
                                 Eigen::MatrixXd C, Eigen::MatrixXd D,
                                 std::vector<std::string> state_names,
                                 std::vector<std::string> input_names,
                                 std::vector<std::string> output_names,
                                 std::vector<std::string> input_units,
                                 std::vector<std::string> output_units)
    : E_(std::move(E)), A_(std::move(A)), B_(std::move(B)), C_(std::move(C)), D_(std::move(D)) {
  const Index n = E_.rows();
  if (n == 0) throw DimensionError("DescriptorModel: E is 0x0; a model needs at least one state");
  check_dims(E_, n, n, "E", "square");
  check_dims(A_, n, n, "A", "same size as E");
  if (B_.size() == 0) B_.resize(n, 0);
  check_dims(B_, n, B_.cols(), "B", "n rows, one column per input");
  if (C_.size() == 0) C_.resize(0, n);
  check_dims(C_, C_.rows(), n, "C", "one column per state");
  const Index m = B_.cols(), p = C_.rows();
  if (D_.rows() == 0 && D_.cols() == 0) D_ = Eigen::MatrixXd::Zero(p, m);
  check_dims(D_, p, m, "D", "p x m, one row per output, one column per input");
  check_finite(E_, "E");
  check_finite(A_, "A");
  check_finite(B_, "B");
  check_finite(C_, "C");
  check_finite(D_, "D");
  state_names_ = names_or_default(std::move(state_names), n, "x", "state names");
  input_names_ = names_or_default(std::move(input_names), m, "u", "input names");
  output_names_ = names_or_default(std::move(output_names), p, "z", "output names");
  input_units_ = units_or_empty(std::move(input_units), m, "input units");
  output_units_ = units_or_empty(std::move(output_units), p, "output units");
}

}  // namespace mbsgen
