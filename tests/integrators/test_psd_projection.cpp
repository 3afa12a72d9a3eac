// Projection of element Hessians onto the positive semi-definite matrices: the Hessian of a tet in
// a stable state is kept, that of a compressed tet becomes the nearest PSD matrix.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <limits>

#include "integrators/elements/psd_projection.hpp"
#include "materials/all_models.hpp"

namespace depthfem {
namespace {

using Vec12 = Eigen::Matrix<double, 12, 1>;

// A tet of edges about 0.1 m (not right-angled) deformed by F: its 12x12 Hessian.
Mat12 tet_hessian(const MaterialModel& model, const Mat3& F) {
  Mat3 Dm;
  Dm << 0.1, 0.02, -0.01, 0.01, 0.09, 0.03, -0.02, 0.01, 0.11;
  const Vec3 fiber = Vec3(1, 2, 0.5).normalized();
  TetLocal local;
  std::visit(
      [&](const auto& m) {
        tet_local<2>(m, Mat3(F * Dm), Mat3(Dm.inverse()), Dm.determinant() / 6, fiber, local);
      },
      model);
  return local.hessian;
}

Mat3 rotation() {
  return Eigen::AngleAxisd(0.7, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
}

Vec12 eigenvalues(const Mat12& h) {
  return Eigen::SelfAdjointEigenSolver<Mat12>(h).eigenvalues();
}

// Stretched by 0.2 to 0.9 % along three oblique axes, then rotated: every principal strain is
// tensile, so every principal stress is tensile (isotropic parts with lambda >= 0; fibers
// stretched).
Mat3 stretched() {
  const Mat3 Q = Eigen::AngleAxisd(0.4, Vec3(0.3, 1, -0.2).normalized()).toRotationMatrix();
  return rotation() * Q * Vec3(1.002, 1.005, 1.009).asDiagonal() * Q.transpose();
}

// In the stretched state the Hessian is PSD in exact arithmetic: the material part is the
// small-strain elasticity tensor (positive), the initial-stress part adds sigma-weighted squares
// of the gradients (non-negative under tension); its only zero eigenvalues are the three
// translations, which rounding leaves at about +-1e-16 |H|. The projection leaves it untouched
// (Cholesky test of the node 1..3 block) or rebuilds it from its eigen-decomposition to the
// backward error (a few eps |H|): 1e-12 |H| bounds both.
TEST(PsdProjection, KeepsTheHessianOfAStretchedTet) {
  for (const MaterialModel& model : all_models()) {
    const Mat12 h = tet_hessian(model, stretched());
    const double scale = h.cwiseAbs().maxCoeff();
    const Vec12 lambda = eigenvalues(h);
    ASSERT_GE(lambda(0), -1e-12 * lambda(11)) << material_name(model) << ": not a stable state";
    EXPECT_GT(lambda(3), 1e-6 * lambda(11)) << material_name(model);  // rotations stiffened
    Mat12 p = h;
    project_to_psd(p);
    EXPECT_LE((p - h).cwiseAbs().maxCoeff(), 1e-12 * scale) << material_name(model);
  }
}

// Shortened by 30 % along one axis (no lateral expansion: every principal stress compressive),
// then rotated. Compression makes the linearised rotations about the two transverse axes lower the
// energy: negative eigenvalues of order sigma V / |x|^2. The projection P must be the nearest PSD
// matrix: same eigenvectors, eigenvalues max(lambda, 0), so P - H = sum over lambda < 0 of
// |lambda| v v^T is PSD and ||P - H||_F = sqrt(sum lambda_-^2). Tolerances: 1e-12 of the largest
// eigenvalue for what rounding should leave at zero, 1e-10 relative for the distance.
TEST(PsdProjection, ClampsTheNegativeEigenvaluesOfACompressedTet) {
  const Mat3 F = rotation() * Vec3(1, 1, 0.7).asDiagonal();
  for (const MaterialModel& model : all_models()) {
    const Mat12 h = tet_hessian(model, F);
    const Vec12 lambda = eigenvalues(h);
    const double top = lambda(11);
    ASSERT_LT(lambda(0), -1e-3 * top) << material_name(model) << ": no negative eigenvalue";
    Mat12 p = h;
    EXPECT_TRUE(project_to_psd(p));
    EXPECT_EQ((p - p.transpose()).cwiseAbs().maxCoeff(), 0.0);
    const Vec12 mu = eigenvalues(p);
    for (int k = 0; k < 12; ++k)
      EXPECT_NEAR(mu(k), std::max(lambda(k), 0.0), 1e-12 * top) << material_name(model) << k;
    EXPECT_GE(eigenvalues(p - h)(0), -1e-12 * top) << material_name(model);
    const double distance = lambda.cwiseMin(0.0).norm();
    EXPECT_NEAR((p - h).norm(), distance, 1e-10 * distance) << material_name(model);
  }
}

// A Hessian whose node 1..3 block has a Cholesky factor is returned bit for bit; so is one with a
// non-finite entry.
TEST(PsdProjection, LeavesPositiveAndNonFiniteHessiansAlone) {
  Mat12 h = tet_hessian(NeoHookean::from_youngs(3e4, 0.4), stretched());
  const Mat12 kept = h;
  EXPECT_FALSE(project_to_psd(h));
  EXPECT_EQ(h, kept);
  Mat12 bad = tet_hessian(NeoHookean::from_youngs(3e4, 0.4), Vec3(1, 1, 0.7).asDiagonal());
  bad(3, 4) = bad(4, 3) = std::numeric_limits<double>::infinity();
  const Mat12 bad_kept = bad;
  EXPECT_FALSE(project_to_psd(bad));
  EXPECT_EQ(bad.cwiseEqual(bad_kept).count(), 144);
}

}  // namespace
}  // namespace depthfem
