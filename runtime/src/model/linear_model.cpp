#include "mbsgen/runtime/model/linear_model.hpp"

#include <sstream>

#include "mbsgen/runtime/error.hpp"

namespace mbsgen {
namespace {

std::string dims(const Eigen::MatrixXd& A) {
  std::ostringstream s;
  s << A.rows() << "x" << A.cols();
  return s.str();
}

void check_finite(const Eigen::MatrixXd& A, const char* name, const char* who = "LinearModel") {
  for (Eigen::Index j = 0; j < A.cols(); ++j)
    for (Eigen::Index i = 0; i < A.rows(); ++i)
      if (!std::isfinite(A(i, j))) {
        std::ostringstream s;
        s << who << ": " << name << " (" << dims(A) << ") has a non-finite entry " << A(i, j)
          << " at (" << i + 1 << "," << j + 1 << ")";
        throw NonFiniteError(s.str());
      }
}

void check_dims(const Eigen::MatrixXd& A, Eigen::Index r, Eigen::Index c, const char* name,
                const char* expected, const char* who = "LinearModel") {
  if (A.rows() != r || A.cols() != c) {
    std::ostringstream s;
    s << who << ": " << name << " is " << dims(A) << " but must be " << r << "x" << c << " ("
      << expected << ")";
    throw DimensionError(s.str());
  }
}

std::vector<std::string> names_or_default(std::vector<std::string> names, Eigen::Index n,
                                          const char* prefix, const char* what) {
  if (names.empty()) {
    for (Eigen::Index i = 0; i < n; ++i) names.push_back(prefix + std::to_string(i + 1));
    return names;
  }
  if (static_cast<Eigen::Index>(names.size()) != n) {
    std::ostringstream s;
    s << "LinearModel: " << names.size() << " " << what << " given for " << n << " entries";
    throw DimensionError(s.str());
  }
  return names;
}

std::vector<std::string> units_or_empty(std::vector<std::string> units, Eigen::Index n,
                                        const char* what) {
  if (units.empty()) return std::vector<std::string>(static_cast<std::size_t>(n));
  if (static_cast<Eigen::Index>(units.size()) != n) {
    std::ostringstream s;
    s << "LinearModel: " << units.size() << " " << what << " given for " << n << " entries";
    throw DimensionError(s.str());
  }
  return units;
}

Eigen::Index band_of(const Eigen::MatrixXd& A) {
  Eigen::Index b = 0;
  for (Eigen::Index j = 0; j < A.cols(); ++j)
    for (Eigen::Index i = 0; i < A.rows(); ++i)
      if (A(i, j) != 0.0) b = std::max(b, i > j ? i - j : j - i);
  return b;
}

}  // namespace

LinearModel::LinearModel(Eigen::MatrixXd M, Eigen::MatrixXd Q, Eigen::MatrixXd K,
                         Eigen::MatrixXd B, Eigen::MatrixXd C_y, Eigen::MatrixXd C_v,
                         std::vector<std::string> coordinate_names,
                         std::vector<std::string> input_names,
                         std::vector<std::string> output_names,
                         std::vector<std::string> coordinate_units,
                         std::vector<std::string> input_units,
                         std::vector<std::string> output_units)
    : M_(std::move(M)), Q_(std::move(Q)), K_(std::move(K)), B_(std::move(B)),
      C_y_(std::move(C_y)), C_v_(std::move(C_v)) {
  const Eigen::Index f = M_.rows();
  if (f == 0) throw DimensionError("LinearModel: M is 0x0; a model needs at least one coordinate");
  check_dims(M_, f, f, "M", "square");
  if (Q_.size() == 0) Q_ = Eigen::MatrixXd::Zero(f, f);
  check_dims(Q_, f, f, "Q", "same size as M");
  check_dims(K_, f, f, "K", "same size as M");
  if (B_.size() == 0) B_.resize(f, 0);
  check_dims(B_, f, B_.cols(), "B", "f rows, one column per input");
  const bool have_outputs = C_y_.size() != 0 || C_v_.size() != 0;
  if (!have_outputs) {
    C_y_ = Eigen::MatrixXd::Identity(f, f);
    C_v_ = Eigen::MatrixXd::Zero(f, f);
    if (output_names.empty()) output_names = coordinate_names;
    if (output_units.empty()) output_units = coordinate_units;
  } else if (C_y_.size() == 0) {
    C_y_ = Eigen::MatrixXd::Zero(C_v_.rows(), f);
  } else if (C_v_.size() == 0) {
    C_v_ = Eigen::MatrixXd::Zero(C_y_.rows(), f);
  }
  check_dims(C_y_, C_y_.rows(), f, "C_y", "one column per coordinate");
  check_dims(C_v_, C_y_.rows(), f, "C_v", "same size as C_y");
  check_finite(M_, "M");
  check_finite(Q_, "Q");
  check_finite(K_, "K");
  check_finite(B_, "B");
  check_finite(C_y_, "C_y");
  check_finite(C_v_, "C_v");
  coordinate_names_ = names_or_default(std::move(coordinate_names), f, "y", "coordinate names");
  input_names_ = names_or_default(std::move(input_names), B_.cols(), "u", "input names");
  output_names_ = names_or_default(std::move(output_names), C_y_.rows(),
                                   have_outputs ? "z" : "y", "output names");
  coordinate_units_ = units_or_empty(std::move(coordinate_units), f, "coordinate units");
  input_units_ = units_or_empty(std::move(input_units), B_.cols(), "input units");
  output_units_ = units_or_empty(std::move(output_units), C_y_.rows(), "output units");
  has_Q_ = (Q_.array() != 0.0).any();
  bandwidth_ = std::max({band_of(M_), band_of(Q_), band_of(K_)});
}

LinearModel::LinearModel(Eigen::MatrixXd M, Eigen::MatrixXd Q, Eigen::MatrixXd K)
    : LinearModel(M, std::move(Q), std::move(K),
                  Eigen::MatrixXd::Identity(M.rows(), M.rows()), Eigen::MatrixXd(),
                  Eigen::MatrixXd()) {}

LinearModel LinearModel::with_output_terms(Eigen::MatrixXd C_a, Eigen::MatrixXd D) const {
  constexpr const char* who = "LinearModel::with_output_terms";
  const Eigen::Index p = num_outputs(), f = size(), m = num_inputs();
  auto is_empty = [](const Eigen::MatrixXd& A) { return A.rows() == 0 && A.cols() == 0; };
  if (!is_empty(C_a)) check_dims(C_a, p, f, "C_a", "p x f, the size of C_y", who);
  if (!is_empty(D)) check_dims(D, p, m, "D", "p x m, one row per output, one column per input", who);
  check_finite(C_a, "C_a", who);
  check_finite(D, "D", who);
  LinearModel copy(*this);
  // Exactly zero is stored empty: analyses then take the path of a model without the terms.
  copy.C_a_ = (C_a.array() != 0.0).any() ? std::move(C_a) : Eigen::MatrixXd();
  copy.D_ = (D.array() != 0.0).any() ? std::move(D) : Eigen::MatrixXd();
  return copy;
}

LinearModel LinearModel::with_input_rates(Eigen::MatrixXd B1, Eigen::MatrixXd B2, Eigen::MatrixXd D1) const {
  constexpr const char* who = "LinearModel::with_input_rates";
  const Eigen::Index p = num_outputs(), f = size(), m = num_inputs();
  auto is_empty = [](const Eigen::MatrixXd& A) { return A.rows() == 0 && A.cols() == 0; };
  if (!is_empty(B1)) check_dims(B1, f, m, "B1", "f x m, the size of B", who);
  if (!is_empty(B2)) check_dims(B2, f, m, "B2", "f x m, the size of B", who);
  if (!is_empty(D1)) check_dims(D1, p, m, "D1", "p x m, one row per output, one column per input", who);
  check_finite(B1, "B1", who);
  check_finite(B2, "B2", who);
  check_finite(D1, "D1", who);
  LinearModel copy(*this);
  auto keep = [](Eigen::MatrixXd& A) { return (A.array() != 0.0).any() ? std::move(A) : Eigen::MatrixXd(); };
  copy.B1_ = keep(B1);
  copy.B2_ = keep(B2);
  copy.D1_ = keep(D1);
  return copy;
}

namespace {

// The rows and columns of a (all of one kind when its list is null); 0×0 (zero) stays 0×0.
Eigen::MatrixXd pick(const Eigen::MatrixXd& a, const std::vector<Eigen::Index>* rows, const std::vector<Eigen::Index>* cols) {
  if (a.size() == 0) return a;
  const Eigen::Index r = rows ? static_cast<Eigen::Index>(rows->size()) : a.rows();
  const Eigen::Index c = cols ? static_cast<Eigen::Index>(cols->size()) : a.cols();
  Eigen::MatrixXd out(r, c);
  for (Eigen::Index j = 0; j < c; ++j)
    for (Eigen::Index i = 0; i < r; ++i)
      out(i, j) = a(rows ? (*rows)[static_cast<std::size_t>(i)] : i, cols ? (*cols)[static_cast<std::size_t>(j)] : j);
  return out;
}

std::vector<std::string> pick(const std::vector<std::string>& names, const std::vector<Eigen::Index>& which) {
  std::vector<std::string> out;
  if (names.empty()) return out;
  for (Eigen::Index i : which) out.push_back(names[static_cast<std::size_t>(i)]);
  return out;
}

void check_indices(const std::vector<Eigen::Index>& which, Eigen::Index n, const char* what) {
  for (Eigen::Index i : which)
    if (i < 0 || i >= n)
      throw DimensionError(std::string("LinearModel::select: ") + what + " " + std::to_string(i) + " of " + std::to_string(n));
}

}  // namespace

LinearModel LinearModel::select(const std::vector<Eigen::Index>& in, const std::vector<Eigen::Index>& out) const {
  check_indices(in, num_inputs(), "input");
  check_indices(out, num_outputs(), "output");
  return LinearModel(M_, Q_, K_, pick(B_, nullptr, &in), pick(C_y_, &out, nullptr), pick(C_v_, &out, nullptr),
                     coordinate_names_, pick(input_names_, in), pick(output_names_, out), coordinate_units_,
                     pick(input_units_, in), pick(output_units_, out))
      .with_output_terms(pick(C_a_, &out, nullptr), pick(D_, &out, &in))
      .with_input_rates(pick(B1_, nullptr, &in), pick(B2_, nullptr, &in), pick(D1_, &out, &in));
}

MatrixSensitivity select(const MatrixSensitivity& d, const std::vector<Eigen::Index>& in, const std::vector<Eigen::Index>& out) {
  MatrixSensitivity r = d;
  r.B = pick(d.B, nullptr, &in);
  r.C_y = pick(d.C_y, &out, nullptr);
  r.C_v = pick(d.C_v, &out, nullptr);
  r.C_a = pick(d.C_a, &out, nullptr);
  r.D = pick(d.D, &out, &in);
  r.B1 = pick(d.B1, nullptr, &in);
  r.B2 = pick(d.B2, nullptr, &in);
  r.D1 = pick(d.D1, &out, &in);
  return r;
}

bool LinearModel::input_has_rates(Eigen::Index j) const {
  for (const Eigen::MatrixXd* A : {&B1_, &B2_, &D1_})
    if (A->size() != 0 && (A->col(j).array() != 0.0).any()) return true;
  return false;
}

bool LinearModel::is_symmetric_undamped() const {
  return !has_Q_ && M_ == M_.transpose() && K_ == K_.transpose();
}

}  // namespace mbsgen
