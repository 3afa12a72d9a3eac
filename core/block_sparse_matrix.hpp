#pragma once
/// Sparse symmetric-pattern matrix of dense 3x3 node blocks (block compressed sparse row).

#include <Eigen/SparseCore>
#include <cstdint>
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
  /// The coupled pairs by rows: row_begin (#nodes + 1 offsets into col) and, per row node, its
  /// column nodes sorted and unique, the diagonal included.
  struct Rows {
    std::vector<Index> row_begin, col;
  };
  Rows rows() const;
  /// The union of two patterns of the same nodes, row by row.
  static Rows merged(const Rows& a, const Rows& b);

 private:
  Index num_nodes_;
  std::vector<std::pair<Index, Index>> pairs_;
};

/// Which entries of a matrix a scalar view holds.
enum class Triangle {
  kFull,   ///< every entry
  kUpper,  ///< columns >= row: of a symmetric matrix also its lower triangle by columns
};

/// Scalar compressed-row pattern (rows and columns are dofs, columns sorted within a row) of a
/// BlockSparseMatrix, built once per block pattern. The upper triangle by rows of a symmetric
/// matrix is its lower triangle by columns: what CHOLMOD reads.
struct ScalarPattern {
  Triangle triangle = Triangle::kFull;
  std::vector<Index> row_begin = {};  ///< 3 #nodes + 1 offsets into col
  std::vector<Index> col = {};        ///< column of every entry
  /// Per node (or empty: none): 1 where the node's off-diagonal blocks are left out, since the
  /// matrix holds them zero (a fully prescribed node after Constraints::project).
  std::vector<char> decoupled;
  /// Whether block (i, j) of the block pattern is part of this one.
  bool keeps(Index i, Index j) const {
    return i == j || decoupled.empty() || !(decoupled[size_t(i)] || decoupled[size_t(j)]);
  }
};

/// Global stiffness matrix over interleaved degrees of freedom (dof 3 * node + component),
/// stored as 3x3 blocks: block k couples row node i with column node col(k) and its nine values
/// sit together, row-major, at values()[9 k ..]. One tet scatters 16 blocks = 16 short contiguous
/// runs (a scalar CSR would take 48 runs of 3), so assembly touches a third of the cache lines.
/// Kernels precompute block indices once per pattern and scatter without searching.
class BlockSparseMatrix {
 public:
  BlockSparseMatrix() = default;
  /// Builds the pattern (values zero) from the couplings gathered in `builder`.
  explicit BlockSparseMatrix(const SparsityBuilder& builder);
  /// Builds the pattern (values zero) from rows as SparsityBuilder::rows() gives them.
  explicit BlockSparseMatrix(SparsityBuilder::Rows rows);

  /// Identifies the pattern: every pattern built gets a new version (also one with the same
  /// number of blocks); copies share it. Solvers key their per-pattern analysis on it.
  std::uint64_t pattern_version() const { return pattern_version_; }

  Index num_nodes() const { return static_cast<Index>(row_begin_.size()) - 1; }
  Index num_blocks() const { return static_cast<Index>(col_.size()); }
  /// Index of block (i, j); -1 when nodes i and j are not coupled.
  Index block_index(Index i, Index j) const;
  /// For every block of this pattern its index in `other` (of the same nodes), -1 where other
  /// lacks it: how a module bound to this pattern moves its indices to other's (a merge of the
  /// sorted rows, linear in the blocks).
  std::vector<Index> block_map(const BlockSparseMatrix& other) const;
  /// Block indices of the node pairs of every row of `cliques` (#rows x K node indices): (a, b) of
  /// row r at K K r + K a + b; empty as soon as some pair of nodes is found not coupled (the
  /// search stops there). TBB-parallel over rows.
  std::vector<Index> clique_block_indices(
      const Eigen::Ref<const Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic>>& cliques) const;
  /// Blocks of row node i span [row_begin(i), row_begin(i + 1)).
  Index row_begin(Index i) const { return row_begin_[i]; }
  /// Column node of block k.
  Index block_col(Index k) const { return col_[k]; }

  void set_zero() { std::fill(values_.begin(), values_.end(), 0.0); }
  /// The nine row-major values of block k.
  Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> block(Index k) {
    return Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values_.data() + 9 * k);
  }
  Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> block(Index k) const {
    return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values_.data() + 9 * k);
  }
  /// Adds B to block k (not thread safe for one block).
  template <class Block>
  void add_block(Index k, const Block& B) {
    double* v = values_.data() + 9 * k;
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 3; ++d) v[3 * c + d] += B(c, d);
  }

  /// Adds the K x K blocks of a dense 3K x 3K matrix B (node-major) to blocks off[K a + b].
  template <int K, class Dense>
  void add_blocks(const Index* off, const Dense& B) {
    for (int a = 0; a < K; ++a)
      for (int b = 0; b < K; ++b) add_block(off[K * a + b], B.template block<3, 3>(3 * a, 3 * b));
  }

  /// A += s B for a matrix B with the same pattern.
  void add_scaled(const BlockSparseMatrix& B, double s);
  /// y = A x (TBB-parallel over block rows; deterministic).
  void multiply(const VectorX& x, VectorX& y) const;
  /// The scalar diagonal (3 * #nodes).
  VectorX diagonal() const;
  /// The same matrix as an Eigen compressed sparse matrix (a reference for tests).
  Eigen::SparseMatrix<double> to_sparse() const;
  /// The scalar pattern of the whole matrix or of its upper triangle, without the off-diagonal
  /// blocks of the `decoupled` nodes (ScalarPattern::decoupled).
  ScalarPattern scalar_pattern(Triangle triangle, std::vector<char> decoupled = {}) const;
  /// Writes the values in the order of `pattern` (from scalar_pattern() of this pattern) to
  /// out[0, pattern.col.size()); TBB-parallel over block rows.
  void scalar_values(const ScalarPattern& pattern, double* out) const;

 private:
  std::vector<Index> row_begin_;
  std::vector<Index> col_;
  std::vector<double> values_;
  std::uint64_t pattern_version_ = 0;
};

}  // namespace depthfem
