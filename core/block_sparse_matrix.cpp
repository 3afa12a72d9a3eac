#include "core/block_sparse_matrix.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <iterator>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace depthfem {

void SparsityBuilder::add_clique(std::span<const Index> nodes) {
  for (Index a : nodes)
    for (Index b : nodes) pairs_.emplace_back(a, b);
}

namespace {

std::atomic<std::uint64_t> last_pattern_version{0};

// Rows of `count[i]` columns each, written by fill(i, first column) on both threads: the
// offsets by a prefix sum, then the rows in parallel (each row's work is its own).
template <class Fill>
SparsityBuilder::Rows rows_of(const std::vector<Index>& count, Fill fill) {
  const size_t n = count.size();
  SparsityBuilder::Rows out{std::vector<Index>(n + 1, 0), {}};
  size_t total = 0;
  for (size_t i = 0; i < n; ++i) {
    total += static_cast<size_t>(count[i]);
    if (total > static_cast<size_t>(std::numeric_limits<Index>::max() / 9))
      throw std::length_error("BlockSparseMatrix: more than 2^31 / 9 blocks");
    out.row_begin[i + 1] = static_cast<Index>(total);
  }
  out.col.resize(total);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const auto& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) fill(i, out.col.data() + out.row_begin[i]);
  });
  return out;
}

}  // namespace

// The pairs bucketed by row (a counting sort, linear in their number), then each row's columns
// deduplicated in place (a mark per column and thread: the cliques of contact pairs repeat a
// column many times in a row) and sorted, rows in parallel.
SparsityBuilder::Rows SparsityBuilder::rows() const {
  const size_t n = static_cast<size_t>(num_nodes_);
  std::vector<size_t> bucket(n + 1, 1);  // every row holds its diagonal
  bucket[0] = 0;
  for (const auto& [a, b] : pairs_) ++bucket[static_cast<size_t>(a) + 1];
  for (size_t i = 0; i < n; ++i) bucket[i + 1] += bucket[i];
  std::vector<Index> all(bucket[n]);
  std::vector<size_t> next(bucket.begin(), bucket.end() - 1);
  for (size_t i = 0; i < n; ++i) all[next[i]++] = static_cast<Index>(i);
  for (const auto& [a, b] : pairs_) all[next[static_cast<size_t>(a)]++] = b;
  std::vector<Index> count(n);
  tbb::enumerable_thread_specific<std::vector<Index>> marks(n, Index(-1));  // row last seen
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const auto& r) {
    std::vector<Index>& mark = marks.local();
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const auto first = all.begin() + static_cast<std::ptrdiff_t>(bucket[i]),
                 last = all.begin() + static_cast<std::ptrdiff_t>(bucket[i + 1]);
      auto unique_end = first;
      for (auto p = first; p != last; ++p) {
        Index& seen = mark[static_cast<size_t>(*p)];
        if (seen == static_cast<Index>(i)) continue;
        seen = static_cast<Index>(i);
        *unique_end++ = *p;
      }
      std::sort(first, unique_end);
      count[i] = static_cast<Index>(unique_end - first);
    }
  });
  return rows_of(count, [&](size_t i, Index* to) {
    std::copy_n(all.begin() + static_cast<std::ptrdiff_t>(bucket[i]), count[i], to);
  });
}

SparsityBuilder::Rows SparsityBuilder::merged(const Rows& a, const Rows& b) {
  if (a.row_begin.size() != b.row_begin.size())
    throw std::logic_error("SparsityBuilder::merged: patterns of different node counts");
  const size_t n = a.row_begin.size() - 1;
  const auto row = [](const Rows& p, size_t i) {
    return std::pair(p.col.begin() + p.row_begin[i], p.col.begin() + p.row_begin[i + 1]);
  };
  // The union's size per row: both rows' columns less those they share.
  std::vector<Index> count(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const auto& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      auto [p, p_end] = row(a, i);
      auto [q, q_end] = row(b, i);
      Index shared = 0;
      while (p != p_end && q != q_end) {
        if (*p < *q) {
          ++p;
        } else if (*q < *p) {
          ++q;
        } else {
          ++shared, ++p, ++q;
        }
      }
      count[i] =
          (a.row_begin[i + 1] - a.row_begin[i]) + (b.row_begin[i + 1] - b.row_begin[i]) - shared;
    }
  });
  return rows_of(count, [&](size_t i, Index* to) {
    const auto [p, p_end] = row(a, i);
    const auto [q, q_end] = row(b, i);
    std::set_union(p, p_end, q, q_end, to);
  });
}

BlockSparseMatrix::BlockSparseMatrix(const SparsityBuilder& builder)
    : BlockSparseMatrix(builder.rows()) {}

