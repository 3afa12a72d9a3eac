#pragma once
/// Partition of elements into spatially compact chunks, the chunks colored so that chunks of one
/// color share no node.

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <functional>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

/// Elements in processing order, cut into chunks, chunks grouped by color.
/// Chunk k holds order[chunk_begin[k] .. chunk_begin[k+1]); color c holds chunks
/// color_begin[c] .. color_begin[c+1]. Elements follow a Morton (Z-order) curve through their
/// centroids, so a chunk is a compact piece of the mesh and a kernel that walks it in order
/// reuses the node and matrix entries it scatters to while they are in cache. Chunks of one
/// color share no node: they can scatter concurrently without races, and with each chunk walked
/// in order and colors in order the result does not depend on the number of threads.
struct ElementPartition {
  std::vector<Index> order;
  std::vector<Index> chunk_begin;  ///< #chunks + 1 offsets into `order`
  std::vector<Index> color_begin;  ///< #colors + 1 offsets into chunks
  Index num_chunks() const { return static_cast<Index>(chunk_begin.size()) - 1; }
  Index num_colors() const { return static_cast<Index>(color_begin.size()) - 1; }
};

/// Partitions the elements given as rows of node indices, with one centroid per element, into
/// chunks of at most `chunk_size` elements, and colors the chunks greedily.
ElementPartition partition_elements(
    const Eigen::Ref<const Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic>>& elements,
    Index num_nodes, const Points& centroids, Index chunk_size = 1024);

/// Runs chunk(k) for every chunk k, colors one after the other (`color_begin`: #colors + 1 chunk
/// offsets) and the chunks of one color concurrently: they share no node, so they may add into
/// node data (gradients, matrix blocks) without races, each in its own order. Returns the sum of
/// what the calls return (T: double, a fixed-size Eigen vector), added in a fixed tree, one chunk
/// per leaf, so that results do not depend on the number of threads.
template <class T, class ChunkFn>
T run_by_color(const std::vector<Index>& color_begin, const T& zero, ChunkFn chunk) {
  T total = zero;
  for (size_t c = 0; c + 1 < color_begin.size(); ++c) {
    total += tbb::parallel_deterministic_reduce(
        tbb::blocked_range<Index>(color_begin[c], color_begin[c + 1], 1), zero,
        [&](const tbb::blocked_range<Index>& chunks, T acc) {
          for (Index k = chunks.begin(); k < chunks.end(); ++k) acc += chunk(k);
          return acc;
        },
        std::plus<T>());
  }
  return total;
}

}  // namespace depthfem
