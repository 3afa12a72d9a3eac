// What run_scene writes to the results file, read back: per-tet stress and strain of the
// homogeneous uniaxial_block scene against the closed forms of tests/materials/closed_forms.hpp
// (uniaxial stretch, and simple shear prescribed on every node), the per-region blocks of a
// two-region mesh against the neo-Hookean closed form, and the fields the output section and the
// scene's physics choose.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "apps/scene_runner.hpp"
#include "core/error.hpp"
#include "core/hdf5_file.hpp"
#include "core/mesh_generators.hpp"
#include "core/results_file.hpp"
#include "materials/closed_forms.hpp"

namespace depthfem {
namespace {

using namespace closed_form;
using testing::load;
using testing::run;
using testing::temp_path;
using testing::TemporaryResults;

const std::string kAllFields = R"(output={"stress": true, "strain": true})";

// Every tet of step `step` of `h5` has the Cauchy stress `sigma` and the logarithmic strain
// `log_v` of the homogeneous state F, to `tolerance` x the largest stress component (strain and
// volume ratio: x 1); von Mises is sqrt(3/2 s : s) of sigma's deviator s.
void expect_homogeneous(const std::string& h5, Index step, const Mat3& F, const Mat3& sigma,
                        const Mat3& log_v, double tolerance) {
  const Eigen::MatrixXd stress = read_step_dataset(h5, step, "stress");
  const Eigen::MatrixXd von_mises = read_step_dataset(h5, step, "von_mises");
  const Eigen::MatrixXd strain = read_step_dataset(h5, step, "strain");
  const Eigen::MatrixXd volume_ratio = read_step_dataset(h5, step, "volume_ratio");
  ASSERT_EQ(stress.cols(), 6);
  const Mat3 s = sigma - sigma.trace() / 3 * Mat3::Identity();
  const double scale = sigma.cwiseAbs().maxCoeff(), mises = std::sqrt(1.5 * s.squaredNorm());
  const int row[6] = {0, 1, 2, 0, 1, 0}, col[6] = {0, 1, 2, 1, 2, 2};  // xx yy zz xy yz xz
  for (Index t = 0; t < stress.rows(); ++t) {
    for (int c = 0; c < 6; ++c) {
      EXPECT_NEAR(stress(t, c), sigma(row[c], col[c]), tolerance * scale)
          << "tet " << t << " " << c;
      EXPECT_NEAR(strain(t, c), log_v(row[c], col[c]), tolerance) << "tet " << t << " " << c;
    }
    EXPECT_NEAR(von_mises(t), mises, tolerance * scale) << "tet " << t;
    EXPECT_NEAR(volume_ratio(t), F.determinant(), tolerance) << "tet " << t;
  }
}

// uniaxial_block stretched to l = 1.5: F = diag(l, t, t) with the closed-form lateral stretch,
// sigma = diag(P11 / t^2, 0, 0). The solve leaves the nodes within 1e-8 m of the closed form (the
// scene test), so F, the strain and the stress relative to their scale are within about 1e-7.
// output.every N writes every N-th completed step and the last one (here 5 steps, N = 2: steps
// 1, 3 and 4), with its own index and the same positions as a run that writes every step. (A
// failed run's last completed step takes the same path: written when the driver returns.)
TEST(RunScene, OutputEveryNStepsKeepsTheLast) {
  const TemporaryResults all("every_1"), some("every_2");
  const RunResult a = run(load("falling_bars", {"dynamic.duration=0.05"}), all.path);
  const RunResult b =
      run(load("falling_bars", {"dynamic.duration=0.05", "output.every=2"}), some.path);
  ASSERT_TRUE(a.success && b.success) << a.message << b.message;
  ASSERT_EQ(b.steps.size(), 5u) << "every step is still completed and kept";
  EXPECT_EQ(read_results_summary(all.path).num_steps, 5);
  EXPECT_EQ(read_results_summary(some.path).num_steps, 3);
  for (Index index : {1, 3, 4}) {
    const StepState written = read_step_state(some.path, index);
    EXPECT_EQ(written.x, read_step_state(all.path, index).x) << "step " << index;
  }
  EXPECT_THROW(read_step_state(some.path, 2), InputError) << "step 2 is not written";
}

TEST(RunScene, UniaxialStressAndStrainReadBackMatchTheClosedForm) {
  const auto check = [](const std::string& material_json, const auto& model) {
    SCOPED_TRACE(material_json);
    const TemporaryResults out("run_scene");
    const RunResult r =
        run(load("uniaxial_block", {"bodies.0.material=" + material_json, kAllFields}), out.path);
    ASSERT_TRUE(r.success) << r.message;
    const double l = 1.5, t = lateral_stretch(model, l);
    const Mat3 sigma = Vec3(closed_uniaxial(model, l, t).P11 / (t * t), 0, 0).asDiagonal();
    const Mat3 log_v = Vec3(std::log(l), std::log(t), std::log(t)).asDiagonal();
    expect_homogeneous(out.path, Index(r.steps.size()) - 1, Vec3(l, t, t).asDiagonal(), sigma,
                       log_v, 1e-6);
  };
  check(R"({"model": "mooney_rivlin", "C1": 4000, "C2": 1000, "a": 20000})",
        MooneyRivlin{4e3, 1e3, 2e4});
  check(R"({"model": "fiber_veronda", "alpha": 1500, "beta": 0.8, "a": 20000,
            "fiber_alpha": 2000, "fiber_beta": 3, "fiber_direction": [1, 0, 0]})",
        FiberReinforced<Veronda>{{1.5e3, 0.8, 2e4}, 2e3, 3});
}

