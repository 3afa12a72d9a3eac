#pragma once
/// Bounding-volume hierarchy of axis-aligned boxes (paper section 5.5): built top down by
/// splitting along the greatest extent, refit bottom up when the primitives move.

#include <Eigen/Geometry>
#include <span>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

using Box3 = Eigen::AlignedBox3d;

/// A binary tree over primitive boxes. Nodes are stored parents before children, so a reverse
/// sweep refits every node after its children; the primitive boxes are kept in leaf order, so a
/// leaf's boxes lie side by side in memory.
class AabbTree {
 public:
  AabbTree() = default;
  /// Builds over `boxes` (one per primitive; primitive ids are their positions).
  explicit AabbTree(std::span<const Box3> boxes, int leaf_size = 4);

  /// Recomputes every node box from new primitive boxes (same count and order).
  void refit(std::span<const Box3> boxes);

  /// Calls visit(primitive) for every primitive whose box intersects `query`.
  template <class Visit>
  void query(const Box3& query, Visit&& visit) const {
    walk([&](const Box3& b) { return !b.intersects(query); }, visit, query_order);
  }

  /// Every primitive, in the order query() visits them: each query visits a subsequence of it.
  std::vector<Index> walk_order() const {
    std::vector<Index> out;
    out.reserve(order_.size());
    walk([](const Box3&) { return false; }, [&](Index primitive) { out.push_back(primitive); },
         query_order);
    return out;
  }

  /// Calls visit(primitive, lower_bound) for primitives in order of increasing box distance
  /// from p, while visit returns a bound (squared distance) that prunes the rest: the search
  /// for the nearest primitive by branch and bound.
  template <class Visit>
  void nearest(const Vec3& p, double best_squared, Visit&& visit) const {
    walk([&](const Box3& b) { return b.squaredExteriorDistance(p) >= best_squared; },
         [&](Index primitive) { best_squared = visit(primitive, best_squared); },
         [&](const Box3& l, const Box3& r) {
           return l.squaredExteriorDistance(p) < r.squaredExteriorDistance(p);
         });
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
  /// The child order of query() and walk_order(): the same for every node, whatever the boxes.
  static bool query_order(const Box3&, const Box3&) { return false; }

  /// Depth-first walk that skips every node and primitive box `pruned(box)` rejects (it may
  /// tighten as the walk goes), calls visit(primitive) for the rest, and descends into the left
  /// child first where left_first(left box, right box) holds.
  template <class Pruned, class Visit, class LeftFirst>
  void walk(Pruned&& pruned, Visit&& visit, LeftFirst&& left_first) const {
    if (nodes_.empty()) return;
    Index stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top) {
      const Node& n = nodes_[stack[--top]];
      if (pruned(n.box)) continue;
      if (n.count > 0) {
        for (Index k = n.first; k < n.first + n.count; ++k)
          if (!pruned(boxes_[k])) visit(order_[k]);
      } else {
        const bool left = left_first(nodes_[n.first].box, nodes_[n.first + 1].box);
        stack[top++] = left ? n.first + 1 : n.first;  // the last pushed is visited first
        stack[top++] = left ? n.first : n.first + 1;
      }
    }
  }

  std::vector<Node> nodes_;
  std::vector<Index> order_;  ///< primitive in each leaf slot
  std::vector<Box3> boxes_;   ///< box of each leaf slot's primitive
};

/// Box of each tet of `tets` at positions x, grown by `margin` [m].
std::vector<Box3> tet_boxes(const Points& x, const TetIndices& tets, double margin = 0);
/// Box of each triangle of `tris` at positions x, grown by `margin` [m].
std::vector<Box3> triangle_boxes(const Points& x, const TriIndices& tris, double margin = 0);

}  // namespace depthfem
