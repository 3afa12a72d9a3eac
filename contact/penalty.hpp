#pragma once
/// Penalty energy of one clipped polygon (paper section 5.3, steps 4 and 5), written once for any
/// scalar type: double for energies, Dual2<N> for exact gradients and Hessians (the node-to-surface
/// module, and the test oracle of the staged derivatives of tet_polygon_penalty and
/// field_polygon_penalty in penalty_derivatives.hpp).
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
  V3 operator*(double s) const requires(!std::is_same_v<S, double>) {
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

/// c = (R2 - R1) x (R3 - R1): twice the area vector of the triangle R1 R2 R3.
template <class S>
V3<S> area_vector(const V3<S>& R1, const V3<S>& R2, const V3<S>& R3) {
  return (R2 - R1).cross(R3 - R1);
}

/// Whether a fan triangle with area vector c counts, from c2 = c . c: c2 > min_area2. Zero-area
/// triangles (collinear or repeated points, which a clip can produce) have no defined normal and
/// contribute nothing; the energy and its derivatives (penalty_derivatives.hpp) share this test.
inline bool fan_triangle_counts(double c2, double min_area2) {
  return c2 > min_area2;
}

/// eps/2 int g^2 over the triangle (R1, R2, R3) with vertex depths G; zero for a triangle that
/// does not count.
template <class S>
S triangle_penalty(const V3<S>& R1, const V3<S>& R2, const V3<S>& R3, const S& G1, const S& G2,
                   const S& G3, double eps, double min_area2) {
  using std::sqrt;
  const V3<S> c = area_vector(R1, R2, R3);
  const S c2 = c.dot(c);
  if (!fan_triangle_counts(value_of(c2), min_area2)) return S(0.0);
  const S area = sqrt(c2) * 0.5;
  return area * (G1 * G1 + G2 * G2 + G3 * G3 + G1 * G2 + G1 * G3 + G2 * G3) * (eps / 12.0);
}

/// The corners a clipped-polygon vertex depends on, numbered tet corners 0..3 and triangle
/// corners 4..6: R = x_A + t (x_B - x_A), t where the segment A B crosses the plane through
/// C0, C1, C2 (crossing_parameter). A triangle corner inside the tet has A = B and no t.
struct VertexCorners {
  int A = 0, B = 0;
  std::array<int, 3> C{};
  bool crossing() const { return A != B; }
};

inline VertexCorners vertex_corners(const ClipVertex& v) {
  switch (v.kind) {
    case ClipVertex::Kind::kTriangleVertex:
      return {4 + v.a, 4 + v.a, {}};
    case ClipVertex::Kind::kTriangleEdgeFace:  // triangle edge (a, b) through tet face `face`
      return {4 + v.a, 4 + v.b, {kTetFace[v.face][0], kTetFace[v.face][1], kTetFace[v.face][2]}};
    case ClipVertex::Kind::kTetEdge:  // tet edge (a, b) through the triangle
      return {v.a, v.b, {4, 5, 6}};
  }
  return {};
}

/// t = d_A / (d_A - d_B) with d_x = m . (x - C0), m = (C1 - C0) x (C2 - C0): where the segment
/// A B crosses the plane through C0, C1, C2 (d_x is six times the signed volume of C0 C1 C2 x).
template <class S>
S crossing_parameter(const V3<S>& A, const V3<S>& B, const V3<S>& C0, const V3<S>& C1,
                     const V3<S>& C2) {
  const V3<S> m = (C1 - C0).cross(C2 - C0);
  const S dA = m.dot(A - C0), dB = m.dot(B - C0);
  return dA / (dA - dB);
}

/// The point A + t (B - A).
template <class S>
V3<S> segment_point(const V3<S>& A, const V3<S>& B, const S& t) {
  return A + (B - A) * t;
}

/// Position of a clipped-polygon vertex as a function of tet corners P and triangle corners Q.
template <class S>
V3<S> clip_vertex(const ClipVertex& v, const std::array<V3<S>, 4>& P,
                  const std::array<V3<S>, 3>& Q) {
  const VertexCorners c = vertex_corners(v);
  const auto X = [&](int i) -> const V3<S>& { return i < 4 ? P[i] : Q[i - 4]; };
  if (!c.crossing()) return X(c.A);
  return segment_point(X(c.A), X(c.B),
                       crossing_parameter(X(c.A), X(c.B), X(c.C[0]), X(c.C[1]), X(c.C[2])));
}

/// Gradient a of the tet's linear depth field G(x) = g0 + a . (x - P0) with node depths g:
/// a = D^-T (g1 - g0, g2 - g0, g3 - g0), D = [P1 - P0, P2 - P0, P3 - P0] (D^-T = cof D / det D).
template <class S>
V3<S> depth_gradient(const std::array<V3<S>, 4>& P, const std::array<double, 4>& g) {
  const V3<S> d0 = P[1] - P[0], d1 = P[2] - P[0], d2 = P[3] - P[0];
  const V3<S> c0 = d1.cross(d2), c1 = d2.cross(d0), c2 = d0.cross(d1);
  const S inv_det = inverse_of(d0.dot(c0));
  return (c0 * (g[1] - g[0]) + c1 * (g[2] - g[0]) + c2 * (g[3] - g[0])) * inv_det;
}

/// W of the polygon where triangle Q cuts tet P, with node depths g of the tet corners: the
/// depth at each polygon vertex is G = g0 + a . (R - P0) (depth_gradient); the polygon is fanned
/// from its first vertex.
template <class S>
S tet_polygon_penalty(const ClipPolygon& poly, const std::array<V3<S>, 4>& P,
                      const std::array<V3<S>, 3>& Q, const std::array<double, 4>& g, double eps,
                      double min_area2) {
  if (poly.size < 3) return S(0.0);
  const V3<S> a = depth_gradient(P, g);
  std::array<V3<S>, 8> R;
  std::array<S, 8> G;
  for (int k = 0; k < poly.size; ++k) {
    R[k] = clip_vertex(poly.vertex[k], P, Q);
    G[k] = a.dot(R[k] - P[0]) + g[0];
  }
  S W(0.0);
  for (int k = 1; k + 1 < poly.size; ++k)
    W += triangle_penalty(R[0], R[k], R[k + 1], G[0], G[k], G[k + 1], eps, min_area2);
  return W;
}

/// W of the part of triangle Q where the linear interpolant of vertex depths G is positive
/// (an analytic obstacle; the crossings have depth 0).
template <class S>
S field_polygon_penalty(const ClipPolygon& poly, const std::array<V3<S>, 3>& Q,
                        const std::array<S, 3>& Gq, double eps, double min_area2) {
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
  for (int k = 1; k + 1 < poly.size; ++k)
    W += triangle_penalty(R[0], R[k], R[k + 1], G[0], G[k], G[k + 1], eps, min_area2);
  return W;
}

}  // namespace depthfem
