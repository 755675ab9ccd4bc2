// Proofs that an expression of a program is zero for all values of its variables (internal to the
// generator: the structural zeros of the linear matrices, linear/structural_zeros.cpp, their
// symmetry and sensitivities, and the constraint equations that vanish identically,
// mechanics/loop_closure.cpp). Every intermediate is written out, sin and cos of each argument
// replaced by symbols s, c with c² = 1 − s², the radicals of each base B by powers of one symbol
// t = B^(1/Q) with t^Q = B, the rational normal form's numerator expanded and reduced by those
// relations; an expression beyond the size budgets is not proved (never a wrong zero).
#pragma once

#include "mbsgen/generator/symbolic/program.hpp"

#include <cstddef>
#include <functional>
#include <memory>
#include <unordered_map>
#include <utility>
#include <vector>

namespace mbsgen {

/// True when e (an expression of the program) is proved zero for all values of its variables
/// (false when it is not zero or not proved within the budget). bound_terms = false: without the
/// bound on the expansion's terms, only on the written-out size (loop closure's test of
/// constraint equations that vanish identically).
bool proved_zero(Program& program, const GiNaC::ex& e, bool bound_terms = true);
/// True when entry(0), …, entry(count − 1) are all proved zero as above; false, before any is
/// expanded, when one is beyond the budget (entries are formed in order, up to that one).
bool all_proved_zero(Program& program, std::size_t count, const std::function<GiNaC::ex(std::size_t)>& entry);

namespace detail {

using GiNaC::ex;

// Written-out expressions beyond this many nodes are not expanded (expansion can swell them
// exponentially); their candidates stay unproved.
constexpr std::size_t kProofBudget = 20000;

enum class Proof { zero, nonzero, too_large };

// Number of nodes of an expression's tree (shared subtrees counted each time), saturating at
// `limit`. The sizes of subtrees are kept by node, with the node: the written-out candidates
// share most of their subtrees (Program::inline_all), and walking each tree anew up to the budget
// took a third of a 40-link chain's generation once its 6,320 numerically zero entries of N
// were all candidates.
class TreeSize {
 public:
  explicit TreeSize(std::size_t limit) : limit_(limit) {}

  std::size_t operator()(const ex& root) {
    struct Frame {
      ex e;
      std::size_t next = 0, sum = 1;
    };
    std::vector<Frame> stack;
    std::size_t result = known(root);
    if (result > 0) return result;
    stack.push_back({root});
    while (!stack.empty()) {
      Frame& f = stack.back();
      if (f.sum < limit_ && f.next < f.e.nops()) {
        const ex child = f.e.op(f.next++);
        if (const std::size_t n = known(child)) {
          f.sum = std::min(limit_, f.sum + n);
        } else {
          stack.push_back({child});  // (f is not used after this)
        }
        continue;
      }
      const std::size_t n = std::min(limit_, f.sum);
      sizes_.emplace(&GiNaC::ex_to<GiNaC::basic>(f.e), std::make_pair(f.e, n));
      stack.pop_back();
      if (stack.empty())
        result = n;
      else
        stack.back().sum = std::min(limit_, stack.back().sum + n);
    }
    return result;
  }

 private:
  // The size of a leaf or of a node seen before; 0 otherwise.
  std::size_t known(const ex& e) const {
    if (e.nops() == 0) return 1;
    auto it = sizes_.find(&GiNaC::ex_to<GiNaC::basic>(e));
    return it == sizes_.end() ? 0 : it->second.second;
  }

  std::size_t limit_;
  // node → (the node, kept alive so that its address is not reused; its size)
  std::unordered_map<const GiNaC::basic*, std::pair<ex, std::size_t>> sizes_;
};

// The proofs of many written-out candidates of one program (the linear matrices' entries, their
// symmetry). The candidates share most of their subtrees (Program::inline_all), and what is found
// of a subtree — its size, the bound of its expanded terms, whether it divides or holds a sine,
// its sines and cosines as symbols — is found once for all of them: the 60-link chain's 3,540
// proofs of the symmetry of K walked every shared subtree anew, 12 s of its 23 s generation, and
// take 6.4 s so (docs/generator.md, "Generation time"). Only the time depends on it: a verdict
// is the one the candidate alone gets.
class Prover {
 public:
  Prover();
  ~Prover();
  Prover(const Prover&) = delete;
  Prover& operator=(const Prover&) = delete;

  /// Whether written_out is within the budgets: kProofBudget nodes, and, without a division,
  /// kExpansionBudget terms expanded.
  bool within_budgets(const ex& written_out);
  /// zero, nonzero, or too_large (beyond the budgets).
  Proof prove(const ex& written_out);

 private:
  struct Shared;
  std::unique_ptr<Shared> shared_;
};

}  // namespace detail
}  // namespace mbsgen