// The boundary conditions of uniaxial_block that move every node by simple shear u = g y e_x,
// one condition per layer of nodes y = 0, 0.5, 1 (ramped with the load factor or time).
std::string shear_layers(double g) {
  const auto text = [](double v) {  // every digit: std::to_string would round 5e-7 to 0
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
  };
  std::string layers;
  for (const double y : {0.0, 0.5, 1.0})
    layers += std::string(layers.empty() ? "" : ", ") +
              R"({"type": "displaced", "displacement": [)" + text(g * y) +
              R"(, 0, 0], "nodes": {"box": {"lo": [-1, )" + std::to_string(y - 0.1) +
              R"(, -1], "hi": [2, )" + std::to_string(y + 0.1) + R"(, 2]}}})";
  return "boundary=[" + layers + "]";
}

// The unit cube with every node moved by simple shear (shear_layers): F = I + g e_x e_y^T in
// every tet exactly, sigma = P F^T (J = 1) with the
// hand-derived P, and ln V = asinh(g/2) / sqrt(1 + g^2/4) [[g/2, 1, 0], [1, -g/2, 0], [0, 0, 0]]
// (derived in tests/integrators/test_element_fields.cpp). Only round-off separates them: 1e-10.
TEST(RunScene, SimpleShearStressReadBackMatchesTheClosedForm) {
  const double g = 0.4, c = std::asinh(g / 2) / std::sqrt(1 + g * g / 4);
  Mat3 log_v = Mat3::Zero();
  log_v.topLeftCorner<2, 2>() << c * g / 2, c, c, -c * g / 2;
  const auto check = [&](const std::string& material_json, const auto& model) {
    SCOPED_TRACE(material_json);
    const TemporaryResults out("run_scene");
    const RunResult r = run(
        load("uniaxial_block", {"bodies.0.material=" + material_json, shear_layers(g), kAllFields}),
        out.path);
    ASSERT_TRUE(r.success) << r.message;
    Mat3 F = Mat3::Identity();
    F(0, 1) = g;
    expect_homogeneous(out.path, Index(r.steps.size()) - 1, F,
                       simple_shear_piola(model, g) * F.transpose(), log_v, 1e-10);
  };
  check(R"({"model": "neo_hookean", "mu": 10000, "lambda": 40000})", NeoHookean{1e4, 4e4});
  check(R"({"model": "mooney_rivlin", "C1": 4000, "C2": 1000, "a": 20000})",
        MooneyRivlin{4e3, 1e3, 2e4});
}

