#include "contact/material_depth_contact.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <functional>

#include "contact/penalty.hpp"
#include "core/lumped_mass.hpp"

namespace depthfem {

namespace {
constexpr Index kChunk = 256;  // triangles (or pairs) per task; fixed for reproducible results

std::array<Vec3, 4> tet_corners(const Points& x, const TetIndices& tets, Index t) {
  return {x.row(tets(t, 0)), x.row(tets(t, 1)), x.row(tets(t, 2)), x.row(tets(t, 3))};
}
std::array<Vec3, 3> tri_corners(const Points& x, const TriIndices& tris, Index f) {
  return {x.row(tris(f, 0)), x.row(tris(f, 1)), x.row(tris(f, 2))};
}

// True when some fan triangle of the polygon counts (fan_triangle_counts). A polygon without one
// (a triangle touching a tet along an edge or at a point, as where bodies rest on each other)
// adds nothing to the energy or its derivatives, so it is not kept as a pair: it would only
// cost clipping, integration and couplings in the Hessian pattern.
bool has_area(const ClipPolygon& poly, double min_area2) {
  for (int k = 1; k + 1 < poly.size; ++k) {
    const Vec3 c = (poly.x[k] - poly.x[0]).cross(poly.x[k + 1] - poly.x[0]);
    if (fan_triangle_counts(c.squaredNorm(), min_area2)) return true;
  }
  return false;
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
        if (poly.size >= 3 && has_area(poly, min_area2_)) found[c].push_back({f, t, poly});
      });
    }
  });
  pairs_.clear();
  stats_ = ContactStats{};
  for (Index c = 0; c < chunks; ++c) {
    pairs_.insert(pairs_.end(), found[c].begin(), found[c].end());
    stats_.candidates += candidates[c];
  }
  stats_.active = static_cast<Index>(pairs_.size());
  // A pair whose nodes are not coupled in the bound pattern needs a new pattern.
  pattern_changed_ = false;
  if (bound_) {
    for (const ContactPair& p : pairs_) {
      const std::array<Index, 7> v = pair_nodes(p);
      for (Index i : v)
        for (Index j : v)
          if (bound_->block_index(i, j) < 0) {
            pattern_changed_ = true;
            return;
          }
    }
  }
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
  const Index n = static_cast<Index>(pairs_.size());
  if (!gradient) {
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<Index>(0, n, kChunk), 0.0,
        [&](const tbb::blocked_range<Index>& r, double acc) {
          for (Index k = r.begin(); k < r.end(); ++k) acc += pair_energy(x, pairs_[k]);
          return acc;
        },
        std::plus<double>());
  }
  // Derivatives per pair in parallel (Hessians only when asked for), then scattered in pair order.
  std::vector<double> energies(static_cast<size_t>(n));
  std::vector<PairGradient> gradients(static_cast<size_t>(n));
  std::vector<PairHessian> hessians(hessian ? static_cast<size_t>(n) : 0);
  tbb::parallel_for(tbb::blocked_range<Index>(0, n, 16), [&](const tbb::blocked_range<Index>& r) {
    for (Index k = r.begin(); k < r.end(); ++k)
      energies[k] = pair_derivatives(x, pairs_[k], gradients[k], hessian ? &hessians[k] : nullptr);
  });
  double energy = 0;
  stats_.force = 0;
  stats_.area = 0;
  for (Index k = 0; k < n; ++k) {
    const std::array<Index, 7> v = pair_nodes(pairs_[k]);
    energy += energies[k];
    // A polygon with zero depth everywhere (a surface resting on another, a bonded interface)
    // touches but does not press.
    if (energies[k] > 0) {
      const ClipPolygon& p = pairs_[k].polygon;
      for (int j = 1; j + 1 < p.size; ++j)
        stats_.area += 0.5 * (p.x[j] - p.x[0]).cross(p.x[j + 1] - p.x[0]).norm();
    }
    stats_.force += gradients[k].tail<9>().reshaped(3, 3).rowwise().sum().norm();
    for (int a = 0; a < 7; ++a) gradient->segment<3>(3 * v[a]) += gradients[k].segment<3>(3 * a);
    if (!hessian) continue;
    for (int a = 0; a < 7; ++a)
      for (int b = 0; b < 7; ++b)
        hessian->add_block(hessian->block_index(v[a], v[b]), hessians[k].block<3, 3>(3 * a, 3 * b));
  }
  return energy;
}

}  // namespace depthfem
