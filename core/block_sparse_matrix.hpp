#pragma once
/// Sparse symmetric-pattern matrix made of 3x3 node blocks, stored as scalar CSR.

#include <Eigen/SparseCore>
#include <span>
#include <utility>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

/// Collects node couplings ("cliques": sets of nodes that all interact) before a pattern is built.
class SparsityBuilder {
 public:
  explicit SparsityBuilder(Index num_nodes) : num_nodes_(num_nodes) {}
  /// Couples every pair of the given nodes (including each node with itself).
  void add_clique(std::span<const Index> nodes);
  Index num_nodes() const { return num_nodes_; }
  /// Sorted, unique (row node, column node) pairs, diagonal pairs for every node included.
  std::vector<std::pair<Index, Index>> pairs() const;

 private:
  Index num_nodes_;
  std::vector<std::pair<Index, Index>> pairs_;
};

/// Global stiffness matrix over interleaved degrees of freedom (dof 3 * node + component).
/// Every stored node block is a dense 3x3, so the three scalar rows of a node share one column
/// list: entry (3i + c, 3j + d) sits at values()[block_offset(i, j) + c * row_stride(i) + d].
/// Kernels precompute block offsets once per pattern and scatter without searching.
class BlockSparseMatrix {
 public:
  using Matrix = Eigen::SparseMatrix<double, Eigen::RowMajor, Index>;

  BlockSparseMatrix() = default;
  /// Builds the pattern (values zero) from the couplings gathered in `builder`.
  explicit BlockSparseMatrix(const SparsityBuilder& builder);

  Index num_nodes() const { return static_cast<Index>(stride_.size()); }
  /// Offset of scalar entry (3i, 3j); -1 when nodes i and j are not coupled.
  Index block_offset(Index i, Index j) const;
  /// Entries per scalar row of node i (3 x number of coupled nodes).
  Index row_stride(Index i) const { return stride_[i]; }

  void set_zero() { A_.coeffs().setZero(); }
  double* values() { return A_.valuePtr(); }
  const Matrix& matrix() const { return A_; }
  Matrix& matrix() { return A_; }

  /// Adds a 3x3 block at a precomputed offset for row node i (not thread safe for one block).
  template <class Block>
  void add_block(Index offset, Index i, const Block& B) {
    double* v = A_.valuePtr() + offset;
    const Index s = stride_[i];
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 3; ++d) v[c * s + d] += B(c, d);
  }

 private:
  Matrix A_;
  std::vector<Index> stride_;
};

}  // namespace depthfem