// A viscoelastic cube sheared at the constant rate g' (g = 1e-6 at t = 1 s; every node prescribed,
// shear_layers) with one Prony term: the viscous shear stress is
//   q(t) = mu beta tau g' (1 - e^-t/tau),
// which Simo's recursion gives exactly for a strain linear in time (at small strain: 1e-6). The
// step's dissipated energy is, per its definition (viscoelastic_history.hpp) for a simple shear
// with Q = q (e_x e_y^T + e_y e_x^T) and dE_xy = dg / 2,
//   V [(q_n + q_n+1) / 2 dg - (q_n+1^2 - q_n^2) / (2 beta mu)].
TEST(RunScene, ViscousStressAndDissipationOfAShearRateReadBack) {
  const double g = 1e-6, mu = 1e4, beta = 0.4, tau = 0.3, dt = 0.1;
  const TemporaryResults out("run_scene");
  const RunResult r =
      run(load("uniaxial_block",
               {R"(bodies.0.material={"model": "neo_hookean", "mu": 10000, "lambda": 40000,
                "viscoelastic": {"relaxation_times": [0.3], "weights": [0.4]}})",
                shear_layers(g), "analysis=dynamic",
                R"(dynamic={"integrator": "newmark", "time_step": 0.1, "duration": 1})"}),
          out.path);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_EQ(r.steps.size(), 10u);
  double q_before = 0;
  for (Index k = 0; k < 10; ++k) {
    const double t = (k + 1) * dt, q = mu * beta * tau * g * (1 - std::exp(-t / tau));
    const Eigen::MatrixXd viscous = read_step_dataset(out.path, k, "viscous_stress");
    ASSERT_EQ(viscous.cols(), 6);
    for (Index e = 0; e < viscous.rows(); ++e) {
      EXPECT_NEAR(viscous(e, 3), q, 1e-6 * q) << "step " << k << " tet " << e;  // xy
      EXPECT_LE(viscous.row(e).cwiseAbs().maxCoeff(), q * (1 + 1e-6));
    }
    const double dissipated =
        (q_before + q) / 2 * g * dt - (q * q - q_before * q_before) / (2 * beta * mu);
    EXPECT_NEAR(read_step_dataset(out.path, k, "dissipated_energy")(0, 0), dissipated,
                1e-5 * std::abs(dissipated))
        << "step " << k;
    EXPECT_EQ(*r.steps[k].dissipated_energy,
              read_step_dataset(out.path, k, "dissipated_energy")(0, 0));
    q_before = q;
  }
}

// The output section chooses what each step holds; contact fields need contact, velocities a
// time-dependent analysis, and the material depth is written only with material-depth contact.
TEST(RunScene, OutputSectionAndPhysicsChooseTheFields) {
  const auto datasets = [](const std::vector<std::string>& overrides, const std::string& scene) {
    const TemporaryResults out("run_scene");
    const RunResult r = run(load(scene, overrides), out.path);
    EXPECT_TRUE(r.success) << r.message;
    std::string names;
    for (const char* name : {"displacement", "v", "stress", "strain", "contact_pressure"}) {
      try {
        read_step_dataset(out.path, 0, name);
        names += std::string(names.empty() ? "" : " ") + name;
      } catch (const InputError&) {
      }
    }
    return names;
  };
  EXPECT_EQ(datasets({}, "uniaxial_block"), "displacement");
  EXPECT_EQ(datasets({R"(output={"displacement": false, "stress": true})"}, "uniaxial_block"),
            "stress");
  EXPECT_EQ(datasets({"dynamic.duration=0.01", R"(output={"strain": true})"}, "falling_bars"),
            "displacement v strain");
  const std::string wall =
      R"(obstacles=[{"name": "wall", "type": "plane", "point": [3, 0, 0], "normal": [-1, 0, 0], "penalty": 1e6}])";
  EXPECT_EQ(datasets({wall}, "uniaxial_block"), "displacement contact_pressure");
  EXPECT_EQ(datasets({wall, R"(output={"contact": false})"}, "uniaxial_block"), "displacement");
}

