// The contact scenes of apps/scenes: the hard cases of the contact issue.
#include <gtest/gtest.h>

#include <cmath>

#include "apps/scene_runner.hpp"
#include "core/lumped_mass.hpp"

namespace depthfem {
namespace {

using testing::load;
using testing::run;

// Extreme z of the nodes of one body.
double body_z(const Scene& s, const Points& x, Index body, bool top) {
  const Body& b = s.mesh.bodies[body];
  const auto z = x.col(2).segment(b.first_node, b.num_nodes);
  return top ? z.maxCoeff() : z.minCoeff();
}

// Start 30 % inside each other; the static run with quasi-viscosity must push them apart until
// the faces meet: remaining overlap below 1 % of the thickness (0.2 m).
TEST(ContactScenes, OverlappingBlocksSeparate) {
  const Scene s = load("blocks_overlap");
  ASSERT_NEAR(body_z(s, s.mesh.X, 0, true) - body_z(s, s.mesh.X, 1, false), 0.06, 1e-12);
  const RunResult r = run(s);
  ASSERT_TRUE(r.success) << r.message;
  const double overlap = body_z(s, r.x, 0, true) - body_z(s, r.x, 1, false);
  EXPECT_LT(overlap, 0.002);
  EXPECT_GT(overlap, -0.002) << "the free block must come to rest on the other, not fly off";
}

// Released in mid-air, the ball falls 0.2 m in a static run and rests on the floor: the floor
// carries its weight (that of the meshed ball: lumped masses x g) and the penetration is small.
TEST(ContactScenes, BallFallsOntoTheFloorInAStaticRun) {
  const Scene s = load("ball_drop");
  const RunResult r = run(s);
  ASSERT_TRUE(r.success) << r.message;
  const double weight = lumped_mass(s.mesh.X, s.mesh.tets, s.tet_density).sum() * 9.81;
  ASSERT_TRUE(r.steps.back().contact_force.has_value());
  EXPECT_NEAR(*r.steps.back().contact_force, weight, 0.01 * weight);
  const double lowest = r.x.col(2).minCoeff();
  EXPECT_LT(lowest, 0.0);
  EXPECT_GT(lowest, -0.005) << "penetration beyond 5 % of the radius";
  EXPECT_LT((r.x - s.mesh.X).col(2).mean(), -0.19) << "the ball must have fallen";
}

// Pressed 2 cm and slid 0.5 m in 50 fixed steps: every step converges at its first attempt
// (no increment is ever cut), in few Newton iterations.
TEST(ContactScenes, SlidingBlockConvergesAtEveryStep) {
  const Scene s = load("sliding_blocks");
  const RunResult r = run(s);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_EQ(r.steps.size(), 50u);
  for (size_t k = 0; k < r.steps.size(); ++k) {
    EXPECT_NEAR(r.steps[k].load, 0.02 * (k + 1), 1e-12);
    EXPECT_LE(r.steps[k].newton_iterations, 10) << "step " << k;
  }
  // The slider carries a downward load: the drive pushes it into the base.
  EXPECT_LT(r.steps.back().reactions(1, 2), 0);
}

}  // namespace
}  // namespace depthfem
