#pragma once
/// The order in which a contact module walks its pairs, and where their Hessian blocks go.

#include <string>
#include <vector>

#include "core/block_sparse_matrix.hpp"
#include "core/element_partition.hpp"

namespace depthfem {

/// A contact module's pairs (each a clique of K nodes: a tet and a triangle, a node and a
/// triangle, a triangle) ordered along a Morton curve and cut into chunks colored so that the
/// chunks of one color share no node, with every pair's K x K Hessian block indices in the bound
/// pattern. run() adds pair derivatives into the gradient and the matrix from the chunks of a color
/// concurrently, without searching or allocating; every entry receives its terms in pair order,
/// whatever the number of threads.
class PairSchedule {
 public:
  using Nodes = Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic>;

  /// Orders the pairs given by their nodes (#pairs x K) and centres (#pairs x 3) and returns, for
  /// each position, the index of the pair placed there. With a bound pattern, finds the pairs'
  /// blocks in it (has_blocks() tells whether all were there); when some are missing, the pairs
  /// join the kept cliques that add_couplings() puts in the next pattern.
  std::vector<Index> arrange(const Nodes& nodes, const Points& centres, Index num_nodes,
                             const BlockSparseMatrix* bound);
  /// Couples the nodes of the current pairs and of the kept ones: a pattern with room for the
  /// pairs that come and go between Newton iterations, so that it (and the direct solver's
  /// analysis) changes only when a pair never seen since the last change appears. The kept set
  /// is the union of the pair sets that needed a new pattern, started afresh from the current
  /// pairs when it has grown to more than twice their number.
  void add_couplings(SparsityBuilder& builder) const;
  /// Finds the pairs' blocks in `hessian`; throws std::logic_error naming `module` if the pattern
  /// lacks one (it was built from the module's couplings).
  void bind(const BlockSparseMatrix& hessian, const std::string& module);
  /// Whether every pair's blocks are known (the pattern holds all couplings).
  bool has_blocks() const {
    return blocks_.size() == static_cast<size_t>(nodes_.size() * nodes_.cols());
  }

  Index size() const { return static_cast<Index>(nodes_.rows()); }
  /// Node a of pair k (in processing order).
  Index node(Index k, int a) const { return nodes_(k, a); }
  const Nodes& nodes() const { return nodes_; }
  /// The K x K block indices of pair k, (a, b) at K a + b.
  const Index* blocks(Index k) const {
    return blocks_.data() + static_cast<size_t>(k) * nodes_.cols() * nodes_.cols();
  }

  /// Sum over pairs of pair(k) (T: double or a fixed-size Eigen vector), the chunks of a color
  /// run concurrently (run_by_color): pair(k) may add into the data of pair k's nodes.
  template <class T, class PairFn>
  T run(const T& zero, PairFn pair) const {
    return run_by_color(color_begin_, zero, [&](Index c) {
      T acc = zero;
      for (Index k = chunk_begin_[c]; k < chunk_begin_[c + 1]; ++k) acc += pair(k);
      return acc;
    });
  }

 private:
  Nodes nodes_;
  Nodes kept_;  // rows: the cliques add_couplings() adds, sorted, without repeats
  std::vector<Index> chunk_begin_, color_begin_;
  std::vector<Index> blocks_;  // K K per pair; empty while some are missing
};

}  // namespace depthfem