// A cube of 2 x 2 x 2 cells whose cells form a checkerboard of two element regions, "soft" and
// "stiff" (neo-Hookean, shear moduli 10 kPa and 100 kPa), read from a Gmsh file whose tets
// alternate between them cell by cell, sheared and stretched by its top face. The results hold
// one block per region with the region's 24 tets in their file order, and each block's stress
// and volume ratio are, tet by tet, the neo-Hookean Cauchy stress
// sigma = (mu (F F^T - I) + lambda ln J I) / J of F = Ds Dm^-1 from the block's own tets and
// points with its region's moduli. The library computes the same closed form through
// P F^T / J: only round-off separates them (1e-10 of the largest stress; observed 2e-14).
TEST(RunScene, EachRegionIsABlockWithItsOwnTetsAndStresses) {
  const TetMesh cube = box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(2, 2, 2)});
  std::vector<std::vector<Index>> region_tets(2);  // file tets of "soft" (0) and "stiff" (1)
  std::ostringstream msh;
  msh << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n3 1 \"soft\"\n"
         "3 2 \"stiff\"\n$EndPhysicalNames\n$Nodes\n"
      << cube.X.rows() << "\n";
  msh.precision(17);
  for (Index i = 0; i < cube.X.rows(); ++i)
    msh << i + 1 << " " << cube.X(i, 0) << " " << cube.X(i, 1) << " " << cube.X(i, 2) << "\n";
  msh << "$EndNodes\n$Elements\n" << cube.tets.rows() << "\n";
  for (Index t = 0; t < cube.tets.rows(); ++t) {
    const Vec3 c = (cube.X.row(cube.tets(t, 0)) + cube.X.row(cube.tets(t, 1)) +
                    cube.X.row(cube.tets(t, 2)) + cube.X.row(cube.tets(t, 3))) /
                   4;
    const int region =
        int(std::floor(2 * c.x()) + std::floor(2 * c.y()) + std::floor(2 * c.z())) % 2;
    region_tets[region].push_back(t);
    msh << t + 1 << " 4 2 " << region + 1 << " " << region + 1;
    for (int k = 0; k < 4; ++k) msh << " " << cube.tets(t, k) + 1;
    msh << "\n";
  }
  msh << "$EndElements\n";
  ASSERT_EQ(region_tets[0].size(), 24u);
  ASSERT_NE(region_tets[0].back(), 23) << "the regions must interleave in the file";
  const std::string mesh_path = temp_path("checker.msh"), scene_path = temp_path("checker.json");
  std::ofstream(mesh_path) << msh.str();
  std::ofstream(scene_path) << R"({"name": "checker", "bodies": [{"name": "cube",
      "mesh": {"file": ")" + mesh_path +
                                   R"("},
      "materials": {"soft": {"model": "neo_hookean", "mu": 1e4, "lambda": 4e4},
                    "stiff": {"model": "neo_hookean", "mu": 1e5, "lambda": 4e5}}}],
    "boundary": [
      {"type": "fixed", "nodes": {"plane": {"normal": [0, 0, 1], "offset": 0}}},
      {"type": "displaced", "displacement": [0.1, 0, 0.1],
       "nodes": {"plane": {"normal": [0, 0, 1], "offset": 1}}}],
    "output": {"stress": true, "strain": true}})";
  const TemporaryResults out("regions");
  const RunResult r = run(load_scene(scene_path), out.path);
  std::filesystem::remove(mesh_path);
  std::filesystem::remove(scene_path);
  ASSERT_TRUE(r.success) << r.message;
  const Index last = Index(r.steps.size()) - 1;

  const H5File file = H5File::open(out.path);
  const double mu[2] = {1e4, 1e5}, lambda[2] = {4e4, 4e5};
  const char* names[2] = {"cube/soft (neo_hookean)", "cube/stiff (neo_hookean)"};
  const Eigen::MatrixXd x = read_step_dataset(out.path, last, "x");
  const Eigen::MatrixXd all_stress = read_step_dataset(out.path, last, "stress");
  const Eigen::MatrixXd all_volume_ratio = read_step_dataset(out.path, last, "volume_ratio");
  const std::vector<double> tet_region = file.read_doubles("/mesh/tet_region");
  ASSERT_EQ(x.rows(), cube.X.rows());
  for (int k = 0; k < 2; ++k) {
    SCOPED_TRACE(names[k]);
    const std::string block = "blocks/" + std::to_string(k);
    EXPECT_EQ(file.string_attribute("/mesh/" + block, "name"), names[k]);
    const std::vector<double> local = file.read_doubles("/mesh/" + block + "/tets");
    // The region's rows of the tet fields: contiguous, region after region.
    const Index first =
        Index(std::find(tet_region.begin(), tet_region.end(), k) - tet_region.begin());
    const Index count = Index(std::count(tet_region.begin(), tet_region.end(), k));
    ASSERT_EQ(count, Index(region_tets[k].size()));
    const Eigen::MatrixXd stress = all_stress.middleRows(first, count);
    const VectorX volume_ratio = all_volume_ratio.col(0).segment(first, count);
    ASSERT_EQ(local.size(), 4 * region_tets[k].size());
    const double scale = stress.cwiseAbs().maxCoeff();
    EXPECT_GT(scale, 10.0) << "the region must be deformed";
    const int row[6] = {0, 1, 2, 0, 1, 0}, col[6] = {0, 1, 2, 1, 2, 2};  // xx yy zz xy yz xz
    for (size_t t = 0; t < region_tets[k].size(); ++t) {
      Eigen::Vector4i corners;
      for (int c = 0; c < 4; ++c) {
        corners(c) = int(local[4 * t + c]);
        EXPECT_EQ(corners(c), cube.tets(region_tets[k][t], c)) << "tet " << t << " of the region";
      }
      Mat3 Dm, Ds;
      for (int c = 0; c < 3; ++c) {
        Dm.col(c) = (cube.X.row(corners(c + 1)) - cube.X.row(corners(0))).transpose();
        Ds.col(c) = (x.row(corners(c + 1)) - x.row(corners(0))).transpose();
      }
      const Mat3 F = Ds * Dm.inverse();
      const double J = F.determinant();
      const Mat3 sigma = (mu[k] * (F * F.transpose() - Mat3::Identity()) +
                          lambda[k] * std::log(J) * Mat3::Identity()) /
                         J;
      for (int c = 0; c < 6; ++c)
        EXPECT_NEAR(stress(Index(t), c), sigma(row[c], col[c]), 1e-10 * scale) << "tet " << t;
      EXPECT_NEAR(volume_ratio(Index(t)), J, 1e-12) << "tet " << t;
    }
  }
  EXPECT_FALSE(file.exists("/mesh/blocks/2"));
}

