#pragma once
/// Frictionless penalty contact with the material-depth gap (paper section 5): every boundary
/// triangle against every tet of another body (and of its own body, for self-contact), the
/// penalty eps/2 g^2 integrated exactly over their intersection polygon. Pairs of two rigid
/// bodies (a body against itself included) are not searched: all their nodes are prescribed, so
/// they exert no force on an unknown. Nor are the interfaces a scene excludes (ContactOptions).

#include <array>
#include <functional>
#include <span>
#include <vector>

#include "contact/aabb_tree.hpp"
#include "contact/clip.hpp"
#include "contact/contact_interfaces.hpp"
#include "contact/pair_schedule.hpp"
#include "contact/penalty_derivatives.hpp"
#include "core/force_module.hpp"
#include "core/mesh.hpp"

namespace depthfem {

struct ContactOptions {
  double penalty = 1e6;      ///< eps [Pa/m]: contact pressure per metre of material depth
  bool self_contact = true;  ///< triangles against the tets of their own body
  /// Pairs of bodies (a <= b; a == b: self-contact) not searched: interfaces that boundary
  /// conditions hold together, such as a tissue attached to a bone, whose coinciding surfaces
  /// only touch. Their report rows stay, at zero.
  std::vector<std::array<Index, 2>> excluded = {};
  /// The candidate list's margin per mean edge length (bench/results/knee.md, third round); 0
  /// searches the refitted trees at every prepare() where a node has moved.
  double list_margin = 0.1;
};

/// A boundary triangle cutting a tet, with the polygon they share.
struct ContactPair {
  Index tri = 0, tet = 0;
  ClipPolygon polygon;
};

/// A triangle's net force from the pairs it forms with the tets of one body, with the area and
/// depth integral of those pairs' polygons: what report() writes for the triangle.
struct ContactShare {
  Index tri = 0, body = 0;
  Vec3 force = Vec3::Zero();  ///< [N] on the triangle's body
  double area = 0;            ///< [m^2]
  double depth_integral = 0;  ///< [m^3]
};

/// A distributed run's part of the contact: the trees hold, prepare() lists and clips, and
/// pairs() and evaluate() hold only the tets `owned` marks 1 (#tets; this rank's) and their
/// pairs; report() merges every rank's shares, which `concatenate` brings together.
struct ContactPart {
  std::vector<char> owned;
  /// Every rank's values (7 per share) one after another, rank 0's first, on every rank.
  std::function<std::vector<double>(const std::vector<double>&)> concatenate;
};

/// How many pairs the last prepare() examined and kept.
struct ContactStats {
  Index candidates = 0;   ///< triangle-tet pairs whose boxes overlap
  Index active = 0;       ///< pairs with an intersection polygon of non-zero area
  Index listed = 0;       ///< pairs on the candidate list (boxes within twice the list margin)
  bool relisted = false;  ///< whether this prepare() brought the list up to date
  Index searched_triangles = 0;  ///< triangles whose candidates it searched the trees for
};

/// The contact force module. Geometry (tree, clipping, depth lookup) lives in aabb_tree, clip
/// and material_depth; this class pairs elements and integrates the penalty (penalty.hpp).
/// Pair search and integration run in parallel. The trees are searched for a candidate list,
/// each triangle's tets whose boxes come within twice a margin of its box; prepare() tests only
/// the listed pairs' boxes and searches the trees again only when some node has moved farther
/// than the margin since the list took it (or at begin_step): where a few nodes have, only for
/// the triangles and tets of those nodes (bench/results/knee.md, tenth round). The pairs are
/// those a search of the trees at every call finds, in the same order. prepare() orders the pairs
/// (PairSchedule) and finds their 49 Hessian blocks each in the bound pattern; evaluate() adds each
/// pair's derivatives as it computes them, chunks of a color concurrently, without searching or
/// allocating. Every block and gradient entry receives its terms in pair order, whatever the
/// number of threads.
class MaterialDepthContact final : public ForceModule {
 public:
  /// `depth` per node [m] (material_depth(mesh)); `part`: a distributed run's (empty: all).
  MaterialDepthContact(const Mesh& mesh, VectorX depth, ContactOptions options,
                       ContactPart part = {});

  std::string name() const override { return "contact"; }
  void begin_step(const Points& x) override;
  void prepare(const Points& x) override;
  void add_couplings(SparsityBuilder& builder) const override;
  void bind(const BlockSparseMatrix& hessian) override;
  bool pattern_changed() const override { return pattern_changed_; }
  double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const override;
  /// One row per interface (ContactInterfaces): every pair of bodies "a/b" and, with
  /// self-contact, every body against itself "a (self)"; areas are those of the clipped
  /// triangles that press (some depth inside the tet). A triangle's pairs are netted per body it
  /// enters (the in-plane pulls of the pieces a triangle is cut into cancel), and each net force,
  /// with its area and depth integral, goes to the interface's row and to the triangle in
  /// step.surface.
  void report(const Points& x, StepRecord& step) const override;
  std::vector<std::string> interface_names() const override { return interfaces_.names(); }

