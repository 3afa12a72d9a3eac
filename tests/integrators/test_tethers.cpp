// Tethers (quasi-viscosity, inertia, damping) against finite differences, and the step at which
// a tet turns flat against a dense scan of det F along the step.
#include <gtest/gtest.h>

#include <numeric>
#include <random>

#include "core/mass.hpp"
#include "core/mesh_generators.hpp"
#include "finite_differences.hpp"
#include "integrators/elements/inversion_step.hpp"
#include "integrators/forces/consistent_mass.hpp"
#include "integrators/forces/elasticity.hpp"
#include "integrators/forces/stiffness_tether.hpp"

namespace depthfem {
namespace {

using testing::central_directional;
using testing::central_gradient_dofs;

Points random_points(Index n, unsigned seed, double scale) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-scale, scale);
  Points p(n, 3);
  for (Index i = 0; i < p.size(); ++i) p(i) = u(rng);
  return p;
}

// The block pattern of one tet's clique over `n` nodes, bound to `m`.
BlockSparseMatrix bound_pattern(ForceModule& m, Index n) {
  SparsityBuilder b(n);
  m.add_couplings(b);
  BlockSparseMatrix H(b);
  m.bind(H);
  return H;
}

// Checks a module's gradient against central differences of its energy (step 1e-7 on
// coordinates of order 0.1: agreement ~1e-8 relative, asserted at 1e-6) and its Hessian times
// random directions against differences of its gradient (1e-6).
void expect_derivatives(ForceModule& m, const Points& x, BlockSparseMatrix& H) {
  const Index n = static_cast<Index>(x.rows());
  VectorX g = VectorX::Zero(3 * n);
  H.set_zero();
  m.evaluate(x, &g, &H);
  const auto energy = [&](const Points& y) { return m.evaluate(y, nullptr, nullptr); };
  const VectorX g_fd = central_gradient_dofs(energy, x, 1e-7);
  EXPECT_LE((g - g_fd).cwiseAbs().maxCoeff(), 1e-6 * g.cwiseAbs().maxCoeff());
  const auto gradient = [&](const VectorX& z) {
    VectorX gz = VectorX::Zero(3 * n);
    m.evaluate(as_points(z), &gz, nullptr);
    return gz;
  };
  const Eigen::SparseMatrix<double> S = H.to_sparse();
  for (unsigned trial = 0; trial < 3; ++trial) {
    const VectorX v = as_dofs(random_points(n, 40 + trial, 1.0));
    const VectorX Hv = S * v, Hv_fd = central_directional(gradient, as_dofs(x), v, 1e-7);
    EXPECT_LE((Hv - Hv_fd).cwiseAbs().maxCoeff(), 1e-6 * Hv.cwiseAbs().maxCoeff());
  }
}

TEST(Tethers, NodalSpringMatchesFiniteDifferencesAndItsQuadraticForm) {
  const Index n = 5;
  NodalSpring spring("inertia", (VectorX(n) << 1, 2, 0.5, 3, 4).finished());
  spring.set_scale(25.0);
  const Points anchor = random_points(n, 1, 0.3), x = random_points(n, 2, 0.3);
  spring.set_anchor(anchor);
  BlockSparseMatrix H = bound_pattern(spring, n);
  expect_derivatives(spring, x, H);
  // E = s * 1/2 (x - a)^T K (x - a).
  EXPECT_NEAR(spring.evaluate(x, nullptr, nullptr), 25.0 * spring.quadratic_form(x - anchor),
              1e-14 * spring.evaluate(x, nullptr, nullptr));
}

