// Exact derivatives of the pair penalty: automatic differentiation (Dual2<21>) against finite
// differences, and the staged chain rule against automatic differentiation, in every clip case;
// the same for a triangle in an obstacle's depth field (Dual2<9>).
#include <gtest/gtest.h>

#include <random>

#include "contact/clip.hpp"
#include "contact/penalty.hpp"
#include "contact/penalty_derivatives.hpp"
#include "finite_differences.hpp"

namespace depthfem {
namespace {

using Vec21 = Eigen::Matrix<double, 21, 1>;
constexpr double kEps = 1e5;

// W of the triangle (variables 12..20) against the tet (0..11), clipped at these positions.
double energy(const Vec21& z, const std::array<double, 4>& g) {
  std::array<Vec3, 4> P;
  std::array<Vec3, 3> Q;
  std::array<V3<double>, 4> Pv;
  std::array<V3<double>, 3> Qv;
  for (int a = 0; a < 4; ++a) P[a] = z.segment<3>(3 * a), Pv[a] = make_point<double>(P[a], 0);
  for (int b = 0; b < 3; ++b) Q[b] = z.segment<3>(12 + 3 * b), Qv[b] = make_point<double>(Q[b], 0);
  return tet_polygon_penalty(clip_triangle_by_tet(P, Q), Pv, Qv, g, kEps, 0.0);
}

Dual2<21> energy_dual(const Vec21& z, const std::array<double, 4>& g, ClipPolygon* out) {
  using D = Dual2<21>;
  std::array<Vec3, 4> P;
  std::array<Vec3, 3> Q;
  std::array<V3<D>, 4> Pv;
  std::array<V3<D>, 3> Qv;
  for (int a = 0; a < 4; ++a) P[a] = z.segment<3>(3 * a), Pv[a] = make_point<D>(P[a], 3 * a);
  for (int b = 0; b < 3; ++b)
    Q[b] = z.segment<3>(12 + 3 * b), Qv[b] = make_point<D>(Q[b], 12 + 3 * b);
  *out = clip_triangle_by_tet(P, Q);
  return tet_polygon_penalty(*out, Pv, Qv, g, kEps, 0.0);
}

// Central differences with step 1e-6 on coordinates of order 1: truncation ~1e-12 x third
// derivative, round-off ~1e-16 W / 1e-6; agreement to 1e-6 relative (gradient) and 1e-5
// (Hessian, from differences of the exact gradient) is well inside both.
TEST(PenaltyDerivatives, MatchFiniteDifferencesInEveryClipCase) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-0.4, 1.2), jitter(-0.15, 0.15);
  const std::array<double, 4> g = {0.02, 0.35, 0.1, 0.6};
  int tested = 0, kinds[3] = {0, 0, 0};
  while (tested < 40) {
    Vec21 z;
    const Vec3 corners[4] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
    for (int a = 0; a < 4; ++a)
      for (int k = 0; k < 3; ++k) z(3 * a + k) = corners[a](k) + jitter(rng);
    for (int i = 12; i < 21; ++i) z(i) = u(rng);
    ClipPolygon poly;
    const Dual2<21> W = energy_dual(z, g, &poly);
    if (poly.size < 3 || W.v < 1e-6 * kEps) continue;
    ++tested;
    for (int k = 0; k < poly.size; ++k) ++kinds[static_cast<int>(poly.vertex[k].kind)];
    EXPECT_NEAR(W.v, energy(z, g), 1e-12 * W.v);
    const double h = 1e-6;
    const Vec21 grad_fd =
        testing::central_gradient([&](const Vec21& y) { return energy(y, g); }, z, h);
    const Eigen::MatrixXd hess_fd = testing::central_jacobian(
        [&](const Vec21& y) {
          ClipPolygon clipped;
          return energy_dual(y, g, &clipped).g;
        },
        z, h);
    EXPECT_LE((W.g - grad_fd).cwiseAbs().maxCoeff(), 1e-6 * W.g.cwiseAbs().maxCoeff())
        << "config " << tested;
    EXPECT_LE((W.h - hess_fd).cwiseAbs().maxCoeff(), 1e-5 * W.h.cwiseAbs().maxCoeff())
        << "config " << tested;
    EXPECT_LE((W.h - W.h.transpose()).cwiseAbs().maxCoeff(), 1e-12 * W.h.cwiseAbs().maxCoeff());
    // Translation invariance: forces sum to zero.
    for (int k = 0; k < 3; ++k) {
      double sum = 0;
      for (int a = 0; a < 7; ++a) sum += W.g(3 * a + k);
      EXPECT_NEAR(sum, 0.0, 1e-10 * W.g.cwiseAbs().maxCoeff());
    }
  }
  for (int k = 0; k < 3; ++k) EXPECT_GT(kinds[k], 5) << "vertex kind " << k << " not covered";
}

