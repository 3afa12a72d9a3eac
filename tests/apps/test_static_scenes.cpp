// The static scenes of apps/scenes against closed forms and the issue's requirements.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>

#include "apps/scene_runner.hpp"
#include "core/mesh_generators.hpp"
#include "core/results_file.hpp"
#include "materials/closed_forms.hpp"

namespace depthfem {
namespace {

using testing::load;
using testing::run;

// Mean z displacement of the nodes on the free end x = 1.
double tip_deflection(const Scene& s, const Points& x) {
  double sum = 0;
  int n = 0;
  for (Index i = 0; i < s.mesh.num_nodes(); ++i)
    if (std::abs(s.mesh.X(i, 0) - 1.0) < 1e-12) {
      sum += x(i, 2) - s.mesh.X(i, 2);
      ++n;
    }
  return sum / n;
}

// Cantilever under self weight q = rho g A: Timoshenko tip deflection
// q L^4 / (8 E I) + q L^2 / (2 kappa G A), shear coefficient kappa = 10 (1 + nu) / (12 + 11 nu)
// for a rectangle. Linear tets converge slowly in bending (shear locking), so three meshes are
// compared: the error must fall at each refinement and the finest be within 3 %.
TEST(StaticScenes, CantileverConvergesToTimoshenkoBeam) {
  const double E = 1e8, nu = 0.3, rho = 1000, g = 9.81, L = 1, a = 0.1;
  const double A = a * a, I = a * a * a * a / 12, G = E / (2 * (1 + nu)),
               kappa = 10 * (1 + nu) / (12 + 11 * nu);
  const double q = rho * g * A;
  const double reference = q * std::pow(L, 4) / (8 * E * I) + q * L * L / (2 * kappa * G * A);
  double previous_error = 1;
  for (const char* cells : {"[40,4,4]", "[80,8,8]", "[160,16,16]"}) {
    const Scene s = load("cantilever_gravity", {std::string("bodies.0.mesh.cells=") + cells});
    const RunResult r = run(s);
    ASSERT_TRUE(r.success) << r.message;
    const double error = std::abs(-tip_deflection(s, r.x) / reference - 1);
    EXPECT_LT(error, previous_error) << cells;
    previous_error = error;
    RecordProperty(std::string("relative_error_") + cells, std::to_string(error));
  }
  EXPECT_LT(previous_error, 0.03);
}

// Homogeneous uniaxial stress: F = diag(1.5, t, t) in every tet, so the discrete solution is
// exact and must match the closed form to the solver tolerance.
template <class M>
void expect_uniaxial(const std::string& material_json, const M& model) {
  const Scene s = load("uniaxial_block", {"bodies.0.material=" + material_json});
  const RunResult r = run(s);
  ASSERT_TRUE(r.success) << r.message;
  const double l = 1.5, t = closed_form::lateral_stretch(model, l);
  const double P11 = closed_form::closed_uniaxial(model, l, t).P11;
  for (Index i = 0; i < s.mesh.num_nodes(); ++i) {
    const Vec3 expected(l * s.mesh.X(i, 0), t * s.mesh.X(i, 1), t * s.mesh.X(i, 2));
    EXPECT_LE((r.x.row(i).transpose() - expected).norm(), 1e-8) << material_json << " node " << i;
  }
  // Reaction of the moving plane (condition 3, "pull") = P11 x reference area 1.
  EXPECT_NEAR(r.steps.back().reactions(3, 0), P11, 1e-8 * std::abs(P11)) << material_json;
}

TEST(StaticScenes, UniaxialBlockMatchesClosedFormForEveryMaterial) {
  expect_uniaxial(R"({"model": "neo_hookean", "mu": 10000, "lambda": 40000})",
                  NeoHookean{1e4, 4e4});
  expect_uniaxial(R"({"model": "mooney_rivlin", "C1": 4000, "C2": 1000, "a": 20000})",
                  MooneyRivlin{4e3, 1e3, 2e4});
  expect_uniaxial(R"({"model": "veronda", "alpha": 1500, "beta": 0.8, "a": 20000})",
                  Veronda{1.5e3, 0.8, 2e4});
  expect_uniaxial(
      R"({"model": "nearly_incompressible_mooney_rivlin", "C1": 4000, "C2": 1000, "kappa": 500000})",
      NearlyIncompressibleMooneyRivlin{4e3, 1e3, 5e5});
  expect_uniaxial(R"({"model": "fiber_mooney_rivlin", "C1": 4000, "C2": 1000, "a": 20000,
                      "fiber_alpha": 2000, "fiber_beta": 3, "fiber_direction": [1, 0, 0]})",
                  FiberReinforced<MooneyRivlin>{{4e3, 1e3, 2e4}, 2e3, 3});
  expect_uniaxial(R"({"model": "fiber_veronda", "alpha": 1500, "beta": 0.8, "a": 20000,
                      "fiber_alpha": 2000, "fiber_beta": 3, "fiber_direction": [1, 0, 0]})",
                  FiberReinforced<Veronda>{{1.5e3, 0.8, 2e4}, 2e3, 3});
}

