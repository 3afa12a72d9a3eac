// Exact derivatives of the pair penalty against finite differences, in every clip case.
#include <gtest/gtest.h>

#include <random>

#include "contact/penalty.hpp"

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
  for (int b = 0; b < 3; ++b) Q[b] = z.segment<3>(12 + 3 * b), Qv[b] = make_point<D>(Q[b], 12 + 3 * b);
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
    Vec21 grad_fd;
    Eigen::Matrix<double, 21, 21> hess_fd;
    for (int i = 0; i < 21; ++i) {
      Vec21 zp = z, zm = z;
      zp(i) += h;
      zm(i) -= h;
      grad_fd(i) = (energy(zp, g) - energy(zm, g)) / (2 * h);
      ClipPolygon pp, pm;
      hess_fd.col(i) = (energy_dual(zp, g, &pp).g - energy_dual(zm, g, &pm).g) / (2 * h);
    }
    EXPECT_LE((W.g - grad_fd).cwiseAbs().maxCoeff(), 1e-6 * W.g.cwiseAbs().maxCoeff()) << "config " << tested;
    EXPECT_LE((W.h - hess_fd).cwiseAbs().maxCoeff(), 1e-5 * W.h.cwiseAbs().maxCoeff()) << "config " << tested;
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

}  // namespace
}  // namespace depthfem