RunResult run_restarted(const Scene& scene, const std::string& out, const std::string& restart,
                        Index step) {
  std::ostringstream log;
  RunOptions options;
  options.out = out;
  options.restart = restart;
  options.restart_step = step;
  return run_scene(scene, options, log);
}

// A static run restarted from a completed step ends in the state of the run it restarts: twist_bar
// turned 180 degrees in increments of 0.1, restarted at load 0.4 (step 3). Both solves stop at
// the scene's tolerance, 1e-9 E h^2 per dof (rms), i.e. residual forces near 1e-9 E h^2 and,
// through a stiffness of order E h per node, positions within about 1e-9 h = 5e-11 m of the
// exact equilibrium; 1e-8 m leaves a factor 200 for the conditioning of the twisted bar (measured:
// 1.1e-16 m, both runs' last Newton iterations converging quadratically to round-off).
TEST(RunScene, RestartedStaticRunEndsInTheSameState) {
  const Scene scene =
      load("twist_bar", {"solver.initial_increment=0.1", "solver.max_increment=0.1"});
  const TemporaryResults whole("restart_whole"), rest("restart_rest");
  const RunResult a = run(scene, whole.path);
  ASSERT_TRUE(a.success) << a.message;
  ASSERT_EQ(a.steps.size(), 10u);
  const RunResult b = run_restarted(scene, rest.path, whole.path, 3);
  ASSERT_TRUE(b.success) << b.message;
  ASSERT_EQ(b.steps.size(), 6u) << "loads 0.5 to 1 after a restart at 0.4";
  EXPECT_EQ(b.steps.front().load, 0.5);
  EXPECT_EQ(b.steps.back().load, 1.0);
  EXPECT_LT((b.x - a.x).cwiseAbs().maxCoeff(), 1e-8);
  // The restart's own file holds its steps, read back as positions the same.
  EXPECT_EQ(read_step_state(rest.path).x, b.x);
}

// A run of `scene` into `out` that stops after step `last` as a killed one would: the observer's
// error ends it there, every step up to `last` written (and no later one).
RunResult run_stopped_after(const Scene& scene, const std::string& out, Index last) {
  std::ostringstream log;
  RunOptions options;
  options.out = out;
  options.observer = [&](const StepRecord& step, const Points&) {
    if (step.index == last) throw InputError("stopped after step " + std::to_string(last));
  };
  return run_scene(scene, options, log);
}

