// Elasticity force module: patch test, global derivatives against finite differences,
// reproducibility across thread counts.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <Eigen/Eigenvalues>

#include <numeric>
#include <random>

#include "core/error.hpp"
#include "core/mesh_generators.hpp"
#include "finite_differences.hpp"
#include "integrators/assembled.hpp"
#include "integrators/elements/psd_projection.hpp"
#include "integrators/elements/tet_kernel.hpp"
#include "integrators/forces/elasticity.hpp"
#include "materials/all_models.hpp"
#include "materials/lanes.hpp"

namespace depthfem {
namespace {

using testing::assemble;
using testing::Assembled;
using testing::perturbed;
using testing::whole_mesh;

// Patch test: under x = A X + b every tet has F = A, so the energy is psi(A) V exactly, and
// interior nodes are in equilibrium (their element forces cancel by the divergence theorem).
TEST(Elasticity, PatchTestForEveryMaterial) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3(0.3, 0.2, 0.1), Eigen::Vector3i(3, 3, 3)});
  Mat3 A;
  A << 1.2, 0.1, -0.05, 0.03, 0.9, 0.2, -0.1, 0.05, 1.1;
  const Vec3 b(0.4, -0.2, 1.0), fiber = Vec3(1, 1, 0).normalized();
  const Points x = (m.X * A.transpose()).rowwise() + b.transpose();
  for (const MaterialModel& model : all_models()) {
    Elasticity e(m.X, m.tets, {whole_mesh(m, model, fiber)});
    const Assembled r = assemble(e, x);
    const double psi =
        std::visit([&](const auto& mat) { return energy_density(mat, A, fiber); }, model);
    EXPECT_NEAR(r.energy, psi * 0.3 * 0.2 * 0.1, 1e-12 * std::abs(r.energy))
        << material_name(model);
    const double scale = r.gradient.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0);
    int interior = 0;
    for (Index v = 0; v < m.X.rows(); ++v) {
      const Vec3 p = m.X.row(v);
      const bool inside =
          (p.array() > 1e-9).all() && (p.array() < Vec3(0.3, 0.2, 0.1).array() - 1e-9).all();
      if (!inside) continue;
      ++interior;
      EXPECT_LE(r.gradient.segment<3>(3 * v).norm(), 1e-12 * scale)
          << material_name(model) << " node " << v;
    }
    EXPECT_EQ(interior, 8);
  }
}

// Central differences: the step 1e-7 (positions ~0.1 m) balances truncation and round-off;
// the agreement expected is ~1e-7 relative, asserted at 1e-6.
TEST(Elasticity, GradientAndHessianMatchFiniteDifferences) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3(0.2, 0.1, 0.1), Eigen::Vector3i(2, 2, 2)});
  const Points x = perturbed(m.X, 0.01, 3);
  std::mt19937 rng(11);
  for (const MaterialModel& model : all_models()) {
    Elasticity e(m.X, m.tets, {whole_mesh(m, model, Vec3(0.3, -1, 0.5).normalized())});
    Assembled r = assemble(e, x);
    ASSERT_TRUE(std::isfinite(r.energy));
    const Eigen::SparseMatrix<double> H = r.hessian.to_sparse();
    EXPECT_LE((Eigen::MatrixXd(H) - Eigen::MatrixXd(H).transpose()).cwiseAbs().maxCoeff(),
              1e-10 * H.coeffs().cwiseAbs().maxCoeff());
    testing::expect_derivatives_match(e, x, r, rng, material_name(model));
  }
}

TEST(Elasticity, SameResultsOnOneAndTwoThreads) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3(1, 0.5, 0.5), Eigen::Vector3i(16, 8, 8)});
  const Points x = perturbed(m.X, 0.005, 5);
  // Two groups with different models, split by tet parity.
  ElasticGroup a{MooneyRivlin{4e3, 1e3, 2e4}, {}, Points()},
      b{Veronda{1.5e3, 0.8, 2e4}, {}, Points()};
  for (Index t = 0; t < m.tets.rows(); ++t) (t % 2 ? a : b).tets.push_back(t);
  Elasticity e(m.X, m.tets, {a, b});
  // Deterministic by construction (coloring + fixed chunking): identical, not merely close.
  testing::expect_same_bits_on_one_and_two_threads([&] { return assemble(e, x); });
}

