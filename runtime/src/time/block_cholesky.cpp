// Cholesky factors of a block-diagonal mass matrix, block by block (block_cholesky.hpp).
#include "time/block_cholesky.hpp"

#include <algorithm>
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
constexpr std::size_t kSmallestRefined = 4;  // the largest block's size, for solve_refined()
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
constexpr int kCorrections = 5;  // LAPACK xPORFS's ITMAX

std::size_t at(Index i) { return static_cast<std::size_t>(i); }

// G's lower triangle := that of M's block on the coordinates `index` (ascending, so M's lower
// triangle: what compute() factors and solve_refined() refines).
template <class Block>
void gather_lower(const MatrixXd& M, const std::vector<Index>& index, Block& G) {
  for (Index c = 0; c < G.cols(); ++c)
    for (Index r = c; r < G.rows(); ++r) G(r, c) = M(index[at(r)], index[at(c)]);
}

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
// M's lower triangle and the old blocks' coordinates (so the blocks only ever merge: an entry
// between two that is zero at one state only, sin 0, does not split them again and again, at
// most n − 1 partitions in all), by union–find; each with factors of its size.
void BlockCholesky::partition(const MatrixXd& M) {
  std::vector<Index> parent(at(n_));
  std::iota(parent.begin(), parent.end(), Index{0});
  auto root = [&parent](Index i) {
    while (parent[at(i)] != i) i = parent[at(i)] = parent[at(parent[at(i)])];
    return i;
  };
  auto join = [&](Index i, Index j) {
    const Index a = root(i), b = root(j);
    if (a != b) parent[at(std::max(a, b))] = std::min(a, b);
  };
  for (const std::vector<Index>& block : blocks_)
    for (const Index i : block) join(i, block.front());
  for (Index j = 0; j < n_; ++j)
    for (Index i = j + 1; i < n_; ++i)
      if (M(i, j) != 0) join(i, j);
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
  // Refinement where a block is large enough that factoring it costs more than refining it: a
  // 6×6 Cholesky factorization and solve is a chain of 6 square roots and 27 divisions, a refined
  // solve a few products with the inverse (the middle ear: 1.25–1.3× faster); a 2×2 one costs
  // less than the refinement's checks (the double pendulum was 10–20 % slower refined).
  std::size_t largest = 0;
  for (const std::vector<Index>& b : blocks_) largest = std::max(largest, b.size());
  refinable_ = static_cast<Index>(largest) <= kLargestFixed && largest >= kSmallestRefined;
}

bool BlockCholesky::compute(const MatrixXd& M) {
  eigen_assert(M.rows() == n_ && M.cols() == n_);
  factored_ = false;
  if (blocks_.empty() || !partition_holds(M)) partition(M);
  if (whole_) {  // dense: no copies
    auto& llt = std::get<Dynamic>(factors_[0]).llt;
    llt.compute(M);
    if (llt.info() != Eigen::Success) return false;
    diagonal_ = llt.matrixLLT().diagonal();
    return factored_ = true;
  }
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    const std::vector<Index>& index = blocks_[b];
    const bool ok = std::visit(
        [&](auto& f) {
          using F = std::decay_t<decltype(f)>;
          if constexpr (std::is_same_v<F, Dynamic>) {
            gather_lower(M, index, f.gathered);
            f.llt.compute(f.gathered);
          } else {
            using Matrix = typename std::decay_t<decltype(f.llt)>::MatrixType;
            Matrix G = Matrix::Zero();  // the lower triangle is read (and the whole copied)
            gather_lower(M, index, G);
            f.llt.compute(G);
            // The inverse for solve_refined(): applied in s² multiplications and additions, where
            // the triangular solves divide by the pivots in a chain (6×6: a tenth of the time).
            if (refinable_ && f.llt.info() == Eigen::Success) f.inverse = f.llt.solve(Matrix::Identity());
          }
          if (f.llt.info() != Eigen::Success) return false;
          for (std::size_t r = 0; r < index.size(); ++r)
            diagonal_[index[r]] = f.llt.matrixLLT()(static_cast<Index>(r), static_cast<Index>(r));
          return true;
        },
        factors_[b]);
    if (!ok) return false;
  }
  return factored_ = true;
}

namespace {

// The block's share of solve_refined(): y = −G⁻¹ c from the inverse P of a nearby block, by
// y ← y + P (−c − G y), until its componentwise backward error
// max_i |c + G y|_i / (|G| |y| + |c|)_i (LAPACK xPORFS's measure) is 4·size·ε. The iteration
// watches it with the denominators of the first iterate (the corrections change y by a hundredth
// or less); the goal is then confirmed with those of the last (a small component of y, far off
// in the first iterate, would make the first ones too large). Refused where the goal is not met
// within five corrections (xPORFS's ITMAX), and early where it will not be: a first correction
// that gains less than a hundredfold (1e-2 per correction cannot gain the 13 decades from a first
// iterate 1e-2 off in five), or a later one that does not halve the error.
template <class Matrix, class Vector>
bool refine_block(const Matrix& G, const Matrix& P, const Vector& c, Vector& y) {
  const double goal = 4 * static_cast<double>(G.rows()) * kEpsilon;
  // The denominators, + the smallest normal number: a zero row (c_i = 0, (|G| |y|)_i = 0) gives
  // 0/min = 0, not NaN.
  auto denominators = [&](Vector& d) {
    d = c.cwiseAbs();
    d.noalias() += G.cwiseAbs() * y.cwiseAbs();
    d.array() += std::numeric_limits<double>::min();
  };
  auto backward_error = [](const Vector& residual, const Vector& d) {  // +∞ for a NaN
    double error = 0;
    for (Index i = 0; i < residual.size(); ++i) {
      const double q = std::abs(residual[i]) / d[i];
      if (!(q <= std::numeric_limits<double>::max())) return std::numeric_limits<double>::infinity();
      error = std::max(error, q);
    }
    return error;
  };
  y.noalias() = -(P * c);
  Vector scale, fresh;
  denominators(scale);
  double first = 0, last = 0;
  for (int k = 0; k <= kCorrections; ++k) {
    Vector residual = -c;
    residual.noalias() -= G * y;
    const double error = backward_error(residual, scale);
    if (error <= goal) {
      denominators(fresh);
      if (backward_error(residual, fresh) <= goal) return true;
    }
    if (!(error < std::numeric_limits<double>::infinity())) return false;
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
  eigen_assert(M.rows() == n_ && M.cols() == n_);
  if (!factored_ || !refinable_ || !partition_holds(M)) return false;
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
            Matrix G = Matrix::Zero();
            Vector c = Vector::Zero(), y = Vector::Zero();
            gather_lower(M, index, G);  // the symmetric matrix of the lower triangle, as factored
            G.template triangularView<Eigen::StrictlyUpper>() = G.transpose().eval();
            for (Index j = 0; j < c.size(); ++j) c[j] = b[index[at(j)]];
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
            part.setZero();
            solve(part);
          }
        },
        factors_[k]);
  }
}

}  // namespace mbsgen::detail