// Step `k` of `restarted` (a run restarted after step `last` of another) against step
// last + 1 + k of the uninterrupted run `whole`: the same time and, to `tolerance` [m, m/s, Pa]
// (0: bitwise), the same positions, velocities and viscous stress.
void expect_same_step(const std::string& whole, const std::string& restarted, Index last, Index k,
                      double tolerance, bool viscous) {
  const Index at = last + 1 + k;
  const std::string what = "step " + std::to_string(at);
  EXPECT_EQ(read_step_dataset(restarted, k, "load"), read_step_dataset(whole, at, "load")) << what;
  std::vector<std::string> names = {"x", "v"};
  if (viscous) names.push_back("viscous_stress");
  for (const std::string& name : names) {
    const Eigen::MatrixXd a = read_step_dataset(whole, at, name),
                          b = read_step_dataset(restarted, k, name);
    ASSERT_EQ(a.rows(), b.rows()) << what << " " << name;
    const double scale = name == "viscous_stress" ? std::max(1.0, a.cwiseAbs().maxCoeff()) : 1.0;
    if (tolerance == 0) {
      EXPECT_EQ(a, b) << what << " " << name;
    } else {
      EXPECT_LE((a - b).cwiseAbs().maxCoeff(), tolerance * scale) << what << " " << name;
    }
  }
}

// A time-dependent run stopped after step 11 and restarted from its file ends as the
// uninterrupted run: falling_bars_viscoelastic (three bars, relaxation times 0.1 ms to 100 ms
// against the 10 ms step) over 0.3 s, by implicit Euler, Newmark and generalized-alpha. With
// the CG linear solver every step is a function of the state the file holds (positions,
// velocities, time, the acceleration and the per-tet history of the restart record), so the
// restarted steps are bitwise those of the uninterrupted run: positions, velocities, viscous
// stress, dissipated energy. (The direct solver keeps its last factor across steps as a CG
// preconditioner, which a restart cannot have: see the next test.) The file written every 4th
// step restarts from its last written step, 11 (every 4th: 3, 7, 11).
TEST(RunScene, RestartedDynamicRunEqualsTheUninterruptedOne) {
  for (const char* integrator : {"implicit_euler", "newmark", "generalized_alpha"}) {
    SCOPED_TRACE(integrator);
    const Scene scene =
        load("falling_bars_viscoelastic",
             {std::string(R"(dynamic={"integrator": ")") + integrator +
                  R"(", "time_step": 0.01, "duration": 0.3})",
              "solver.linear_solver=cg", "solver.linear_tolerance=1e-6", "output.every=4"});
    const TemporaryResults whole("restart_whole"), part("restart_part"), rest("restart_rest");
    const RunResult a = run(scene, whole.path);
    ASSERT_TRUE(a.success) << a.message;
    const RunResult stopped = run_stopped_after(scene, part.path, 11);
    ASSERT_FALSE(stopped.success);
    ASSERT_EQ(read_results_summary(part.path).num_steps, 3) << "steps 3, 7 and 11 written";
    const RunResult b = run_restarted(scene, rest.path, part.path, -1);
    ASSERT_TRUE(b.success) << b.message;
    ASSERT_EQ(b.steps.size(), 18u) << "steps 12 to 29";
    EXPECT_EQ(b.x, a.x);
    for (size_t k = 0; k < b.steps.size(); ++k) {
      const StepRecord &r = b.steps[k], &u = a.steps[12 + k];
      EXPECT_EQ(r.load, u.load);
      EXPECT_EQ(r.newton_iterations, u.newton_iterations) << "step " << 12 + k;
      EXPECT_EQ(r.energy, u.energy) << "step " << 12 + k;
      EXPECT_EQ(r.dissipated_energy, u.dissipated_energy) << "step " << 12 + k;
    }
    // Written: steps 15, 19, 23, 27 and the last, 29 (rows 3, 7, 11, 15, 17 of the restart).
    for (const Index k : {3, 7, 11, 15, 17})
      expect_same_step(whole.path, rest.path, 11, k, 0.0, true);
  }
}