// The first n tets of m one by one through tet_local (each Hessian through project_to_psd when
// `project`), scattered through block_index into a matrix of the pattern of `pattern`.
struct Reference {
  Assembled sum;
  int projected = 0;  ///< tets whose Hessian the projection changed
};
Reference scalar_reference(const TetMesh& m, Index n, const MaterialModel& model, const Vec3& fiber,
                           const Points& x, const BlockSparseMatrix& pattern, bool project) {
  Reference ref{{0, VectorX::Zero(3 * x.rows()), pattern}};
  BlockSparseMatrix& H = ref.sum.hessian;
  H.set_zero();
  for (Index t = 0; t < n; ++t) {
    Mat3 Dm, Ds;
    for (int a = 0; a < 3; ++a) {
      Dm.col(a) = (m.X.row(m.tets(t, a + 1)) - m.X.row(m.tets(t, 0))).transpose();
      Ds.col(a) = (x.row(m.tets(t, a + 1)) - x.row(m.tets(t, 0))).transpose();
    }
    TetLocal local;
    std::visit(
        [&](const auto& mat) {
          tet_local<2>(mat, Ds, Mat3(Dm.inverse()), Dm.determinant() / 6, fiber, local);
        },
        model);
    if (project) ref.projected += project_to_psd(local.hessian);
    ref.sum.energy += local.energy;
    for (int a = 0; a < 4; ++a) {
      ref.sum.gradient.segment<3>(3 * m.tets(t, a)) += local.gradient.col(a);
      for (int b = 0; b < 4; ++b)
        H.add_block(H.block_index(m.tets(t, a), m.tets(t, b)),
                    local.hessian.block<3, 3>(3 * a, 3 * b));
    }
  }
  return ref;
}

// The module runs whole batches of kLanes rows through the batched kernel and the rows left at the
// end of a chunk through the scalar one. 5 x 3 x 3 cells = 270 tets, of which the group takes 269:
// one chunk with a remainder for every lane count (269 = 33 x 8 + 5 = 67 x 4 + 1 = 134 x 2 + 1).
// Reference: tet_local on every tet, scattered through block_index. The kernels agree to rounding
// (~1e-16, see test_batched_tet_kernel.cpp), and the sums over at most 24 tets per entry keep it
// there: 1e-13 of the largest entry.
TEST(Elasticity, BatchedAssemblyEqualsTheScalarKernelEverywhere) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3(0.5, 0.3, 0.3), Eigen::Vector3i(5, 3, 3)});
  const Index n = static_cast<Index>(m.tets.rows()) - 1;
  ASSERT_NE(n % kLanes, 0);
  const Points x = perturbed(m.X, 0.01, 9);
  const Vec3 fiber = Vec3(0.3, -1, 0.5).normalized();
  for (const MaterialModel& model : all_models()) {
    ElasticGroup group = whole_mesh(m, model, fiber);
    group.tets.pop_back();
    if (group.fibers.rows()) group.fibers.conservativeResize(n, 3);
    Elasticity e(m.X, m.tets, {group});
    const Assembled r = assemble(e, x);
    const Reference ref = scalar_reference(m, n, model, fiber, x, r.hessian, false);
    const double energy = ref.sum.energy;
    const VectorX& gradient = ref.sum.gradient;
    const BlockSparseMatrix& H = ref.sum.hessian;
    EXPECT_NEAR(r.energy, energy, 1e-13 * std::abs(energy)) << material_name(model);
    EXPECT_LE((r.gradient - gradient).cwiseAbs().maxCoeff(), 1e-13 * gradient.cwiseAbs().maxCoeff())
        << material_name(model);
    const Eigen::MatrixXd batched(r.hessian.to_sparse()), scalar(H.to_sparse());
    EXPECT_LE((batched - scalar).cwiseAbs().maxCoeff(), 1e-13 * scalar.cwiseAbs().maxCoeff())
        << material_name(model);
  }
}

