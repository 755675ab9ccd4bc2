// The residuals of a fit and their exact Jacobian at θ (fit.hpp has the mathematics): one per
// thread, each with its own copy of the model. Private to the runtime's fit/.
#pragma once

#include <Eigen/Core>

#include <complex>
#include <string>
#include <vector>

#include "mbsgen/runtime/fit/fit.hpp"

namespace mbsgen::detail {

class FitEvaluator {
 public:
  /// Checks the problem: parameters known to the model and to its sensitivity kernel, bounds
  /// around the start, inputs and outputs of the data known (NameError naming the file and line).
  FitEvaluator(const GeneratedModel& model, const MeasuredData& data, const std::vector<FitParameter>& parameters);

  int rows() const { return data_rows_ + static_cast<int>(priors_.size()); }
  int data_rows() const { return data_rows_; }
  int cols() const { return static_cast<int>(params_.size()); }
  bool weighted() const { return weighted_; }
  bool log_space(int j) const { return params_[static_cast<std::size_t>(j)].log_space; }
  const std::vector<std::string>& names() const { return names_; }
  const Eigen::VectorXd& theta_lower() const { return lower_; }
  const Eigen::VectorXd& theta_upper() const { return upper_; }
  Eigen::VectorXd start() const;
  Eigen::VectorXd theta_of(const Eigen::VectorXd& p) const;
  Eigen::VectorXd values(const Eigen::VectorXd& theta) const;

  /// r (and J when asked) at θ; false (with the reason in `why`) when the model cannot be
  /// evaluated there (unphysical values, no equilibrium, a singular response).
  bool evaluate(const Eigen::VectorXd& theta, Eigen::VectorXd& r, Eigen::MatrixXd* J, std::string* why = nullptr);

  /// The data points with the model's responses at θ0 and θ and the weighted residuals at θ.
  std::vector<FitResult::Point> points(const Eigen::VectorXd& theta0, const Eigen::VectorXd& theta);

 private:
  struct Responses {  // at one θ: H per response point, modal values per modal point
    std::vector<std::vector<std::complex<double>>> frf;  // [data set][point]
    std::vector<std::vector<std::pair<double, double>>> modal;  // (f, ζ)
  };
  void compute(const Eigen::VectorXd& theta, bool jacobian, Responses& out, Eigen::MatrixXd* dlnH_re,
               Eigen::MatrixXd* dlnH_im, Eigen::MatrixXd* dmodal_f, Eigen::MatrixXd* dmodal_z);

  GeneratedModel model_;
  const MeasuredData& data_;
  std::vector<FitParameter> params_;
  std::vector<std::string> names_;
  std::vector<std::size_t> index_;  // of each fitted parameter in the model's parameters
  Eigen::VectorXd lower_, upper_;
  std::vector<double> hz_;          // every frequency of the data, sorted, unique
  std::vector<std::vector<std::size_t>> at_;  // [data set][point] → index in hz_
  std::vector<std::pair<Eigen::Index, Eigen::Index>> io_;  // [data set] (input, output) in the restricted model
  std::vector<Eigen::Index> inputs_, outputs_;  // the data's inputs and outputs (the model's indices)
  std::vector<int> priors_;         // fitted parameters with a prior
  int data_rows_ = 0;
  bool weighted_ = true;
  bool modal_ = false;
};

}  // namespace mbsgen::detail
