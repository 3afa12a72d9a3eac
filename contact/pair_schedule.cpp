#include "contact/pair_schedule.hpp"

#include <algorithm>
#include <stdexcept>

namespace depthfem {

namespace {
constexpr Index kChunk = 256;  // pairs per chunk; fixed for reproducible results

// The rows of a and b, sorted, without repeats.
PairSchedule::Nodes sorted_union(const PairSchedule::Nodes& a, const PairSchedule::Nodes& b) {
  const Index K = std::max(a.cols(), b.cols());
  std::vector<const Index*> rows;
  rows.reserve(static_cast<size_t>(a.rows() + b.rows()));
  // Rows of a column-major matrix are strided: copy both into one row-major block first.
  std::vector<Index> flat(static_cast<size_t>((a.rows() + b.rows()) * K));
  Index r = 0;
  for (const PairSchedule::Nodes* m : {&a, &b})
    for (Index k = 0; k < m->rows(); ++k, ++r)
      for (Index c = 0; c < K; ++c) flat[static_cast<size_t>(r * K + c)] = (*m)(k, c);
  for (Index k = 0; k < r; ++k) rows.push_back(flat.data() + k * K);
  const auto less = [K](const Index* x, const Index* y) {
    return std::lexicographical_compare(x, x + K, y, y + K);
  };
  std::sort(rows.begin(), rows.end(), less);
  rows.erase(std::unique(rows.begin(), rows.end(),
                         [K](const Index* x, const Index* y) { return std::equal(x, x + K, y); }),
             rows.end());
  PairSchedule::Nodes out(static_cast<Index>(rows.size()), K);
  for (Index k = 0; k < out.rows(); ++k)
    for (Index c = 0; c < K; ++c) out(k, c) = rows[static_cast<size_t>(k)][c];
  return out;
}
}  // namespace

std::vector<Index> PairSchedule::arrange(const Nodes& nodes, const Points& centres, Index num_nodes,
                                         const BlockSparseMatrix* bound) {
  const ElementPartition part = partition_elements(nodes, num_nodes, centres, kChunk);
  nodes_.resize(nodes.rows(), nodes.cols());
  for (Index k = 0; k < nodes.rows(); ++k) nodes_.row(k) = nodes.row(part.order[k]);
  chunk_begin_ = part.chunk_begin;
  color_begin_ = part.color_begin;
  blocks_ = bound ? bound->clique_block_indices(nodes_) : std::vector<Index>();
  if (!has_blocks()) {
    kept_ = sorted_union(kept_, nodes_);
    if (kept_.rows() > 2 * nodes_.rows()) kept_ = sorted_union(nodes_, Nodes(0, nodes_.cols()));
  }
  return part.order;
}

void PairSchedule::add_couplings(SparsityBuilder& builder) const {
  for (const Nodes* cliques : {&nodes_, &kept_}) {
    std::vector<Index> clique(static_cast<size_t>(cliques->cols()));
    for (Index k = 0; k < cliques->rows(); ++k) {
      for (Index c = 0; c < cliques->cols(); ++c) clique[static_cast<size_t>(c)] = (*cliques)(k, c);
      builder.add_clique(clique);
    }
  }
}

void PairSchedule::bind(const BlockSparseMatrix& hessian, const std::string& module) {
  blocks_ = hessian.clique_block_indices(nodes_);
  if (!has_blocks())
    throw std::logic_error(module + ": the Hessian pattern lacks a pair's coupling");
}

}  // namespace depthfem
