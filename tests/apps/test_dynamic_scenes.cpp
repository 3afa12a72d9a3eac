// Time integration: exact discrete free falls, energy behaviour of each scheme on falling_bars,
// the first bending period of a clamped bar against beam theory, damped and viscous runs settling
// to the static solution, and the errors the explicit schemes raise.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "apps/scene_runner.hpp"
#include "core/error.hpp"
#include "core/mass.hpp"
#include "core/results_file.hpp"

namespace depthfem {
namespace {

using testing::load;
using testing::run;

// With gravity only, every node moves alike and elastic forces vanish. Implicit Euler and
// symplectic Euler (velocity first) both give v_n = v_0 + n h g and
// x_n = x_0 + n h v_0 + h^2 g n (n + 1) / 2 exactly; Newmark (exact for constant acceleration,
// whatever beta and gamma), generalized-alpha (its balance (1 - alpha_m) a^{n+1} + alpha_m a^n = g
// keeps a = g) and ARKODE's explicit and diagonally implicit Runge-Kutta (order >= 2: exact for
// quadratic solutions) give x_0 + t v_0 + g t^2 / 2. With the consistent mass matrix, whose rows
// sum to the lumped masses that carry gravity, the uniform acceleration g still balances the weight
// exactly.
TEST(DynamicScenes, FreeFallFollowsTheDiscreteSolutionOfEachIntegrator) {
  const std::string path = testing::temp_path("free_fall.json");
  std::ofstream(path) << R"({
    "analysis": "dynamic", "gravity": [0, 0, -9.81],
    "bodies": [{"name": "b", "mesh": {"generator": "box", "lo": [0, 0, 0], "hi": [0.3, 0.2, 0.1], "cells": [3, 2, 1]},
                "material": {"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3}, "velocity": [1, 0, 2]}],
    "dynamic": {"time_step": 0.0002, "duration": 0.002},
    "solver": {"tolerance": 1e-12}
  })";
  const double h = 0.0002, n = 10, t = n * h;
  const Vec3 v0(1, 0, 2), g(0, 0, -9.81);
  const Vec3 first_order = t * v0 + h * h * g * n * (n + 1) / 2;
  const Vec3 exact = t * v0 + 0.5 * t * t * g;
  // Each case: the scene's "dynamic" section beyond time_step and duration.
  const std::pair<const char*, Vec3> cases[] = {
      {R"("integrator": "implicit_euler")", first_order},
      {R"("integrator": "symplectic_euler")", first_order},
      {R"("integrator": "newmark")", exact},
      {R"("integrator": "arkode")", exact},
      {R"("integrator": "generalized_alpha")", exact},
      {R"("integrator": "generalized_alpha", "generalized_alpha": {"rho_inf": 0})", exact},
      {R"("integrator": "arkode_dirk", "arkode": {"order": 2})", exact},
      {R"("integrator": "arkode_dirk", "arkode": {"order": 4})", exact},
      {R"("integrator": "newmark", "newmark": {"beta": 0.3, "gamma": 0.6})", exact},
      {R"("integrator": "newmark", "mass": "consistent")", exact},
      {R"("integrator": "implicit_euler", "mass": "consistent")", first_order}};
  for (const auto& [integrator, expected] : cases) {
    const Scene s =
        load_scene(path, {parse_override(R"(dynamic={"time_step": 0.0002, "duration": 0.002, )" +
                                         std::string(integrator) + "}")});
    const RunResult r = run(s);
    ASSERT_TRUE(r.success) << r.message;
    ASSERT_EQ(r.steps.size(), 10u);
    for (Index i = 0; i < s.mesh.num_nodes(); ++i)
      EXPECT_LE((r.x.row(i) - s.mesh.X.row(i) - expected.transpose()).norm(), 1e-12)
          << integrator << " node " << i;
  }
  std::filesystem::remove(path);
}

// Prescribed motion holds exactly at every step of every integrator: the face x = 0 of a falling
// box is displaced linearly in time (u t / duration) while the rest moves freely.
TEST(DynamicScenes, EveryIntegratorHonoursDirichletConditionsExactly) {
  const std::string path = testing::temp_path("prescribed.json");
  std::ofstream(path) << R"({
    "analysis": "dynamic", "gravity": [0, 0, -9.81],
    "bodies": [{"name": "b", "mesh": {"generator": "box", "lo": [0, 0, 0], "hi": [0.3, 0.2, 0.1], "cells": [3, 2, 1]},
                "material": {"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3}}],
    "boundary": [{"type": "displaced", "displacement": [0.01, 0.02, 0.03],
                  "nodes": {"plane": {"normal": [1, 0, 0], "offset": 0}}}],
    "dynamic": {"time_step": 0.0002, "duration": 0.002}
  })";
  for (const char* integrator : {"implicit_euler", "newmark", "generalized_alpha",
                                 "symplectic_euler", "arkode", "arkode_dirk", "cvode_bdf"}) {
    const Scene s =
        load_scene(path, {parse_override(std::string("dynamic.integrator=") + integrator)});
    const std::vector<Index>& face = s.constraints[0].nodes;
    double worst = 0, free_motion = 0;
    RunOptions options;
    options.observer = [&](const StepRecord& st, const Points& x) {
      const Vec3 u = Vec3(0.01, 0.02, 0.03) * (st.load / 0.002);
      for (Index i : face)
        worst = std::max(worst, (x.row(i) - s.mesh.X.row(i) - u.transpose()).norm());
      free_motion =
          std::max(free_motion,
                   (x.row(s.mesh.num_nodes() - 1) - s.mesh.X.row(s.mesh.num_nodes() - 1)).norm());
    };
    std::ostringstream log;
    const RunResult r = run_scene(s, options, log);
    ASSERT_TRUE(r.success) << integrator << ": " << r.message;
    EXPECT_LE(worst, 1e-15) << integrator;
    EXPECT_GT(free_motion, 1e-5) << integrator << ": the free end must move";
  }
  std::filesystem::remove(path);
}

// The explicit stepper refuses a step above the stable limit with a message, and below it its
// energy stays bounded: on the swinging bars the total energy wanders by under 5 % of the
// largest kinetic energy reached (symplectic Euler has no secular drift).
TEST(DynamicScenes, SymplecticEulerRefusesUnstableStepsAndKeepsEnergyBounded) {
  const RunResult refused = run(load("falling_bars", {"dynamic.integrator=symplectic_euler"}));
  EXPECT_FALSE(refused.success) << "a 0.01 s explicit step must be refused";
  EXPECT_TRUE(refused.steps.empty());
  EXPECT_NE(refused.message.find("exceeds the stable limit"), std::string::npos) << refused.message;
  const Scene s = load("falling_bars", {"dynamic.integrator=symplectic_euler",
                                        "dynamic.time_step=2e-4", "dynamic.duration=0.3"});
  const RunResult r = run(s);
  ASSERT_TRUE(r.success) << r.message;
  const VectorX m = lumped_mass(s.mesh.X, s.mesh.tets, s.tet_density);
  const double initial = -(m.transpose() * (s.mesh.X * s.gravity)).value();
  double deviation = 0, kinetic = 0;
  for (const StepRecord& st : r.steps) {
    deviation = std::max(deviation, std::abs(st.kinetic_energy + st.energy - initial));
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
    const double e = r.steps[k].kinetic_energy + r.steps[k].energy;
    EXPECT_LE(e, previous + 1e-9 * std::abs(previous)) << "step " << k;
    previous = e;
  }
  EXPECT_LT(previous, initial - 1.0) << "the bars must have swung down";
}

// Newmark's average-acceleration rule conserves the energy of linear systems exactly and has no
// numerical dissipation: on the swinging (nonlinear) bars the mechanical energy stays within 0.5 %
// of the largest kinetic energy over 1 s (measured 0.1 %; the nonlinear terms leave an O(h^2)
// error), where implicit Euler at the same step loses over 30 % (measured 42 %).
TEST(DynamicScenes, NewmarkKeepsTheEnergyImplicitEulerDissipates) {
  double lost[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    const Scene s = load("falling_bars", {k == 0 ? "dynamic.integrator=newmark"
                                                 : "dynamic.integrator=implicit_euler",
                                          "dynamic.duration=1.0"});
    const RunResult r = run(s);
    ASSERT_TRUE(r.success) << r.message;
    const VectorX m = lumped_mass(s.mesh.X, s.mesh.tets, s.tet_density);
    const double initial = -(m.transpose() * (s.mesh.X * s.gravity)).value();
    double kinetic = 0;
    for (const StepRecord& st : r.steps) {
      kinetic = std::max(kinetic, st.kinetic_energy);
      lost[k] = std::max(lost[k], std::abs(st.kinetic_energy + st.energy - initial));
    }
    lost[k] /= kinetic;
  }
  EXPECT_LT(lost[0], 0.005) << "Newmark";
  EXPECT_GT(lost[1], 0.3) << "implicit Euler";
  std::printf("energy error / peak kinetic energy: Newmark %.4f, implicit Euler %.4f\n", lost[0],
              lost[1]);
}

// Tip deflection of the cantilever_gravity bar (mean over the tip face) at every step.
std::vector<double> tip_deflection(const Scene& s, const std::string& out) {
  std::vector<Index> tip;
  for (Index i = 0; i < s.mesh.num_nodes(); ++i)
    if (std::abs(s.mesh.X(i, 0) - 1.0) < 1e-9) tip.push_back(i);
  std::vector<double> w = {0.0};
  const ResultsSummary summary = read_results_summary(out);
  for (Index k = 0; k < summary.num_steps; ++k) {
    const Points x = read_step_positions(out, k);
    double sum = 0;
    for (Index i : tip) sum += x(i, 2) - s.mesh.X(i, 2);
    w.push_back(sum / static_cast<double>(tip.size()));
  }
  return w;
}

// Period of the dominant oscillation of samples w_k = w(k h): the T whose least-squares fit
// A + B cos(2 pi t / T) + C sin(2 pi t / T) leaves the smallest residual (scanned in 1e-5 T steps).
double dominant_period(const std::vector<double>& w, double h, double lo, double hi) {
  double best = 0, best_residual = std::numeric_limits<double>::infinity();
  for (double T = lo; T <= hi; T += 1e-5 * lo) {
    Eigen::MatrixXd A(static_cast<Eigen::Index>(w.size()), 3);
    for (size_t k = 0; k < w.size(); ++k) {
      const double phase = 2 * std::numbers::pi * static_cast<double>(k) * h / T;
      A.row(static_cast<Eigen::Index>(k)) << 1.0, std::cos(phase), std::sin(phase);
    }
    const VectorX b = Eigen::Map<const VectorX>(w.data(), static_cast<Eigen::Index>(w.size()));
    const double residual = (A * A.colPivHouseholderQr().solve(b) - b).squaredNorm();
    if (residual < best_residual) best_residual = residual, best = T;
  }
  return best;
}

// Free vibration: gravity switched on at t = 0 sets the clamped bar oscillating about its sag,
// mostly in its first bending mode. Euler-Bernoulli: omega_1 = 1.8751^2 sqrt(E I / (rho A L^4));
// for this bar (L/H = 10, nu = 0.3) shear lowers it by under 1 %. Newmark with 40 steps per
// period lengthens the period by (omega h)^2 / 12 = 0.2 %. Linear tets are too stiff in bending
// (static tip deflection -21.5 % / -7.3 % at 4 / 8 cells through the thickness): the period
// converges from below, and with 8 cells it is within 5 % (measured -10.3 % and -2.8 %).
TEST(DynamicScenes, ClampedBarVibratesAtTheBeamTheoryPeriod) {
  const double E = 1e8, rho = 1000, H = 0.1, L = 1.0;
  const double beam =
      2 * std::numbers::pi / (1.8751 * 1.8751 * std::sqrt(E * H * H / (12 * rho * std::pow(L, 4))));
  const testing::TemporaryResults out("vibration");
  double error[2];
  for (int k = 0; k < 2; ++k) {
    const Scene s =
        load("cantilever_gravity",
             {"analysis=dynamic", "solver.linear_solver=cg",
              R"(dynamic={"integrator": "newmark", "time_step": 0.005, "duration": 0.25})",
              k == 0 ? "bodies.0.mesh.cells=[40,4,4]" : "bodies.0.mesh.cells=[80,8,8]"});
    const RunResult r = run(s, out.path);
    ASSERT_TRUE(r.success) << r.message;
    error[k] =
        dominant_period(tip_deflection(s, out.path), 0.005, 0.7 * beam, 1.3 * beam) / beam - 1;
  }
  EXPECT_LT(error[0], error[1]) << "the period converges from below";
  EXPECT_LT(std::abs(error[1]), 0.05) << "8 cells through the thickness";
}

// Damped motion ends where the static analysis of the same scene does: Newmark with Rayleigh
// damping (mass- and stiffness-proportional), and quasistatic viscous flow, both from rest. The
// Newton tolerance is tightened so that the settled states are resolved beyond 1e-4 of the sag
// (a time step stops iterating once the residual is below it, however slowly the flow creeps).
TEST(DynamicScenes, DampedAndViscousRunsSettleToTheStaticSolution) {
  const Scene static_scene = load("cantilever_gravity", {"solver.tolerance=1e-11"});
  const RunResult reference = run(static_scene);
  ASSERT_TRUE(reference.success) << reference.message;
  const double sag = (reference.x - static_scene.mesh.X).cwiseAbs().maxCoeff();
  for (const char* setting :
       {R"(dynamic={"integrator": "newmark", "time_step": 0.01, "duration": 1.0,
                                         "damping": {"mass": 30, "stiffness": 0.002}})",
        R"(dynamic={"time_step": 0.05, "duration": 1.0, "viscosity": 20})"}) {
    const bool viscous = std::string(setting).find("viscosity") != std::string::npos;
    const Scene s = load(
        "cantilever_gravity",
        {viscous ? "analysis=quasistatic" : "analysis=dynamic", setting, "solver.tolerance=1e-11"});
    const RunResult r = run(s);
    ASSERT_TRUE(r.success) << r.message;
    EXPECT_LT((r.x - reference.x).cwiseAbs().maxCoeff(), 1e-4 * sag) << setting;
    EXPECT_LT(r.steps.back().kinetic_energy, 1e-8 * std::abs(reference.steps.back().energy))
        << setting;
  }
}

// bars_drop over its whole 0.8 s, as bench/results/verification.md tells it. The floor stops every
// node within 5 % of the bar thickness (0.1 m; corners hit at up to 2.9 m/s), and implicit Euler
// with contact only loses mechanical energy. At 0.2 s the low bar holds the middle one up (its
// centre above 0.12 m, where lying on the floor would put it at 0.05 m); the top bar then lands on
// the middle one's end and tips it over the low one like a see-saw (its raised end climbs above
// 0.3 m, where lying across the low bar it reaches 0.2 m); nothing holds the low bar sideways (all
// contact is frictionless), so it is squeezed out from under the middle one, more than its own
// width (0.1 m); at 0.8 s all three lie flat on the floor (centres within 2 mm of 0.05 m, tops
// within 5 mm of 0.1 m).
TEST(DynamicScenes, BarsDropOntoTheFloorAndOntoEachOther) {
  const Scene s = load("bars_drop");
  ASSERT_EQ(s.dynamic_options.duration, 0.8);
  const auto body_z = [&](const Points& x, Index b) {
    return x.col(2).segment(s.mesh.bodies[b].first_node, s.mesh.bodies[b].num_nodes);
  };
  double lowest = std::numeric_limits<double>::infinity(), rise = 0, previous = 0;
  double middle_at_0_2 = 0, middle_highest = 0;
  bool first = true;
  RunOptions options;
  options.observer = [&](const StepRecord& st, const Points& x) {
    lowest = std::min(lowest, x.col(2).minCoeff());
    const double e = st.kinetic_energy + st.energy;
    if (!first) rise = std::max(rise, e - previous);
    previous = e;
    first = false;
    if (st.load == 0.2) middle_at_0_2 = body_z(x, 1).mean();
    middle_highest = std::max(middle_highest, body_z(x, 1).maxCoeff());
  };
  std::ostringstream log;
  const RunResult r = run_scene(s, options, log);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_EQ(r.steps.back().load, 0.8);
  EXPECT_GT(lowest, -0.005);
  const VectorX m = lumped_mass(s.mesh.X, s.mesh.tets, s.tet_density);
  const double initial = -(m.transpose() * (s.mesh.X * s.gravity)).value();
  EXPECT_LT(previous, initial);
  EXPECT_LE(rise, 1e-6 * initial) << "largest step-to-step rise of the mechanical energy";
  EXPECT_GT(middle_at_0_2, 0.12) << "the low bar holds the middle one up at 0.2 s";
  EXPECT_GT(middle_highest, 0.3) << "the top bar tips the middle one over the low one";
  const Body& low = s.mesh.bodies[0];
  const double low_shift = (r.x.col(1).segment(low.first_node, low.num_nodes).mean() -
                            s.mesh.X.col(1).segment(low.first_node, low.num_nodes).mean());
  EXPECT_GT(std::abs(low_shift), 0.1) << "the low bar is squeezed out sideways";
  for (Index b = 0; b < 3; ++b) {
    EXPECT_NEAR(body_z(r.x, b).mean(), 0.05, 0.002)
        << s.mesh.bodies[b].name << " lies on the floor";
    EXPECT_NEAR(body_z(r.x, b).maxCoeff(), 0.1, 0.005) << s.mesh.bodies[b].name << " lies flat";
  }
}

// ARKODE's failures surface with its flag name; invalid orders are refused when the scene is read.
// falling_bars_viscoelastic under Newmark for 0.5 s: its soft bar relaxes in 0.1 ms, a hundredth
// of the 10 ms step, so within each step it is the equilibrium model (shear modulus beta_inf mu,
// the bulk modulus unchanged): the step's isochoric scale exceeds beta_inf by beta tau / h =
// 3e-3 and the history term is of that order times the stress change of a step. Its tips
// follow an elastic bar with those moduli to 1 % of their largest deflection (1.07 m; measured
// 0.26 %). Every step dissipates energy.
TEST(DynamicScenes, ViscoelasticBarFasterThanTheStepMovesAsTheRelaxedBar) {
  const std::vector<std::string> newmark = {"dynamic.integrator=newmark", "dynamic.duration=0.5"};
  const Scene viscous = load("falling_bars_viscoelastic", newmark);
  const auto& nh = std::get<NeoHookean>(viscous.groups[0].material);
  const double mu = 0.7 * nh.mu, lambda = nh.lambda + 2.0 / 3.0 * (nh.mu - mu);
  std::vector<std::string> relaxed = newmark;
  relaxed.push_back(R"(bodies.0.material={"model": "neo_hookean", "mu": )" + std::to_string(mu) +
                    R"(, "lambda": )" + std::to_string(lambda) + "}");
  const Scene elastic = load("falling_bars_viscoelastic", relaxed);
  std::vector<Points> x[2];
  for (int k = 0; k < 2; ++k) {
    RunOptions options;
    options.observer = [&](const StepRecord& step, const Points& at) {
      x[k].push_back(at);
      if (k == 0) {
        ASSERT_TRUE(step.dissipated_energy.has_value());
        EXPECT_GT(*step.dissipated_energy, 0) << "step " << step.index;
      }
    };
    std::ostringstream log;
    const RunResult r = run_scene(k == 0 ? viscous : elastic, options, log);
    ASSERT_TRUE(r.success) << r.message;
  }
  ASSERT_EQ(x[0].size(), 50u);
  double deflection = 0, difference = 0;
  const Points& X = viscous.mesh.X;
  for (Index i = 0; i < X.rows(); ++i) {
    if (std::abs(X(i, 0) - 1) > 1e-9 || X(i, 1) > 0.2) continue;  // the soft bar's tip
    for (size_t n = 0; n < x[0].size(); ++n) {
      deflection = std::max(deflection, std::abs(x[0][n](i, 2) - X(i, 2)));
      difference = std::max(difference, (x[0][n].row(i) - x[1][n].row(i)).norm());
    }
  }
  EXPECT_GT(deflection, 0.5);
  EXPECT_LT(difference, 0.01 * deflection);
}

TEST(DynamicScenes, SundialsFailuresAreReportedWithTheirFlag) {
  const RunResult r = run(
      load("falling_bars", {R"(dynamic.arkode={"max_steps": 2})", "dynamic.integrator=arkode"}));
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("ARK_TOO_MUCH_WORK"), std::string::npos) << r.message;
  EXPECT_EQ(r.steps.size(), 0u);
  const RunResult bdf = run(
      load("falling_bars", {R"(dynamic.cvode={"max_steps": 2})", "dynamic.integrator=cvode_bdf"}));
  EXPECT_FALSE(bdf.success);
  EXPECT_NE(bdf.message.find("cvode: CV_TOO_MUCH_WORK at t = 0.000000 s: more than 2 internal "
                             "steps in the output interval"),
            std::string::npos)
      << bdf.message;
  EXPECT_EQ(bdf.steps.size(), 0u);
  try {
    load("falling_bars", {"dynamic.integrator=arkode", R"(dynamic.arkode={"order": 7})"});
    FAIL() << "order 7 has no default table";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("dynamic.arkode.order: must be 2, 3, 4, 5, 6 or 8"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace depthfem
