#pragma once
/// Bounding-volume hierarchy of axis-aligned boxes (paper section 5.5): built top down by
/// splitting along the greatest extent, refit bottom up when the primitives move.

#include <Eigen/Geometry>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

using Box3 = Eigen::AlignedBox3d;

/// A binary tree over primitive boxes. Nodes are stored parents before children, so a reverse
/// sweep refits every node after its children.
class AabbTree {
 public:
  AabbTree() = default;
  /// Builds over `boxes` (one per primitive; primitive ids are their positions).
  explicit AabbTree(const std::vector<Box3>& boxes, int leaf_size = 4);

  /// Recomputes every node box from new primitive boxes (same count and order).
  void refit(const std::vector<Box3>& boxes);

  /// Calls visit(primitive) for every primitive whose box intersects `query`.
  template <class Visit>
  void query(const Box3& query, Visit&& visit) const {
    if (nodes_.empty()) return;
    Index stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top) {
      const Node& n = nodes_[stack[--top]];
      if (!n.box.intersects(query)) continue;
      if (n.count > 0) {
        for (Index k = n.first; k < n.first + n.count; ++k)
          if (boxes_[order_[k]].intersects(query)) visit(order_[k]);
      } else {
        stack[top++] = n.first;
        stack[top++] = n.first + 1;
      }
    }
  }

  /// Calls visit(primitive, lower_bound) for primitives in order of increasing box distance
  /// from p, while visit returns a bound (squared distance) that prunes the rest: the search
  /// for the nearest primitive by branch and bound.
  template <class Visit>
  void nearest(const Vec3& p, double best_squared, Visit&& visit) const {
    if (nodes_.empty()) return;
    Index stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top) {
      const Node& n = nodes_[stack[--top]];
      if (n.box.squaredExteriorDistance(p) >= best_squared) continue;
      if (n.count > 0) {
        for (Index k = n.first; k < n.first + n.count; ++k)
          if (boxes_[order_[k]].squaredExteriorDistance(p) < best_squared) best_squared = visit(order_[k], best_squared);
      } else {
        // Visit the nearer child first (pushed last).
        const double dl = nodes_[n.first].box.squaredExteriorDistance(p);
        const double dr = nodes_[n.first + 1].box.squaredExteriorDistance(p);
        stack[top++] = dl < dr ? n.first + 1 : n.first;
        stack[top++] = dl < dr ? n.first : n.first + 1;
      }
    }
  }

  Index size() const { return static_cast<Index>(boxes_.size()); }
  Index num_nodes() const { return static_cast<Index>(nodes_.size()); }

 private:
  struct Node {
    Box3 box;
    Index first = 0;  ///< leaf: first slot in order_; inner: index of the left child (right = +1)
    Index count = 0;  ///< leaf: number of primitives; inner: 0
  };
  void build(Index node, Index begin, Index end, int leaf_size, std::vector<Vec3>& centers);

  std::vector<Node> nodes_;
  std::vector<Index> order_;
  std::vector<Box3> boxes_;
};

/// Box of each tet of `tets` at positions x, grown by `margin` [m].
std::vector<Box3> tet_boxes(const Points& x, const TetIndices& tets, double margin = 0);
/// Box of each triangle of `tris` at positions x, grown by `margin` [m].
std::vector<Box3> triangle_boxes(const Points& x, const TriIndices& tris, double margin = 0);

}  // namespace depthfem
