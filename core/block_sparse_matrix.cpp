#include "core/block_sparse_matrix.hpp"

#include <algorithm>

namespace depthfem {

void SparsityBuilder::add_clique(std::span<const Index> nodes) {
  for (Index a : nodes)
    for (Index b : nodes) pairs_.emplace_back(a, b);
}

std::vector<std::pair<Index, Index>> SparsityBuilder::pairs() const {
  std::vector<std::pair<Index, Index>> p = pairs_;
  for (Index i = 0; i < num_nodes_; ++i) p.emplace_back(i, i);
  std::sort(p.begin(), p.end());
  p.erase(std::unique(p.begin(), p.end()), p.end());
  return p;
}

BlockSparseMatrix::BlockSparseMatrix(const SparsityBuilder& builder) {
  const Index n = builder.num_nodes();
  const std::vector<std::pair<Index, Index>> pairs = builder.pairs();
  std::vector<Index> blocks_in_row(static_cast<size_t>(n), 0);
  for (const auto& [i, j] : pairs) ++blocks_in_row[i];

  A_.resize(3 * n, 3 * n);
  A_.resizeNonZeros(9 * static_cast<Eigen::Index>(pairs.size()));
  Index* outer = A_.outerIndexPtr();
  Index* inner = A_.innerIndexPtr();
  stride_.resize(static_cast<size_t>(n));
  outer[0] = 0;
  for (Index i = 0; i < n; ++i) {
    stride_[i] = 3 * blocks_in_row[i];
    for (int c = 0; c < 3; ++c) outer[3 * i + c + 1] = outer[3 * i + c] + stride_[i];
  }
  size_t p = 0;
  for (Index i = 0; i < n; ++i) {
    for (Index k = 0; k < blocks_in_row[i]; ++k, ++p) {
      const Index j = pairs[p].second;
      for (int c = 0; c < 3; ++c)
        for (int d = 0; d < 3; ++d) inner[outer[3 * i + c] + 3 * k + d] = 3 * j + d;
    }
  }
  A_.coeffs().setZero();
}

Index BlockSparseMatrix::block_offset(Index i, Index j) const {
  const Index begin = A_.outerIndexPtr()[3 * i];
  const Index* first = A_.innerIndexPtr() + begin;
  const Index* last = first + stride_[i];
  const Index* it = std::lower_bound(first, last, 3 * j);
  if (it == last || *it != 3 * j) return -1;
  return begin + static_cast<Index>(it - first);
}

}  // namespace depthfem
