// Implicit Euler dynamics: the exact discrete free fall, and energy dissipation on falling_bars.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "apps/scene_runner.hpp"
#include "core/lumped_mass.hpp"

namespace depthfem {
namespace {

using testing::load;
using testing::run;

// With gravity only, every node moves alike and elastic forces vanish: implicit Euler gives
// v_n = n h g and x_n = x_0 + h^2 g n (n + 1) / 2 exactly (the Newton solve is linear).
TEST(DynamicScenes, FreeFallFollowsTheDiscreteImplicitEulerSolution) {
  const std::string path = (std::filesystem::temp_directory_path() / "depthfem_free_fall.json").string();
  std::ofstream(path) << R"({
    "analysis": "dynamic", "gravity": [0, 0, -9.81],
    "bodies": [{"name": "b", "mesh": {"generator": "box", "lo": [0, 0, 0], "hi": [0.3, 0.2, 0.1], "cells": [3, 2, 1]},
                "material": {"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3}, "velocity": [1, 0, 2]}],
    "dynamic": {"time_step": 0.02, "duration": 0.2},
    "solver": {"tolerance": 1e-12}
  })";
  const Scene s = load_scene(path);
  std::filesystem::remove(path);
  const RunResult r = run(s);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_EQ(r.steps.size(), 10u);
  const double h = 0.02, n = 10;
  const Vec3 expected = n * h * Vec3(1, 0, 2) + h * h * Vec3(0, 0, -9.81) * n * (n + 1) / 2;
  for (Index i = 0; i < s.mesh.num_nodes(); ++i)
    EXPECT_LE((r.x.row(i) - s.mesh.X.row(i) - expected.transpose()).norm(), 1e-9) << "node " << i;
}

// Implicit Euler dissipates: the mechanical energy (kinetic + elastic + gravitational) of the
// swinging bars never rises from one step to the next.
TEST(DynamicScenes, ImplicitEulerEnergyDecreasesMonotonically) {
  const Scene s = load("falling_bars", {"dynamic.duration=0.6"});
  const RunResult r = run(s);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_EQ(r.steps.size(), 60u);
  // Released from rest in the reference state: no kinetic or elastic energy, gravity -sum m g.X.
  const VectorX m = lumped_mass(s.mesh.X, s.mesh.tets, s.tet_density);
  double previous = -(m.transpose() * (s.mesh.X * s.gravity)).value();
  const double initial = previous;
  for (size_t k = 0; k < r.steps.size(); ++k) {
    const double e = r.steps[k].kinetic_energy + r.steps[k].potential_energy;
    EXPECT_LE(e, previous + 1e-9 * std::abs(previous)) << "step " << k;
    previous = e;
  }
  EXPECT_LT(previous, initial - 1.0) << "the bars must have swung down";
}

}  // namespace
}  // namespace depthfem