// Half a turn requested as one increment: adaptive loading must cut it (the first reported step
// is below full load), end at full load with every tet positively oriented, and by symmetry of
// the problem about the mid-plane the mid-section has turned a quarter turn.
TEST(StaticScenes, TwistBarReachesHalfTurnWithoutInvertedElements) {
  const Scene s = load("twist_bar");
  ASSERT_EQ(s.static_options.initial_increment, 1.0);
  const RunResult r = run(s);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_GT(r.steps.size(), 1u);
  EXPECT_LT(r.steps.front().load, 1.0);
  EXPECT_EQ(r.steps.back().load, 1.0);
  const Elasticity e(s.mesh.X, s.mesh.tets, s.groups);
  EXPECT_EQ(e.first_inverted(r.x), -1);
  double sum = 0;
  int n = 0;
  for (Index i = 0; i < s.mesh.num_nodes(); ++i) {
    const Vec3 X = s.mesh.X.row(i), x = r.x.row(i);
    if (std::abs(X(0) - 0.5) > 1e-12 || std::hypot(X(1), X(2)) < 0.05) continue;
    sum += std::remainder(std::atan2(x(2), x(1)) - std::atan2(X(2), X(1)), 2 * std::numbers::pi);
    ++n;
  }
  EXPECT_NEAR(sum / n * 180 / std::numbers::pi, 90.0, 0.5);
  // The twisted end sits exactly where the rotation puts it.
  for (Index i = 0; i < s.mesh.num_nodes(); ++i)
    if (std::abs(s.mesh.X(i, 0) - 1) < 1e-12) {
      EXPECT_NEAR(r.x(i, 1), -s.mesh.X(i, 1), 1e-12);
      EXPECT_NEAR(r.x(i, 2), -s.mesh.X(i, 2), 1e-12);
    }
}

// Past the Euler load the straight column is an unstable equilibrium. With quasi-viscosity the
// solver must end on a buckled state whose energy is below that of the straight branch, which
// is computed by holding the centre line on the axis (no bending possible, Poisson expansion free).
TEST(StaticScenes, BucklingColumnLeavesTheStraightBranch) {
  const Scene s = load("buckling_column");
  ASSERT_GT(s.quasi_viscosity, 0);
  const RunResult buckled = run(s);
  ASSERT_TRUE(buckled.success) << buckled.message;
  // Largest sideways displacement of any node.
  const auto lateral = [&](const Points& x) {
    return (x - s.mesh.X).leftCols<2>().rowwise().norm().maxCoeff();
  };
  EXPECT_GT(lateral(buckled.x), 0.05)
      << "the column must bend visibly (section half-width 0.025 m)";

  Scene straight = load("buckling_column", {"solver.quasi_viscosity=0"});
  std::vector<Index> axis;
  for (Index i = 0; i < s.mesh.num_nodes(); ++i)
    if (std::hypot(s.mesh.X(i, 0), s.mesh.X(i, 1)) < 1e-12) axis.push_back(i);
  ASSERT_EQ(axis.size(), 81u);
  straight.constraints.push_back({"axis", axis, OnLine{Vec3::UnitZ()}});
  const RunResult st = run(straight);
  ASSERT_TRUE(st.success) << st.message;
  EXPECT_LT(lateral(st.x), 1e-3);  // only the Poisson expansion of the section
  EXPECT_LT(buckled.steps.back().energy, 0.5 * st.steps.back().energy);
}

