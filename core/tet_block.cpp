#include "core/tet_block.hpp"

#include <string>

#include "core/element_partition.hpp"
#include "core/error.hpp"

namespace depthfem {

TetBlock make_tet_block(const Points& X, const TetIndices& tets, std::span<const Index> which,
                        const Points& fibers) {
  const Index n = static_cast<Index>(which.size());
  const bool has_fiber = fibers.rows() > 0;
  if (has_fiber && fibers.rows() != n) {
    throw InputError("fiber directions: " + std::to_string(fibers.rows()) + " given for " +
                     std::to_string(n) + " elements");
  }
  TetIndices local(n, 4);
  Points centroids(n, 3);
  for (Index e = 0; e < n; ++e) {
    local.row(e) = tets.row(which[e]);
    centroids.row(e) =
        0.25 * (X.row(local(e, 0)) + X.row(local(e, 1)) + X.row(local(e, 2)) + X.row(local(e, 3)));
  }
  const ElementPartition part = partition_elements(local, static_cast<Index>(X.rows()), centroids);

  TetBlock b;
  b.nodes.resize(n, 4);
  b.Dm_inv.resize(n, 9);
  b.volume.resize(n);
  b.tet.resize(n);
  if (has_fiber) b.fiber.resize(n, 3);
  b.chunk_begin = part.chunk_begin;
  b.color_begin = part.color_begin;
  for (Index r = 0; r < n; ++r) {
    const Index e = part.order[r];
    const Index t = which[e];
    b.nodes.row(r) = local.row(e);
    b.tet(r) = t;
    Mat3 Dm;
    for (int a = 0; a < 3; ++a)
      Dm.col(a) = (X.row(local(e, a + 1)) - X.row(local(e, 0))).transpose();
    const double det = Dm.determinant();
    if (!(det > 0)) {
      throw InputError("tet " + std::to_string(t) + " has non-positive rest volume " +
                       std::to_string(det / 6));
    }
    const Mat3 Dinv = Dm.inverse();
    for (int k = 0; k < 9; ++k) b.Dm_inv(r, k) = Dinv(k);
    b.volume(r) = det / 6;
    if (has_fiber) {
      const Vec3 f = fibers.row(e).transpose();
      if (!(f.norm() > 0) || !f.allFinite()) {
        throw InputError("tet " + std::to_string(t) + " has a zero or non-finite fiber direction");
      }
      b.fiber.row(r) = f.normalized().transpose();
    }
  }
  return b;
}

}  // namespace depthfem