// A restart with the default direct solver: falling_bars_viscoelastic by quasistatic viscous flow
// (implicit Euler) and Newmark, and the elastic falling_bars by Newmark; and by symplectic Euler.
// The direct solver keeps its last factor as the CG preconditioner of the next solve, which a
// restarted run does not have: where the uninterrupted run's first solve after the restart point
// goes on with CG on it and the restarted run factors, the two solutions differ within the Newton
// tolerance (1e-9 E h^2 per dof: forces near 1e-9 x 2e5 Pa x (0.05 m)^2 = 5e-7 N, positions within
// about 1e-9 h = 5e-11 m of the step's exact solution), which the bars' dynamics carry on without
// growth over 18 steps; 1e-8 m and m/s leave a factor 200. Measured: bitwise equal on these scenes
// (their first solve of a step factors in both runs); on the kill test's block on a floor, 3e-15 m
// and 2e-13 m/s over 55 steps. Symplectic Euler solves nothing: bitwise, also viscoelastic, where
// the force of the first step after the restart is the one the restart record holds (re-evaluated
// from the restored history it differed by round-off: measured 4e-17 m/s, 1e-13 Pa of viscous
// stress).
TEST(RunScene, RestartedDynamicRunFollowsTheUninterruptedOneWithTheDirectSolver) {
  struct Case {
    const char* scene;
    const char* dynamic;
    double tolerance;
    bool viscous;
    const char* analysis = "dynamic";
  };
  for (const Case& c :
       {Case{"falling_bars_viscoelastic",
             R"(dynamic={"time_step": 0.01, "duration": 0.3, "viscosity": 20})", 1e-8, true,
             "quasistatic"},
        Case{"falling_bars_viscoelastic",
             R"(dynamic={"integrator": "newmark", "time_step": 0.01, "duration": 0.3})", 1e-8,
             true},
        Case{"falling_bars",
             R"(dynamic={"integrator": "newmark", "time_step": 0.01, "duration": 0.3})", 1e-8,
             false},
        Case{"falling_bars",
             R"(dynamic={"integrator": "symplectic_euler", "time_step": 1e-5, "duration": 3e-4})",
             0.0, false},
        Case{"falling_bars_viscoelastic",
             R"(dynamic={"integrator": "symplectic_euler", "time_step": 1e-5, "duration": 3e-4})",
             0.0, true}}) {
    SCOPED_TRACE(std::string(c.scene) + " " + c.analysis + " " + c.dynamic);
    const Scene scene = load(c.scene, {std::string("analysis=") + c.analysis, c.dynamic});
    const TemporaryResults whole("restart_whole"), part("restart_part"), rest("restart_rest");
    ASSERT_TRUE(run(scene, whole.path).success);
    ASSERT_FALSE(run_stopped_after(scene, part.path, 11).success);
    const RunResult b = run_restarted(scene, rest.path, part.path, -1);
    ASSERT_TRUE(b.success) << b.message;
    ASSERT_EQ(b.steps.size(), 18u);
    for (Index k = 0; k < 18; ++k)
      expect_same_step(whole.path, rest.path, 11, k, c.tolerance, c.viscous);
  }
}

