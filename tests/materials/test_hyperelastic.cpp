// Every material model: derivatives against finite differences, stress-free reference state,
// closed-form uniaxial and simple-shear responses, barrier at J -> 0.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "finite_differences.hpp"
#include "materials/closed_forms.hpp"
#include "materials/material.hpp"
#include "materials/random_state.hpp"

namespace depthfem {
namespace {

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

// Representative parameters [Pa]; soft-tissue scale so that errors are judged against ~1e4 Pa.
NeoHookean neo() {
  return NeoHookean::from_youngs(3e4, 0.4);
}
MooneyRivlin mr() {
  return {4e3, 1e3, 2e4};
}
Veronda veronda() {
  return {1.5e3, 0.8, 2e4};
}
NearlyIncompressibleMooneyRivlin nimr() {
  return {4e3, 1e3, 5e5};
}
FiberReinforced<MooneyRivlin> fiber_mr() {
  return {mr(), 2e3, 3.0};
}
FiberReinforced<Veronda> fiber_veronda() {
  return {veronda(), 2e3, 3.0};
}

using testing::RandomState;

template <class M>
class MaterialTest : public ::testing::Test {};

template <class M>
M sample();
template <>
NeoHookean sample() {
  return neo();
}
template <>
MooneyRivlin sample() {
  return mr();
}
template <>
Veronda sample() {
  return veronda();
}
template <>
NearlyIncompressibleMooneyRivlin sample() {
  return nimr();
}
template <>
FiberReinforced<MooneyRivlin> sample() {
  return fiber_mr();
}
template <>
FiberReinforced<Veronda> sample() {
  return fiber_veronda();
}

using AllMaterials =
    ::testing::Types<NeoHookean, MooneyRivlin, Veronda, NearlyIncompressibleMooneyRivlin,
                     FiberReinforced<MooneyRivlin>, FiberReinforced<Veronda>>;
TYPED_TEST_SUITE(MaterialTest, AllMaterials);

// Central differences with step 1e-6 on entries of F of order 1 have truncation error ~1e-12 *
// third derivative and round-off ~1e-16 * psi / 1e-6; relative 1e-6 of the largest entry bounds
// both for these moduli with a wide margin.
TYPED_TEST(MaterialTest, StressMatchesFiniteDifferencesOfEnergy) {
  const TypeParam m = sample<TypeParam>();
  RandomState rnd;
  for (int trial = 0; trial < 25; ++trial) {
    const Mat3 F = rnd.F();
    const Vec3 f = rnd.fiber();
    const Mat3 P = first_piola(m, F, f);
    const Mat3 P_fd =
        testing::central_gradient([&](const Mat3& G) { return energy_density(m, G, f); }, F, 1e-6);
    EXPECT_LE((P - P_fd).cwiseAbs().maxCoeff(), 1e-6 * P.cwiseAbs().maxCoeff() + 1e-6)
        << "trial " << trial << "\nP=\n"
        << P << "\nfd=\n"
        << P_fd;
  }
}

TYPED_TEST(MaterialTest, StressDerivativeMatchesFiniteDifferencesOfStress) {
  const TypeParam m = sample<TypeParam>();
  RandomState rnd;
  for (int trial = 0; trial < 25; ++trial) {
    const Mat3 F = rnd.F();
    const Vec3 f = rnd.fiber();
    const Mat9 D = first_piola_derivative(m, F, f);
    Mat9 D_fd;
    for (int k = 0; k < 9; ++k) {  // column k: dP/dF_k, the derivative along the unit F_k
      Mat3 E = Mat3::Zero();
      E(k) = 1;
      const Mat3 dP = testing::central_directional(
          [&](const Mat3& G) { return first_piola(m, G, f); }, F, E, 1e-6);
      D_fd.col(k) = Eigen::Map<const Vec9>(dP.data());
    }
    EXPECT_LE((D - D_fd).cwiseAbs().maxCoeff(), 1e-6 * D.cwiseAbs().maxCoeff())
        << "trial " << trial;
    EXPECT_LE((D - D.transpose()).cwiseAbs().maxCoeff(), 1e-12 * D.cwiseAbs().maxCoeff());
  }
}

TYPED_TEST(MaterialTest, ReferenceStateIsStressFreeWithZeroEnergy) {
  const TypeParam m = sample<TypeParam>();
  RandomState rnd;
  const Mat3 I = Mat3::Identity();
  for (int trial = 0; trial < 5; ++trial) {
    const Vec3 f = rnd.fiber();
    EXPECT_NEAR(energy_density(m, I, f), 0.0, 1e-9);
    EXPECT_LE(first_piola(m, I, f).cwiseAbs().maxCoeff(), 1e-9);  // moduli ~1e4: 1e-13 relative
  }
  // Rotations are stress-free as well (frame indifference): P(R) = 0.
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  EXPECT_LE(first_piola(m, R, R.transpose() * Vec3::UnitZ()).cwiseAbs().maxCoeff(), 1e-9);
}

TYPED_TEST(MaterialTest, EnergyIsABarrierAgainstInversion) {
  const TypeParam m = sample<TypeParam>();
  const double mu = linearized_moduli(m).mu;
  Mat3 F = Mat3::Identity();
  double previous = 0;
  for (double s : {0.5, 0.1, 1e-2, 1e-4, 1e-8}) {
    F(2, 2) = s;
    const double psi = energy_density(m, F);
    EXPECT_GT(psi, previous) << "psi must grow as J = " << s << " -> 0";
    previous = psi;
  }
  EXPECT_GT(previous, 5 * mu);  // -ln(1e-8) ~ 18 times a modulus
  F(2, 2) = -0.1;
  EXPECT_TRUE(std::isinf(energy_density(m, F)));
  F(2, 2) = 0.0;
  EXPECT_TRUE(std::isinf(energy_density(m, F)));
}

using namespace closed_form;

TYPED_TEST(MaterialTest, UniaxialStretchMatchesClosedForm) {
  const TypeParam m = sample<TypeParam>();
  for (double l : {0.6, 0.9, 1.05, 1.3, 1.6}) {
    const double t = lateral_stretch(m, l);
    const Uniaxial expected = closed_uniaxial(m, l, t);
    const Mat3 P = first_piola(m, Vec3(l, t, t).asDiagonal(), Vec3::UnitX());
    const double scale = std::abs(expected.P11);
    EXPECT_NEAR(P(0, 0), expected.P11, 1e-12 * scale) << "stretch " << l;
    EXPECT_NEAR(P(1, 1), 0.0, 1e-9 * scale) << "lateral stress must vanish, stretch " << l;
    EXPECT_NEAR(P(2, 2), 0.0, 1e-9 * scale);
    EXPECT_LE((P - Mat3(P.diagonal().asDiagonal())).cwiseAbs().maxCoeff(), 1e-12 * scale);
  }
}

TYPED_TEST(MaterialTest, SmallStrainSlopeIsYoungsModulus) {
  const TypeParam m = sample<TypeParam>();
  const LinearizedModuli lin = linearized_moduli(m);
  // A fiber along the load adds psi_44 (dI4/dF00)^2 = alpha beta^2 * 4 to C_xxxx only; with the
  // lateral strain unchanged the uniaxial modulus along the fiber is E + 4 alpha beta^2.
  double E = lin.youngs();
  if constexpr (TypeParam::kUsesFiber) E += 4 * m.alpha * m.beta * m.beta;
  const double e = 1e-6, l = 1 + e, t = lateral_stretch(m, l);
  EXPECT_NEAR(closed_uniaxial(m, l, t).P11 / e, E, 1e-4 * E);
  EXPECT_NEAR((1 - t) / e, lin.poisson(), 1e-4);
}

TYPED_TEST(MaterialTest, SimpleShearMatchesClosedForm) {
  const TypeParam m = sample<TypeParam>();
  for (double g : {0.05, 0.3, 0.8}) {
    Mat3 F = Mat3::Identity();
    F(0, 1) = g;
    const Mat3 expected = simple_shear_piola(m, g);
    const Mat3 P = first_piola(m, F, Vec3::UnitY());
    EXPECT_LE((P - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff())
        << "shear " << g << "\nP=\n"
        << P << "\nexpected=\n"
        << expected;
  }
}

// ---- Model-specific facts
// ------------------------------------------------------------------------
TEST(MooneyRivlin, ShearModulusIsTwiceC1PlusC2) {
  const MooneyRivlin m = mr();
  EXPECT_NEAR(linearized_moduli(m).mu, 2 * (m.C1 + m.C2), 1e-9);
}

// lambda = 4 (a + C2): the linearisation (by finite differences of the stress, in
// linearized_moduli) must return the requested E and nu for any admissible C2.
TEST(MooneyRivlin, FromYoungsHasThoseSmallStrainModuli) {
  for (const double nu : {0.0, 0.3, 0.45, 0.49}) {
    for (const double c2_share : {0.0, 0.25, 0.5}) {
      const double E = 3e4, mu = E / (2 * (1 + nu));
      const MooneyRivlin m = MooneyRivlin::from_youngs(E, nu, c2_share * mu / 2);
      EXPECT_NO_THROW(m.validate());
      const LinearizedModuli lin = linearized_moduli(m);
      EXPECT_NEAR(lin.youngs(), E, 1e-7 * E) << "nu " << nu << ", C2 share " << c2_share;
      EXPECT_NEAR(lin.poisson(), nu, 1e-7) << "nu " << nu << ", C2 share " << c2_share;
    }
  }
  EXPECT_THROW(MooneyRivlin::from_youngs(3e4, 0.5), std::invalid_argument);
  EXPECT_THROW(MooneyRivlin::from_youngs(3e4, 0.3, 1e5), std::invalid_argument);
}

TEST(NeoHookean, LinearizedModuliAreTheLameParameters) {
  const NeoHookean m = neo();
  const LinearizedModuli lin = linearized_moduli(m);
  EXPECT_NEAR(lin.mu, m.mu, 1e-9);
  EXPECT_NEAR(lin.lambda, m.lambda, 1e-9);
  EXPECT_NEAR(lin.youngs(), 3e4, 1e-7);
  EXPECT_NEAR(lin.poisson(), 0.4, 1e-12);
}

// The Veronda form as printed in the paper, evaluated with the same machinery: at F = I it
// carries the hydrostatic stress 4 alpha (1 + beta) I derived next to `Veronda`.
struct PrintedVeronda {
  double alpha, beta, a;
  static constexpr bool kUsesI2 = true;
  static constexpr bool kUsesFiber = false;
  template <int kOrder>
  InvariantDerivatives<> evaluate(const Invariants<>& inv) const {
    const double I3 = inv.J * inv.J;
    InvariantDerivatives<> e;
    e.psi =
        2 * alpha * std::exp(inv.I1 - 3) + alpha * beta * (inv.I2 - 3) + a * I3 - a * std::log(I3);
    e.d[kI1] = 2 * alpha * std::exp(inv.I1 - 3);
    e.d[kI2] = alpha * beta;
    e.d[kJ] = 2 * a * inv.J - 2 * a / inv.J;
    return e;
  }
};

TEST(Veronda, PrintedFormIsNotStressFreeAndTheCorrectionIs) {
  const Veronda v = veronda();
  const PrintedVeronda printed{v.alpha, v.beta, v.a};
  const Mat3 P_printed = first_piola(printed, Mat3::Identity());
  EXPECT_LE((P_printed - 4 * v.alpha * (1 + v.beta) * Mat3::Identity()).cwiseAbs().maxCoeff(),
            1e-9);
  EXPECT_LE(first_piola(v, Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-9);
  // The correction only changes the volumetric part: deviatoric shear response is identical.
  Mat3 F = Mat3::Identity();
  F(0, 1) = 0.4;
  EXPECT_NEAR(first_piola(v, F)(0, 1), first_piola(printed, F)(0, 1), 1e-9);
}

TEST(MaterialModel, NamesAndValidation) {
  EXPECT_EQ(material_name(MaterialModel{fiber_veronda()}), "fiber_veronda");
  EXPECT_TRUE(material_uses_fiber(MaterialModel{fiber_mr()}));
  EXPECT_FALSE(material_uses_fiber(MaterialModel{mr()}));
  EXPECT_NO_THROW(validate_material(MaterialModel{nimr()}));
  EXPECT_THROW(validate_material(MaterialModel{MooneyRivlin{-1, 1, 1}}), std::invalid_argument);
  EXPECT_THROW(validate_material(MaterialModel{NeoHookean{1e3, -1e4}}), std::invalid_argument);
  EXPECT_THROW(NeoHookean::from_youngs(1e3, 0.5), std::invalid_argument);
}

}  // namespace
}  // namespace depthfem
