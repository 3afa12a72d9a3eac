// Newton with line search on energies whose minimiser is known in closed form, and the line
// search starting below the modules' max_step or, as the paper's, at the full step.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <utility>

#include "integrators/solvers/newton.hpp"

namespace depthfem {
namespace {

// E(x) = sum_i k/2 |d_i|^2 + q/4 |d_i|^4 with d_i = x_i - a_i: strictly convex, minimised at a.
// Hessian per node: k I + q (|d|^2 I + 2 d d^T).
class QuarticWell final : public ForceModule {
 public:
  QuarticWell(Points a, double k, double q) : a_(std::move(a)), k_(k), q_(q) {}
  std::string name() const override { return "quartic well"; }
  void add_couplings(SparsityBuilder&) const override {}
  void bind(const BlockSparseMatrix& H) override {
    diagonal_.resize(static_cast<size_t>(a_.rows()));
    for (Index i = 0; i < a_.rows(); ++i) diagonal_[i] = H.block_index(i, i);
  }
  double evaluate(const Points& x, VectorX* g, BlockSparseMatrix* H) const override {
    double E = 0;
    for (Index i = 0; i < x.rows(); ++i) {
      const Vec3 d = (x.row(i) - a_.row(i)).transpose();
      const double d2 = d.squaredNorm();
      E += 0.5 * k_ * d2 + 0.25 * q_ * d2 * d2;
      if (g) g->segment<3>(3 * i) += (k_ + q_ * d2) * d;
      if (H)
        H->add_block(diagonal_[i],
                     Mat3((k_ + q_ * d2) * Mat3::Identity() + 2 * q_ * d * d.transpose()));
    }
    return E;
  }

 private:
  Points a_;
  double k_, q_;
  std::vector<Index> diagonal_;
};

TEST(Newton, ConvergesQuadraticallyToTheClosedFormMinimiser) {
  Points a(5, 3);
  a << 0.3, -1, 2, 1, 1, 1, -2, 0.5, 0, 0, 0, 0.7, 4, -3, 1;
  PhaseTimers timers;
  System system(5, timers);
  system.add(std::make_unique<QuarticWell>(a, 2.0, 50.0));
  NewtonOptions options;
  options.tolerance = 1e-12;
  const Constraints none;
  NewtonSolver newton(system, none, options);
  Points x = Points::Zero(5, 3);
  const NewtonResult r = newton.solve(x);
  ASSERT_TRUE(r.converged) << r.failure;
  EXPECT_LE((x - a).cwiseAbs().maxCoeff(), 1e-12);
  // Quadratic convergence: once the residual is below 1, r_{k+1} <= C r_k^2 with C of the order
  // of the third derivative over the second (q |d| / k ~ 25 here); asserted with C = 100.
  int quadratic = 0;
  for (size_t k = 0; k + 1 < r.residuals.size(); ++k) {
    if (r.residuals[k] > 1 || r.residuals[k + 1] < 1e-13) continue;
    EXPECT_LE(r.residuals[k + 1], 100 * r.residuals[k] * r.residuals[k]) << "iteration " << k;
    ++quadratic;
  }
  EXPECT_GE(quadratic, 2);
}

// E(x) = sum_i k/2 |x_i - t|^2 - mu ln(1 - n.x_i): a spring pulls every node towards t beyond
// the wall n.x = 1, the barrier keeps it inside. The minimiser solves, along n, the quadratic
// k (s - s_t) = mu / (1 - s). Illegal trial points (n.x >= 1) are counted.
class Wall final : public ForceModule {
 public:
  Wall(bool limits_step) : limits_step_(limits_step) {}
  static constexpr double k = 1.0, mu = 0.01, s_t = 3.0;
  std::string name() const override { return "wall"; }
  void add_couplings(SparsityBuilder&) const override {}
  void bind(const BlockSparseMatrix& H) override { block_ = H.block_index(0, 0); }
  double evaluate(const Points& x, VectorX* g, BlockSparseMatrix* H) const override {
    const double s = x(0, 0), gap = 1 - s;
    if (!(gap > 0)) {
      ++illegal;
      return std::numeric_limits<double>::infinity();
    }
    const double E = 0.5 * k * (s - s_t) * (s - s_t) - mu * std::log(gap);
    if (g) (*g)(0) += k * (s - s_t) + mu / gap;
    if (H) H->block(block_)(0, 0) += k + mu / (gap * gap);
    return E;
  }
  double max_step(const Points& x, const Points& dx) const override {
    if (!limits_step_ || dx(0, 0) <= 0) return std::numeric_limits<double>::infinity();
    return (1 - x(0, 0)) / dx(0, 0);
  }
  mutable int illegal = 0;

 private:
  bool limits_step_;
  Index block_ = 0;
};

// Root of k (s - s_t)(1 - s) = mu inside the wall.
double wall_minimiser() {
  const double b = 1 + Wall::s_t, c = Wall::s_t - Wall::mu / Wall::k;
  return 0.5 * (b - std::sqrt(b * b - 4 * c));
}

// Newton from x = 0 to 1e-12 on the wall, the other two coordinates held: the position reached
// and the number of illegal trial points (a failed test where Newton does not converge).
std::pair<double, int> solve_wall(bool limits_step, NewtonOptions options) {
  PhaseTimers timers;
  System system(1, timers);
  Wall& wall = system.add(std::make_unique<Wall>(limits_step));
  const Constraints fixed_yz(Points::Zero(1, 3), {{"yz", {0}, OnLine{Vec3::UnitX()}}});
  options.tolerance = 1e-12;
  NewtonSolver newton(system, fixed_yz, options);
  Points x = Points::Zero(1, 3);
  const NewtonResult r = newton.solve(x);
  EXPECT_TRUE(r.converged) << r.failure;
  return {x(0, 0), wall.illegal};
}

TEST(Newton, LineSearchStartsBelowTheModulesMaxStep) {
  const auto [with_limit, illegal_with_limit] = solve_wall(true, {});
  const auto [without_limit, illegal_without_limit] = solve_wall(false, {});
  EXPECT_NEAR(with_limit, wall_minimiser(), 1e-12);
  EXPECT_NEAR(without_limit, wall_minimiser(), 1e-12);
  EXPECT_EQ(illegal_with_limit, 0) << "with max_step no trial point crosses the wall";
  EXPECT_GT(illegal_without_limit, 0)
      << "without it the full Newton step does (the test would notice)";
}

// The paper's line search (full_step_first): the full Newton step is tried even where the
// module knows it crosses the wall, and halved through the illegal trials to the same minimiser.
TEST(Newton, FullStepFirstHalvesThroughIllegalTrials) {
  NewtonOptions options;
  options.line_search = LineSearchRule::kResidual;
  options.full_step_first = true;
  options.gradient_fallback = false;
  const auto [s, illegal] = solve_wall(true, options);
  EXPECT_NEAR(s, wall_minimiser(), 1e-12);
  EXPECT_GT(illegal, 0) << "the full step from x = 0 crosses the wall at s = 1";
}

}  // namespace
}  // namespace depthfem