// A load that cannot be reached (shortening the unit block by 1.5) stops with a clear error once
// the increment falls below its minimum; the completed increments stay readable in the file.
TEST(StaticScenes, FailedRunKeepsCompletedIncrements) {
  const std::string out = testing::temp_path("failed_run.h5");
  const Scene s = load("uniaxial_block", {"boundary.3.offset=-1.5", "solver.min_increment=0.01"});
  const RunResult r = run(s, out);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("min_increment"), std::string::npos) << r.message;
  ASSERT_GE(r.steps.size(), 2u);
  EXPECT_LT(r.steps.back().load, 2.0 / 3.0);  // the block cannot be shortened to zero length
  const ResultsSummary summary = read_results_summary(out);
  EXPECT_EQ(summary.status, "failed");
  EXPECT_EQ(summary.num_steps, static_cast<Index>(r.steps.size()));
  EXPECT_EQ(summary.message, r.message);
  EXPECT_EQ((read_step_positions(out, summary.num_steps - 1) - r.x).cwiseAbs().maxCoeff(), 0.0);
  testing::remove_results(out);
}

// Every failed attempt prints one line (a failed attempt completes no step, so this is all a
// long one shows): the buckling column with Newton cut to two iterations fails its first half of
// the load and succeeds at a quarter; every attempt line starts from the last completed load and
// aims above the next one.
TEST(StaticScenes, EveryFailedAttemptPrintsALine) {
  const Scene s =
      load("buckling_column", {"solver.max_newton_iterations=2", "solver.initial_increment=0.5",
                               "solver.max_increment=0.5", "solver.min_increment=0.1"});
  std::ostringstream log;
  const RunResult r = run_scene(s, RunOptions{}, log);
  std::istringstream lines(log.str());
  std::string line;
  double completed = 0;
  int attempts = 0;
  std::vector<double> targets;
  while (std::getline(lines, line)) {
    double from = 0, to = 0;
    if (std::sscanf(line.c_str(), "attempt  load %lf -> %lf  failed", &from, &to) == 2) {
      ++attempts;
      EXPECT_EQ(from, completed) << line;
      EXPECT_NE(line.find("no convergence in 2 Newton iterations"), std::string::npos) << line;
      targets.push_back(to);
    } else if (std::sscanf(line.c_str(), "step %*d  load %lf", &to) == 1) {
      for (double target : targets) EXPECT_GT(target, to) << line;
      targets.clear();
      completed = to;
    }
  }
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps.front().load, 0.25);
  EXPECT_GE(attempts, 1);
  EXPECT_NE(log.str().find("attempt  load 0.0000 -> 0.5000  failed  newton  2"), std::string::npos)
      << log.str();
}

