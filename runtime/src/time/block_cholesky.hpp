// Cholesky factors of a mass matrix that splits into independent blocks, and solves with them
// (internal to simulation.cpp, which solves with M at every evaluation of the accelerations).
//
// Where the nonzeros of M's lower triangle fall into k groups of coordinates that share none,
// M is block diagonal after a symmetric permutation, and its Cholesky factor is too: k small
// factorizations replace one of order n. This is exact, not an approximation: the groups are
// those of the matrix at hand (an entry is in no block only when it is exactly zero), judged at
// every factorization (a check of the zeros outside the blocks, and the groups again where one is
// not zero; blocks only ever merge). Bodies in absolute coordinates joined by springs or
// ligaments give such an M: the middle ear's is three blocks of 6 (malleus, incus, stapes), a
// ninth of the work of its 18×18.
//
// Most evaluations then need no factorization at all: M changes little from one evaluation to
// the next (the middle ear's by 1e-5 of itself over a run), and solve_refined() solves with the
// inverses of the last factored M's blocks as the approximate solver of iterative refinement in
// working precision, until the componentwise backward error (LAPACK xPORFS's measure; Higham,
// Accuracy and Stability of Numerical Algorithms, 2nd ed., Ch. 12) is 4·(block size)·ε, that of
// a backward-stable solve. Where it does not get there fast (M moved too far from the factored
// one), the caller factors M afresh. The singularity of M is the caller's to judge, on fresh
// factors: a refined solve proves M near the factored one only along its right-hand side.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <variant>
#include <vector>

namespace mbsgen::detail {

class BlockCholesky {
 public:
  explicit BlockCholesky(Eigen::Index n);

  /// Factors M from its lower triangle, as Eigen's LLT does. False where a block is not
  /// numerically positive definite.
  bool compute(const Eigen::MatrixXd& M);
  /// The diagonal of the factor L (M = L Lᵀ), in M's order.
  const Eigen::VectorXd& diagonal() const { return diagonal_; }
  /// x = −M⁻¹ b, after a successful compute() (x and b may not alias).
  void solve_negated(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  /// x = −M⁻¹ b for an M near the last one compute() factored, by iterative refinement on that
  /// one's inverse (all blocks of up to 8 coordinates, the largest of 4 or more: smaller ones
  /// factor faster than they refine; M's nonzeros within the same blocks;
  /// the lower triangle read, as compute() reads it). False, with x undefined, where that does
  /// not apply or does not reach a componentwise backward error of 4·(block size)·ε within five
  /// corrections (the first gaining a hundredfold, each later one halving it): M too far from
  /// the factored one, or not finite. Then compute() M itself.
  bool solve_refined(const Eigen::MatrixXd& M, const Eigen::VectorXd& b, Eigen::VectorXd& x);
  /// How many blocks the last compute() found (1 for a dense or empty M).
  std::size_t blocks() const { return blocks_.size(); }

 private:
  bool partition_holds(const Eigen::MatrixXd& M) const;
  void partition(const Eigen::MatrixXd& M);

  // A block's factors: of fixed size up to 8 (Eigen's fixed-size LLT has no per-call overhead
  // for the size: 6×6 in two thirds of the dynamic one's time), else dynamic with its work space.
  template <int N>
  struct Fixed {
    Eigen::LLT<Eigen::Matrix<double, N, N>> llt;
    Eigen::Matrix<double, N, N> inverse;  // of the factored block (solve_refined())
  };
  struct Dynamic {
    Eigen::MatrixXd gathered;
    Eigen::LLT<Eigen::MatrixXd> llt;
    Eigen::VectorXd rhs;
  };
  using Factors = std::variant<Fixed<1>, Fixed<2>, Fixed<3>, Fixed<4>, Fixed<5>, Fixed<6>, Fixed<7>, Fixed<8>, Dynamic>;

  Eigen::Index n_;
  std::vector<std::vector<Eigen::Index>> blocks_;  // the coordinates of each block, ascending
  std::vector<int> block_of_;                        // each coordinate's block
  std::vector<Eigen::Index> outside_;                // M's lower entries between blocks (column-major)
  std::vector<Factors> factors_;
  bool whole_ = false;      // one dynamic block of all coordinates: M factored in place
  bool refinable_ = false;  // solve_refined() applies: every block of fixed size, one of 4 or more
  bool factored_ = false;   // the last compute() succeeded
  Eigen::VectorXd diagonal_;
};

}  // namespace mbsgen::detail