// The reference tet with each corner moved by up to 0.15 in each coordinate.
std::array<Vec3, 4> jittered_tet(std::mt19937& rng) {
  std::uniform_real_distribution<double> jitter(-0.15, 0.15);
  std::array<Vec3, 4> P = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  for (Vec3& p : P) p += Vec3(jitter(rng), jitter(rng), jitter(rng));
  return P;
}

// Fan triangles of the polygon that do not count (zero area up to rounding).
int skipped_fan_triangles(const ClipPolygon& poly, const std::array<Vec3, 4>& P,
                          const std::array<Vec3, 3>& Q, double min_area2) {
  std::array<V3<double>, 4> Pv;
  std::array<V3<double>, 3> Qv;
  for (int a = 0; a < 4; ++a) Pv[a] = make_point<double>(P[a], 0);
  for (int b = 0; b < 3; ++b) Qv[b] = make_point<double>(Q[b], 0);
  int skipped = 0;
  for (int k = 1; k + 1 < poly.size; ++k) {
    const V3<double> c =
        area_vector(clip_vertex(poly.vertex[0], Pv, Qv), clip_vertex(poly.vertex[k], Pv, Qv),
                    clip_vertex(poly.vertex[k + 1], Pv, Qv));
    skipped += !fan_triangle_counts(c.dot(c), min_area2);
  }
  return skipped;
}

// The staged derivatives against Dual2<21> on the same polygon. Both are exact; they differ by
// rounding only, a few ulps of the largest terms times the conditioning of the crossings
// (1 / (d_A - d_B)): observed up to about 1e-12 relative to the largest entry, so 1e-10 leaves
// a margin near 100. The energies agree to rounding as well: the same formulas, rounded differently
// where the compiler fuses multiply-adds (1e-11 relative covers tiny polygons cut near a tet
// corner, whose crossings cancel digits). The gradient-only call gives the same gradient.
void expect_staged_equals_dual(const ClipPolygon& poly, const std::array<Vec3, 4>& P,
                               const std::array<Vec3, 3>& Q, const std::array<double, 4>& g,
                               double min_area2) {
  using D = Dual2<21>;
  std::array<V3<D>, 4> Pd;
  std::array<V3<D>, 3> Qd;
  std::array<V3<double>, 4> Pv;
  std::array<V3<double>, 3> Qv;
  for (int a = 0; a < 4; ++a)
    Pd[a] = make_point<D>(P[a], 3 * a), Pv[a] = make_point<double>(P[a], 0);
  for (int b = 0; b < 3; ++b)
    Qd[b] = make_point<D>(Q[b], 12 + 3 * b), Qv[b] = make_point<double>(Q[b], 0);
  const D W = tet_polygon_penalty(poly, Pd, Qd, g, kEps, min_area2);
  PairGradient grad, grad_only;
  PairHessian hess;
  const double energy =
      tet_polygon_penalty_derivatives(poly, P, Q, g, kEps, min_area2, grad, &hess);
  const double energy_only =
      tet_polygon_penalty_derivatives(poly, P, Q, g, kEps, min_area2, grad_only, nullptr);
  EXPECT_NEAR(energy, tet_polygon_penalty(poly, Pv, Qv, g, kEps, min_area2), 1e-11 * energy);
  EXPECT_NEAR(energy, W.v, 1e-11 * W.v);
  EXPECT_DOUBLE_EQ(energy_only, energy);
  const double gmax = W.g.cwiseAbs().maxCoeff(), hmax = W.h.cwiseAbs().maxCoeff();
  EXPECT_LE((grad - W.g).cwiseAbs().maxCoeff(), 1e-10 * gmax);
  EXPECT_LE((hess - W.h).cwiseAbs().maxCoeff(), 1e-10 * hmax);
  EXPECT_LE((grad_only - grad).cwiseAbs().maxCoeff(), 1e-15 * gmax);
}

