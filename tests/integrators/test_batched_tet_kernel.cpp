// The batched tet kernel against the scalar reference tet_local, lane by lane, for every material
// model: random deformations, elements near inversion, inverted elements and padding lanes.
#include <gtest/gtest.h>

#include <random>

#include "core/types.hpp"
#include "integrators/elements/batched_tet_kernel.hpp"
#include "materials/all_models.hpp"
#include "materials/material.hpp"

namespace depthfem {
namespace {

using V = Lanes<kLanes>;

// One tet's inputs in the scalar kernel's form.
struct TetInput {
  Mat3 Ds, D;
  double volume;
  Vec3 fiber;
};

// A rest tet with random corners near the unit corner tet and current edges Ds = F Dm, F chosen
// by `make_F`.
template <class MakeF>
TetInput random_tet(std::mt19937& rng, MakeF make_F) {
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  Mat3 Dm = 0.1 * Mat3::Identity();
  for (int k = 0; k < 9; ++k) Dm(k) += 0.02 * u(rng);
  Vec3 f(u(rng), u(rng), u(rng));
  f += Vec3(1, 0.5, 0.2);
  return {make_F(rng) * Dm, Dm.inverse(), Dm.determinant() / 6, f.normalized()};
}

// F = I + 0.3 (uniform entries in [-1, 1]): stretches, shears and rotations of order 30 %.
Mat3 moderate_F(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Mat3 F = Mat3::Identity();
  for (int k = 0; k < 9; ++k) F(k) += 0.3 * u(rng);
  if (F.determinant() <= 0) F.col(0) *= -1;
  return F;
}

// A rotation times diag(s, s, J / s^2) with J in [1e-6, 1e-2]: a tet flattened almost to zero
// volume, where the barrier terms dominate.
Mat3 nearly_inverted_F(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const double J = std::pow(10.0, -6 + 4 * u(rng)), s = 0.8 + 0.4 * u(rng);
  const Eigen::Quaterniond q(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
  return q.normalized().toRotationMatrix() * Vec3(s, s, J / (s * s)).asDiagonal();
}

void set_lane(TetBatchInput<V>& in, int l, const TetInput& t) {
  for (int k = 0; k < 9; ++k) {
    in.Ds[k].set(l, t.Ds(k));
    in.D[k].set(l, t.D(k));
  }
  in.volume.set(l, t.volume);
  for (int k = 0; k < 3; ++k) in.fiber[k].set(l, t.fiber(k));
}

// |a - b| <= tol * scale entry by entry, where scale is the largest magnitude in the reference:
// both kernels round each entry to within a few ulps of the largest term that enters it, and
// the chain rule sums terms no larger than the largest entry times the (bounded) size of D.
// (Largest magnitudes taken entry by entry: GCC 12 warns falsely inside Eigen's AVX-512 maxCoeff
// of fixed-size matrices.)
template <class M>
double max_abs(const M& m) {
  double largest = 0;
  for (Eigen::Index k = 0; k < m.size(); ++k) largest = std::max(largest, std::abs(m(k)));
  return largest;
}
template <class A, class B>
void expect_close(const A& batched, const B& reference, double tol, const std::string& what) {
  EXPECT_LE(max_abs((batched - reference).eval()), tol * max_abs(reference)) << what;
}

// Runs kOrder on batches of tets made by make_F and compares every lane with tet_local.
template <int kOrder, class MakeF>
void compare_with_reference(const MaterialModel& model, MakeF make_F, unsigned seed) {
  std::mt19937 rng(seed);
  for (int batch = 0; batch < 50; ++batch) {
    std::array<TetInput, kLanes> tets;
    TetBatchInput<V> in;
    for (int l = 0; l < kLanes; ++l) set_lane(in, l, tets[l] = random_tet(rng, make_F));
    TetBatch<V> out;
    std::visit([&](const auto& m) { tet_batch<kOrder>(m, in, out); }, model);
    for (int l = 0; l < kLanes; ++l) {
      TetLocal ref;
      std::visit(
          [&](const auto& m) {
            tet_local<kOrder>(m, tets[l].Ds, tets[l].D, tets[l].volume, tets[l].fiber, ref);
          },
          model);
      const std::string what = material_name(model) + " order " + std::to_string(kOrder) +
                               " batch " + std::to_string(batch) + " lane " + std::to_string(l);
      ASSERT_TRUE(std::isfinite(ref.energy)) << what;
      EXPECT_NEAR(out.energy[l], ref.energy, 1e-13 * std::abs(ref.energy)) << what;
      if constexpr (kOrder >= 1) {
        Eigen::Matrix<double, 3, 4> g;
        for (int a = 0; a < 4; ++a)
          for (int c = 0; c < 3; ++c) g(c, a) = out.gradient[a][c][l];
        expect_close(g, ref.gradient, 1e-13, what + " gradient");
      }
      if constexpr (kOrder >= 2) expect_close(out.hessian_of(l), ref.hessian, 1e-13, what);
    }
  }
}

TEST(BatchedTetKernel, MatchesTheScalarKernelOnRandomDeformations) {
  for (const MaterialModel& model : all_models()) {
    compare_with_reference<0>(model, moderate_F, 1);
    compare_with_reference<1>(model, moderate_F, 2);
    compare_with_reference<2>(model, moderate_F, 3);
  }
}

TEST(BatchedTetKernel, MatchesTheScalarKernelNearInversion) {
  for (const MaterialModel& model : all_models()) {
    compare_with_reference<0>(model, nearly_inverted_F, 4);
    compare_with_reference<1>(model, nearly_inverted_F, 5);
    compare_with_reference<2>(model, nearly_inverted_F, 6);
  }
}

// Lanes are independent: an inverted tet gets +infinity energy and zero derivatives (as in
// tet_local), and padding lanes holding zeros (a degenerate tet) or NaN do not disturb the
// others, whatever their position in the batch.
TEST(BatchedTetKernel, InvertedAndPaddingLanesLeaveTheOthersAlone) {
  std::mt19937 rng(7);
  const MooneyRivlin m{4e3, 1e3, 2e4};
  for (int valid = 1; valid < kLanes; ++valid) {
    std::array<TetInput, kLanes> tets;
    TetBatchInput<V> in;
    for (int l = 0; l < valid; ++l) set_lane(in, l, tets[l] = random_tet(rng, moderate_F));
    Mat3 reflect = Mat3::Identity();
    reflect(2, 2) = -1;
    // A Mat3, not Eigen's product expression, which would refer to the destroyed moderate_F(r).
    tets[valid] = random_tet(rng, [&](std::mt19937& r) -> Mat3 { return reflect * moderate_F(r); });
    set_lane(in, valid, tets[valid]);
    for (int l = valid + 1; l < kLanes; ++l) {
      const double fill = l % 2 ? 0.0 : std::numeric_limits<double>::quiet_NaN();
      set_lane(in, l, {Mat3::Constant(fill), Mat3::Constant(fill), fill, Vec3::Constant(fill)});
    }
    TetBatch<V> out;
    tet_batch<2>(m, in, out);
    for (int l = 0; l < valid; ++l) {
      TetLocal ref;
      tet_local<2>(m, tets[l].Ds, tets[l].D, tets[l].volume, tets[l].fiber, ref);
      EXPECT_NEAR(out.energy[l], ref.energy, 1e-13 * std::abs(ref.energy));
      expect_close(out.hessian_of(l), ref.hessian, 1e-13, "lane " + std::to_string(l));
    }
    EXPECT_EQ(out.energy[valid], std::numeric_limits<double>::infinity());
    EXPECT_EQ(max_abs(out.hessian_of(valid)), 0.0);
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c) EXPECT_EQ(out.gradient[a][c][valid], 0.0);
  }
}

}  // namespace
}  // namespace depthfem
