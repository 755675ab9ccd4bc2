// First-order (descriptor) linear model  E ẋ = A x + B u,  z = C x + D u. Nonholonomic systems
// (rolling wheels, the Whipple bicycle) have fewer speeds than coordinates, so their
// linearization is not M ÿ + Q ẏ + K y = B u (linear_model.hpp) but this form, with
// x = [coordinates; independent speeds] and, in practice, E = blkdiag(I, M_r) with M_r symmetric
// positive definite. Its modes and frequency response: spectral/descriptor_eigen.hpp.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace mbsgen {

/// Read-only description of a linear descriptor model with n states, m inputs, p outputs:
///
///     E ẋ = A x + B u,      z = C x + D u.
///
/// - E (n×n): descriptor matrix, may be singular (algebraic equations, infinite eigenvalues);
/// - A (n×n): state matrix; its exactly zero columns (ignorable coordinates, emitted by the
///   generator as exact 0.0) give exact zero eigenvalues (DescriptorEigenSolver);
/// - B (n×m): input matrix; C (p×n): output matrix; D (p×m): feedthrough (zero if not given).
///
/// The constructor validates dimensions and finiteness and throws DimensionError or
/// NonFiniteError naming "DescriptorModel", the matrix and its dimensions. Names and units are
/// optional (empty vectors give default names "x1".., "u1".., "z1".. and empty units).
class DescriptorModel {
 public:
  /// E, A n×n (n ≥ 1); B n×m (m ≥ 0; 0×0 means m = 0); C p×n (p ≥ 0; 0×0 means p = 0);
  /// D p×m, or 0×0 meaning zero.
  DescriptorModel(Eigen::MatrixXd E, Eigen::MatrixXd A, Eigen::MatrixXd B, Eigen::MatrixXd C,
                  Eigen::MatrixXd D = {}, std::vector<std::string> state_names = {},
                  std::vector<std::string> input_names = {},
                  std::vector<std::string> output_names = {},
                  std::vector<std::string> input_units = {},
                  std::vector<std::string> output_units = {});

  Eigen::Index size() const { return E_.rows(); }         ///< n, number of states
  Eigen::Index num_inputs() const { return B_.cols(); }   ///< m
  Eigen::Index num_outputs() const { return C_.rows(); }  ///< p

  const Eigen::MatrixXd& E() const { return E_; }  ///< n×n descriptor matrix
  const Eigen::MatrixXd& A() const { return A_; }  ///< n×n state matrix
  const Eigen::MatrixXd& B() const { return B_; }  ///< n×m input matrix
  const Eigen::MatrixXd& C() const { return C_; }  ///< p×n output matrix
  const Eigen::MatrixXd& D() const { return D_; }  ///< p×m feedthrough (zeros if not given)

  const std::vector<std::string>& state_names() const { return state_names_; }
  const std::vector<std::string>& input_names() const { return input_names_; }
  const std::vector<std::string>& output_names() const { return output_names_; }
  const std::vector<std::string>& input_units() const { return input_units_; }
  const std::vector<std::string>& output_units() const { return output_units_; }

 private:
  Eigen::MatrixXd E_, A_, B_, C_, D_;
  std::vector<std::string> state_names_, input_names_, output_names_;
  std::vector<std::string> input_units_, output_units_;
};

}  // namespace mbsgen