BlockSparseMatrix::BlockSparseMatrix(SparsityBuilder::Rows rows)
    : row_begin_(std::move(rows.row_begin)),
      col_(std::move(rows.col)),
      pattern_version_(++last_pattern_version) {
  // Scalar views index 9 values per block with Index (rows() and merged() refuse more).
  values_.assign(9 * col_.size(), 0.0);
}

std::vector<Index> BlockSparseMatrix::block_map(const BlockSparseMatrix& other) const {
  if (other.num_nodes() != num_nodes())
    throw std::logic_error("BlockSparseMatrix::block_map: patterns of different node counts");
  std::vector<Index> to(col_.size(), -1);
  tbb::parallel_for(tbb::blocked_range<Index>(0, num_nodes(), 256), [&](const auto& r) {
    for (Index i = r.begin(); i < r.end(); ++i) {
      Index k = other.row_begin_[i];
      for (Index m = row_begin_[i]; m < row_begin_[i + 1]; ++m) {
        while (k < other.row_begin_[i + 1] && other.col_[k] < col_[m]) ++k;
        if (k < other.row_begin_[i + 1] && other.col_[k] == col_[m]) to[m] = k;
      }
    }
  });
  return to;
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
  // Each row of a clique's nodes walked once against the clique's nodes in ascending order: a
  // merge, where a binary search per pair branches unpredictably.
  tbb::parallel_for(
      tbb::blocked_range<Index>(0, rows, 4096), [&](const tbb::blocked_range<Index>& r) {
        std::vector<Index> by_node(static_cast<size_t>(K));  // clique positions by node
        for (Index e = r.begin(); e < r.end() && !missing.load(std::memory_order_relaxed); ++e) {
          std::iota(by_node.begin(), by_node.end(), Index(0));
          std::ranges::sort(by_node, {}, [&](Index b) { return cliques(e, b); });
          for (Index a = 0; a < K; ++a) {
            const Index i = cliques(e, a), end = row_begin_[i + 1];
            Index k = row_begin_[i];
            for (Index b : by_node) {
              const Index j = cliques(e, b);
              while (k < end && col_[k] < j) ++k;
              const bool found = k < end && col_[k] == j;
              if (!found) missing = true;
              off[(static_cast<size_t>(e) * K + a) * K + b] = found ? k : -1;
            }
          }
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

// Row 3i+c holds, for every block k = (i, j) of block row i, the entries (3i+c, 3j+d) =
// values[9k + 3c + d]; the upper triangle keeps j > i, and d >= c in the diagonal block.
ScalarPattern BlockSparseMatrix::scalar_pattern(Triangle triangle,
                                                std::vector<char> decoupled) const {
  const bool upper = triangle == Triangle::kUpper;
  ScalarPattern p;
  p.triangle = triangle;
  p.decoupled = std::move(decoupled);
  p.row_begin.assign(3 * static_cast<size_t>(num_nodes()) + 1, 0);
  for (Index i = 0; i < num_nodes(); ++i)
    for (int c = 0; c < 3; ++c) {
      Index n = 0;
      for (Index k = row_begin_[i]; k < row_begin_[i + 1]; ++k)
        if (!p.keeps(i, col_[k]))
          continue;
        else if (!upper || col_[k] > i)
          n += 3;
        else if (col_[k] == i)
          n += 3 - c;
      p.row_begin[3 * i + c + 1] = p.row_begin[3 * i + c] + n;
    }
  p.col.resize(p.row_begin.back());
  for (Index i = 0; i < num_nodes(); ++i)
    for (int c = 0; c < 3; ++c) {
      Index q = p.row_begin[3 * i + c];
      for (Index k = row_begin_[i]; k < row_begin_[i + 1]; ++k) {
        const Index j = col_[k];
        if ((upper && j < i) || !p.keeps(i, j)) continue;
        for (int d = upper && j == i ? c : 0; d < 3; ++d) p.col[q++] = 3 * j + d;
      }
    }
  return p;
}

void BlockSparseMatrix::scalar_values(const ScalarPattern& pattern, double* out) const {
  const bool upper = pattern.triangle == Triangle::kUpper;
  tbb::parallel_for(tbb::blocked_range<Index>(0, num_nodes(), 512),
                    [&](const tbb::blocked_range<Index>& r) {
                      for (Index i = r.begin(); i < r.end(); ++i)
                        for (int c = 0; c < 3; ++c) {
                          double* o = out + pattern.row_begin[3 * i + c];
                          for (Index k = row_begin_[i]; k < row_begin_[i + 1]; ++k) {
                            const Index j = col_[k];
                            if ((upper && j < i) || !pattern.keeps(i, j)) continue;
                            const double* v = values_.data() + 9 * static_cast<size_t>(k) + 3 * c;
                            for (int d = upper && j == i ? c : 0; d < 3; ++d) *o++ = v[d];
                          }
                        }
                    });
}

}  // namespace depthfem
