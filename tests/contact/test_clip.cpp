// Clipping and penalty integration against brute-force quadrature.
#include <gtest/gtest.h>

#include <random>

#include "contact/clip.hpp"
#include "contact/penalty.hpp"

namespace depthfem {
namespace {

using Tet = std::array<Vec3, 4>;
using Tri = std::array<Vec3, 3>;

// Regular-ish positively oriented tet around the origin.
Tet reference_tet() {
  return {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
}

// Area of the part of Q inside P and the integral of g^2 there (g linear in the tet, corner
// values gv), by the midpoint rule on n^2 congruent sub-triangles of Q; cells cut by the tet
// boundary cause an error of order (perimeter x cell size), i.e. relative ~ 3 / n.
std::pair<double, double> brute_force(const Tet& P, const Tri& Q, const std::array<double, 4>& gv,
                                      int n) {
  Mat3 D;
  for (int k = 0; k < 3; ++k) D.col(k) = P[k + 1] - P[0];
  const Mat3 Dinv = D.inverse();
  const double cell = 0.5 * (Q[1] - Q[0]).cross(Q[2] - Q[0]).norm() / (double(n) * n);
  double area = 0, integral = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; i + j < n; ++j)
      for (int up = 0; up < 2; ++up) {
        if (up && i + j == n - 1) continue;
        // Centroid of the sub-triangle in barycentric grid coordinates.
        const double s = up ? (i + 2.0 / 3) / n : (i + 1.0 / 3) / n;
        const double t = up ? (j + 2.0 / 3) / n : (j + 1.0 / 3) / n;
        const Vec3 x = Q[0] + s * (Q[1] - Q[0]) + t * (Q[2] - Q[0]);
        const Vec3 l = Dinv * (x - P[0]);
        if (l.minCoeff() < 0 || l.sum() > 1) continue;
        const double g =
            gv[0] + l(0) * (gv[1] - gv[0]) + l(1) * (gv[2] - gv[0]) + l(2) * (gv[3] - gv[0]);
        area += cell;
        integral += cell * g * g;
      }
  return {area, integral};
}

double polygon_area(const ClipPolygon& p) {
  double a = 0;
  for (int k = 1; k + 1 < p.size; ++k)
    a += 0.5 * (p.x[k] - p.x[0]).cross(p.x[k + 1] - p.x[0]).norm();
  return a;
}

int count(const ClipPolygon& p, ClipVertex::Kind kind) {
  int c = 0;
  for (int k = 0; k < p.size; ++k) c += p.vertex[k].kind == kind;
  return c;
}

TEST(Clip, AreaAndPenaltyMatchQuadratureOnRandomConfigurations) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-0.4, 1.2);
  const Tet P = reference_tet();
  const std::array<double, 4> gv = {0.3, 0.1, 0.5, 0.2};
  int tested = 0, kinds[3] = {0, 0, 0};
  while (tested < 60) {
    const Tri Q = {Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)),
                   Vec3(u(rng), u(rng), u(rng))};
    if ((Q[1] - Q[0]).cross(Q[2] - Q[0]).norm() < 0.2) continue;  // avoid slivers
    const ClipPolygon poly = clip_triangle_by_tet(P, Q);
    const auto [area, integral] = brute_force(P, Q, gv, 800);
    if (area < 1e-3) {
      EXPECT_LT(polygon_area(poly), 5e-3);
      continue;
    }
    ++tested;
    for (int k = 0; k < 3; ++k) kinds[k] += count(poly, static_cast<ClipVertex::Kind>(k)) > 0;
    EXPECT_LE(poly.size, 7);
    EXPECT_NEAR(polygon_area(poly), area, 5e-3 * area + 1e-4);
    // W = eps/2 int g^2 with eps = 2: W equals the integral of g^2.
    std::array<V3<double>, 4> Pv;
    std::array<V3<double>, 3> Qv;
    for (int a = 0; a < 4; ++a) Pv[a] = make_point<double>(P[a], 0);
    for (int b = 0; b < 3; ++b) Qv[b] = make_point<double>(Q[b], 0);
    EXPECT_NEAR(tet_polygon_penalty(poly, Pv, Qv, gv, 2.0, 0.0), integral, 5e-3 * integral + 1e-5);
    // Positions re-evaluated from the labels agree with the clipped ones.
    for (int k = 0; k < poly.size; ++k) {
      const V3<double> r = clip_vertex(poly.vertex[k], Pv, Qv);
      EXPECT_LE((Vec3(r.x, r.y, r.z) - poly.x[k]).norm(), 1e-12);
    }
  }
  // The random set covers every kind of polygon vertex.
  for (int k = 0; k < 3; ++k) EXPECT_GT(kinds[k], 3) << "vertex kind " << k;
}

TEST(Clip, TriangleInsideAndOutside) {
  const Tet P = reference_tet();
  const Tri inside = {Vec3(0.1, 0.1, 0.1), Vec3(0.3, 0.1, 0.1), Vec3(0.1, 0.3, 0.1)};
  const ClipPolygon a = clip_triangle_by_tet(P, inside);
  ASSERT_EQ(a.size, 3);
  EXPECT_EQ(count(a, ClipVertex::Kind::kTriangleVertex), 3);
  EXPECT_NEAR(polygon_area(a), 0.02, 1e-15);
  const Tri outside = {Vec3(2, 0, 0), Vec3(3, 0, 0), Vec3(2, 1, 0)};
  EXPECT_LT(clip_triangle_by_tet(P, outside).size, 3);
  // A large triangle in the plane x + y + z = 1/2 cuts the tet in the equilateral triangle
  // (1/2,0,0), (0,1/2,0), (0,0,1/2) of side sqrt(2)/2 and area sqrt(3)/8, corners on tet edges.
  const Tri big = {Vec3(5, -2, -2.5), Vec3(-2, 5, -2.5), Vec3(-2.5, -2.5, 5.5)};
  const ClipPolygon c = clip_triangle_by_tet(P, big);
  EXPECT_EQ(c.size, 3);
  EXPECT_EQ(count(c, ClipVertex::Kind::kTetEdge), 3);
  EXPECT_NEAR(polygon_area(c), std::sqrt(3.0) / 8, 1e-12);
}

TEST(Clip, FieldClipKeepsThePositivePart) {
  const Tri Q = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const ClipPolygon p = clip_triangle_by_field(Q, {1.0, -1.0, -1.0});
  ASSERT_EQ(p.size, 3);  // the corner triangle where g > 0, legs 1/2
  EXPECT_NEAR(polygon_area(p), 0.125, 1e-15);
  EXPECT_EQ(clip_triangle_by_field(Q, {-1.0, -2.0, -0.5}).size, 0);
}

}  // namespace
}  // namespace depthfem
