#pragma once
/// The tet kernel of tet_kernel.hpp for a batch of W tets at once: every scalar of the per-tet
/// computation is a lane value (V = Lanes<W>), lane l holding tet l of the batch. tet_local stays
/// the reference and serves the rows left over at the end of a chunk.
///
/// With Ds = [x1-x0, x2-x0, x3-x0], D = Dm^-1 and F = Ds D:
///   gradient on node b + 1:  V (P D^T)(:, b),   node 0: minus their sum;
///   Hessian on nodes 1..3:   K = V A dP/dF A^T with A = D (x) I3, i.e.
///     K(3b + d, 3c + e) = V sum_jl D(b, j) dP/dF(d + 3j, e + 3l) D(c, l),
///   rows and columns of node 0 minus the sums over the other nodes.

#include <array>

#include "integrators/elements/tet_kernel.hpp"
#include "materials/batched_stress.hpp"

namespace depthfem {

/// What a batch of tets needs, one lane per tet: current edge vectors Ds and D = Dm^-1
/// (column-major 3x3), rest volume [m^3] and unit fiber direction (read by fiber materials only).
template <class V>
struct TetBatchInput {
  LaneMatrix3<V> Ds, D;
  V volume;
  std::array<V, 3> fiber;
};

/// What a batch of tets contributes, one lane per tet: energy [J], gradient [N] per node and
/// component, and the symmetric 12x12 Hessian [N/m] (node-major, row 3 a + c is node a,
/// component c; both triangles filled).
template <class V>
struct TetBatch {
  V energy;
  std::array<std::array<V, 3>, 4> gradient;
  std::array<std::array<V, 12>, 12> hessian;

  /// The 12x12 Hessian of the tet in lane l (for a per-element projection, tests).
  Mat12 hessian_of(int l) const {
    Mat12 h;
    for (int r = 0; r < 12; ++r)
      for (int s = 0; s < 12; ++s) h(r, s) = hessian[r][s][l];
    return h;
  }
  /// Replaces the Hessian of the tet in lane l.
  void set_hessian_of(int l, const Mat12& h) {
    for (int r = 0; r < 12; ++r)
      for (int s = 0; s < 12; ++s) hessian[r][s].set(l, h(r, s));
  }
};

/// Evaluates a batch: energy (kOrder 0), + gradient (1), + Hessian (2). Lanes with det F <= 0
/// get energy +infinity and zero gradient and Hessian, as tet_local gives them.
template <int kOrder, Material M, class V>
void tet_batch(const M& m, const TetBatchInput<V>& in, TetBatch<V>& out) {
  const auto D = [&](int b, int j) -> const V& { return in.D[3 * j + b]; };
  LaneMatrix3<V> F;
  deformation_gradient(in.Ds.data(), in.D.data(), F.data());
  const BatchedStress<V> s = evaluate_batched_stress<kOrder>(m, F, in.fiber);
  out.energy = in.volume * s.psi;
  if constexpr (kOrder == 0) return;

    // G = V P D^T on nodes 1..3; node 0 balances them.
#pragma GCC unroll 3
  for (int i = 0; i < 3; ++i) {
    V sum(0.0);
#pragma GCC unroll 3
    for (int b = 0; b < 3; ++b) {
      const V g = in.volume * (s.P[i] * D(b, 0) + s.P[3 + i] * D(b, 1) + s.P[6 + i] * D(b, 2));
      out.gradient[b + 1][i] = g;
      sum += g;
    }
    out.gradient[0][i] = -sum;
  }
  if constexpr (kOrder == 1) return;

  // K = V A dP/dF A^T a column at a time: column t = 3c + e of U = dP/dF A^T is
  //   U(p, t) = sum_l dP/dF(p, e + 3l) D(c, l),
  // and K(3b + d, t) = sum_j (V D(b, j)) U(d + 3j, t) on and above the diagonal, written into the
  // node 1..3 part of the 12x12 with its mirror image.
  LaneMatrix3<V> VD;
#pragma GCC unroll 9
  for (int k = 0; k < 9; ++k) VD[k] = in.volume * in.D[k];
  auto& H = out.hessian;
#pragma GCC unroll 9
  for (int t = 0; t < 9; ++t) {
    const int c = t / 3, e = t % 3;
    std::array<V, 9> u;
#pragma GCC unroll 9
    for (int p = 0; p < 9; ++p)
      u[p] = s.dPdF(p, e) * D(c, 0) + s.dPdF(p, e + 3) * D(c, 1) + s.dPdF(p, e + 6) * D(c, 2);
#pragma GCC unroll 9
    for (int r = 0; r <= t; ++r) {
      const int b = r / 3, d = r % 3;
      const V k = VD[b] * u[d] + VD[3 + b] * u[d + 3] + VD[6 + b] * u[d + 6];
      H[3 + r][3 + t] = k;
      H[3 + t][3 + r] = k;
    }
  }
  // Node 0: H(3 + r, e) = -sum_c K(r, 3c + e), and H(d, e) = -sum_b H(3 + 3b + d, e).
#pragma GCC unroll 9
  for (int r = 0; r < 9; ++r)
#pragma GCC unroll 3
    for (int e = 0; e < 3; ++e) {
      const V k = -(H[3 + r][3 + e] + H[3 + r][6 + e] + H[3 + r][9 + e]);
      H[3 + r][e] = k;
      H[e][3 + r] = k;
    }
#pragma GCC unroll 3
  for (int d = 0; d < 3; ++d)
#pragma GCC unroll 3
    for (int e = d; e < 3; ++e) {
      const V k = -(H[3 + d][e] + H[6 + d][e] + H[9 + d][e]);
      H[d][e] = k;
      H[e][d] = k;
    }
}

}  // namespace depthfem
