#include "contact/material_depth_contact.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <stdexcept>

#include "contact/penalty.hpp"
#include "core/lumped_mass.hpp"

namespace depthfem {

namespace {
constexpr Index kChunk = 256;  // triangles per task of the pair search

std::array<Vec3, 4> tet_corners(const Points& x, const TetIndices& tets, Index t) {
  return {x.row(tets(t, 0)), x.row(tets(t, 1)), x.row(tets(t, 2)), x.row(tets(t, 3))};
}
std::array<Vec3, 3> tri_corners(const Points& x, const TriIndices& tris, Index f) {
  return {x.row(tris(f, 0)), x.row(tris(f, 1)), x.row(tris(f, 2))};
}
}  // namespace

MaterialDepthContact::MaterialDepthContact(const Mesh& mesh, VectorX depth, ContactOptions options)
    : tets_(mesh.tets),
      tris_(mesh.tris),
      tet_body_(mesh.tet_body),
      tri_body_(mesh.tri_body),
      depth_(std::move(depth)),
      options_(options) {
  // Sub-triangles with area below 1e-12 of a typical element face count as degenerate.
  const double h = mean_edge_length(mesh.X, mesh.tets);
  min_area2_ = std::pow(1e-12 * h * h, 2);
  tree_ = AabbTree(tet_boxes(mesh.X, tets_));
}

std::array<Index, 7> MaterialDepthContact::pair_nodes(const ContactPair& p) const {
  return {tets_(p.tet, 0), tets_(p.tet, 1), tets_(p.tet, 2), tets_(p.tet, 3),
          tris_(p.tri, 0), tris_(p.tri, 1), tris_(p.tri, 2)};
}

void MaterialDepthContact::begin_step(const Points& x, double) {
  tree_ = AabbTree(tet_boxes(x, tets_));
}

void MaterialDepthContact::prepare(const Points& x) {
  tree_.refit(tet_boxes(x, tets_));
  const Index n = static_cast<Index>(tris_.rows());
  const Index chunks = (n + kChunk - 1) / kChunk;
  std::vector<std::vector<ContactPair>> found(static_cast<size_t>(chunks));
  std::vector<Index> candidates(static_cast<size_t>(chunks), 0);
  tbb::parallel_for(Index(0), chunks, [&](Index c) {
    for (Index f = c * kChunk; f < std::min(n, (c + 1) * kChunk); ++f) {
      const std::array<Vec3, 3> Q = tri_corners(x, tris_, f);
      Box3 box;
      for (const Vec3& q : Q) box.extend(q);
      tree_.query(box, [&](Index t) {
        if (tet_body_(t) == tri_body_(f)) {
          if (!options_.self_contact) return;
          for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 3; ++b)
              if (tets_(t, a) == tris_(f, b)) return;  // shares a node: never in contact
        }
        ++candidates[c];
        ClipPolygon poly = clip_triangle_by_tet(tet_corners(x, tets_, t), Q);
        if (poly.size >= 3) found[c].push_back({f, t, poly});
      });
    }
  });
  std::vector<ContactPair> all;
  stats_ = ContactStats{};
  for (Index c = 0; c < chunks; ++c) {
    all.insert(all.end(), found[c].begin(), found[c].end());
    stats_.candidates += candidates[c];
  }
  const Index n_pairs = static_cast<Index>(all.size());
  stats_.active = n_pairs;
  // Processing order: along a Morton curve through the polygons' centres, in colored chunks.
  PairSchedule::Nodes nodes(n_pairs, 7);
  Points centres(n_pairs, 3);
  for (Index k = 0; k < n_pairs; ++k) {
    const ContactPair& p = all[k];
    nodes.row(k) = Eigen::Map<const Eigen::Matrix<Index, 1, 7>>(pair_nodes(p).data());
    Vec3 centre = Vec3::Zero();
    for (int v = 0; v < p.polygon.size; ++v) centre += p.polygon.x[v];
    centres.row(k) = centre.transpose() / p.polygon.size;
    for (int v = 1; v + 1 < p.polygon.size; ++v)
      stats_.area +=
          0.5 * (p.polygon.x[v] - p.polygon.x[0]).cross(p.polygon.x[v + 1] - p.polygon.x[0]).norm();
  }
  const std::vector<Index> order =
      schedule_.arrange(nodes, centres, static_cast<Index>(depth_.size()), bound_);
  pairs_.resize(all.size());
  for (Index k = 0; k < n_pairs; ++k) pairs_[k] = all[order[k]];
  // A pair whose nodes are not coupled in the bound pattern needs a new one (bind() follows).
  pattern_changed_ = bound_ && !schedule_.has_blocks();
}

void MaterialDepthContact::add_couplings(SparsityBuilder& builder) const {
  for (const ContactPair& p : pairs_) {
    const std::array<Index, 7> v = pair_nodes(p);
    builder.add_clique(v);
  }
}

void MaterialDepthContact::bind(const BlockSparseMatrix& hessian) {
  bound_ = &hessian;
  pattern_changed_ = false;
  schedule_.bind(hessian, name());
}

std::array<double, 4> MaterialDepthContact::pair_depths(const ContactPair& p) const {
  return {depth_(tets_(p.tet, 0)), depth_(tets_(p.tet, 1)), depth_(tets_(p.tet, 2)),
          depth_(tets_(p.tet, 3))};
}

double MaterialDepthContact::pair_energy(const Points& x, const ContactPair& p) const {
  std::array<V3<double>, 4> P;
  std::array<V3<double>, 3> Q;
  for (int a = 0; a < 4; ++a) P[a] = make_point<double>(x.row(tets_(p.tet, a)), 0);
  for (int b = 0; b < 3; ++b) Q[b] = make_point<double>(x.row(tris_(p.tri, b)), 0);
  return tet_polygon_penalty(p.polygon, P, Q, pair_depths(p), options_.penalty, min_area2_);
}

double MaterialDepthContact::pair_derivatives(const Points& x, const ContactPair& p,
                                              PairGradient& gradient, PairHessian* hessian) const {
  return tet_polygon_penalty_derivatives(p.polygon, tet_corners(x, tets_, p.tet),
                                         tri_corners(x, tris_, p.tri), pair_depths(p),
                                         options_.penalty, min_area2_, gradient, hessian);
}

double MaterialDepthContact::evaluate(const Points& x, VectorX* gradient,
                                      BlockSparseMatrix* hessian) const {
  if (!gradient) return schedule_.run(0.0, [&](Index k) { return pair_energy(x, pairs_[k]); });
  if (hessian && !schedule_.has_blocks())
    throw std::logic_error("contact: bind() the Hessian after prepare() found new pairs");
  // Each pair's derivatives are added as soon as they are computed; energy and force sum.
  const Eigen::Vector2d sums = schedule_.run(Eigen::Vector2d(0, 0), [&](Index k) {
    PairGradient grad;
    PairHessian hess;
    const double energy = pair_derivatives(x, pairs_[k], grad, hessian ? &hess : nullptr);
    for (int a = 0; a < 7; ++a)
      gradient->segment<3>(3 * schedule_.node(k, a)) += grad.segment<3>(3 * a);
    if (hessian) hessian->add_blocks<7>(schedule_.blocks(k), hess);
    return Eigen::Vector2d(energy, grad.tail<9>().reshaped(3, 3).rowwise().sum().norm());
  });
  stats_.force = sums(1);
  return sums(0);
}

}  // namespace depthfem
