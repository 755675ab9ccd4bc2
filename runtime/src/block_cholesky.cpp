// Cholesky factors of a block-diagonal mass matrix, block by block (block_cholesky.hpp).
#include "block_cholesky.hpp"

#include <cmath>
#include <limits>
#include <numeric>
#include <type_traits>

namespace mbsgen::detail {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

constexpr Index kLargestFixed = 8;
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
constexpr int kCorrections = 5;  // LAPACK xPORFS's ITMAX

template <int N>
using FixedMatrix = Eigen::Matrix<double, N, N>;

std::size_t at(Index i) { return static_cast<std::size_t>(i); }

}  // namespace

BlockCholesky::BlockCholesky(Index n) : n_(n), block_of_(at(n), 0), diagonal_(n) {}

// Whether every entry of M's lower triangle outside the blocks is zero.
bool BlockCholesky::partition_holds(const MatrixXd& M) const {
  const double* m = M.data();
  for (const Index k : outside_)
    if (m[k] != 0) return false;
  return true;
}

// The blocks: the connected components of the graph whose edges are the nonzeros (and NaNs) of
// M's lower triangle, by union–find; each with factors of its size.
void BlockCholesky::partition(const MatrixXd& M) {
  std::vector<Index> parent(at(n_));
  std::iota(parent.begin(), parent.end(), Index{0});
  auto root = [&parent](Index i) {
    while (parent[at(i)] != i) i = parent[at(i)] = parent[at(parent[at(i)])];
    return i;
  };
  for (Index j = 0; j < n_; ++j)
    for (Index i = j + 1; i < n_; ++i)
      if (M(i, j) != 0) {
        const Index a = root(i), b = root(j);
        if (a != b) parent[at(std::max(a, b))] = std::min(a, b);
      }
  blocks_.clear();
  std::vector<int> block_of_root(at(n_), -1);
  for (Index i = 0; i < n_; ++i) {  // blocks in the order of their first coordinate
    int& b = block_of_root[at(root(i))];
    if (b < 0) {
      b = static_cast<int>(blocks_.size());
      blocks_.emplace_back();
    }
    blocks_[at(b)].push_back(i);
    block_of_[at(i)] = b;
  }
  if (n_ == 0) blocks_.emplace_back();
  outside_.clear();
  for (Index j = 0; j < n_; ++j)
    for (Index i = j + 1; i < n_; ++i)
      if (block_of_[at(i)] != block_of_[at(j)]) outside_.push_back(i + j * n_);
  factors_.clear();
  for (const std::vector<Index>& block : blocks_) {
    const Index size = static_cast<Index>(block.size());
    switch (size) {
      case 1: factors_.emplace_back(std::in_place_type<Fixed<1>>); break;
      case 2: factors_.emplace_back(std::in_place_type<Fixed<2>>); break;
      case 3: factors_.emplace_back(std::in_place_type<Fixed<3>>); break;
      case 4: factors_.emplace_back(std::in_place_type<Fixed<4>>); break;
      case 5: factors_.emplace_back(std::in_place_type<Fixed<5>>); break;
      case 6: factors_.emplace_back(std::in_place_type<Fixed<6>>); break;
      case 7: factors_.emplace_back(std::in_place_type<Fixed<7>>); break;
      case 8: factors_.emplace_back(std::in_place_type<Fixed<8>>); break;
      default: {
        Dynamic d;
        d.gathered.setZero(size, size);
        d.rhs.resize(size);
        d.llt = Eigen::LLT<MatrixXd>(size);
        factors_.emplace_back(std::move(d));
      }
    }
  }
  whole_ = blocks_.size() == 1 && n_ > kLargestFixed;
}

bool BlockCholesky::compute(const MatrixXd& M) {
  if (blocks_.empty() || !partition_holds(M)) partition(M);
  if (whole_) {  // dense: no copies
    auto& llt = std::get<Dynamic>(factors_[0]).llt;
    llt.compute(M);
    if (llt.info() != Eigen::Success) return false;
    diagonal_ = llt.matrixLLT().diagonal();
    return true;
  }
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    const std::vector<Index>& index = blocks_[b];
    const bool ok = std::visit(
        [&](auto& f) {
          using F = std::decay_t<decltype(f)>;
          if constexpr (std::is_same_v<F, Dynamic>) {
            for (Index c = 0; c < f.gathered.cols(); ++c)
              for (Index r = c; r < f.gathered.rows(); ++r) f.gathered(r, c) = M(index[at(r)], index[at(c)]);
            f.llt.compute(f.gathered);
          } else {
            using Matrix = typename std::decay_t<decltype(f.llt)>::MatrixType;
            Matrix G = Matrix::Zero();  // the lower triangle is read (and the whole copied)
            for (Index c = 0; c < G.cols(); ++c)
              for (Index r = c; r < G.rows(); ++r) G(r, c) = M(index[at(r)], index[at(c)]);
            f.llt.compute(G);
            if (f.llt.info() == Eigen::Success) f.inverse = f.llt.solve(Matrix::Identity());
          }
          if (f.llt.info() != Eigen::Success) return false;
          for (std::size_t r = 0; r < index.size(); ++r)
            diagonal_[index[r]] = f.llt.matrixLLT()(static_cast<Index>(r), static_cast<Index>(r));
          return true;
        },
        factors_[b]);
    if (!ok) return false;
  }
  return true;
}

