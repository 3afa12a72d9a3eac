// Every shipped scene (the long ones shortened) gives bitwise the same positions at every step
// on one thread and on two: the README's promise that results do not depend on the number of
// threads. Assembly, contact, the direct solver's factorisation (tiles cut by their sizes) and
// BLAS (on the calling thread) are all built to keep it.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "apps/scene_runner.hpp"

namespace depthfem {
namespace {

using testing::load;

// Shortened where the full run is long (together about a minute for both thread counts on
// two cores): fewer or smaller steps, a coarser mesh, a looser Newton tolerance.
const std::map<std::string, std::vector<std::string>>& shortened_scenes() {
  static const std::map<std::string, std::vector<std::string>> scenes = {
      {"ball_drop", {}},
      // 50 of 160 steps: the bars land on the floor and on each other.
      {"bars_drop", {"dynamic.duration=0.25"}},
      {"blocks_overlap", {}},
      // The column buckles in the settling steps at full load.
      {"buckling_column", {"solver.initial_increment=0.5", "solver.max_increment=0.5"}},
      {"cantilever_gravity", {}},
      {"falling_bars", {"dynamic.duration=0.5"}},
      {"falling_bars_viscoelastic", {"dynamic.duration=0.5"}},
      {"fold_slab", {}},
      // The first step (d = 1 mm) on the full mesh: its factorisations (1e11 flops) are the
      // ones that differed, when they went to OpenBLAS's threads.
      {"hertz_sphere",
       {"obstacles.0.motion=[0,0,0.001]", "solver.initial_increment=1", "solver.max_increment=1"}},
      // The knee meshes: one step of 0.5 degrees (0.25 on the fine mesh) to a relative residual
      // of 1e-3: one or two Newton iterations, each with contact, assembly, factorisation and
      // solve on the paper-size meshes.
      {"knee_flexion",
       {"boundary.0.angle_deg=0.5", "boundary.1.angle_deg=0.5", "solver.initial_increment=1",
        "solver.max_increment=1", "solver.tolerance=1e-3"}},
      {"knee_flexion_fine",
       {"boundary.0.angle_deg=0.25", "boundary.1.angle_deg=0.25", "solver.initial_increment=1",
        "solver.max_increment=1", "solver.tolerance=1e-3"}},
      {"knee_flexion_incompressible",
       {"boundary.0.angle_deg=0.5", "boundary.1.angle_deg=0.5", "solver.initial_increment=1",
        "solver.max_increment=1", "solver.tolerance=1e-3"}},
      // The paper's algorithm is slow on the knee (bench/results/knee_paper.md): a tenth of a
      // degree to a relative residual of 1e-3.
      {"knee_flexion_paper",
       {"boundary.0.angle_deg=0.1", "boundary.1.angle_deg=0.1", "solver.initial_increment=1",
        "solver.max_increment=1", "solver.tolerance=1e-3"}},
      {"knee_flexion_veronda",
       {"boundary.0.angle_deg=0.5", "boundary.1.angle_deg=0.5", "solver.initial_increment=1",
        "solver.max_increment=1", "solver.tolerance=1e-3"}},
      {"sliding_blocks",
       {"boundary.1.displacement=[0.05,0,-0.02]", "solver.initial_increment=0.2",
        "solver.max_increment=0.2"}},
      {"twist_bar", {}},
      {"uniaxial_block", {}},
  };
  return scenes;
}

// The positions and energy of every completed step of a run on `threads` threads.
struct Trajectory {
  bool success = false;
  std::string message;
  std::vector<Points> x;
  std::vector<double> energy;
};

Trajectory run_on(const Scene& scene, int threads) {
  Trajectory t;
  RunOptions options;
  options.threads = threads;
  options.observer = [&](const StepRecord& step, const Points& x) {
    t.x.push_back(x);
    t.energy.push_back(step.energy);
  };
  std::ostringstream log;
  const RunResult r = run_scene(scene, options, log);
  t.success = r.success;
  t.message = r.message;
  return t;
}

TEST(ThreadCount, EveryShippedSceneGivesTheSameBitsOnOneAndTwoThreads) {
  for (const auto& [name, overrides] : shortened_scenes()) {
    const auto start = std::chrono::steady_clock::now();
    const Scene scene = load(name, overrides);
    const Trajectory one = run_on(scene, 1), two = run_on(scene, 2);
    ASSERT_TRUE(one.success) << name << ": " << one.message;
    ASSERT_TRUE(two.success) << name << ": " << two.message;
    ASSERT_GT(one.x.size(), 0u) << name;
    ASSERT_EQ(one.x.size(), two.x.size()) << name << ": steps on one and two threads";
    for (size_t k = 0; k < one.x.size(); ++k) {
      // Exact equality of every coordinate, not closeness.
      EXPECT_TRUE(one.x[k] == two.x[k]) << name << " step " << k << ": positions apart by up to "
                                        << (one.x[k] - two.x[k]).cwiseAbs().maxCoeff() << " m";
      EXPECT_EQ(one.energy[k], two.energy[k]) << name << " step " << k;
    }
    std::printf("%s: %zu steps identical on 1 and 2 threads (%.1f s)\n", name.c_str(), one.x.size(),
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
}

// The list above holds every scene of apps/scenes.
TEST(ThreadCount, EveryShippedSceneIsCompared) {
  for (const auto& entry :
       std::filesystem::directory_iterator(std::string(DEPTHFEM_SOURCE_DIR) + "/apps/scenes")) {
    if (entry.path().extension() != ".json") continue;
    EXPECT_TRUE(shortened_scenes().count(entry.path().stem().string()))
        << entry.path() << " is not compared on one and two threads";
  }
}

}  // namespace
}  // namespace depthfem
