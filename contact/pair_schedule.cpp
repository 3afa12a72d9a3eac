#include "contact/pair_schedule.hpp"

#include <stdexcept>

namespace depthfem {

namespace {
constexpr Index kChunk = 256;  // pairs per chunk; fixed for reproducible results
}  // namespace

std::vector<Index> PairSchedule::arrange(const Nodes& nodes, const Points& centres, Index num_nodes,
                                         const BlockSparseMatrix* bound) {
  const ElementPartition part = partition_elements(nodes, num_nodes, centres, kChunk);
  nodes_.resize(nodes.rows(), nodes.cols());
  for (Index k = 0; k < nodes.rows(); ++k) nodes_.row(k) = nodes.row(part.order[k]);
  chunk_begin_ = part.chunk_begin;
  color_begin_ = part.color_begin;
  blocks_ = bound ? bound->clique_block_indices(nodes_) : std::vector<Index>();
  return part.order;
}

void PairSchedule::bind(const BlockSparseMatrix& hessian, const std::string& module) {
  blocks_ = hessian.clique_block_indices(nodes_);
  if (!has_blocks())
    throw std::logic_error(module + ": the Hessian pattern lacks a pair's coupling");
}

}  // namespace depthfem