// Gravity ramps with the load: a bar sagging in ten increments of 0.1 is, at every step, the
// equilibrium under that fraction of its weight, the same state a single increment reaches under
// the scaled gravity. Both solves stop at a Newton residual of 1e-13 of the force scale (apps
// README), which bounds their difference far below the 1e-8 of the sag asserted.
TEST(StaticScenes, RampedGravityGivesTheEquilibriumOfEveryIncrement) {
  const std::vector<std::string> bar = {"bodies.0.mesh.cells=[20,2,2]",
                                        "bodies.0.material.youngs=1e7", "solver.tolerance=1e-13"};
  std::vector<std::string> ramped = bar;
  ramped.insert(ramped.end(), {"solver.initial_increment=0.1", "solver.max_increment=0.1"});
  std::vector<Points> states;
  RunOptions options;
  options.observer = [&](const StepRecord&, const Points& x) { states.push_back(x); };
  std::ostringstream log;
  const Scene s = load("cantilever_gravity", ramped);
  const RunResult r = run_scene(s, options, log);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_EQ(states.size(), 10u);
  const double sag = (states.back() - s.mesh.X).cwiseAbs().maxCoeff();
  EXPECT_GT(sag, 0.05) << "a sag well beyond small strain";
  for (int k = 1; k <= 10; ++k) {
    std::vector<std::string> single = bar;
    single.push_back("gravity=[0,0," + std::to_string(-9.81 * k / 10) + "]");
    const RunResult one = run(load("cantilever_gravity", single));
    ASSERT_TRUE(one.success) << one.message;
    EXPECT_LE((states[k - 1] - one.x).cwiseAbs().maxCoeff(), 1e-8 * sag) << "increment " << k;
  }
}

