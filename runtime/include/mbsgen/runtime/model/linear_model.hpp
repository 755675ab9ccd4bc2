// The linear(ized) model  M ÿ + Q ẏ + K y = B u,  z = C_y y + C_v ẏ + C_a ÿ + D u
// (seed eqs. 3.8-3.10; C_a and D for joint loads, issue 15 §3).
#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "mbsgen/runtime/error.hpp"

namespace mbsgen {

/// Read-only description of a linear second-order model with f coordinates, m inputs and
/// p outputs (seed eq. 3.8, docs/design.md, "Linearization"):
///
///     M ÿ + Q ẏ + K y = B u,      z = C_y y + C_v ẏ + C_a ÿ + D u.
///
/// - M (f×f, kg or kg·m², per coordinate): mass matrix, may be singular (massless coordinates);
/// - Q (f×f, N·s/m ...): velocity matrix, damping D = sym(Q) plus gyroscopic G = skew(Q);
/// - K (f×f, N/m ...): stiffness, symmetric part plus circulatory N = skew(K);
/// - B (f×m): input matrix; C_y, C_v (p×f): output matrices;
/// - C_a (p×f) and D (p×m), optional (with_output_terms): outputs that depend on the
///   accelerations and directly on the inputs, such as joint loads (issue 15 §3 (c)). Without
///   them (the constructors) both are zero and stored empty (0×0).
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

  /// p×f output matrix on ÿ, or 0×0 when it is zero (has_output_accelerations() false).
  const Eigen::MatrixXd& C_a() const { return C_a_; }
  /// p×m feedthrough of the inputs into the outputs, or 0×0 when it is zero (has_feedthrough()
  /// false).
  const Eigen::MatrixXd& D() const { return D_; }
  bool has_output_accelerations() const { return C_a_.size() != 0; }  ///< C_a ≠ 0
  bool has_feedthrough() const { return D_.size() != 0; }             ///< D ≠ 0

  /// A copy of this model whose outputs are z = C_y y + C_v ẏ + C_a ÿ + D u (these C_a and D
  /// replace any it had). C_a must be p×f and D p×m, or empty (0×0, meaning zero); an exactly zero matrix is stored empty, so that analyses keep
  /// the path of a model without it. Throws DimensionError or NonFiniteError naming
  /// "LinearModel::with_output_terms", the matrix and its dimensions.
  LinearModel with_output_terms(Eigen::MatrixXd C_a, Eigen::MatrixXd D) const;

  /// Prescribed motion (issue 19): inputs that move a support excite through their rates and
  /// accelerations too, M ÿ + Q ẏ + K y = B u + B1 u̇ + B2 ü and z += D1 u̇, so that a harmonic
  /// input sees B(Ω) = B + iΩB1 − Ω²B2 and D(Ω) = D + iΩD1. B1 (f×m, N s/m …), B2 (f×m) and
  /// D1 (p×m), each 0×0 when zero (has_input_rates() false without any).
  const Eigen::MatrixXd& B1() const { return B1_; }
  const Eigen::MatrixXd& B2() const { return B2_; }
  const Eigen::MatrixXd& D1() const { return D1_; }
  bool has_input_rates() const { return B1_.size() != 0 || B2_.size() != 0 || D1_.size() != 0; }
  /// True when input j has a nonzero column of B1, B2 or D1.
  bool input_has_rates(Eigen::Index j) const;
  /// A copy with these B1, B2 (f×m) and D1 (p×m), each possibly empty (0×0, zero); an exactly
  /// zero matrix is stored empty. Throws DimensionError or NonFiniteError naming
  /// "LinearModel::with_input_rates", the matrix and its dimensions.
  LinearModel with_input_rates(Eigen::MatrixXd B1, Eigen::MatrixXd B2, Eigen::MatrixXd D1) const;

  /// A copy with only the inputs `inputs` (columns of B, B1, B2, D, D1) and the outputs `outputs`
  /// (rows of C_y, C_v, C_a, D, D1), in the order given, with their names and units: a response or
  /// its derivatives then solve one right-hand side per chosen input, not per input of the model
  /// (the middle ear has seven). DimensionError for an index out of range.
  LinearModel select(const std::vector<Eigen::Index>& inputs, const std::vector<Eigen::Index>& outputs) const;

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
  Eigen::MatrixXd C_a_, D_;  // 0×0 when zero
  Eigen::MatrixXd B1_, B2_, D1_;  // 0×0 when zero
  std::vector<std::string> coordinate_names_, input_names_, output_names_;
  std::vector<std::string> coordinate_units_, input_units_, output_units_;
  bool has_Q_ = false;
  Eigen::Index bandwidth_ = 0;
};

/// The derivatives of a linear model's matrices by one parameter, in the LinearModel's shapes;
/// C_a, D, B1, B2, D1 are 0×0 when the model has none (as in LinearModel).
struct MatrixSensitivity {
  std::string parameter;
  double value = 0;  ///< the parameter's value (for relative sensitivities)
  Eigen::MatrixXd M, Q, K, B, C_y, C_v, C_a, D, B1, B2, D1;
  Eigen::VectorXd dy0, dyd0;  ///< the operating point's derivatives (zero when it does not move)
};

/// The derivative of LinearModel::select(inputs, outputs): the same columns and rows of d.
MatrixSensitivity select(const MatrixSensitivity& d, const std::vector<Eigen::Index>& inputs,
                         const std::vector<Eigen::Index>& outputs);

}  // namespace mbsgen
