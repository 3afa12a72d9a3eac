#include "contact/penetration_depth.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <limits>

#include "contact/aabb_tree.hpp"
#include "contact/material_depth.hpp"

namespace depthfem {

double deepest_penetration(const Mesh& mesh, const Points& x,
                           const std::vector<ContactPair>& pairs) {
  // One tree over the current boundary triangles of each body that pairs enter.
  std::vector<AabbTree> trees(mesh.bodies.size());
  for (const ContactPair& p : pairs) {
    const Index b = mesh.tet_body(p.tet);
    if (trees[b].size() > 0) continue;
    const Body& body = mesh.bodies[b];
    trees[b] = AabbTree(triangle_boxes(x, mesh.tris.middleRows(body.first_tri, body.num_tris)));
  }
  const auto normal = [&](Index f) -> Vec3 {
    const Vec3 a = x.row(mesh.tris(f, 0)), b = x.row(mesh.tris(f, 1)), c = x.row(mesh.tris(f, 2));
    return (b - a).cross(c - a);
  };
  // f's own neighbourhood: the triangles that share a node with it and face the same way.
  const auto beside = [&](Index f, Index g) {
    bool shares = false;
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) shares = shares || mesh.tris(f, a) == mesh.tris(g, c);
    return shares && normal(f).dot(normal(g)) > 0;
  };
  const Index n = static_cast<Index>(pairs.size());
  return tbb::parallel_reduce(
      tbb::blocked_range<Index>(0, n, 64), 0.0,
      [&](const tbb::blocked_range<Index>& r, double deepest) {
        for (Index k = r.begin(); k < r.end(); ++k) {
          const ContactPair& p = pairs[k];
          const Index b = mesh.tet_body(p.tet);
          const Body& body = mesh.bodies[b];
          const bool self = mesh.tri_body(p.tri) == b;
          for (int v = 0; v < p.polygon.size; ++v) {
            const Vec3& q = p.polygon.x[v];
            double best = std::numeric_limits<double>::infinity();
            trees[b].nearest(q, best, [&](Index local, double bound) {
              const Index f = body.first_tri + local;
              if (self && beside(f, p.tri)) return bound;
              const Vec3 c = closest_point_on_triangle(
                  q, x.row(mesh.tris(f, 0)), x.row(mesh.tris(f, 1)), x.row(mesh.tris(f, 2)));
              best = std::min(bound, (c - q).squaredNorm());
              return best;
            });
            deepest = std::max(deepest, std::sqrt(best));
          }
        }
        return deepest;
      },
      [](double a, double b) { return std::max(a, b); });
}

}  // namespace depthfem
