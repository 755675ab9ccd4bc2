// Cholesky factors of a block-diagonal mass matrix, block by block (block_cholesky.hpp).
#include "block_cholesky.hpp"

#include <numeric>
#include <type_traits>

namespace mbsgen::detail {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

constexpr Index kLargestFixed = 8;

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