TEST(StagedContactDerivatives, EqualAutomaticDifferentiationInEveryClipCase) {
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(-0.4, 1.2);
  const std::array<double, 4> g = {0.02, 0.35, 0.1, 0.6};
  int tested = 0, kinds[3] = {0, 0, 0}, sizes[8] = {};
  while (tested < 200) {
    const std::array<Vec3, 4> P = jittered_tet(rng);
    const std::array<Vec3, 3> Q = {Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)),
                                   Vec3(u(rng), u(rng), u(rng))};
    const ClipPolygon poly = clip_triangle_by_tet(P, Q);
    if (poly.size < 3) continue;
    ++tested;
    ++sizes[poly.size];
    for (int k = 0; k < poly.size; ++k) ++kinds[static_cast<int>(poly.vertex[k].kind)];
    SCOPED_TRACE("configuration " + std::to_string(tested));
    expect_staged_equals_dual(poly, P, Q, g, 0.0);
  }
  for (int k = 0; k < 3; ++k) EXPECT_GT(kinds[k], 20) << "vertex kind " << k << " not covered";
  for (int n = 3; n <= 6; ++n) EXPECT_GT(sizes[n], 0) << "no polygon with " << n << " vertices";
}

// Degenerate polygons: a triangle corner on a tet face (one neighbour inside, one outside), or a
// triangle edge through a tet edge, make the clip repeat a point, so that some fan triangles have
// zero area up to rounding. With the module's threshold (area 1e-12 of an element face) they do
// not count, for the energy and the derivatives alike.
TEST(StagedContactDerivatives, EqualAutomaticDifferentiationWithDegenerateFanTriangles) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0, 1), u(-0.4, 1.2);
  const std::array<double, 4> g = {0.3, 0.05, 0.2, 0.45};
  const double min_area2 = 1e-24;
  int tested = 0, skipped = 0, kinds[3] = {0, 0, 0};
  for (int trial = 0; trial < 400; ++trial) {
    const std::array<Vec3, 4> P = jittered_tet(rng);
    const Vec3 centroid = (P[0] + P[1] + P[2] + P[3]) / 4;
    std::array<Vec3, 3> Q;
    if (trial % 2 == 0) {  // corner Q0 on face f, Q1 inside the tet, Q2 beyond the face
      const int f = trial / 2 % 4;
      const Vec3 &A = P[kTetFace[f][0]], &B = P[kTetFace[f][1]], &C = P[kTetFace[f][2]];
      const double s = 0.1 + 0.5 * unit(rng), t = 0.1 + 0.4 * unit(rng) * (1 - s);
      Q[0] = A + s * (B - A) + t * (C - A);
      Q[1] =
          Q[0] + (0.3 + 0.6 * unit(rng)) * (centroid - Q[0]) + 0.05 * Vec3(u(rng), u(rng), u(rng));
      Q[2] =
          Q[0] - (0.3 + 0.6 * unit(rng)) * (centroid - Q[0]) + 0.3 * Vec3(u(rng), u(rng), u(rng));
    } else {  // edge Q0 Q1 through a point of tet edge (a, b)
      const int a = trial / 2 % 4, b = (a + 1 + trial / 8 % 3) % 4;
      const Vec3 X = P[a] + (0.2 + 0.6 * unit(rng)) * (P[b] - P[a]);
      const Vec3 dir = Vec3(u(rng), u(rng), u(rng));
      Q[0] = X - (0.2 + unit(rng)) * dir;
      Q[1] = X + (0.2 + unit(rng)) * dir;
      Q[2] = centroid + Vec3(u(rng), u(rng), u(rng));
    }
    const ClipPolygon poly = clip_triangle_by_tet(P, Q);
    if (poly.size < 3) continue;
    ++tested;
    skipped += skipped_fan_triangles(poly, P, Q, min_area2);
    for (int k = 0; k < poly.size; ++k) ++kinds[static_cast<int>(poly.vertex[k].kind)];
    SCOPED_TRACE("trial " + std::to_string(trial));
    expect_staged_equals_dual(poly, P, Q, g, min_area2);
  }
  EXPECT_GT(tested, 200);
  EXPECT_GT(skipped, 50) << "too few zero-area fan triangles";
  for (int k = 0; k < 3; ++k) EXPECT_GT(kinds[k], 20) << "vertex kind " << k << " not covered";
}

// ---- A triangle in an obstacle's depth field (field_polygon_penalty_derivatives).

using Vec9 = Eigen::Matrix<double, 9, 1>;

