// Per-tet stress and strain against closed forms: on a box deformed homogeneously by uniaxial
// stretch and by simple shear, every tet's Cauchy stress is P F^T / J with the hand-derived P of
// each material (tests/materials/closed_forms.hpp), its logarithmic strain the closed-form ln V,
// and a tet in no material group (a rigid body) carries no stress.
#include <gtest/gtest.h>

#include <cmath>

#include "core/mesh_generators.hpp"
#include "integrators/elements/element_fields.hpp"
#include "materials/closed_forms.hpp"

namespace depthfem {
namespace {

using namespace closed_form;

// A 2 x 1 x 1 box of 2 x 2 x 2 cells (48 tets): the first 24 tets of material m with fibers along
// `fiber`, the rest in no group.
struct Sample {
  TetMesh box = box_mesh({Vec3::Zero(), Vec3(2, 1, 1), Eigen::Vector3i(2, 2, 2)});
  std::vector<ElasticGroup> groups;
  template <class M>
  Sample(const M& m, const Vec3& fiber) {
    ElasticGroup g{m, {}, Points()};
    for (Index t = 0; t < 24; ++t) g.tets.push_back(t);
    if (material_uses_fiber(g.material)) g.fibers = fiber.transpose().replicate(24, 1);
    groups.push_back(std::move(g));
  }
  ElementFields at(const Mat3& F) const {
    const Points x = box.X * F.transpose();
    return element_fields(box.X, box.tets, groups, x, {true, true});
  }
};

// (xx, yy, zz, xy, yz, xz) of a symmetric matrix.
Eigen::Matrix<double, 1, 6> voigt(const Mat3& S) {
  return {S(0, 0), S(1, 1), S(2, 2), S(0, 1), S(1, 2), S(0, 2)};
}

template <class M>
class ElementFieldsTest : public ::testing::Test {};

template <class M>
M sample_material();
template <>
NeoHookean sample_material() {
  return NeoHookean::from_youngs(3e4, 0.4);
}
template <>
MooneyRivlin sample_material() {
  return {4e3, 1e3, 2e4};
}
template <>
Veronda sample_material() {
  return {1.5e3, 0.8, 2e4};
}
template <>
NearlyIncompressibleMooneyRivlin sample_material() {
  return {4e3, 1e3, 5e5};
}
template <>
FiberReinforced<MooneyRivlin> sample_material() {
  return {{4e3, 1e3, 2e4}, 2e3, 3.0};
}

using Materials = ::testing::Types<NeoHookean, MooneyRivlin, Veronda,
                                   NearlyIncompressibleMooneyRivlin, FiberReinforced<MooneyRivlin>>;
TYPED_TEST_SUITE(ElementFieldsTest, Materials);

// F = diag(l, t, t) with the lateral stretch t that frees the lateral faces: sigma = diag(P11 /
// t^2, 0, 0) (P F^T / J with J = l t^2), von Mises |sigma_xx|, ln V = diag(ln l, ln t, ln t).
// Tolerances: P comes from the library's chain rule at 1e-12 of the closed form (the material
// tests), and the 2x2x2 Dm^-1 inversions cost a few ulps more: 1e-10 of the stress scale.
TYPED_TEST(ElementFieldsTest, UniaxialStretchMatchesClosedForm) {
  const TypeParam m = sample_material<TypeParam>();
  const Sample s(m, Vec3::UnitX());
  for (double l : {0.7, 1.3}) {
    const double t = lateral_stretch(m, l);
    const double sxx = closed_uniaxial(m, l, t).P11 / (t * t);
    const ElementFields e = s.at(Vec3(l, t, t).asDiagonal());
    const Eigen::Matrix<double, 1, 6> stress(sxx, 0, 0, 0, 0, 0);
    const Eigen::Matrix<double, 1, 6> strain(std::log(l), std::log(t), std::log(t), 0, 0, 0);
    for (Index k = 0; k < 48; ++k) {
      SCOPED_TRACE("stretch " + std::to_string(l) + ", tet " + std::to_string(k));
      if (k < 24) {
        EXPECT_LE((e.stress.row(k) - stress).cwiseAbs().maxCoeff(), 1e-10 * std::abs(sxx));
        EXPECT_NEAR(e.von_mises(k), std::abs(sxx), 1e-10 * std::abs(sxx));
      } else {
        EXPECT_EQ(e.stress.row(k).norm(), 0.0);
        EXPECT_EQ(e.von_mises(k), 0.0);
      }
      EXPECT_LE((e.strain.row(k) - strain).cwiseAbs().maxCoeff(), 1e-14);
      EXPECT_NEAR(e.volume_ratio(k), l * t * t, 1e-14);
    }
  }
}

// F = I + g e_x e_y^T (fiber along y), J = 1: sigma = P F^T with the hand-derived P. ln V has the
// closed form asinh(g/2) / sqrt(1 + g^2/4) [[g/2, 1, 0], [1, -g/2, 0], [0, 0, 0]]: with
// s = sqrt(1 + g^2/4), B = F F^T = (1 + g^2/2) I + g M for that matrix M (eigenvalues +-s), whose
// eigenvalues 1 + g^2/2 +- g s are (s +- g/2)^2, and ln(s + g/2) = asinh(g/2).
TYPED_TEST(ElementFieldsTest, SimpleShearMatchesClosedForm) {
  const TypeParam m = sample_material<TypeParam>();
  const Sample s(m, Vec3::UnitY());
  for (double g : {0.3, 0.8}) {
    Mat3 F = Mat3::Identity();
    F(0, 1) = g;
    const Mat3 sigma = simple_shear_piola(m, g) * F.transpose();
    const double root = std::sqrt(1 + g * g / 4), c = std::asinh(g / 2) / root;
    const Eigen::Matrix<double, 1, 6> strain(c * g / 2, -c * g / 2, 0, c, 0, 0);
    const ElementFields e = s.at(F);
    const double scale = sigma.cwiseAbs().maxCoeff();
    for (Index k = 0; k < 24; ++k) {
      SCOPED_TRACE("shear " + std::to_string(g) + ", tet " + std::to_string(k));
      EXPECT_LE((e.stress.row(k) - voigt(sigma)).cwiseAbs().maxCoeff(), 1e-10 * scale);
      EXPECT_LE((e.strain.row(k) - strain).cwiseAbs().maxCoeff(), 1e-14);
      EXPECT_NEAR(e.volume_ratio(k), 1.0, 1e-14);
    }
  }
}

// Only what is asked for is computed.
TEST(ElementFields, LeavesFieldsNotAskedForEmpty) {
  const Sample s(MooneyRivlin{4e3, 1e3, 2e4}, Vec3::UnitX());
  const ElementFields stress =
      element_fields(s.box.X, s.box.tets, s.groups, s.box.X, {true, false});
  EXPECT_EQ(stress.stress.rows(), 48);
  EXPECT_EQ(stress.strain.rows(), 0);
  EXPECT_EQ(stress.volume_ratio.rows(), 0);
  const ElementFields strain =
      element_fields(s.box.X, s.box.tets, s.groups, s.box.X, {false, true});
  EXPECT_EQ(strain.stress.rows(), 0);
  EXPECT_EQ(strain.von_mises.rows(), 0);
  EXPECT_EQ(strain.strain.rows(), 48);
}

}  // namespace
}  // namespace depthfem