namespace {

// The block's share of solve_refined(): y = −G⁻¹ c from the inverse P of a nearby block, by
// y ← y + P (−c − G y). Its componentwise backward error max_i |c + G y|_i / (|G| |y| + |c|)_i
// (the denominators from the first iterate: later ones differ from it by the corrections, a
// hundredth at most) must reach 4·size·ε, or stagnate there.
template <class Matrix, class Vector>
bool refine_block(const Matrix& G, const Matrix& P, const Vector& c, Vector& y) {
  y.noalias() = -(P * c);
  Vector scale = c.cwiseAbs();
  scale.noalias() += G.cwiseAbs() * y.cwiseAbs();
  scale.array() += std::numeric_limits<double>::min();  // a zero row: 0/min = 0, not NaN
  const double goal = 4 * static_cast<double>(G.rows()) * kEpsilon;
  double first = 0, last = 0;
  for (int k = 0; k <= kCorrections; ++k) {
    Vector residual = -c;
    residual.noalias() -= G * y;
    const auto ratio = residual.cwiseAbs().array() / scale.array();
    if ((ratio <= goal).all()) return true;  // (false for a NaN)
    if (!ratio.allFinite()) return false;
    const double error = ratio.maxCoeff();
    if (k == 1 && !(error <= 1e-2 * first)) return false;  // M has moved too far
    if (k >= 2 && !(error <= 0.5 * last)) return false;   // stagnates above the goal
    if (k == 0) first = error;
    last = error;
    if (k == kCorrections) return false;
    y.noalias() += P * residual;
  }
  return false;
}

}  // namespace

bool BlockCholesky::solve_refined(const MatrixXd& M, const VectorXd& b, VectorXd& x) {
  if (whole_ || blocks_.empty() || !partition_holds(M)) return false;
  for (std::size_t k = 0; k < blocks_.size(); ++k) {
    const std::vector<Index>& index = blocks_[k];
    const bool ok = std::visit(
        [&](auto& f) {
          using F = std::decay_t<decltype(f)>;
          if constexpr (std::is_same_v<F, Dynamic>) {
            return false;
          } else {
            using Matrix = typename std::decay_t<decltype(f.llt)>::MatrixType;
            using Vector = Eigen::Matrix<double, Matrix::RowsAtCompileTime, 1>;
            Matrix G;
            Vector c, y;
            for (Index j = 0; j < G.cols(); ++j) {
              c[j] = b[index[at(j)]];
              for (Index i = 0; i < G.rows(); ++i)  // the lower triangle's matrix, as compute() reads it
                G(i, j) = i >= j ? M(index[at(i)], index[at(j)]) : M(index[at(j)], index[at(i)]);
            }
            if (!refine_block(G, f.inverse, c, y)) return false;
            for (Index i = 0; i < y.size(); ++i) x[index[at(i)]] = y[i];
            return true;
          }
        },
        factors_[k]);
    if (!ok) return false;
  }
  return true;
}

void BlockCholesky::solve_negated(const VectorXd& b, VectorXd& x) {
  if (whole_) {
    x.noalias() = std::get<Dynamic>(factors_[0]).llt.solve(b);
    x = -x;
    return;
  }
  for (std::size_t k = 0; k < blocks_.size(); ++k) {
    const std::vector<Index>& index = blocks_[k];
    std::visit(
        [&](auto& f) {
          using F = std::decay_t<decltype(f)>;
          auto solve = [&](auto& part) {
            for (Index r = 0; r < part.size(); ++r) part[r] = b[index[at(r)]];
            f.llt.solveInPlace(part);
            for (Index r = 0; r < part.size(); ++r) x[index[at(r)]] = -part[r];
          };
          if constexpr (std::is_same_v<F, Dynamic>) {
            solve(f.rhs);
          } else {
            Eigen::Matrix<double, std::decay_t<decltype(f.llt)>::MatrixType::RowsAtCompileTime, 1> part;
            solve(part);
          }
        },
        factors_[k]);
  }
}

}  // namespace mbsgen::detail