// A sphere of radius 1 about the origin: depth 1 - |q|, as ObstacleContact computes it.
template <class S>
S sphere_depth(const V3<S>& q) {
  using std::sqrt;
  return -sqrt(q.dot(q)) + 1.0;
}
DepthSample sphere_sample(const Vec3& q) {
  const Vec3 m = q.normalized();
  return {1 - q.norm(), -m, -(Mat3::Identity() - m * m.transpose()) / q.norm()};
}

// W of the triangle z in the sphere's field, clipped at z, with S = double or Dual2<9>.
template <class S>
S field_energy(const Vec9& z, ClipPolygon* out = nullptr) {
  std::array<Vec3, 3> Q;
  std::array<V3<S>, 3> Qv;
  std::array<S, 3> G;
  for (int b = 0; b < 3; ++b) {
    Q[b] = z.segment<3>(3 * b);
    Qv[b] = make_point<S>(Q[b], 3 * b);
    G[b] = sphere_depth(Qv[b]);
  }
  const ClipPolygon poly =
      clip_triangle_by_field(Q, {value_of(G[0]), value_of(G[1]), value_of(G[2])});
  if (out) *out = poly;
  return field_polygon_penalty(poly, Qv, G, kEps, 0.0);
}

// Triangles with corners near the unit sphere, so that one, two or three corners are inside:
// the staged derivatives equal Dual2<9> through the same energy (1e-10 of the largest entry, as
// for the tet pairs), and finite differences of the energy (gradient, 1e-6) and of the staged
// gradient (Hessian, 1e-5), with the step and reasoning of MatchFiniteDifferencesInEveryClipCase.
TEST(StagedObstacleDerivatives, EqualAutomaticDifferentiationAndFiniteDifferences) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> radius(0.85, 1.1), angle(-0.3, 0.3);
  int tested = 0, inside_count[4] = {};
  while (tested < 150) {
    Vec9 z;
    for (int b = 0; b < 3; ++b) {
      const double th = angle(rng), ph = angle(rng);
      z.segment<3>(3 * b) =
          radius(rng) * Vec3(std::sin(th), std::sin(ph), std::cos(th) * std::cos(ph));
    }
    ClipPolygon poly;
    const Dual2<9> W = field_energy<Dual2<9>>(z, &poly);
    if (poly.size < 3 || W.v < 1e-12 * kEps) continue;
    ++tested;
    int inside = 0;
    for (int b = 0; b < 3; ++b) inside += z.segment<3>(3 * b).norm() < 1;
    ++inside_count[inside];
    SCOPED_TRACE("configuration " + std::to_string(tested));
    std::array<Vec3, 3> Q;
    std::array<DepthSample, 3> depth;
    for (int b = 0; b < 3; ++b) Q[b] = z.segment<3>(3 * b), depth[b] = sphere_sample(Q[b]);
    TriangleGradient grad, grad_only;
    TriangleHessian hess;
    const double energy = field_polygon_penalty_derivatives(poly, Q, depth, kEps, 0.0, grad, &hess);
    field_polygon_penalty_derivatives(poly, Q, depth, kEps, 0.0, grad_only, nullptr);
    EXPECT_NEAR(energy, W.v, 1e-12 * W.v);
    EXPECT_LE((grad - W.g).cwiseAbs().maxCoeff(), 1e-10 * W.g.cwiseAbs().maxCoeff());
    EXPECT_LE((hess - W.h).cwiseAbs().maxCoeff(), 1e-10 * W.h.cwiseAbs().maxCoeff());
    EXPECT_EQ((grad_only - grad).cwiseAbs().maxCoeff(), 0.0);
    const double h = 1e-6;
    const Vec9 grad_fd =
        testing::central_gradient([&](const Vec9& y) { return field_energy<double>(y); }, z, h);
    const Eigen::MatrixXd hess_fd =
        testing::central_jacobian([&](const Vec9& y) { return field_energy<Dual2<9>>(y).g; }, z, h);
    EXPECT_LE((grad - grad_fd).cwiseAbs().maxCoeff(), 1e-6 * grad.cwiseAbs().maxCoeff());
    EXPECT_LE((hess - hess_fd).cwiseAbs().maxCoeff(), 1e-5 * hess.cwiseAbs().maxCoeff());
  }
  for (int k = 1; k <= 3; ++k) EXPECT_GT(inside_count[k], 10) << k << " corners inside";
}

}  // namespace
}  // namespace depthfem
