#include "core/block_sparse_matrix.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <stdexcept>

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
  const std::vector<std::pair<Index, Index>> pairs = builder.pairs();
  row_begin_.assign(static_cast<size_t>(builder.num_nodes()) + 1, 0);
  col_.resize(pairs.size());
  for (size_t k = 0; k < pairs.size(); ++k) {
    ++row_begin_[pairs[k].first + 1];
    col_[k] = pairs[k].second;
  }
  for (Index i = 0; i < builder.num_nodes(); ++i) row_begin_[i + 1] += row_begin_[i];
  values_.assign(9 * pairs.size(), 0.0);
}

Index BlockSparseMatrix::block_index(Index i, Index j) const {
  const auto first = col_.begin() + row_begin_[i], last = col_.begin() + row_begin_[i + 1];
  const auto it = std::lower_bound(first, last, j);
  if (it == last || *it != j) return -1;
  return static_cast<Index>(it - col_.begin());
}

std::vector<Index> BlockSparseMatrix::clique_block_indices(
    const Eigen::Ref<const Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic>>& cliques) const {
  const Index rows = static_cast<Index>(cliques.rows()), K = static_cast<Index>(cliques.cols());
  std::vector<Index> off(static_cast<size_t>(rows) * K * K);
  std::atomic<bool> missing{false};
  tbb::parallel_for(
      tbb::blocked_range<Index>(0, rows, 4096), [&](const tbb::blocked_range<Index>& r) {
        for (Index e = r.begin(); e < r.end() && !missing.load(std::memory_order_relaxed); ++e)
          for (Index a = 0; a < K; ++a)
            for (Index b = 0; b < K; ++b) {
              const Index k = block_index(cliques(e, a), cliques(e, b));
              if (k < 0) missing = true;
              off[(static_cast<size_t>(e) * K + a) * K + b] = k;
            }
      });
  if (missing) off.clear();
  return off;
}

void BlockSparseMatrix::add_scaled(const BlockSparseMatrix& B, double s) {
  if (B.col_ != col_ || B.row_begin_ != row_begin_)
    throw std::logic_error("add_scaled: the patterns differ");
  for (size_t k = 0; k < values_.size(); ++k) values_[k] += s * B.values_[k];
}

void BlockSparseMatrix::multiply(const VectorX& x, VectorX& y) const {
  y.resize(3 * num_nodes());
  tbb::parallel_for(tbb::blocked_range<Index>(0, num_nodes(), 256),
                    [&](const tbb::blocked_range<Index>& r) {
                      for (Index i = r.begin(); i < r.end(); ++i) {
                        Vec3 s = Vec3::Zero();
                        for (Index k = row_begin_[i]; k < row_begin_[i + 1]; ++k)
                          s += block(k) * x.segment<3>(3 * col_[k]);
                        y.segment<3>(3 * i) = s;
                      }
                    });
}

VectorX BlockSparseMatrix::diagonal() const {
  VectorX d(3 * num_nodes());
  for (Index i = 0; i < num_nodes(); ++i) d.segment<3>(3 * i) = block(block_index(i, i)).diagonal();
  return d;
}

Eigen::SparseMatrix<double> BlockSparseMatrix::to_sparse() const {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(values_.size());
  for (Index i = 0; i < num_nodes(); ++i)
    for (Index k = row_begin_[i]; k < row_begin_[i + 1]; ++k)
      for (int c = 0; c < 3; ++c)
        for (int d = 0; d < 3; ++d)
          t.emplace_back(3 * i + c, 3 * col_[k] + d, values_[9 * k + 3 * c + d]);
  Eigen::SparseMatrix<double> A(3 * num_nodes(), 3 * num_nodes());
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

}  // namespace depthfem
