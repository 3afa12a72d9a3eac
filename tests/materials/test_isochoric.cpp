// The isochoric part of every material model (materials/isochoric.hpp): derivatives against
// finite differences, invariance under dilation, and the exact split of the nearly
// incompressible Mooney-Rivlin model.
#include <gtest/gtest.h>

#include <random>

#include "finite_differences.hpp"
#include "materials/all_models.hpp"
#include "materials/isochoric.hpp"
#include "materials/random_state.hpp"

namespace depthfem {
namespace {

using testing::RandomState;

// Runs check(F, f) at `trials` random deformation gradients and fiber directions (fixed seed).
template <class Check>
void at_random_states(int trials, Check check) {
  RandomState rnd;
  for (int trial = 0; trial < trials; ++trial) {
    const Mat3 F = rnd.F();
    const Vec3 f = rnd.fiber();
    check(F, f);
  }
}

// Runs check(Isochoric<M>{m}, name) for every model of all_models().
template <class Check>
void for_each_isochoric(Check check) {
  for (const MaterialModel& model : all_models())
    std::visit([&]<class M>(const M& m) { check(Isochoric<M>{m}, material_name(model)); }, model);
}

// Central differences with step 1e-6 on entries of F of order 1: truncation ~1e-12 times the
// third derivative, round-off ~1e-16 psi / 1e-6; 1e-6 of the largest entry bounds both (as for
// the models themselves in test_hyperelastic.cpp).
TEST(Isochoric, StressAndItsDerivativeMatchFiniteDifferences) {
  for_each_isochoric([](const auto& m, const std::string& name) {
    at_random_states(20, [&](const Mat3& F, const Vec3& f) {
      const Mat3 P = first_piola(m, F, f);
      const Mat3 P_fd = testing::central_gradient(
          [&](const Mat3& G) { return energy_density(m, G, f); }, F, 1e-6);
      EXPECT_LE((P - P_fd).cwiseAbs().maxCoeff(), 1e-6 * P.cwiseAbs().maxCoeff()) << name;
      const Mat9 D = first_piola_derivative(m, F, f);
      for (int k = 0; k < 9; ++k) {
        Mat3 E = Mat3::Zero();
        E(k) = 1;
        const Mat3 dP = testing::central_directional(
            [&](const Mat3& G) { return first_piola(m, G, f); }, F, E, 1e-6);
        EXPECT_LE((D.col(k) - Eigen::Map<const Vec9>(dP.data())).cwiseAbs().maxCoeff(),
                  1e-6 * D.cwiseAbs().maxCoeff())
            << name << " column " << k;
      }
    });
  });
}

// psi_iso(s F) = psi_iso(F) for any s > 0 (up to round-off), so the isochoric part carries no
// bulk stiffness and its stress is deviatoric: tr(P F^T) = 0. At F = I it is stress-free with
// the base model's shear modulus and (models without fibers) zero small-strain bulk modulus.
TEST(Isochoric, IsInvariantUnderDilationAndKeepsTheShearModulus) {
  for_each_isochoric([](const auto& m, const std::string& name) {
    at_random_states(10, [&](const Mat3& F, const Vec3& f) {
      const double psi = energy_density(m, F, f);
      for (double s : {0.5, 0.9, 1.7})
        EXPECT_NEAR(energy_density(m, s * F, f), psi, 1e-12 * (std::abs(psi) + 1e3)) << name;
      const Mat3 P = first_piola(m, F, f);
      EXPECT_LE(std::abs((P * F.transpose()).trace()), 1e-10 * P.norm()) << name;
    });
    EXPECT_LE(first_piola(m, Mat3::Identity()).norm(), 1e-9) << name;
    const LinearizedModuli iso = linearized_moduli(m), full = linearized_moduli(m.base);
    EXPECT_NEAR(iso.mu, full.mu, 1e-12 * full.mu) << name;
    // linearized_moduli reads lambda off dP_00/dF_11, which an isochoric fiber term along e_x
    // also stiffens (I4~ couples the fiber stretch with J); the dilation test above covers it.
    if (!m.kUsesFiber) {
      EXPECT_NEAR(iso.bulk(), 0.0, 1e-9 * full.mu) << name;
    }
  });
}

// NearlyIncompressibleMooneyRivlin is split exactly: psi = psi_iso + kappa/2 ((J^2-1)/2 - ln J).
TEST(Isochoric, SplitsTheNearlyIncompressibleMooneyRivlinExactly) {
  const NearlyIncompressibleMooneyRivlin m{4e3, 1e3, 5e5};
  const Isochoric<NearlyIncompressibleMooneyRivlin> iso{m};
  at_random_states(10, [&](const Mat3& F, const Vec3& /*f*/) {
    const double J = F.determinant();
    const double volumetric = 0.5 * m.kappa * (0.5 * (J * J - 1) - std::log(J));
    EXPECT_NEAR(energy_density(iso, F) + volumetric, energy_density(m, F),
                1e-12 * std::abs(energy_density(m, F)));
  });
}

}  // namespace
}  // namespace depthfem
