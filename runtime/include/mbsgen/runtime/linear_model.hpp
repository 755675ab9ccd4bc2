// The linear(ized) model  M ÿ + Q ẏ + K y = B u,  z = C_y y + C_v ẏ  (seed eqs. 3.8-3.10).
#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "mbsgen/runtime/error.hpp"

namespace mbsgen {

/// Read-only description of a linear second-order model with f coordinates, m inputs and
/// p outputs (seed eq. 3.8, DESIGN.md §2):
///
///     M ÿ + Q ẏ + K y = B u,      z = C_y y + C_v ẏ.
///
/// - M (f×f, kg or kg·m², per coordinate): mass matrix, may be singular (massless coordinates);
/// - Q (f×f, N·s/m ...): velocity matrix, damping D = sym(Q) plus gyroscopic G = skew(Q);
/// - K (f×f, N/m ...): stiffness, symmetric part plus circulatory N = skew(K);
/// - B (f×m): input matrix; C_y, C_v (p×f): output matrices.
///
/// The constructor validates dimensions and finiteness and throws DimensionError or
/// NonFiniteError naming the function, the matrix and its dimensions. Names and units are
/// optional (empty vectors get default names "y1".., "u1".., "z1"..).
class LinearModel {
 public:
  /// Full constructor. Q may be empty (0×0) meaning zero; B may be f×0; C_y and C_v may both be
  /// empty (0×0) meaning "outputs are the coordinates" (C_y = E, C_v = 0); if only one of them is
  /// given the other is zero of the same size.
  LinearModel(Eigen::MatrixXd M, Eigen::MatrixXd Q, Eigen::MatrixXd K, Eigen::MatrixXd B,
              Eigen::MatrixXd C_y, Eigen::MatrixXd C_v,
              std::vector<std::string> coordinate_names = {},
              std::vector<std::string> input_names = {},
              std::vector<std::string> output_names = {},
              std::vector<std::string> coordinate_units = {},
              std::vector<std::string> input_units = {},
              std::vector<std::string> output_units = {});

  /// Convenience: M, Q, K only; B = E (one input per coordinate), outputs = coordinates.
  LinearModel(Eigen::MatrixXd M, Eigen::MatrixXd Q, Eigen::MatrixXd K);

  Eigen::Index size() const { return M_.rows(); }          ///< f, number of coordinates
  Eigen::Index num_inputs() const { return B_.cols(); }    ///< m
  Eigen::Index num_outputs() const { return C_y_.rows(); } ///< p

  const Eigen::MatrixXd& M() const { return M_; }      ///< f×f mass matrix
  const Eigen::MatrixXd& Q() const { return Q_; }      ///< f×f velocity (damping+gyroscopic) matrix
  const Eigen::MatrixXd& K() const { return K_; }      ///< f×f stiffness (+circulatory) matrix
  const Eigen::MatrixXd& B() const { return B_; }      ///< f×m input matrix
  const Eigen::MatrixXd& C_y() const { return C_y_; }  ///< p×f output matrix on y
  const Eigen::MatrixXd& C_v() const { return C_v_; }  ///< p×f output matrix on ẏ

  bool has_damping() const { return has_Q_; }  ///< false when Q is exactly zero
  /// True when M and K are exactly symmetric and Q is exactly zero (fast path of the modes).
  bool is_symmetric_undamped() const;

  const std::vector<std::string>& coordinate_names() const { return coordinate_names_; }
  const std::vector<std::string>& input_names() const { return input_names_; }
  const std::vector<std::string>& output_names() const { return output_names_; }
  const std::vector<std::string>& coordinate_units() const { return coordinate_units_; }
  const std::vector<std::string>& input_units() const { return input_units_; }
  const std::vector<std::string>& output_units() const { return output_units_; }

  /// Largest |i−j| over the nonzero entries of M, Q and K (0 for diagonal, 1 for a chain).
  Eigen::Index bandwidth() const { return bandwidth_; }

 private:
  Eigen::MatrixXd M_, Q_, K_, B_, C_y_, C_v_;
  std::vector<std::string> coordinate_names_, input_names_, output_names_;
  std::vector<std::string> coordinate_units_, input_units_, output_units_;
  bool has_Q_ = false;
  Eigen::Index bandwidth_ = 0;
};

}  // namespace mbsgen
