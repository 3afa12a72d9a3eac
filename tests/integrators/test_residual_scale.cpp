// The per-dof force scale of the Newton test: each node is judged against the stiffest material
// around it, not against the stiffest material of the scene.
#include <gtest/gtest.h>

#include "core/mass.hpp"
#include "integrators/solvers/newton.hpp"
#include "integrators/solvers/residual_scale.hpp"

namespace depthfem {
namespace {

TEST(ResidualScale, EachNodeTakesTheStiffestMaterialAroundIt) {
  // Tets (0,1,2,3) soft, (1,2,3,4) stiff, (2,3,4,5) in no elastic group (a rigid body's).
  Points X(6, 3);
  X << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2;
  TetIndices tets(3, 4);
  tets << 0, 1, 2, 3, 1, 2, 3, 4, 2, 3, 4, 5;
  const NeoHookean soft = NeoHookean::from_youngs(1e4, 0.3),
                   stiff = NeoHookean::from_youngs(1e9, 0.3);
  const std::vector<ElasticGroup> groups = {{soft, {0}, Points()}, {stiff, {1}, Points()}};
  const VectorX s = residual_force_scale(X, tets, groups);
  const double h2 = std::pow(mean_edge_length(X, tets), 2);
  ASSERT_EQ(s.size(), 18);
  const double expected[6] = {1e4, 1e9, 1e9, 1e9, 1e9, 1e9};  // node 5: no elastic tet
  for (Index i = 0; i < 6; ++i)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(s(3 * i + c), expected[i] * h2, 1e-6 * expected[i] * h2);
}

// The defect this scale removes: a residual of 1 N on a node of soft tissue must count as 1 N
// against the soft tissue's force scale however stiff another region of the scene is (before,
// one scale E_max h^2 for every dof loosened the soft tissue's test by E_max / E_soft).
TEST(ResidualScale, ASoftNodeIsJudgedIndependentlyOfTheStiffestMaterial) {
  Points X(5, 3);
  X << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1;
  TetIndices tets(2, 4);
  tets << 0, 1, 2, 3, 1, 2, 3, 4;
  const NeoHookean soft = NeoHookean::from_youngs(1e4, 0.3);
  VectorX residual = VectorX::Zero(15);
  residual(0) = 1.0;  // node 0 belongs to the soft tet only
  const double h2 = std::pow(mean_edge_length(X, tets), 2);
  for (const double stiff : {1e4, 1e9, 1e15}) {
    NewtonOptions options;
    options.force_scale = residual_force_scale(
        X, tets, {{soft, {0}, Points()}, {NeoHookean::from_youngs(stiff, 0.3), {1}, Points()}});
    EXPECT_NEAR(scaled_residual(options, residual), 1.0 / (1e4 * h2), 1e-12 / (1e4 * h2)) << stiff;
  }
  NewtonOptions unscaled;
  EXPECT_EQ(scaled_residual(unscaled, residual), 1.0) << "without a scale the norm is in newtons";
}

}  // namespace
}  // namespace depthfem