// A restart names its file in one line for every refusal: another mesh (other counts, or as many
// nodes and tets elsewhere), a missing step, another analysis.
TEST(RunScene, RestartRefusesWhatItCannotContinue) {
  const TemporaryResults bar("restart_bar"), out("restart_out");
  ASSERT_TRUE(run(load("twist_bar", {"solver.initial_increment=0.5"}), bar.path).success);
  const auto message = [&](const Scene& scene, Index step) {
    try {
      run_restarted(scene, out.path, bar.path, step);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string other = message(load("uniaxial_block"), -1);
  EXPECT_NE(other.find(bar.path), std::string::npos) << other;
  EXPECT_NE(other.find("the scene 27 and"), std::string::npos) << other;
  const std::string thicker = message(load("twist_bar", {"bodies.0.mesh.hi=[1, 0.12, 0.12]"}), -1);
  EXPECT_NE(thicker.find(bar.path + ": was written for another mesh: /mesh/X"), std::string::npos)
      << thicker;
  const std::string missing = message(load("twist_bar"), 7);
  EXPECT_NE(missing.find("has no step 7"), std::string::npos) << missing;
  const std::string dynamic = message(
      load("twist_bar", {"analysis=dynamic", R"(dynamic={"time_step": 0.5, "duration": 1})"}), -1);
  EXPECT_NE(dynamic.find(bar.path + ": cannot restart from it: its /run attribute analysis is "
                                    "static, the scene's dynamic"),
            std::string::npos)
      << dynamic;
}

// A time-dependent restart refuses, in one line naming the file: a file of another analysis or of
// another scene on the same mesh (elastic where the scene is viscoelastic and the other way
// round, another integrator's record), a step whose restart record was overwritten, a step at
// the end of the duration, and the ARKODE integrators, whose adaptive state no file holds. The
// files run 0.05 s; the restarted scenes go on to 0.1 s.
TEST(RunScene, DynamicRestartRefusesWhatItCannotContinue) {
  const auto dynamic = [](const char* integrator, double duration) {
    return std::string(R"(dynamic={"integrator": ")") + integrator +
           R"(", "time_step": 0.01, "duration": )" + std::to_string(duration) + "}";
  };
  const TemporaryResults viscous_file("restart_viscous"), elastic_file("restart_elastic"),
      euler_file("restart_euler"), quasistatic_file("restart_quasistatic"), out("restart_out");
  ASSERT_TRUE(run(load("falling_bars_viscoelastic", {dynamic("newmark", 0.05)}), viscous_file.path)
                  .success);
  ASSERT_TRUE(run(load("falling_bars", {dynamic("newmark", 0.05)}), elastic_file.path).success);
  ASSERT_TRUE(
      run(load("falling_bars", {dynamic("implicit_euler", 0.05)}), euler_file.path).success);
  ASSERT_TRUE(run(load("falling_bars",
                       {"analysis=quasistatic",
                        R"(dynamic={"time_step": 0.01, "duration": 0.02, "viscosity": 20})"}),
                  quasistatic_file.path)
                  .success);
  const Scene viscous = load("falling_bars_viscoelastic", {dynamic("newmark", 0.1)});
  const Scene elastic = load("falling_bars", {dynamic("newmark", 0.1)});
  const auto message = [&](const Scene& scene, const std::string& file, Index step) {
    try {
      run_restarted(scene, out.path, file, step);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const auto expect = [&](const Scene& scene, const std::string& file, Index step,
                          const std::string& part) {
    const std::string text = message(scene, file, step);
    EXPECT_EQ(text.rfind(file + ": ", 0), 0u) << text;
    EXPECT_NE(text.find(part), std::string::npos) << text;
    EXPECT_EQ(text.find('\n'), std::string::npos) << text;
  };
  expect(elastic, quasistatic_file.path, -1, "analysis is quasistatic, the scene's dynamic");
  expect(viscous, elastic_file.path, -1, "has no dataset /restart/history");
  expect(elastic, viscous_file.path, -1,
         "holds a viscoelastic history (/restart/history), and the scene has no viscoelastic");
  expect(elastic, euler_file.path, -1, "has no restart record (/restart)");
  expect(viscous, viscous_file.path, 1,
         "/restart/step: no restart record of step 1 (records of steps: 4, 3;");
  expect(load("falling_bars", {dynamic("newmark", 0.05)}), elastic_file.path, -1,
         "step 4 ends at t = 0.05 s, the scene's duration is 0.05 s");
  for (const char* sundials : {"arkode", "arkode_dirk", "cvode_bdf"})
    expect(load("falling_bars", {dynamic(sundials, 0.1)}), elastic_file.path, -1,
           "integrator (arkode, arkode_dirk or cvode_bdf) keeps an adaptive step size");
  // The file of implicit Euler (no restart record) restarts from any of its steps; the Newmark
  // file from its last two.
  const RunResult from_euler = run_restarted(load("falling_bars", {dynamic("implicit_euler", 0.1)}),
                                             out.path, euler_file.path, 1);
  ASSERT_TRUE(from_euler.success) << from_euler.message;
  EXPECT_EQ(from_euler.steps.size(), 8u) << "t = 0.03 to 0.1 s";
  const RunResult from_newmark = run_restarted(viscous, out.path, viscous_file.path, 3);
  ASSERT_TRUE(from_newmark.success) << from_newmark.message;
  EXPECT_EQ(from_newmark.steps.size(), 6u) << "t = 0.05 to 0.1 s";
}

}  // namespace
}  // namespace depthfem