// A quarter of a block under its own weight, on two symmetry planes and a held base: every
// constrained direction belongs to one condition, so the reaction rows sum to minus the
// applied load (the weight) and each symmetry plane carries force along its normal only.
TEST(StaticScenes, ReactionsOfAQuarterModelSumToTheAppliedLoad) {
  const std::string path = testing::temp_path("quarter.json");
  std::ofstream(path) << R"({
    "gravity": [0, 0, -9.81],
    "bodies": [{"name": "quarter", "mesh": {"generator": "box", "lo": [0, 0, 0], "hi": [0.5, 0.5, 0.3], "cells": [5, 5, 3]},
                "material": {"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3}, "density": 1000}],
    "boundary": [
      {"name": "symmetry_x", "type": "plane", "normal": [1, 0, 0], "nodes": {"plane": {"normal": [1, 0, 0], "offset": 0}}},
      {"name": "symmetry_y", "type": "plane", "normal": [0, 1, 0], "nodes": {"plane": {"normal": [0, 1, 0], "offset": 0}}},
      {"name": "base", "type": "fixed", "nodes": {"plane": {"normal": [0, 0, 1], "offset": 0}}}
    ],
    "solver": {"tolerance": 1e-14}
  })";
  const Scene s = load_scene(path);
  std::filesystem::remove(path);
  const RunResult r = run(s);
  ASSERT_TRUE(r.success) << r.message;
  const double weight = 1000 * 0.5 * 0.5 * 0.3 * 9.81;
  const auto& R = r.steps.back().reactions;
  const Vec3 total = R.colwise().sum().transpose();
  EXPECT_LE((total - Vec3(0, 0, weight)).norm(), 1e-10 * weight);
  EXPECT_LE(R.row(0).tail<2>().norm(), 1e-10 * weight) << "symmetry_x pushes along x only";
  EXPECT_LE(std::abs(R(1, 0)) + std::abs(R(1, 2)), 1e-10 * weight) << "symmetry_y along y only";
}

// Every scene shipped in apps/scenes is run by some test; this list is checked against the folder.
TEST(StaticScenes, EveryShippedSceneIsTested) {
  const std::set<std::string> tested = {"cantilever_gravity",
                                        "uniaxial_block",
                                        "twist_bar",
                                        "buckling_column",
                                        "blocks_overlap",
                                        "ball_drop",
                                        "sliding_blocks",
                                        "falling_bars",
                                        "bars_drop",
                                        "hertz_sphere",
                                        "fold_slab",
                                        "knee_flexion",
                                        "knee_flexion_fine",
                                        "knee_flexion_veronda",
                                        "knee_flexion_incompressible",
                                        "knee_flexion_paper",
                                        "falling_bars_viscoelastic"};
  for (const auto& entry :
       std::filesystem::directory_iterator(std::string(DEPTHFEM_SOURCE_DIR) + "/apps/scenes")) {
    if (entry.path().extension() != ".json") continue;
    EXPECT_TRUE(tested.count(entry.path().stem().string())) << entry.path() << " has no test";
    EXPECT_NO_THROW(load_scene(entry.path().string()));
  }
}

// A bar whose half x > 0.5 is a million times stiffer than the other (one mesh file, a material
// per region), stretched 5 % by its ends: the stiff half moves as a rigid block, so the soft half
// must match a soft bar alone whose end is displaced, to the stiff half's own stretch.
TEST(StaticScenes, SoftRegionBesideAStiffOneMatchesTheSoftBarAlone) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / "depthfem_test_stiff_region";
  std::filesystem::create_directories(dir);
  const TetMesh bar = box_mesh({Vec3(0, 0, 0), Vec3(1, 0.1, 0.1), Eigen::Vector3i(10, 2, 2)});
  {
    std::ofstream msh(dir / "bar.msh");
    msh.precision(17);
    msh << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n3 1 \"soft\"\n"
        << "3 2 \"stiff\"\n$EndPhysicalNames\n$Nodes\n"
        << bar.X.rows() << "\n";
    for (Index i = 0; i < bar.X.rows(); ++i)
      msh << i + 1 << " " << bar.X(i, 0) << " " << bar.X(i, 1) << " " << bar.X(i, 2) << "\n";
    msh << "$EndNodes\n$Elements\n" << bar.tets.rows() << "\n";
    for (Index t = 0; t < bar.tets.rows(); ++t) {
      double cx = 0;
      for (int c = 0; c < 4; ++c) cx += bar.X(bar.tets(t, c), 0) / 4;
      msh << t + 1 << " 4 2 " << (cx < 0.5 ? 1 : 2) << " 1";
      for (int c = 0; c < 4; ++c) msh << " " << bar.tets(t, c) + 1;
      msh << "\n";
    }
    msh << "$EndElements\n";
  }
  const std::string soft = R"({"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3})";
  const auto scene = [&](const std::string& name, const std::string& body, double end) {
    std::ofstream((dir / (name + ".json")).string())
        << R"({"bodies": [)" << body << R"(], "boundary": [
          {"type": "fixed", "nodes": {"plane": {"normal": [1, 0, 0], "offset": 0}}},
          {"type": "displaced", "displacement": [0.05, 0, 0],
           "nodes": {"plane": {"normal": [1, 0, 0], "offset": )"
        << end << "}}}]}";
    return load_scene((dir / (name + ".json")).string());
  };
  const Scene both = scene("both", R"({"name": "bar", "mesh": {"file": "bar.msh"},
      "materials": {"soft": )" + soft + R"(, "stiff": {"model": "neo_hookean", "youngs": 1e11,
      "poisson": 0.3}}})",
                           1.0);
  const Scene alone = scene("alone",
                            R"({"name": "bar", "mesh": {"file": "bar.msh",
      "regions": ["soft"]}, "material": )" +
                                soft + "}",
                            0.5);
  const RunResult a = run(both), b = run(alone);
  ASSERT_TRUE(a.success) << a.message;
  ASSERT_TRUE(b.success) << b.message;
  // The soft nodes keep their order in both meshes.
  double worst = 0;
  Index k = 0;
  for (Index i = 0; i < both.mesh.num_nodes(); ++i) {
    if (both.mesh.X(i, 0) > 0.5 + 1e-12) continue;
    ASSERT_TRUE(both.mesh.X.row(i) == alone.mesh.X.row(k));
    worst = std::max(worst, (a.x.row(i) - b.x.row(k)).norm());
    ++k;
  }
  EXPECT_EQ(k, alone.mesh.num_nodes());
  // The stiff half stretches 1e-6 as much as the soft one: about 5e-8 m.
  EXPECT_LT(worst, 5e-7);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace depthfem
