#pragma once
/// Greedy coloring of elements so that no two elements of one color share a node.

#include <span>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

/// Elements grouped by color: `order` lists element positions color by color, and color c spans
/// order[begin[c] .. begin[c+1]). Elements of one color share no node, so a kernel may scatter
/// into per-node storage from all of them at once without races, and results do not depend on
/// the number of threads.
struct ElementColoring {
  std::vector<Index> order;
  std::vector<Index> begin;  ///< #colors + 1 offsets into `order`
  Index num_colors() const { return static_cast<Index>(begin.size()) - 1; }
};

/// Colors the elements given as rows of `elements` (node indices, one row per element) greedily in
/// row order: each element takes the smallest color unused by earlier elements sharing a node.
/// Within a color, elements keep their original relative order.
ElementColoring color_elements(const Eigen::Ref<const Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic>>& elements,
                               Index num_nodes);

}  // namespace depthfem
