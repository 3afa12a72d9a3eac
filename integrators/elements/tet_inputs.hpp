#pragma once
/// What the tet kernels read, taken from a TetBlock (SoA element data) and node positions: one
/// row for the scalar kernel, W consecutive rows for the batched one.

#include "core/tet_block.hpp"
#include "integrators/elements/batched_tet_kernel.hpp"

namespace depthfem {

/// One tet's inputs to tet_local: current edge vectors, Dm^-1, rest volume [m^3], unit fiber.
struct TetInput {
  Mat3 Ds, D;
  double volume = 0;
  Vec3 fiber = Vec3::UnitX();
};

/// Edge vectors x_a - x_0 (a = 1, 2, 3, as columns) of row e of `b` at positions x (#nodes x 3).
inline Mat3 edge_vectors(const TetBlock& b, const Points& x, Index e) {
  Mat3 Ds;
  const Index n0 = b.nodes(e, 0);
  for (int a = 0; a < 3; ++a) {
    const Index na = b.nodes(e, a + 1);
    Ds.col(a) = Vec3(x(na, 0) - x(n0, 0), x(na, 1) - x(n0, 1), x(na, 2) - x(n0, 2));
  }
  return Ds;
}

/// Row e of `b` at positions x (#nodes x 3).
inline TetInput tet_input(const TetBlock& b, const Points& x, Index e) {
  TetInput t;
  t.Ds = edge_vectors(b, x, e);
  t.D = b.dm_inv(e);
  t.volume = b.volume(e);
  if (b.fiber.rows()) t.fiber = b.fiber.row(e).transpose();
  return t;
}

/// Rows e .. e + W of `b` (all inside the block) as one batch, W = V::kWidth: positions gathered
/// through the node index columns, element data loaded from W consecutive entries of each column.
/// Fiber directions are read when kFiber is set.
template <class V, bool kFiber>
TetBatchInput<V> tet_batch_input(const TetBlock& b, const Points& x, Index e) {
  const Index n = b.size();
  TetBatchInput<V> in;
  for (int c = 0; c < 3; ++c) {
    const double* xc = x.col(c).data();
    const V x0 = V::gather(xc, b.nodes.col(0).data() + e);
    for (int a = 1; a < 4; ++a)
      in.Ds[3 * (a - 1) + c] = V::gather(xc, b.nodes.col(a).data() + e) - x0;
  }
  for (int k = 0; k < 9; ++k) in.D[k] = V::load(b.Dm_inv.data() + k * n + e);
  in.volume = V::load(b.volume.data() + e);
  if constexpr (kFiber)
    for (int k = 0; k < 3; ++k) in.fiber[k] = V::load(b.fiber.col(k).data() + e);
  return in;
}

}  // namespace depthfem
