// The contact scenes of apps/scenes: the hard cases of the contact issue.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

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

// A rigid body (no material, no unknowns) driven by a boundary condition on its body pushes a
// deformable block: its nodes follow the prescribed motion exactly, and the block's base carries
// the contact force.
TEST(ContactScenes, RigidBodyWithPrescribedMotionPressesADeformableBlock) {
  const std::string path = (std::filesystem::temp_directory_path() / "depthfem_rigid_press.json").string();
  std::ofstream(path) << R"({
    "bodies": [
      {"name": "block", "mesh": {"generator": "box", "lo": [0, 0, 0], "hi": [1, 1, 0.3], "cells": [5, 5, 3]},
       "material": {"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3}},
      {"name": "stamp", "mesh": {"generator": "box", "lo": [0.33, 0.31, 0.3], "hi": [0.67, 0.71, 0.5], "cells": [3, 3, 2]},
       "rigid": true}
    ],
    "contact": {"model": "material_depth", "penalty": 1e7, "self_contact": false},
    "boundary": [
      {"name": "base", "type": "fixed", "nodes": {"plane": {"normal": [0, 0, 1], "offset": 0}}},
      {"name": "press", "type": "displaced", "displacement": [0, 0, -0.03], "nodes": {"body": "stamp"}}
    ],
    "solver": {"initial_increment": 0.25}
  })";
  const Scene s = load_scene(path);
  std::filesystem::remove(path);
  ASSERT_EQ(s.groups.size(), 1u);  // the rigid body has no elasticity
  const RunResult r = run(s);
  ASSERT_TRUE(r.success) << r.message;
  const Body& stamp = s.mesh.bodies[1];
  for (Index i = stamp.first_node; i < stamp.first_node + stamp.num_nodes; ++i)
    EXPECT_LE((r.x.row(i) - s.mesh.X.row(i) - Eigen::RowVector3d(0, 0, -0.03)).norm(), 1e-14);
  // Condition rows: stamp_rigid (0), base (1), press (2). The base pushes up, the press down,
  // and they balance (no other forces act).
  const auto& R = r.steps.back().reactions;
  EXPECT_GT(R(1, 2), 0);
  EXPECT_NEAR(R(1, 2) + R(2, 2), 0.0, 1e-6 * R(1, 2));
  EXPECT_GT(*r.steps.back().contact_area, 0.1);
}

}  // namespace
}  // namespace depthfem
