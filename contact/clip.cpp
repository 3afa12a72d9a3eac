#include "contact/clip.hpp"

#include <algorithm>
#include <cmath>

namespace depthfem {

namespace {

// A polygon vertex during clipping: position and the triangle edges / tet faces it lies on.
struct Labelled {
  Vec3 x;
  std::uint8_t edges;  // bit e: on triangle edge (e, e+1)
  std::uint8_t faces;  // bit f: on tet face f
  ClipVertex vertex;
};

// The tet edge shared by faces f1 and f2: the two corners that are neither f1 nor f2.
ClipVertex tet_edge(int f1, int f2) {
  ClipVertex v{ClipVertex::Kind::kTetEdge, -1, -1, -1};
  for (int c = 0; c < 4; ++c) {
    if (c == f1 || c == f2) continue;
    (v.a < 0 ? v.a : v.b) = static_cast<std::int8_t>(c);
  }
  return v;
}

int lowest_bit(unsigned m) {
  return __builtin_ctz(m);
}

// Keeps the part of the polygon where d >= 0 (d: signed value at each vertex); the new
// vertices lie on `plane_face` (a tet face, or -1 for an obstacle's zero level). Returns the new
// vertex count, or 0 when a crossing edge lies on no common edge or face (only possible for
// inconsistent rounding in a degenerate configuration; the pair then contributes nothing).
int clip(Labelled* in, int n, const double* d, int plane_face, Labelled* out) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const Labelled& u = in[i];
    const Labelled& v = in[(i + 1) % n];
    const double du = d[i], dv = d[(i + 1) % n];
    if (du >= 0) out[m++] = u;
    if ((du >= 0) == (dv >= 0)) continue;
    Labelled w;
    const double t = du / (du - dv);
    w.x = u.x + t * (v.x - u.x);
    const unsigned edges = u.edges & v.edges, faces = u.faces & v.faces;
    if (!edges && (!faces || plane_face < 0)) return 0;
    if (edges) {  // along a triangle edge: the edge crosses the plane
      const int e = lowest_bit(edges);
      w.edges = static_cast<std::uint8_t>(1u << e);
      w.faces = plane_face >= 0 ? static_cast<std::uint8_t>(1u << plane_face) : 0;
      w.vertex = {ClipVertex::Kind::kTriangleEdgeFace, static_cast<std::int8_t>(e),
                  static_cast<std::int8_t>((e + 1) % 3), static_cast<std::int8_t>(plane_face)};
    } else {  // along an earlier face: the tet edge where the two faces meet
      const int f = lowest_bit(faces);
      w.edges = 0;
      w.faces = static_cast<std::uint8_t>((1u << f) | (1u << plane_face));
      w.vertex = tet_edge(f, plane_face);
    }
    out[m++] = w;
  }
  return m;
}

// Values within `tol` of zero become zero: a point on a plane up to rounding lies on it. Without
// this, an edge lying in a face plane (common in structured meshes) is "crossed" where its two
// rounding-level values differ in sign, and the crossing's derivative ~ 1 / (d_a - d_b) explodes.
// Crossings then always have |d_a - d_b| > tol.
constexpr double kSnap = 1e-12;  // relative to |face normal|^1.5 ~ (edge length)^3
void snap_to_zero(double* d, int n, double tol) {
  for (int i = 0; i < n; ++i)
    if (std::abs(d[i]) <= tol) d[i] = 0;
}

// Of the two tets sharing a face, the one whose outward normal points to the lexicographically
// negative side owns the face (their normals are opposite). Near-zero components count as zero.
bool owns_face(const Vec3& normal) {
  const double tol = 1e-12 * normal.norm();
  for (int k = 0; k < 3; ++k)
    if (std::abs(normal(k)) > tol) return normal(k) < 0;
  return false;
}

ClipPolygon to_polygon(const Labelled* p, int n) {
  ClipPolygon out;
  out.size = n;
  for (int i = 0; i < n; ++i) {
    out.vertex[i] = p[i].vertex;
    out.x[i] = p[i].x;
  }
  return out;
}

void start_with_triangle(const std::array<Vec3, 3>& Q, Labelled* p) {
  for (int i = 0; i < 3; ++i) {
    p[i].x = Q[i];
    p[i].edges = static_cast<std::uint8_t>((1u << i) | (1u << ((i + 2) % 3)));
    p[i].faces = 0;
    p[i].vertex = {ClipVertex::Kind::kTriangleVertex, static_cast<std::int8_t>(i), -1, -1};
  }
}

}  // namespace

ClipPolygon clip_triangle_by_tet(const std::array<Vec3, 4>& P, const std::array<Vec3, 3>& Q) {
  // A tet strictly on one side of the triangle's plane does not meet it: four dot products
  // reject most pairs whose boxes overlap (a surface triangle beside the tets under it) before
  // any clipping.
  const Vec3 m = (Q[1] - Q[0]).cross(Q[2] - Q[0]);
  int above = 0, below = 0;
  for (const Vec3& p : P) {
    const double s = m.dot(p - Q[0]);
    above += s > 0;
    below += s < 0;
  }
  if (above == 4 || below == 4) return ClipPolygon{};
  Labelled a[8], b[8];
  start_with_triangle(Q, a);
  int n = 3;
  Labelled* cur = a;
  Labelled* next = b;
  for (int f = 0; f < 4 && n > 0; ++f) {
    // Inside of face f: d = n_f . (P_i - x) >= 0 with n_f the outward normal of the face.
    const Vec3& Pi = P[kTetFace[f][0]];
    const Vec3 normal = (P[kTetFace[f][1]] - Pi).cross(P[kTetFace[f][2]] - Pi);
    double d[8];
    for (int i = 0; i < n; ++i) d[i] = normal.dot(Pi - cur[i].x);
    const double length = normal.norm();
    snap_to_zero(d, n, kSnap * length * std::sqrt(length));
    if (std::all_of(d, d + n, [](double v) { return v == 0; })) {
      // The polygon lies in the face plane. The face is shared by two tets (or is on the
      // boundary, where the depth is zero): count it for exactly one of them, so that a
      // triangle lying on an inner face is not integrated twice.
      if (!owns_face(normal)) return ClipPolygon{};
      continue;
    }
    n = clip(cur, n, d, f, next);
    std::swap(cur, next);
  }
  return to_polygon(cur, n);
}

ClipPolygon clip_triangle_by_field(const std::array<Vec3, 3>& Q, const std::array<double, 3>& g) {
  Labelled a[8], b[8];
  start_with_triangle(Q, a);
  double d[3] = {g[0], g[1], g[2]};
  snap_to_zero(d, 3, kSnap * std::max({std::abs(g[0]), std::abs(g[1]), std::abs(g[2])}));
  const int n = clip(a, 3, d, -1, b);
  return to_polygon(b, n);
}

}  // namespace depthfem
