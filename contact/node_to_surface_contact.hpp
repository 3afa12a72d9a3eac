#pragma once
/// The baseline the paper argues against: node-to-surface penalty with a projection-based gap.
/// A boundary node found inside another body is pushed out along the normal of the nearest
/// boundary triangle of that body with energy eps A_i / 2 g^2, g = n . (Q_0 - x_i) (A_i: the
/// node's share of boundary area). The nearest triangle, and so the force direction, jumps as
/// nodes slide across edges: the force is discontinuous in x.

#include <vector>

#include "contact/aabb_tree.hpp"
#include "contact/contact_interfaces.hpp"
#include "contact/dual.hpp"
#include "contact/pair_schedule.hpp"
#include "core/force_module.hpp"
#include "core/mesh.hpp"

namespace depthfem {

class NodeToSurfaceContact final : public ForceModule {
 public:
  NodeToSurfaceContact(const Mesh& mesh, double penalty);

  std::string name() const override { return "node-to-surface contact"; }
  void begin_step(const Points& x) override;
  void prepare(const Points& x) override;
  void add_couplings(SparsityBuilder& builder) const override;
  void bind(const BlockSparseMatrix& hessian) override;
  bool pattern_changed() const override { return pattern_changed_; }
  double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const override;
  /// One row per pair of bodies "a/b" (ContactInterfaces); a pair's area is the boundary area
  /// share of its node.
  void report(const Points& x, StepRecord& step) const override;
  std::vector<std::string> interface_names() const override { return interfaces_.names(); }

  /// Active (node, triangle) pairs of the last prepare(), in processing order (PairSchedule).
  const std::vector<std::pair<Index, Index>>& pairs() const { return pairs_; }

 private:
  /// Energy of pair k (processing order) without derivatives.
  double pair_energy(const Points& x, Index k) const;
  /// Energy of node i against triangle f with derivatives in (node, triangle corners).
  Dual2<12> pair_derivatives(const Points& x, Index i, Index f) const;

  TetIndices tets_;
  TriIndices tris_;
  IndexVector tet_body_, tri_body_;
  std::vector<Index> surface_nodes_;  // nodes on some boundary triangle
  IndexVector node_body_;
  VectorX node_area_;  // boundary area share per node [m^2]
  double penalty_;
  AabbTree tet_tree_, tri_tree_;
  std::vector<std::pair<Index, Index>> pairs_;
  ContactInterfaces interfaces_;
  PairSchedule schedule_;  // of pairs_: node, triangle corners
  const BlockSparseMatrix* bound_ = nullptr;
  bool pattern_changed_ = false;
};

}  // namespace depthfem
