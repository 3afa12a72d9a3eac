// StaticSolver on small spring problems with closed-form equilibria: a hardening two-element bar
// under an end load, adaptive loading (halved after a failed increment, grown after two
// successes in a row), the two-point predictor, prescribed motion exact at every step, and the
// end of a run whose increment no longer changes the load.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "core/error.hpp"
#include "integrators/forces/gravity.hpp"
#include "integrators/pair_springs.hpp"
#include "integrators/solvers/static_solver.hpp"

namespace depthfem {
namespace {

using testing::PairSprings;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEps = std::numeric_limits<double>::epsilon();

// A bar along x of elements (i, j) with rest length L: per element E = k/2 s^2 + q/4 s^4 with
// the stretch s = (x_j - x_i)_x - L, so the tension is f(s) = k s + q s^3 and the tangent
// stiffness k + 3 q s^2. Only x components enter (the nodes are held on the axis).
class HardeningBar final : public testing::TwoNodeElements {
 public:
  HardeningBar(std::vector<Element> elements, double q, double L)
      : TwoNodeElements(std::move(elements)), q_(q), L_(L) {}
  std::string name() const override { return "hardening bar"; }
  double evaluate(const Points& x, VectorX* g, BlockSparseMatrix* H) const override {
    double E = 0;
    for (size_t n = 0; n < elements_.size(); ++n) {
      const Element& e = elements_[n];
      const double s = x(e.j, 0) - x(e.i, 0) - L_;
      E += 0.5 * e.k * s * s + 0.25 * q_ * s * s * s * s;
      const double f = e.k * s + q_ * s * s * s, c = e.k + 3 * q_ * s * s;
      if (g) {
        (*g)(3 * e.j) += f;
        (*g)(3 * e.i) -= f;
      }
      if (H) add_pair(*H, n, Mat3{{c, 0, 0}, {0, 0, 0}, {0, 0, 0}});
    }
    return E;
  }

 private:
  double q_, L_;
};

// No energy, but illegal (+infinity) where node `node` is at x > `limit` (absolute), or has
// moved by more than `limit` from where the step began (relative): a module that fails an
// increment on purpose, like an element that would invert. Records the load of every attempt
// and the first configuration evaluated in it (the first guess).
class Breaker final : public ForceModule {
 public:
  Breaker(Index node, double limit, bool relative)
      : node_(node), limit_(limit), relative_(relative) {}
  std::string name() const override { return "breaker"; }
  void begin_step(const Points& x) override {
    start_ = x(node_, 0);
    first_of_step_ = true;
  }
  void set_load(double load) override { attempts.push_back(load); }
  void prepare(const Points& x) override {
    if (first_of_step_) guesses.push_back(x);
    first_of_step_ = false;
  }
  void add_couplings(SparsityBuilder&) const override {}
  double evaluate(const Points& x, VectorX*, BlockSparseMatrix*) const override {
    const double moved = relative_ ? std::abs(x(node_, 0) - start_) : x(node_, 0);
    return moved > limit_ ? kInf : 0.0;
  }
  std::vector<double> attempts;
  std::vector<Points> guesses;

 private:
  Index node_;
  double limit_;
  bool relative_;
  double start_ = 0;
  bool first_of_step_ = false;
};

// A System over given reference positions and conditions, with a lifecycle that keeps every
// completed step's record and positions.
struct Rig {
  Rig(Points X_, std::vector<Constraint> list)
      : X(std::move(X_)), system(static_cast<Index>(X.rows()), timers), constraints(X, list) {}

