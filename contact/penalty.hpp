#pragma once
/// Penalty energy of one clipped polygon (paper section 5.3, steps 4 and 5), written once for any
/// scalar type: double for energies, Dual2<N> for exact gradients and Hessians.
///
/// For a sub-triangle R1 R2 R3 of area A with linearly interpolated depths G1..G3,
///   W = eps/2 int g^2 da = eps A / 12 (G1^2 + G2^2 + G3^2 + G1 G2 + G1 G3 + G2 G3).

#include <array>
#include <cmath>
#include <type_traits>

#include "contact/clip.hpp"
#include "contact/dual.hpp"

namespace depthfem {

/// A 3-vector of any scalar type (doubles or dual numbers).
template <class S>
struct V3 {
  S x, y, z;
  V3 operator+(const V3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  V3 operator-(const V3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  V3 operator*(const S& s) const { return {x * s, y * s, z * s}; }
  V3 operator*(double s) const
    requires(!std::is_same_v<S, double>)
  {
    return {x * s, y * s, z * s};
  }
  S dot(const V3& o) const { return x * o.x + y * o.y + z * o.z; }
  V3 cross(const V3& o) const { return {y * o.z - z * o.y, z * o.x - x * o.z, x * o.y - y * o.x}; }
};

/// Variables of a point, as doubles (S = double) or as dual variables first, first+1, first+2.
template <class S>
V3<S> make_point(const Vec3& p, int first) {
  if constexpr (std::is_same_v<S, double>) {
    (void)first;
    return {p(0), p(1), p(2)};
  } else {
    return {S::variable(first, p(0)), S::variable(first + 1, p(1)), S::variable(first + 2, p(2))};
  }
}

/// eps/2 int g^2 over the triangle (R1, R2, R3) with vertex depths G; zero-area triangles
/// (collinear points, which a clip can produce) contribute nothing.
template <class S>
S triangle_penalty(const V3<S>& R1, const V3<S>& R2, const V3<S>& R3, const S& G1, const S& G2, const S& G3,
                   double eps, double min_area2) {
  using std::sqrt;
  const V3<S> c = (R2 - R1).cross(R3 - R1);
  const S c2 = c.dot(c);
  if (value_of(c2) <= min_area2) return S(0.0);
  const S area = sqrt(c2) * 0.5;
  return area * (G1 * G1 + G2 * G2 + G3 * G3 + G1 * G2 + G1 * G3 + G2 * G3) * (eps / 12.0);
}

/// Position of a clipped-polygon vertex as a function of tet corners P and triangle corners Q.
template <class S>
V3<S> clip_vertex(const ClipVertex& v, const std::array<V3<S>, 4>& P, const std::array<V3<S>, 3>& Q) {
  switch (v.kind) {
    case ClipVertex::Kind::kTriangleVertex:
      return Q[v.a];
    case ClipVertex::Kind::kTriangleEdgeFace: {
      // Q_a + t (Q_b - Q_a), t = d_a / (d_a - d_b), d = n . (P_i - x) (inside of the face).
      const V3<S>& Pi = P[kTetFace[v.face][0]];
      const V3<S> n = (P[kTetFace[v.face][1]] - Pi).cross(P[kTetFace[v.face][2]] - Pi);
      const S da = n.dot(Pi - Q[v.a]), db = n.dot(Pi - Q[v.b]);
      return Q[v.a] + (Q[v.b] - Q[v.a]) * (da / (da - db));
    }
    case ClipVertex::Kind::kTetEdge: {
      // P_a + s (P_b - P_a), s = e_a / (e_a - e_b), e = m . (x - Q_0), m the triangle normal.
      const V3<S> m = (Q[1] - Q[0]).cross(Q[2] - Q[0]);
      const S ea = m.dot(P[v.a] - Q[0]), eb = m.dot(P[v.b] - Q[0]);
      return P[v.a] + (P[v.b] - P[v.a]) * (ea / (ea - eb));
    }
  }
  return Q[0];
}

/// W of the polygon where triangle Q cuts tet P, with node depths g of the tet corners:
/// the depth field of the tet is G(x) = g0 + a . (x - P0), a = D^-T (g1-g0, g2-g0, g3-g0) with
/// D = [P1-P0, P2-P0, P3-P0] (D^-T = cof D / det D); the polygon is fanned from its first vertex.
template <class S>
S tet_polygon_penalty(const ClipPolygon& poly, const std::array<V3<S>, 4>& P, const std::array<V3<S>, 3>& Q,
                      const std::array<double, 4>& g, double eps, double min_area2) {
  if (poly.size < 3) return S(0.0);
  const V3<S> d0 = P[1] - P[0], d1 = P[2] - P[0], d2 = P[3] - P[0];
  const V3<S> c0 = d1.cross(d2), c1 = d2.cross(d0), c2 = d0.cross(d1);
  const S inv_det = inverse_of(d0.dot(c0));
  const V3<S> a = (c0 * (g[1] - g[0]) + c1 * (g[2] - g[0]) + c2 * (g[3] - g[0])) * inv_det;
  std::array<V3<S>, 8> R;
  std::array<S, 8> G;
  for (int k = 0; k < poly.size; ++k) {
    R[k] = clip_vertex(poly.vertex[k], P, Q);
    G[k] = a.dot(R[k] - P[0]) + g[0];
  }
  S W(0.0);
  for (int k = 1; k + 1 < poly.size; ++k) W += triangle_penalty(R[0], R[k], R[k + 1], G[0], G[k], G[k + 1], eps, min_area2);
  return W;
}

/// W of the part of triangle Q where the linear interpolant of vertex depths G is positive
/// (an analytic obstacle; the crossings have depth 0).
template <class S>
S field_polygon_penalty(const ClipPolygon& poly, const std::array<V3<S>, 3>& Q, const std::array<S, 3>& Gq, double eps,
                        double min_area2) {
  if (poly.size < 3) return S(0.0);
  std::array<V3<S>, 8> R;
  std::array<S, 8> G;
  for (int k = 0; k < poly.size; ++k) {
    const ClipVertex& v = poly.vertex[k];
    if (v.kind == ClipVertex::Kind::kTriangleVertex) {
      R[k] = Q[v.a];
      G[k] = Gq[v.a];
    } else {  // zero crossing on edge (a, b): t = G_a / (G_a - G_b)
      R[k] = Q[v.a] + (Q[v.b] - Q[v.a]) * (Gq[v.a] / (Gq[v.a] - Gq[v.b]));
      G[k] = S(0.0);
    }
  }
  S W(0.0);
  for (int k = 1; k + 1 < poly.size; ++k) W += triangle_penalty(R[0], R[k], R[k + 1], G[0], G[k], G[k + 1], eps, min_area2);
  return W;
}

}  // namespace depthfem