TEST(Tethers, StiffnessTetherIsTheElasticHessianAtTheStepStart) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3(0.2, 0.1, 0.1), Eigen::Vector3i(2, 1, 1)});
  std::vector<Index> all(static_cast<size_t>(m.tets.rows()));
  std::iota(all.begin(), all.end(), 0);
  Elasticity elastic(m.X, m.tets, {{NeoHookean::from_youngs(1e4, 0.3), all, {}}});
  const Index n = static_cast<Index>(m.X.rows());
  StiffnessTether damping("stiffness damping", elastic, 0.01);
  SparsityBuilder b(n);
  elastic.add_couplings(b);
  BlockSparseMatrix H(b);
  elastic.bind(H);  // as in a System: every module bound to the one global pattern
  damping.bind(H);
  const Points start = m.X + random_points(n, 3, 0.005);
  damping.begin_step(start);
  damping.set_scale(50.0);
  damping.set_anchor(start);
  const Points x = start + random_points(n, 4, 0.01);
  expect_derivatives(damping, x, H);
  // Its Hessian is s beta K(start), with K the elastic Hessian there.
  BlockSparseMatrix K(b);
  VectorX g = VectorX::Zero(3 * n);
  elastic.evaluate(start, &g, &K);
  H.set_zero();
  damping.evaluate(x, nullptr, &H);
  const Eigen::MatrixXd expected = 50.0 * 0.01 * Eigen::MatrixXd(K.to_sparse());
  EXPECT_LE((Eigen::MatrixXd(H.to_sparse()) - expected).cwiseAbs().maxCoeff(),
            1e-12 * expected.cwiseAbs().maxCoeff());
}

// The consistent mass matrix: derivatives of its tether, rows summing to the lumped masses, and
// the kinetic energy of a rigid translation, 1/2 m |v|^2.
TEST(Tethers, ConsistentMassRowsSumToTheLumpedMasses) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3(0.2, 0.1, 0.1), Eigen::Vector3i(2, 1, 1)});
  const Index n = static_cast<Index>(m.X.rows());
  const VectorX density = VectorX::LinSpaced(m.tets.rows(), 900, 1100);
  ConsistentMass mass("inertia", m.X, m.tets, density, 3.0);
  BlockSparseMatrix H = bound_pattern(mass, n);
  mass.set_scale(2.0);
  mass.set_anchor(m.X + random_points(n, 7, 0.01));
  expect_derivatives(mass, m.X + random_points(n, 8, 0.01), H);
  // Row sums: H / (s factor) times the unit x translation gives the lumped masses on x dofs.
  VectorX ones_x = VectorX::Zero(3 * n), row_sums;
  ones_x(Eigen::seq(0, 3 * n - 1, 3)).setOnes();
  H.multiply(ones_x, row_sums);
  const VectorX lumped = lumped_mass(m.X, m.tets, density);
  for (Index i = 0; i < n; ++i) EXPECT_NEAR(row_sums(3 * i) / 6.0, lumped(i), 1e-12 * lumped(i));
  const Points v = Vec3(0.3, -1, 2).transpose().replicate(n, 1);
  EXPECT_NEAR(mass.quadratic_form(v), 3.0 * 0.5 * lumped.sum() * 5.09, 1e-12 * lumped.sum());
}

// Random tets and directions: the returned step zeroes det(Ds + a dDs), det stays positive on a
// dense scan before it, and no root is missed where the scan finds a sign change.
TEST(InversionStep, FindsTheFirstRootOfTheDeterminantCubic) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  int roots = 0, none = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Mat3 Ds = Mat3::Identity(), dDs;
    for (int k = 0; k < 9; ++k) {
      Ds(k) += 0.3 * u(rng);
      dDs(k) = 1.5 * u(rng);
    }
    if (Ds.determinant() <= 0) continue;
    const double limit = 2.0, a = inversion_step(Ds, dDs, limit);
    const auto det = [&](double s) { return (Ds + s * dDs).determinant(); };
    const double end = std::isfinite(a) ? a : limit;
    for (int k = 0; k < 1000; ++k) EXPECT_GT(det(end * k / 1000.0), 0) << "trial " << trial;
    if (std::isfinite(a)) {
      ++roots;
      EXPECT_LE(a, limit);
      EXPECT_LE(std::abs(det(a)), 1e-12 * (Ds.norm() + a * dDs.norm()) * Ds.norm() * Ds.norm());
    } else {
      ++none;
      EXPECT_GT(det(limit), 0);
    }
  }
  EXPECT_GT(roots, 100);
  EXPECT_GT(none, 100);
}

}  // namespace
}  // namespace depthfem