  Points X;
  PhaseTimers timers;
  System system;
  Constraints constraints;
  std::vector<StepRecord> steps;
  std::vector<Points> states;
  StepLifecycle lifecycle{
      system, constraints, {}, [this](const StepRecord& s, const Points& x, const Points*) {
        steps.push_back(s);
        states.push_back(x);
      }};
};

// The real root of q s^3 + k s = f (k, q > 0; unique, the cubic is increasing): with
// s = 2 sqrt(k / 3q) sinh(phi), the identity 4 sinh^3 + 3 sinh = sinh(3 phi) gives
// sinh(3 phi) = (3 f / 2k) sqrt(3q / k) (Cardano's formula without its cancellation).
double hardening_stretch(double f, double k, double q) {
  const double a = std::sqrt(k / (3 * q));
  return 2 * a * std::sinh(std::asinh(1.5 * f / (k * a)) / 3);
}

// Two elements of different stiffness along x, clamped at node 0, pulled at node 2 by P. Series
// elements carry the same tension lambda P, so each stretch solves k_e s + q s^3 = lambda P.
struct Bar : Rig {
  static constexpr double L = 0.1, k1 = 1000, k2 = 2000, q = 5e6, P = 20;  // m, N/m, N/m^3, N
  Bar()
      : Rig((Points(3, 3) << 0, 0, 0, L, 0, 0, 2 * L, 0, 0).finished(),
            {{"clamp", {0}, Fixed{}}, {"axis", {1, 2}, OnLine{Vec3::UnitX()}}}) {
    system.add(std::make_unique<HardeningBar>(
        std::vector<HardeningBar::Element>{{0, 1, k1}, {1, 2, k2}}, q, L));
    // The end load as a ramped body force on a unit mass at node 2: E = -lambda P x_2.
    system.add(std::make_unique<Gravity>(VectorX::Unit(3, 2), Vec3(P, 0, 0), true));
  }
};

TEST(StaticSolver, HardeningBarUnderAnEndLoadMatchesTheClosedFormAtEveryIncrement) {
  Bar bar;
  StaticOptions options;
  options.initial_increment = options.max_increment = 0.25;
  options.newton.tolerance = 1e-9;  // [N]
  Points x = bar.X;
  StaticSolver(bar.lifecycle, nullptr, options).run(x);
  ASSERT_EQ(bar.steps.size(), 4u);
  // Error bound from the Newton tolerance: the residual r and the error d satisfy r = K d with
  // K the chain's secant stiffness, whose element stiffnesses are >= k_e (the spring hardens);
  // d = K^-1 r with K^-1 = [[1/c1, 1/c1], [1/c1, 1/c1 + 1/c2]] bounds |d_i| by
  // (2 / k1 + 1 / k2) |r| (2.5e-12 m here, against displacements of 1e-2 m).
  const double bound = (2 / Bar::k1 + 1 / Bar::k2) * options.newton.tolerance;
  for (size_t n = 0; n < 4; ++n) {
    const double lambda = 0.25 * static_cast<double>(n + 1);
    EXPECT_EQ(bar.steps[n].load, lambda);
    const double s1 = hardening_stretch(lambda * Bar::P, Bar::k1, Bar::q);
    const double s2 = hardening_stretch(lambda * Bar::P, Bar::k2, Bar::q);
    const Points& xn = bar.states[n];
    EXPECT_NEAR(xn(1, 0) - Bar::L, s1, bound) << "load " << lambda;
    EXPECT_NEAR(xn(2, 0) - 2 * Bar::L, s1 + s2, bound) << "load " << lambda;
    EXPECT_EQ(xn.col(1).cwiseAbs().maxCoeff(), 0.0) << "held on the axis";
    EXPECT_EQ(xn.col(2).cwiseAbs().maxCoeff(), 0.0) << "held on the axis";
    // The clamp holds the bar against the load: reaction -lambda P, up to the residual left at
    // the two free nodes (|r1 + r2| <= sqrt 2 tolerance).
    EXPECT_NEAR(bar.steps[n].reactions(0, 0), -lambda * Bar::P,
                std::sqrt(2.0) * options.newton.tolerance);
  }
  // The load is large enough for the nonlinearity to matter: the linear answer is far off.
  EXPECT_GT(std::abs(x(1, 0) - Bar::L - Bar::P / Bar::k1), 1e-3);
}

TEST(StaticSolver, TwoPointPredictorExtrapolatesTheLastTwoSolutions) {
  int iterations[2] = {0, 0};
  for (bool predictor : {true, false}) {
    Bar bar;
    Breaker& probe = bar.system.add(std::make_unique<Breaker>(0, kInf, false));  // never fails
    StaticOptions options;
    options.initial_increment = options.max_increment = 0.2;
    options.predictor = predictor;
    options.newton.tolerance = 1e-9;
    Points x = bar.X;
    StaticSolver(bar.lifecycle, nullptr, options).run(x);
    ASSERT_EQ(bar.steps.size(), 5u);
    ASSERT_EQ(probe.guesses.size(), 5u) << "one attempt per increment";
    // The first increment starts from the reference state. Increment k starts from
    // x_(k-1) + (lambda_k - lambda_(k-1)) / (lambda_(k-1) - lambda_(k-2)) (x_(k-1) - x_(k-2))
    // (x_(-1) = X at lambda 0), or from x_(k-1) without the predictor. The constrained
    // components of both stay at their targets, so the guess is this expression exactly (up
    // to the order of operations: 1e-15 relative).
    EXPECT_EQ(probe.guesses[0], bar.X);
    for (size_t k = 1; k < 5; ++k) {
      const Points& last = bar.states[k - 1];
      const Points& before = k >= 2 ? bar.states[k - 2] : bar.X;
      const double load = bar.steps[k - 1].load, previous = k >= 2 ? bar.steps[k - 2].load : 0.0;
      const Points expected =
          predictor
              ? Points(last + (bar.steps[k].load - load) / (load - previous) * (last - before))
              : last;
      EXPECT_LE((probe.guesses[k] - expected).cwiseAbs().maxCoeff(), 1e-15 * 2 * Bar::L)
          << "increment " << k << (predictor ? " with" : " without") << " the predictor";
    }
    for (const StepRecord& s : bar.steps) iterations[predictor ? 0 : 1] += s.newton_iterations;
  }
  // On this smooth load path the extrapolated guess is O(increment^2) off instead of
  // O(increment): Newton needs fewer iterations (measured: 17 against 20).
  EXPECT_LT(iterations[0], iterations[1]);
}

// Node 0 is pulled along x by `u`; node 1 follows through a spring k_a to node 0 and a spring
// k_b to its rest position: u_1 = k_a / (k_a + k_b) u_0.
struct Pulled : Rig {
  static constexpr double k_a = 30, k_b = 10;  // [N/m]
  explicit Pulled(const Vec3& u)
      : Rig((Points(2, 3) << 0, 0, 0, 2, 0, 0).finished(), {{"pull", {0}, Displaced{u}}}) {
    system.add(std::make_unique<PairSprings>(X, std::vector<PairSprings::Pair>{{0, 1, k_a}}));
    auto ground = std::make_unique<NodalSpring>("ground", Eigen::Vector2d(0, k_b));
    ground->set_anchor(X);
    system.add(std::move(ground));
  }
};

TEST(StaticSolver, AdaptiveLoadingHalvesAfterAFailureAndGrowsAfterTwoSuccesses) {
  // Increments that move node 0 by more than 0.035 m fail; node 0 moves 0.1 m per unit load, so
  // increments up to 0.3 pass and 0.4 fails.
  Pulled rig(Vec3(0.1, 0, 0));
  Breaker& breaker = rig.system.add(std::make_unique<Breaker>(0, 0.035, true));
  StaticOptions options;
  options.initial_increment = 0.1;
  options.max_increment = 1.0;
  options.growth = 2.0;
  options.newton.tolerance = 1e-10;
  Points x = rig.X;
  StaticSolver(rig.lifecycle, nullptr, options).run(x);
  // 0.1 and 0.2 at the first increment: after two successes in a row it doubles (0.4 reached
  // with 0.2), and with the third success in a row doubles again; 0.4 -> 0.8 fails and is
  // retried with half the increment (0.6); two more successes double it again (0.8 -> 1, cut
  // to the end of the load).
  const std::vector<double> attempts = {0.1, 0.2, 0.4, 0.8, 0.6, 0.8, 1.0};
  const std::vector<double> completed = {0.1, 0.2, 0.4, 0.6, 0.8, 1.0};
  EXPECT_EQ(breaker.attempts, attempts);
  ASSERT_EQ(rig.steps.size(), completed.size());
  for (size_t n = 0; n < completed.size(); ++n) {
    EXPECT_EQ(rig.steps[n].load, completed[n]) << "step " << n;
    // Linear springs: within the Newton tolerance over the smallest stiffness k_a + k_b.
    const double u0 = 0.1 * completed[n];
    EXPECT_NEAR(rig.states[n](1, 0) - rig.X(1, 0), Pulled::k_a / (Pulled::k_a + Pulled::k_b) * u0,
                options.newton.tolerance / (Pulled::k_a + Pulled::k_b) + 4 * kEps);
  }
}

TEST(StaticSolver, PrescribedMotionIsExactAtEveryStep) {
  // Node 0 displaced, node 1 turned a quarter turn about a vertical axis through c while it is
  // lifted, node 2 free between them on springs: the predictor's straight extrapolation leaves
  // the arc, and the conditions must put node 1 back on it at every step.
  const Points X = (Points(3, 3) << 0, 0, 0, 1, 0, 0, 0.5, 0.5, 0).finished();
  const Vec3 u(0.2, -0.1, 0.3), c(0.5, 0, 0), t(0, 0, 0.4);
  const double angle = std::numbers::pi / 2;
  Rig rig(X, {{"move", {0}, Displaced{u}}, {"turn", {1}, Rotated{Vec3::UnitZ(), c, angle, t}}});
  constexpr double k_a = 30, k_b = 20, k_g = 10;  // [N/m]
  rig.system.add(
      std::make_unique<PairSprings>(X, std::vector<PairSprings::Pair>{{0, 2, k_a}, {1, 2, k_b}}));
  auto ground = std::make_unique<NodalSpring>("ground", Eigen::Vector3d(0, 0, k_g));
  ground->set_anchor(X);
  rig.system.add(std::move(ground));
  StaticOptions options;
  options.initial_increment = options.max_increment = 0.1;
  options.newton.tolerance = 1e-10;
  Points x = X;
  StaticSolver(rig.lifecycle, nullptr, options).run(x);
  ASSERT_EQ(rig.steps.size(), 10u);
  for (size_t n = 0; n < 10; ++n) {
    const double lambda = rig.steps[n].load;
    const Points& xn = rig.states[n];
    const Vec3 x0 = X.row(0).transpose() + lambda * u;
    const Vec3 x1 = c +
                    Eigen::AngleAxisd(lambda * angle, Vec3::UnitZ()) * (X.row(1).transpose() - c) +
                    lambda * t;
    // Exact up to the round-off of imposing them (x - (x - target): an ulp of the coordinates).
    EXPECT_LE((xn.row(0).transpose() - x0).cwiseAbs().maxCoeff(), 2 * kEps) << "load " << lambda;
    EXPECT_LE((xn.row(1).transpose() - x1).cwiseAbs().maxCoeff(), 2 * kEps) << "load " << lambda;
    // Node 2: k_a (d2 - d0) + k_b (d2 - d1) + k_g d2 = 0 for the displacements d, to the Newton
    // tolerance over the smallest stiffness (k_a + k_b + k_g on every direction).
    const Vec3 d2 =
        (k_a * (x0 - X.row(0).transpose()) + k_b * (x1 - X.row(1).transpose())) / (k_a + k_b + k_g);
    EXPECT_LE((xn.row(2) - X.row(2) - d2.transpose()).norm(),
              options.newton.tolerance / (k_a + k_b + k_g) + 4 * kEps)
        << "load " << lambda;
  }
}

TEST(StaticSolver, AnIncrementThatNoLongerChangesTheLoadEndsTheRun) {
  // Node 0 moves 1 m per unit load; beyond load 0.5 (half the 1e-12 resolution of load factors
  // above it) every configuration is illegal, so every increment past 0.5 fails and is halved.
  for (double min_increment : {0.0, 1e-3}) {
    Pulled rig(Vec3(1, 0, 0));
    rig.system.add(std::make_unique<Breaker>(0, 0.5 + 5e-13, false));
    StaticOptions options;
    options.initial_increment = 0.25;
    options.min_increment = min_increment;
    options.newton.tolerance = 1e-10;
    Points x = rig.X;
    std::string message;
    try {
      StaticSolver(rig.lifecycle, nullptr, options).run(x);
    } catch (const SolveError& e) {
      message = e.what();
    }
    if (min_increment == 0) {
      // Halving alone would never stop: the run ends once 0.5 + increment rounds to 0.5.
      EXPECT_NE(message.find("no longer changes the load"), std::string::npos) << message;
    } else {
      EXPECT_NE(message.find("fell below min_increment"), std::string::npos) << message;
    }
    EXPECT_NE(message.find("at load factor 0.5"), std::string::npos) << message;
    // The steps completed before stay valid, and x holds the last of them.
    ASSERT_EQ(rig.steps.size(), 2u);
    EXPECT_EQ(rig.steps.back().load, 0.5);
    EXPECT_EQ(x, rig.states.back());
    EXPECT_NEAR(x(1, 0) - rig.X(1, 0), 0.75 * 0.5, options.newton.tolerance / 40 + 4 * kEps);
  }
}

}  // namespace
}  // namespace depthfem