  /// The shares of pairs() at x, merged: by triangle, the bodies of a triangle in the order its
  /// first pair with each comes.
  std::vector<ContactShare> shares(const Points& x) const;
  /// Shares of several ranks, one after another, merged: by triangle, the same (triangle, body)
  /// summed in the order they come.
  static std::vector<ContactShare> merge(std::span<const ContactShare> shares);
  /// The interface rows and step.surface from the shares of every pair.
  void report_shares(std::span<const ContactShare> shares, StepRecord& step) const;

  /// The active pairs of the last prepare(), in processing order.
  const std::vector<ContactPair>& pairs() const { return pairs_; }
  ContactStats stats() const { return stats_; }
  /// [m] how far a node may move from where the candidate list took it before it is taken anew.
  double list_margin() const { return margin_; }
  /// Triangle f's tets on the candidate list, in the order a search of the trees visits them.
  std::span<const Index> candidates(Index f) const {
    const auto begin = listed_.tets.begin() + listed_.start[static_cast<size_t>(f)];
    return {begin, begin + (listed_.start[static_cast<size_t>(f) + 1] -
                            listed_.start[static_cast<size_t>(f)])};
  }

  /// Energy of one pair (returned), its gradient (21) and, where `hessian` is not null, its
  /// Hessian (21 x 21); variables: tet corners 0..11, triangle corners 12..20.
  double pair_derivatives(const Points& x, const ContactPair& p, PairGradient& gradient,
                          PairHessian* hessian) const;
  double pair_energy(const Points& x, const ContactPair& p) const;

 private:
  std::array<Index, 7> pair_nodes(const ContactPair& p) const;
  std::array<double, 4> pair_depths(const ContactPair& p) const;

  TetIndices tets_;
  TriIndices tris_;
  IndexVector tet_body_, tri_body_;
  VectorX depth_;
  ContactOptions options_;
  double min_area2_ = 0;
  /// Builds trees_ over the (owned) tets of each body at positions x, and walk_rank_.
  void build_trees(const Points& x);
  /// Per triangle (compressed rows), the tets whose boxes at listed_x_ overlap the triangle's
  /// grown by twice the margin, in the order a search of the trees visits them (walk_rank_).
  struct CandidateList {
    std::vector<Index> start, tets;
  };
  /// The boxes of tree b's tets, in its primitive order.
  std::vector<Box3> tree_boxes(const std::vector<Box3>& boxes, size_t b) const;
  /// Refits trees_ to the tets' boxes at listed_x_ (`boxes`, of all tets) and returns the
  /// triangles' boxes there, grown by twice the margin.
  std::vector<Box3> refit_to_listed(const std::vector<Box3>& boxes);
  /// Appends triangle f's candidate tets at listed_x_ (`grown`: its grown box) to `out`.
  void search(Index f, const Box3& grown, std::vector<Index>& out) const;
  /// Whether triangle f and tet t are neighbours in the mesh (one body, a shared node): never
  /// in contact.
  bool neighbours(Index f, Index t) const;
  /// Whether triangle f and tet t are a candidate pair: of searched bodies, not neighbours.
  bool pairable(Index f, Index t) const;
  /// Lists every triangle's candidate tets at listed_x_ (`boxes`: the tets' there) into listed_.
  void list_candidates(const std::vector<Box3>& boxes);
  /// Brings listed_ up to date after the nodes `moved` (a few) were given new places in
  /// listed_x_: the triangles with such a node are searched again, and the tets with one are
  /// looked up among the other triangles (a tree over their boxes); the rest of the list stays.
  /// `boxes`: the tets' boxes at listed_x_.
  void update_candidates(const std::vector<Index>& moved, const std::vector<Box3>& boxes);
  /// The pairs of `list` at x (tets' boxes `boxes`) whose clipped polygon has area, in triangle
  /// order. `candidates`: the pairs clipped.
  std::vector<ContactPair> clip(const Points& x, const std::vector<Box3>& boxes,
                                const CandidateList& list, Index& candidates) const;
  /// Whether triangles of body a are searched against tets of body b.
  bool searched(Index a, Index b) const;

  std::vector<Body> bodies_;
  std::vector<AabbTree> trees_;  // per body over its (owned) tets, primitive k: tree_tets_[k]
  std::vector<std::vector<Index>> tree_tets_;  // per body
  std::vector<Index> walk_rank_;  // per tet: its place in its tree's walk order (-1: no tree)
  double margin_ = 0;             // [m] a node may move this far before the list is made anew
  Points listed_x_;               // each node's place when the list last took it (empty: no list)
  CandidateList listed_;          // made at listed_x_
  std::vector<ContactPair> pairs_;
  PairSchedule schedule_;  // of pairs_: tet corners, triangle corners
  ContactStats stats_;
  ContactInterfaces interfaces_;
  ContactPart part_;
  const BlockSparseMatrix* bound_ = nullptr;
  bool pattern_changed_ = false;
};

}  // namespace depthfem
