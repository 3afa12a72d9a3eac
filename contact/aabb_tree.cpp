#include "contact/aabb_tree.hpp"

#include <algorithm>
#include <stdexcept>

namespace depthfem {

AabbTree::AabbTree(std::span<const Box3> boxes, int leaf_size) : boxes_(boxes.size()) {
  const Index n = static_cast<Index>(boxes.size());
  order_.resize(static_cast<size_t>(n));
  for (Index i = 0; i < n; ++i) order_[i] = i;
  if (n == 0) return;
  std::vector<Vec3> centers(static_cast<size_t>(n));
  for (Index i = 0; i < n; ++i) centers[i] = boxes[i].center();
  nodes_.reserve(2 * static_cast<size_t>(n) / std::max(1, leaf_size) + 1);
  nodes_.emplace_back();
  build(0, 0, n, leaf_size, centers);
  refit(boxes);
}

// Splits order_[begin, end) at the median of the centres along the axis of greatest extent.
// Children are appended as a pair, so the tree depth stays about log2(n / leaf_size).
void AabbTree::build(Index node, Index begin, Index end, int leaf_size,
                     std::vector<Vec3>& centers) {
  if (end - begin <= leaf_size) {
    nodes_[node].first = begin;
    nodes_[node].count = end - begin;
    return;
  }
  Box3 extent;
  for (Index k = begin; k < end; ++k) extent.extend(centers[order_[k]]);
  int axis;
  extent.sizes().maxCoeff(&axis);
  const Index mid = (begin + end) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](Index a, Index b) { return centers[a](axis) < centers[b](axis); });
  const Index left = static_cast<Index>(nodes_.size());
  nodes_.emplace_back();
  nodes_.emplace_back();
  nodes_[node].first = left;
  nodes_[node].count = 0;
  build(left, begin, mid, leaf_size, centers);
  build(left + 1, mid, end, leaf_size, centers);
}

void AabbTree::refit(std::span<const Box3> boxes) {
  if (boxes.size() != boxes_.size())
    throw std::logic_error("AabbTree::refit: primitive count changed");
  for (size_t k = 0; k < boxes_.size(); ++k) boxes_[k] = boxes[static_cast<size_t>(order_[k])];
  for (Index i = num_nodes() - 1; i >= 0; --i) {
    Node& n = nodes_[i];
    n.box.setEmpty();
    if (n.count > 0) {
      for (Index k = n.first; k < n.first + n.count; ++k) n.box.extend(boxes_[k]);
    } else {
      n.box.extend(nodes_[n.first].box);
      n.box.extend(nodes_[n.first + 1].box);
    }
  }
}

namespace {
template <class Indices>
std::vector<Box3> element_boxes(const Points& x, const Indices& elements, double margin) {
  std::vector<Box3> out(static_cast<size_t>(elements.rows()));
  for (Index e = 0; e < elements.rows(); ++e) {
    Box3 b;
    for (Eigen::Index k = 0; k < elements.cols(); ++k) b.extend(Vec3(x.row(elements(e, k))));
    out[e] = Box3(b.min().array() - margin, b.max().array() + margin);
  }
  return out;
}
}  // namespace

std::vector<Box3> tet_boxes(const Points& x, const TetIndices& tets, double margin) {
  return element_boxes(x, tets, margin);
}
std::vector<Box3> triangle_boxes(const Points& x, const TriIndices& tris, double margin) {
  return element_boxes(x, tris, margin);
}

}  // namespace depthfem
