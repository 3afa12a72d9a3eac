// The isochoric split and the scaled model of materials/viscoelastic.hpp for every material
// model: energies against their definition, P and dP/dF against finite differences, the batched
// stress against the scalar one, small-strain moduli; Prony series validation and step
// coefficients.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "finite_differences.hpp"
#include "materials/all_models.hpp"
#include "materials/batched_stress.hpp"
#include "materials/random_state.hpp"
#include "materials/viscoelastic.hpp"

namespace depthfem {
namespace {

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

using testing::RandomState;

// psi - (1 - s) psi(J^-1/3 F): the scaled model from its definition, not through invariants.
template <class M>
double scaled_by_definition(const M& m, double s, const Mat3& F, const Vec3& f) {
  const Mat3 Fbar = std::cbrt(1 / F.determinant()) * F;
  return energy_density(m, F, f) + (s - 1) * energy_density(m, Fbar, f);
}

TEST(Viscoelastic, ScaledEnergyIsTheModelLessItsIsochoricPart) {
  RandomState rnd(4321);
  for (const MaterialModel& model : all_models()) {
    std::visit(
        [&](const auto& m) {
          const IsochoricScaled<std::decay_t<decltype(m)>> scaled{m, 0.37};
          for (int trial = 0; trial < 10; ++trial) {
            const Mat3 F = rnd.F();
            const Vec3 f = rnd.fiber();
            const double expected = scaled_by_definition(m, 0.37, F, f);
            EXPECT_NEAR(energy_density(scaled, F, f), expected,
                        1e-11 * std::abs(energy_density(m, F, f)))
                << material_name(model);
          }
          // Stress-free and zero at F = I.
          const StressState s = evaluate_stress<1>(scaled, Mat3::Identity(), Vec3::UnitX());
          EXPECT_LE(std::abs(s.psi), 1e-9) << material_name(model);
          EXPECT_LE(s.P.cwiseAbs().maxCoeff(), 1e-9) << material_name(model);
        },
        model);
  }
}

// Central differences as in test_hyperelastic.cpp: step 1e-6 on entries of order 1, relative
// 1e-6 of the largest entry.
TEST(Viscoelastic, ScaledStressAndTangentMatchFiniteDifferences) {
  RandomState rnd(4321);
  for (const MaterialModel& model : all_models()) {
    std::visit(
        [&](const auto& m) {
          const IsochoricScaled<std::decay_t<decltype(m)>> scaled{m, 0.37};
          for (int trial = 0; trial < 15; ++trial) {
            const Mat3 F = rnd.F();
            const Vec3 f = rnd.fiber();
            const StressState s = evaluate_stress<2>(scaled, F, f);
            const Mat3 P_fd = testing::central_gradient(
                [&](const Mat3& G) { return energy_density(scaled, G, f); }, F, 1e-6);
            EXPECT_LE((s.P - P_fd).cwiseAbs().maxCoeff(), 1e-6 * s.P.cwiseAbs().maxCoeff())
                << material_name(model) << " trial " << trial;
            Mat9 D_fd;
            for (int k = 0; k < 9; ++k) {
              Mat3 E = Mat3::Zero();
              E(k) = 1;
              const Mat3 dP = testing::central_directional(
                  [&](const Mat3& G) { return first_piola(scaled, G, f); }, F, E, 1e-6);
              D_fd.col(k) = Eigen::Map<const Vec9>(dP.data());
            }
            EXPECT_LE((s.dPdF - D_fd).cwiseAbs().maxCoeff(), 1e-6 * s.dPdF.cwiseAbs().maxCoeff())
                << material_name(model) << " trial " << trial;
          }
        },
        model);
  }
}

// F S_iso = d psi(J^-1/3 F) / dF, the isochoric part's first Piola stress.
TEST(Viscoelastic, IsochoricStressIsTheDerivativeOfTheIsochoricEnergy) {
  RandomState rnd(4321);
  for (const MaterialModel& model : all_models()) {
    std::visit(
        [&](const auto& m) {
          for (int trial = 0; trial < 10; ++trial) {
            const Mat3 F = rnd.F();
            const Vec3 f = rnd.fiber();
            const Mat3 P = F * isochoric_pk2(m, F, f);
            const Mat3 P_fd = testing::central_gradient(
                [&](const Mat3& G) {
                  return energy_density(m, std::cbrt(1 / G.determinant()) * G, f);
                },
                F, 1e-6);
            EXPECT_LE((P - P_fd).cwiseAbs().maxCoeff(), 1e-6 * P.cwiseAbs().maxCoeff())
                << material_name(model) << " trial " << trial;
            const Mat3 S = isochoric_pk2(m, F, f);
            EXPECT_LE((S - S.transpose()).cwiseAbs().maxCoeff(), 1e-12 * S.cwiseAbs().maxCoeff());
            // Deviatoric in the reference sense: S_iso : C = 0.
            EXPECT_LE(std::abs((S.cwiseProduct(F.transpose() * F)).sum()),
                      1e-12 * S.cwiseAbs().maxCoeff());
          }
        },
        model);
  }
}

TEST(Viscoelastic, BatchedScaledStressMatchesTheScalarOne) {
  using V = Lanes<kLanes>;
  RandomState rnd(4321);
  for (const MaterialModel& model : all_models()) {
    std::visit(
        [&](const auto& m) {
          const IsochoricScaled<std::decay_t<decltype(m)>> scaled{m, 0.37};
          Mat3 F[kLanes];
          Vec3 f[kLanes];
          LaneMatrix3<V> Fl;
          std::array<V, 3> fl;
          for (int l = 0; l < kLanes; ++l) {
            F[l] = rnd.F();
            f[l] = rnd.fiber();
            for (int k = 0; k < 9; ++k) Fl[k].set(l, F[l](k));
            for (int k = 0; k < 3; ++k) fl[k].set(l, f[l](k));
          }
          const BatchedStress<V> b = evaluate_batched_stress<2>(scaled, Fl, fl);
          for (int l = 0; l < kLanes; ++l) {
            const StressState s = evaluate_stress<2>(scaled, F[l], f[l]);
            EXPECT_NEAR(b.psi[l], s.psi, 1e-13 * std::abs(s.psi)) << material_name(model);
            const double Ps = s.P.cwiseAbs().maxCoeff(), Ds = s.dPdF.cwiseAbs().maxCoeff();
            for (int p = 0; p < 9; ++p) {
              EXPECT_NEAR(b.P[p][l], s.P(p), 1e-13 * Ps) << material_name(model);
              for (int q = 0; q < 9; ++q)
                EXPECT_NEAR(b.dPdF(p, q)[l], s.dPdF(p, q), 1e-13 * Ds) << material_name(model);
            }
          }
        },
        model);
  }
}

// At small strain psi_iso carries the whole shear modulus and no bulk modulus, so the scaled
// model has shear modulus s mu and the model's bulk modulus. (Fiber models are left out: their
// fiber term couples the fiber strain to the volume change, so their Lame parameter changes.)
TEST(Viscoelastic, ScalingKeepsTheBulkModulusAndScalesTheShearModulus) {
  for (const MaterialModel& model : all_models()) {
    if (material_uses_fiber(model)) continue;
    std::visit(
        [&](const auto& m) {
          const LinearizedModuli base = linearized_moduli(m);
          const LinearizedModuli scaled =
              linearized_moduli(IsochoricScaled<std::decay_t<decltype(m)>>{m, 0.25});
          EXPECT_NEAR(scaled.mu, 0.25 * base.mu, 1e-10 * base.mu) << material_name(model);
          EXPECT_NEAR(scaled.bulk(), base.bulk(), 1e-10 * base.bulk()) << material_name(model);
        },
        model);
  }
}

TEST(PronySeries, ValidationNamesTheEntry) {
  const auto message = [](const PronySeries& p) -> std::string {
    try {
      p.validate();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(message({{0.3, 0.2}, {0.1, 1.0}}), "");
  EXPECT_NE(message({{0.3, 0.2}, {0.1, -1.0}}).find("relaxation_times[1]"), std::string::npos);
  EXPECT_NE(message({{0.3}, {0.0}}).find("relaxation_times[0]"), std::string::npos);
  EXPECT_NE(message({{0.0}, {1.0}}).find("weights[0]"), std::string::npos);
  EXPECT_NE(message({{-0.1}, {1.0}}).find("weights[0]"), std::string::npos);
  EXPECT_NE(message({{0.6, 0.4}, {1, 2}}).find("sum to 1"), std::string::npos);
  EXPECT_NE(message({{0.6}, {1, 2}}).find("one weight per time"), std::string::npos);
}

TEST(PronySeries, StepCoefficientsAndTheirLimits) {
  const PronySeries p{{0.3, 0.2}, {0.1, 2.0}};
  const PronyStep zero = prony_step(p, 0);
  EXPECT_DOUBLE_EQ(zero.scale, 1.0);
  EXPECT_DOUBLE_EQ(zero.gamma[0], 0.3);
  EXPECT_DOUBLE_EQ(zero.decay[1], 1.0);
  const PronyStep step = prony_step(p, 0.05);
  EXPECT_NEAR(step.gamma[0], 0.3 * (1 - std::exp(-0.5)) / 0.5, 1e-15);
  EXPECT_NEAR(step.decay[1], std::exp(-0.025), 1e-15);
  EXPECT_NEAR(step.scale, 0.5 + step.gamma[0] + step.gamma[1], 1e-15);
  const PronyStep tiny = prony_step(p, 1e-300);  // no 0/0: the limit
  EXPECT_NEAR(tiny.gamma[0], 0.3, 1e-15);
  const PronyStep long_step = prony_step(p, 1e6);  // fully relaxed
  EXPECT_NEAR(long_step.scale, 0.5, 1e-5);
}

}  // namespace
}  // namespace depthfem
