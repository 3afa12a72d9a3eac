// The knee-flexion scene (apps/scenes/knee_flexion.json), shortened to its first small steps on
// the paper-size mesh: the scene loads as meant (bodies, regions, node sets, conditions), every
// step converges, no tet inverts, and the deepest penetration stays below the scene's 1 mm target.
#include <gtest/gtest.h>

#include <sstream>

#include "apps/scene_runner.hpp"
#include "core/tet_mesh.hpp"

namespace depthfem {
namespace {

using testing::load;
using testing::run;

// The smallest signed volume of the tets at positions x, relative to the tet's rest volume.
double smallest_volume_ratio(const Mesh& mesh, const Points& x) {
  double smallest = 1e300;
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    const auto corner = [&](const Points& p, int c) -> Vec3 { return p.row(mesh.tets(t, c)); };
    const double now = signed_volume(corner(x, 0), corner(x, 1), corner(x, 2), corner(x, 3));
    const double rest =
        signed_volume(corner(mesh.X, 0), corner(mesh.X, 1), corner(mesh.X, 2), corner(mesh.X, 3));
    smallest = std::min(smallest, now / rest);
  }
  return smallest;
}

TEST(KneeScene, LoadsBodiesRegionsAndConditions) {
  const Scene s = load("knee_flexion");
  ASSERT_EQ(s.mesh.bodies.size(), 3u);
  EXPECT_EQ(s.mesh.bodies[0].name, "femur");
  std::vector<bool> rigid;
  for (const Body& body : s.mesh.bodies) rigid.push_back(body.rigid);
  EXPECT_EQ(rigid, (std::vector<bool>{true, true, false}));
  // The leg: soft tissue and patella, one material each.
  ASSERT_EQ(s.groups.size(), 2u);
  EXPECT_GT(s.groups[0].tets.size(), 10 * s.groups[1].tets.size());
  // Rigid holds, the flexion, the soft tissue on the tibia, the thigh cut in its plane.
  ASSERT_EQ(s.constraints.size(), 5u);
  const Body& leg = s.mesh.bodies[2];
  EXPECT_EQ(s.constraints[2].nodes.size(), static_cast<size_t>(s.mesh.bodies[1].num_nodes));
  for (const Index i : s.constraints[3].nodes) EXPECT_GE(i, leg.first_node);
  for (const Index i : s.constraints[4].nodes) {
    EXPECT_GE(i, leg.first_node);
    EXPECT_NEAR(s.mesh.X(i, 2), 0.590, 1e-12) << "thigh_cut node off the cut plane";
  }
}

// The fine variant: the same conditions, contact, materials and solver options on a mesh of more
// than three times the tets (Newton's cap per increment too: capped at the default 30, the fine
// run failed at 148.9 degrees, bench/results/knee.md). Both factor in single precision (the
// linear solve is 64-82 % of a run; the same end state in a fifth less time than in double,
// bench/results/knee.md, sixth and fifteenth rounds). A run of either is a benchmark:
// bench/knee_flexion.sh.
TEST(KneeScene, FineVariantDiffersInItsMeshAlone) {
  const Scene coarse = load("knee_flexion"), fine = load("knee_flexion_fine");
  EXPECT_GT(fine.mesh.num_tets(), 3 * coarse.mesh.num_tets());
  ASSERT_EQ(fine.constraints.size(), coarse.constraints.size());
  for (size_t k = 0; k < fine.constraints.size(); ++k)
    EXPECT_EQ(fine.constraints[k].name, coarse.constraints[k].name);
  EXPECT_EQ(fine.contact_options.penalty, coarse.contact_options.penalty);
  EXPECT_EQ(fine.contact_options.excluded, coarse.contact_options.excluded);
  EXPECT_EQ(fine.groups.size(), coarse.groups.size());
  const StaticOptions &c = coarse.static_options, &f = fine.static_options;
  EXPECT_EQ(f.initial_increment, c.initial_increment);
  EXPECT_EQ(f.max_increment, c.max_increment);
  EXPECT_EQ(f.min_increment, c.min_increment);
  EXPECT_EQ(fine.tolerance, coarse.tolerance);  // relative; the Newton test scales it per mesh
  EXPECT_EQ(c.newton.max_iterations, 100);
  EXPECT_EQ(f.newton.max_iterations, c.newton.max_iterations);
  EXPECT_EQ(f.newton.linear.kind, c.newton.linear.kind);
  EXPECT_EQ(c.newton.linear.direct.precision, FactorPrecision::kSingle);
  EXPECT_EQ(f.newton.linear.direct.precision, c.newton.linear.direct.precision);
}

// The Veronda variant: the same scene with the soft tissue's model swapped, at the same
// small-strain moduli (shear 10 kPa, Poisson's ratio 0.452).
TEST(KneeScene, VerondaVariantHasTheMooneyRivlinSmallStrainModuli) {
  const Scene mr = load("knee_flexion"), veronda = load("knee_flexion_veronda");
  ASSERT_TRUE(std::holds_alternative<Veronda>(veronda.groups[0].material));
  const LinearizedModuli a = material_moduli(mr.groups[0].material);
  const LinearizedModuli b = material_moduli(veronda.groups[0].material);
  EXPECT_NEAR(a.mu, 1e4, 1e-6);
  EXPECT_NEAR(b.mu, 1e4, 1e-6);
  EXPECT_NEAR(a.poisson(), 0.45, 5e-3);
  EXPECT_NEAR(b.poisson(), a.poisson(), 1e-5);
  EXPECT_EQ(veronda.mesh.num_tets(), mr.mesh.num_tets());
}

// The nearly incompressible variant: the soft tissue on the nodal-pressure formulation with the
// same shear modulus and Poisson's ratio 0.49; the patella and everything else as in the scene.
TEST(KneeScene, IncompressibleVariantTakesNodalPressureAtPoisson049) {
  const Scene mr = load("knee_flexion"), inc = load("knee_flexion_incompressible");
  ASSERT_EQ(inc.groups.size(), mr.groups.size());
  EXPECT_EQ(inc.groups[0].formulation, VolumeFormulation::kNodalPressure);
  EXPECT_EQ(inc.groups[1].formulation, VolumeFormulation::kStandard);
  const LinearizedModuli a = material_moduli(mr.groups[0].material);
  const LinearizedModuli b = material_moduli(inc.groups[0].material);
  EXPECT_NEAR(b.mu, a.mu, 1e-6);
  EXPECT_NEAR(b.poisson(), 0.49, 1e-9);
  EXPECT_EQ(inc.mesh.num_tets(), mr.mesh.num_tets());
  ASSERT_EQ(inc.constraints.size(), mr.constraints.size());
  for (size_t k = 0; k < inc.constraints.size(); ++k)
    EXPECT_EQ(inc.constraints[k].name, mr.constraints[k].name);
}

// The paper-algorithm variant: knee_flexion.json under the solver preset "paper" (every setting
// of apps/README.md's table in force), with the knee's own increments, Newton tolerance and cap.
TEST(KneeScene, PaperVariantIsTheKneeUnderThePaperPreset) {
  const Scene knee = load("knee_flexion"), paper = load("knee_flexion_paper");
  EXPECT_EQ(paper.solver_preset, "paper");
  EXPECT_EQ(paper.mesh.num_tets(), knee.mesh.num_tets());
  ASSERT_EQ(paper.constraints.size(), knee.constraints.size());
  for (size_t k = 0; k < paper.constraints.size(); ++k)
    EXPECT_EQ(paper.constraints[k].name, knee.constraints[k].name);
  EXPECT_EQ(paper.contact_options.penalty, knee.contact_options.penalty);
  EXPECT_EQ(paper.contact_options.excluded, knee.contact_options.excluded);
  const StaticOptions &p = paper.static_options, &k = knee.static_options;
  EXPECT_EQ(p.initial_increment, k.initial_increment);
  EXPECT_EQ(p.max_increment, k.max_increment);
  EXPECT_EQ(p.min_increment, k.min_increment);
  EXPECT_EQ(p.newton.max_iterations, k.newton.max_iterations);
  EXPECT_EQ(paper.tolerance, knee.tolerance);
  // The preset's settings (apps/README.md, "Solver presets").
  EXPECT_EQ(p.newton.linear.kind, LinearSolverKind::kGmres);
  EXPECT_EQ(p.newton.linear.tolerance, 0.1);
  EXPECT_EQ(p.newton.linear.max_iterations, 1000);
  EXPECT_EQ(p.newton.linear.restart, 200);
  EXPECT_EQ(p.newton.line_search, LineSearchRule::kResidual);
  EXPECT_TRUE(p.newton.full_step_first);
  EXPECT_FALSE(p.newton.gradient_fallback);
  EXPECT_TRUE(p.predictor);
  EXPECT_FALSE(p.linearised_start);
  EXPECT_EQ(paper.quasi_viscosity, 300.0);
  EXPECT_EQ(paper.contact_options.list_margin, 0.0);
  // depthfem's defaults, which the preset changes.
  EXPECT_EQ(k.newton.line_search, LineSearchRule::kEnergy);
  EXPECT_FALSE(k.newton.full_step_first);
  EXPECT_TRUE(k.newton.gradient_fallback);
  EXPECT_TRUE(k.linearised_start);
  EXPECT_EQ(knee.quasi_viscosity, 0.0);
  EXPECT_GT(knee.contact_options.list_margin, 0.0);
}

// Keys beside the preset override it, each on its own; the others keep the preset's value.
TEST(KneeScene, KeysBesideThePresetOverrideIt) {
  const Scene s =
      load("knee_flexion_paper", {"solver.line_search=energy", "solver.gmres_restart=7",
                                  "solver.quasi_viscosity=0", "solver.linearised_start=true"});
  const StaticOptions& o = s.static_options;
  EXPECT_EQ(o.newton.line_search, LineSearchRule::kEnergy);
  EXPECT_EQ(o.newton.linear.restart, 7);
  EXPECT_EQ(s.quasi_viscosity, 0.0);
  EXPECT_TRUE(o.linearised_start);
  EXPECT_EQ(o.newton.linear.kind, LinearSolverKind::kGmres);
  EXPECT_TRUE(o.newton.full_step_first);
  EXPECT_FALSE(o.newton.gradient_fallback);
}

// Three steps of 0.5 degrees: about as long as one of the full run's first 3 degree steps, with
// more chances to catch a step that fails.
TEST(KneeScene, FirstStepsConvergeWithoutInversionOrDeepPenetration) {
  const Scene s = load("knee_flexion", {"boundary.0.angle_deg=1.5", "boundary.1.angle_deg=1.5",
                                        "solver.initial_increment=0.3333333333333333",
                                        "solver.max_increment=0.3333333333333333"});
  std::vector<double> worst_volume;
  RunOptions options;
  options.observer = [&](const StepRecord&, const Points& x) {
    worst_volume.push_back(smallest_volume_ratio(s.mesh, x));
  };
  std::ostringstream log;
  const RunResult r = run_scene(s, options, log);
  ASSERT_TRUE(r.success) << r.message << "\n" << log.str();
  ASSERT_GE(r.steps.size(), 3u);
  EXPECT_NEAR(r.steps.back().load, 1.0, 1e-12);
  for (size_t k = 0; k < r.steps.size(); ++k) {
    EXPECT_GT(worst_volume[k], 0.0) << "a tet inverted at step " << k;
    ASSERT_TRUE(r.steps[k].penetration.has_value());
    EXPECT_LT(*r.steps[k].penetration, 1e-3) << "step " << k;
  }
}

// The soft tissue is attached to the tibia, whose surface it covers: the scene excludes the
// tibia/leg interface from the search. Searched, its coinciding surfaces form pairs over the
// whole attachment that only touch (zero depth on the tissue's boundary): they carry no force
// and excluding them leaves the positions as they are.
TEST(KneeScene, TheAttachedTibiaOnlyTouchesTheTissue) {
  const std::vector<std::string> step = {"boundary.0.angle_deg=0.5", "boundary.1.angle_deg=0.5",
                                         "solver.initial_increment=1", "solver.max_increment=1"};
  const Scene excluded = load("knee_flexion", step);
  ASSERT_EQ(excluded.contact_options.excluded, (std::vector<std::array<Index, 2>>{{1, 2}}));
  std::vector<std::string> searched_step = step;
  // Excluding two rigid bodies, never searched anyway, searches every other interface.
  searched_step.push_back("contact.exclude=[\"femur/tibia\"]");
  const Scene searched = load("knee_flexion", searched_step);
  const auto last_positions = [](const Scene& s, StepRecord& last) {
    Points x;
    RunOptions options;
    options.observer = [&](const StepRecord& record, const Points& now) {
      last = record;
      x = now;
    };
    std::ostringstream log;
    const RunResult r = run_scene(s, options, log);
    EXPECT_TRUE(r.success) << r.message << "\n" << log.str();
    return x;
  };
  StepRecord a, b;
  const Points xa = last_positions(excluded, a), xb = last_positions(searched, b);
  const auto row = [](const StepRecord& r, const std::string& name) {
    for (const InterfaceForce& f : r.contact)
      if (f.name == name) return f;
    ADD_FAILURE() << "no row " << name;
    return InterfaceForce{};
  };
  EXPECT_GT(row(b, "tibia/leg").area, 0.01) << "the attachment's pairs [m^2]";
  EXPECT_LT(row(b, "tibia/leg").magnitude, 1e-6) << "[N]";
  EXPECT_EQ(row(a, "tibia/leg").area, 0.0);
  EXPECT_LT((xa - xb).cwiseAbs().maxCoeff(), 1e-8) << "[m]";
}

}  // namespace
}  // namespace depthfem
