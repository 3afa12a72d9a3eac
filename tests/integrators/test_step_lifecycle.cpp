// Every driver follows the one step lifecycle: a step begins (begin_step, set_load), every
// evaluation at a new configuration is preceded by prepare at that configuration, the report
// happens at the converged state and the step's load, and step ends land exactly on the end.
#include <gtest/gtest.h>

#include <limits>
#include <numeric>

#include "contact/obstacle_contact.hpp"
#include "core/mass.hpp"
#include "core/mesh_generators.hpp"
#include "integrators/forces/elasticity.hpp"
#include "integrators/run_stepper.hpp"
#include "integrators/solvers/implicit_stepper.hpp"
#include "integrators/solvers/static_solver.hpp"

namespace depthfem {
namespace {

// E(x) = k/2 sum_i |x_i - (X_i + load s)|^2: a spring pulling every node towards its rest
// position shifted by load x s. Records what the lifecycle calls.
class Probe final : public ForceModule {
 public:
  explicit Probe(Points X) : X_(std::move(X)) {}
  static constexpr double k = 40.0;
  const Vec3 s = Vec3(0.1, -0.2, 0.05);

  std::string name() const override { return "probe"; }
  void begin_step(const Points&) override { ++begun; }
  void set_load(double load) override { load_ = load; }
  void prepare(const Points& x) override { prepared_ = x; }
  void add_couplings(SparsityBuilder&) const override {}
  void bind(const BlockSparseMatrix& H) override {
    diagonal_.resize(static_cast<size_t>(X_.rows()));
    for (Index i = 0; i < X_.rows(); ++i) diagonal_[i] = H.block_index(i, i);
  }
  double evaluate(const Points& x, VectorX* g, BlockSparseMatrix* H) const override {
    if (prepared_.rows() != x.rows() || prepared_ != x) ++unprepared;
    return energy(x, load_, g, H);
  }
  void report(const Points& x, StepRecord& step) const override {
    if (prepared_ != x) ++unprepared;
    reports.push_back({step.index, load_, energy(x, load_, nullptr, nullptr)});
  }
  double energy(const Points& x, double load, VectorX* g, BlockSparseMatrix* H) const {
    double E = 0;
    for (Index i = 0; i < x.rows(); ++i) {
      const Vec3 d = (x.row(i) - X_.row(i)).transpose() - load * s;
      E += 0.5 * k * d.squaredNorm();
      if (g) g->segment<3>(3 * i) += k * d;
      if (H) H->block(diagonal_[i]).diagonal().array() += k;
    }
    return E;
  }

  struct Report {
    Index index;
    double load, energy;
  };
  int begun = 0;
  mutable int unprepared = 0;
  mutable std::vector<Report> reports;

 private:
  Points X_;
  double load_ = 0;
  Points prepared_;
  std::vector<Index> diagonal_;
};

// Three nodes with a probe and, for the implicit schemes, inertia (left out of the energy).
struct Rig {
  explicit Rig(bool with_inertia = false) : with_inertia(with_inertia) {}

  bool with_inertia;
  Points X = (Points(3, 3) << 0, 0, 0, 1, 0, 0, 0, 1, 0).finished();
  PhaseTimers timers;
  System system{3, timers};
  Probe& probe = system.add(std::make_unique<Probe>(X));
  NodalSpring* inertia =
      with_inertia
          ? &system.add(std::make_unique<NodalSpring>("inertia", VectorX::Constant(3, 2.0)))
          : nullptr;
  LifecycleTerms terms = inertia ? LifecycleTerms{{inertia}, inertia} : LifecycleTerms{};
  Constraints none;
  std::vector<StepRecord> steps;
  StepLifecycle lifecycle{
      system, none, terms,
      [this](const StepRecord& s, const Points&, const Points*) { steps.push_back(s); }};