// With projection, both paths (the batched kernel for whole batches, the scalar one for the rows
// left over: 269 tets as above) add the projected Hessian of every tet. Reference: tet_local,
// project_to_psd, scattered. The projection onto the PSD cone is non-expansive in the Frobenius
// norm, so the two kernels' rounding differences (~1e-16) pass through it undiminished at worst;
// with the eigen-solver's backward error (a few eps |H|), 1e-12 of the largest entry bounds the
// difference. The mesh is shortened 30 % along z, so that projection changes many tets.
TEST(Elasticity, ProjectedHessianIsTheSumOfProjectedTetHessians) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3(0.5, 0.3, 0.3), Eigen::Vector3i(5, 3, 3)});
  const Index n = static_cast<Index>(m.tets.rows()) - 1;
  Points x = perturbed(m.X, 0.005, 21);
  x.col(2) *= 0.7;
  const Vec3 fiber = Vec3(0.3, -1, 0.5).normalized();
  for (const MaterialModel& model : all_models()) {
    ElasticGroup group = whole_mesh(m, model, fiber);
    group.tets.pop_back();
    if (group.fibers.rows()) group.fibers.conservativeResize(n, 3);
    Elasticity plain(m.X, m.tets, {group}),
        projected(m.X, m.tets, {group}, {.project_hessian = true});
    const Assembled a = assemble(plain, x), r = assemble(projected, x);
    EXPECT_EQ(r.energy, a.energy);
    EXPECT_EQ((r.gradient - a.gradient).cwiseAbs().maxCoeff(), 0.0);
    const Reference ref = scalar_reference(m, n, model, fiber, x, r.hessian, true);
    const BlockSparseMatrix& H = ref.sum.hessian;
    EXPECT_GT(ref.projected, n / 2) << material_name(model);
    const Eigen::MatrixXd module(r.hessian.to_sparse()), reference(H.to_sparse()),
        unprojected(a.hessian.to_sparse());
    EXPECT_LE((module - reference).cwiseAbs().maxCoeff(), 1e-12 * reference.cwiseAbs().maxCoeff())
        << material_name(model);
    EXPECT_GT((module - unprojected).cwiseAbs().maxCoeff(), 1e-3 * reference.cwiseAbs().maxCoeff())
        << material_name(model);
  }
}

// A column 1 m x 0.05 m x 0.05 m (1 x 1 x 20 cells), clamped at both ends and shortened 20 %:
// about 25 times its Euler strain 4 pi^2 I / (A L^2) = 0.82 %, so the straight state is unstable
// and the stiffness on the free nodes has negative eigenvalues. A sum of PSD element Hessians is
// PSD: with projection the smallest eigenvalue is zero or above, to the rounding of the sum
// (1e-12 of the largest eigenvalue).
TEST(Elasticity, ProjectedHessianOfABuckledColumnHasNoNegativeEigenvalue) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3(0.05, 0.05, 1), Eigen::Vector3i(1, 1, 20)});
  Points x = m.X;
  x.col(2) *= 0.8;
  std::vector<Index> free;
  for (Index v = 0; v < m.X.rows(); ++v)
    if (m.X(v, 2) > 1e-9 && m.X(v, 2) < 1 - 1e-9)
      for (int c = 0; c < 3; ++c) free.push_back(3 * v + c);
  const auto smallest_and_largest = [&](const ElasticityOptions& options) {
    Elasticity e(m.X, m.tets, {whole_mesh(m, NeoHookean::from_youngs(1e6, 0.3), Vec3())}, options);
    const Eigen::MatrixXd K(assemble(e, x).hessian.to_sparse());
    const Eigen::MatrixXd K_free = K(free, free);
    const Eigen::VectorXd lambda =
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(K_free).eigenvalues();
    return std::pair(lambda(0), lambda(lambda.size() - 1));
  };
  const auto [plain_min, plain_max] = smallest_and_largest({});
  EXPECT_LT(plain_min, -1e-6 * plain_max);
  const auto [projected_min, projected_max] = smallest_and_largest({.project_hessian = true});
  EXPECT_GE(projected_min, -1e-12 * projected_max);
}

TEST(Elasticity, InvertedTetGivesInfiniteEnergyAndIsNamed) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(2, 1, 1)});
  Elasticity e(m.X, m.tets, {whole_mesh(m, MooneyRivlin{4e3, 1e3, 2e4}, Vec3::UnitX())});
  EXPECT_EQ(e.first_inverted(m.X), -1);
  Points x = m.X;
  x(0, 0) = 5.0;  // drag a corner node through the box
  EXPECT_TRUE(std::isinf(e.evaluate(x, nullptr, nullptr)));
  const Index bad = e.first_inverted(x);
  ASSERT_GE(bad, 0);
  EXPECT_TRUE((m.tets.row(bad).array() == 0).any());
}

TEST(Elasticity, RejectsBadGroups) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(1, 1, 1)});
  EXPECT_THROW(Elasticity(m.X, m.tets, {{MooneyRivlin{-1, 0, 0}, {0}, Points()}}), InputError);
  EXPECT_THROW(Elasticity(m.X, m.tets, {{MooneyRivlin{1, 0, 1}, {99}, Points()}}), InputError);
  EXPECT_THROW(
      Elasticity(m.X, m.tets, {{FiberReinforced<MooneyRivlin>{{1, 0, 1}, 1, 1}, {0}, Points()}}),
      InputError);
}

}  // namespace
}  // namespace depthfem
