// Implicit Euler dynamics: the exact discrete free fall, and energy dissipation on falling_bars.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "apps/scene_runner.hpp"
#include "core/error.hpp"
#include "core/lumped_mass.hpp"

namespace depthfem {
namespace {

using testing::load;
using testing::run;

// With gravity only, every node moves alike and elastic forces vanish. Implicit Euler and
// symplectic Euler (velocity first) both give v_n = v_0 + n h g and
// x_n = x_0 + n h v_0 + h^2 g n (n + 1) / 2 exactly.
TEST(DynamicScenes, FreeFallFollowsTheDiscreteSolutionOfEachIntegrator) {
  const std::string path = (std::filesystem::temp_directory_path() / "depthfem_free_fall.json").string();
  std::ofstream(path) << R"({
    "analysis": "dynamic", "gravity": [0, 0, -9.81],
    "bodies": [{"name": "b", "mesh": {"generator": "box", "lo": [0, 0, 0], "hi": [0.3, 0.2, 0.1], "cells": [3, 2, 1]},
                "material": {"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3}, "velocity": [1, 0, 2]}],
    "dynamic": {"time_step": 0.0002, "duration": 0.002},
    "solver": {"tolerance": 1e-12}
  })";
  for (const char* integrator : {"implicit_euler", "symplectic_euler"}) {
    const Scene s = load_scene(path, {parse_override(std::string("dynamic.integrator=") + integrator)});
    const RunResult r = run(s);
    ASSERT_TRUE(r.success) << r.message;
    ASSERT_EQ(r.steps.size(), 10u);
    const double h = 0.0002, n = 10;
    const Vec3 expected = n * h * Vec3(1, 0, 2) + h * h * Vec3(0, 0, -9.81) * n * (n + 1) / 2;
    for (Index i = 0; i < s.mesh.num_nodes(); ++i)
      EXPECT_LE((r.x.row(i) - s.mesh.X.row(i) - expected.transpose()).norm(), 1e-12) << integrator << " node " << i;
  }
  std::filesystem::remove(path);
}

// The explicit stepper refuses a step above the stable limit with a message, and below it its
// energy stays bounded: on the swinging bars the total energy wanders by under 5 % of the
// largest kinetic energy reached (symplectic Euler has no secular drift).
TEST(DynamicScenes, SymplecticEulerRefusesUnstableStepsAndKeepsEnergyBounded) {
  try {
    run(load("falling_bars", {"dynamic.integrator=symplectic_euler"}));
    FAIL() << "a 0.01 s explicit step must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("exceeds the stable limit"), std::string::npos) << e.what();
  }
  const Scene s = load("falling_bars", {"dynamic.integrator=symplectic_euler", "dynamic.time_step=2e-4",
                                        "dynamic.duration=0.3"});
  const RunResult r = run(s);
  ASSERT_TRUE(r.success) << r.message;
  const VectorX m = lumped_mass(s.mesh.X, s.mesh.tets, s.tet_density);
  const double initial = -(m.transpose() * (s.mesh.X * s.gravity)).value();
  double deviation = 0, kinetic = 0;
  for (const StepSummary& st : r.steps) {
    deviation = std::max(deviation, std::abs(st.kinetic_energy + st.potential_energy - initial));
    kinetic = std::max(kinetic, st.kinetic_energy);
  }
  EXPECT_GT(kinetic, 1.0);
  EXPECT_LT(deviation, 0.05 * kinetic);
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