  // The protocol, whatever the driver: no evaluation without prepare at that configuration,
  // one report per completed step at its load, every step begun.
  void expect_lifecycle(double duration) const {
    EXPECT_EQ(probe.unprepared, 0);
    ASSERT_EQ(probe.reports.size(), steps.size());
    EXPECT_GE(probe.begun, static_cast<int>(steps.size()));
    for (size_t k = 0; k < steps.size(); ++k) {
      EXPECT_EQ(probe.reports[k].index, steps[k].index);
      EXPECT_EQ(probe.reports[k].load, steps[k].load / duration) << "step " << k;
      EXPECT_NEAR(steps[k].energy, probe.reports[k].energy, 1e-12) << "step " << k;
    }
  }
};

TEST(StepLifecycle, StaticIncrementsOfATenthEndExactlyAtOne) {
  Rig rig;
  StaticOptions options;
  options.initial_increment = options.max_increment = 0.1;
  options.newton.tolerance = 1e-10;
  Points x = rig.X;
  StaticSolver(rig.lifecycle, nullptr, options).run(x);
  ASSERT_EQ(rig.steps.size(), 10u) << "no extra step at a load of 1 - round-off";
  // The decimals k / 10 (3 x 0.1 would be 0.30000000000000004).
  for (size_t k = 0; k < 10; ++k) EXPECT_EQ(rig.steps[k].load, (k + 1) / 10.0);
  EXPECT_EQ(rig.steps.back().load, 1.0);
  rig.expect_lifecycle(1.0);
}

DynamicOptions three_tenths(Integrator integrator) {
  DynamicOptions o;
  o.integrator = integrator;
  o.time_step = 0.3;
  o.duration = 1.0;
  o.newton.tolerance = 1e-10;
  return o;
}

// Steps of 0.3 s over 1 s: four steps, the last one 0.1 s long and ending at exactly 1 s.
void expect_times(const std::vector<StepRecord>& steps) {
  ASSERT_EQ(steps.size(), 4u);
  EXPECT_EQ(steps[0].load, 0.3);
  EXPECT_EQ(steps[1].load, 0.6);
  EXPECT_EQ(steps[2].load, 0.9);  // the decimal, not 3 x 0.3 = 0.8999999999999999
  EXPECT_EQ(steps[3].load, 1.0);
}

TEST(StepLifecycle, ImplicitSchemesFollowItAndEndExactlyAtTheDuration) {
  for (Integrator scheme : {Integrator::kImplicitEuler, Integrator::kNewmark}) {
    Rig rig(true);
    Points x = rig.X, v = Points::Zero(3, 3);
    ImplicitStepper(rig.lifecycle, {rig.inertia, {}}, three_tenths(scheme)).run(x, v);
    expect_times(rig.steps);
    rig.expect_lifecycle(1.0);
  }
}

TEST(StepLifecycle, ExplicitSchemesFollowItAndEndExactlyAtTheDuration) {
  for (Integrator scheme : {Integrator::kSymplecticEuler, Integrator::kArkode}) {
    Rig rig;
    Points x = rig.X, v = Points::Zero(3, 3);
    const VectorX mass = VectorX::Constant(3, 200.0);  // period 14 s: 0.3 s steps are stable
    testing::run_stepper(rig.lifecycle, mass, three_tenths(scheme), {}, 1.0, x, v);
    expect_times(rig.steps);
    rig.expect_lifecycle(1.0);
  }
}

// A block above a floor that rises through its bottom: under both explicit integrators the
// moving obstacle must reach the block and push it (the lifecycle moves it with the time).
TEST(StepLifecycle, MovingObstacleMovesUnderExplicitIntegrators) {
  const Mesh mesh = single_body_mesh(
      box_mesh({Vec3::Zero(), Vec3(0.1, 0.1, 0.1), Eigen::Vector3i(2, 2, 2)}), "block");
  for (Integrator scheme : {Integrator::kSymplecticEuler, Integrator::kArkode}) {
    PhaseTimers timers;
    System system(mesh.num_nodes(), timers);
    std::vector<Index> all(static_cast<size_t>(mesh.num_tets()));
    std::iota(all.begin(), all.end(), 0);
    system.add(std::make_unique<Elasticity>(
        mesh.X, mesh.tets,
        std::vector<ElasticGroup>{{NeoHookean::from_youngs(1e4, 0.3), all, {}}}));
    // The floor starts 2 mm below the block and ends 2 mm above its bottom.
    system.add(std::make_unique<ObstacleContact>(
        mesh, std::vector<Index>{0},
        std::vector<Obstacle>{
            {"floor", PlaneObstacle{Vec3(0, 0, -0.002), Vec3::UnitZ()}, Vec3(0, 0, 0.004), 1e5}}));
    const Constraints none;
    std::vector<StepRecord> steps;
    StepLifecycle lifecycle(
        system, none, {},
        [&](const StepRecord& s, const Points&, const Points*) { steps.push_back(s); });
    DynamicOptions o;
    o.integrator = scheme;
    o.time_step = 2e-3;
    o.duration = 0.1;
    const VectorX mass = lumped_mass(mesh.X, mesh.tets, VectorX::Constant(mesh.num_tets(), 1000.0));
    Points x = mesh.X, v = Points::Zero(mesh.num_nodes(), 3);
    testing::run_stepper(lifecycle, mass, o, {}, 1.0, x, v);
    ASSERT_FALSE(steps.empty());
    ASSERT_EQ(steps.back().contact.size(), 1u);
    EXPECT_EQ(steps.front().contact[0].force.z(), 0.0) << "no contact at first";
    EXPECT_GT(steps.back().contact[0].force.z(), 0.0) << "the risen floor pushes the block up";
    EXPECT_GT(x.col(2).mean(), mesh.X.col(2).mean()) << "the block moved up";
  }
}

}  // namespace
}  // namespace depthfem
