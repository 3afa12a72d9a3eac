// System: the sum of its modules' energies, gradients and Hessians; the Hessian pattern rebuilt
// when a module's couplings change (and only then); max_step the smallest of the modules'; an
// illegal configuration (+infinity energy) reported whatever the other modules add; module_energy
// one module's energy alone.
#include <gtest/gtest.h>

#include <array>
#include <limits>
#include <stdexcept>
#include <tuple>

#include "integrators/forces/gravity.hpp"
#include "integrators/forces/nodal_spring.hpp"
#include "integrators/forces/system.hpp"
#include "integrators/pair_springs.hpp"

namespace depthfem {
namespace {

using testing::PairSprings;

constexpr double kInf = std::numeric_limits<double>::infinity();

// A contact-like coupling: a spring k between nodes a and b that engages in prepare() once node
// a has moved beyond x = 1, and says so through pattern_changed() until the next bind().
class Latch final : public ForceModule {
 public:
  Latch(Index a, Index b, double k) : a_(a), b_(b), k_(k) {}
  std::string name() const override { return "latch"; }
  void prepare(const Points& x) override {
    const bool engage = x(a_, 0) > 1.0;
    if (engage != engaged_) changed_ = true;
    engaged_ = engage;
  }
  bool pattern_changed() const override { return changed_; }
  void add_couplings(SparsityBuilder& builder) const override {
    if (engaged_) builder.add_clique(std::vector<Index>{a_, b_});
  }
  void bind(const BlockSparseMatrix& H) override {
    ++binds;
    changed_ = false;
    blocks_ = {H.block_index(a_, a_), H.block_index(b_, b_), H.block_index(a_, b_),
               H.block_index(b_, a_)};
  }
  double evaluate(const Points& x, VectorX* g, BlockSparseMatrix* H) const override {
    if (!engaged_) return 0;
    const Vec3 d = (x.row(b_) - x.row(a_)).transpose();
    if (g) {
      g->segment<3>(3 * b_) += k_ * d;
      g->segment<3>(3 * a_) -= k_ * d;
    }
    // Without the coupling in the pattern (not rebuilt since it engaged) nothing is written;
    // the test sees it through `unbound`.
    if (H && blocks_[2] < 0) {
      ++unbound;
    } else if (H) {
      const Mat3 K = k_ * Mat3::Identity();
      H->add_block(blocks_[0], K);
      H->add_block(blocks_[1], K);
      H->add_block(blocks_[2], Mat3(-K));
      H->add_block(blocks_[3], Mat3(-K));
    }
    return 0.5 * k_ * d.squaredNorm();
  }
  int binds = 0;
  mutable int unbound = 0;  ///< Hessians asked for while engaged without the coupling bound

 private:
  Index a_, b_;
  double k_;
  bool engaged_ = false, changed_ = false;
  std::array<Index, 4> blocks_{-1, -1, -1, -1};  // (a, a), (b, b), (a, b), (b, a)
};

// Energy `value` (possibly +infinity) with no forces, and a fixed largest step.
class Constant final : public ForceModule {
 public:
  Constant(double value, double max_step) : value_(value), max_step_(max_step) {}
  std::string name() const override { return "constant"; }
  void add_couplings(SparsityBuilder&) const override {}
  double evaluate(const Points&, VectorX*, BlockSparseMatrix*) const override { return value_; }
  double max_step(const Points&, const Points&) const override { return max_step_; }

 private:
  double value_, max_step_;
};

Points reference() {
  Points X(4, 3);
  X << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  return X;
}

// The modules of the sum test, one set per System (each System owns its modules).
std::unique_ptr<NodalSpring> spring() {
  auto s = std::make_unique<NodalSpring>("spring", (VectorX(4) << 3, 5, 7, 11).finished());
  s->set_anchor(reference().array() + 0.25);
  s->set_scale(1.5);
  return s;
}
std::unique_ptr<Gravity> gravity() {
  return std::make_unique<Gravity>((VectorX(4) << 1, 2, 3, 4).finished(), Vec3(0.5, -1, -9.81),
                                   false);
}
std::unique_ptr<PairSprings> pairs() {
  return std::make_unique<PairSprings>(
      reference(), std::vector<PairSprings::Pair>{{0, 1, 13}, {1, 2, 17}, {0, 3, 19}});
}

// The reference nodes moved off it, every coordinate.
Points deformed() {
  Points x = reference();
  x << 0.1, -0.2, 0.05, 1.3, 0.1, -0.1, 0.2, 0.8, 0.3, -0.1, 0.2, 1.4;
  return x;
}

TEST(System, SumsTheModulesEnergiesGradientsAndHessians) {
  const Points X = reference(), x = deformed();
  PhaseTimers timers;
  System all(4, timers);
  all.add(spring());
  all.add(gravity());
  all.add(pairs());
  // Each module alone in its own System, evaluated at the same x.
  System alone[3] = {System(4, timers), System(4, timers), System(4, timers)};
  alone[0].add(spring());
  alone[1].add(gravity());
  alone[2].add(pairs());
  double energy = 0;
  VectorX gradient = VectorX::Zero(12);
  Eigen::MatrixXd hessian = Eigen::MatrixXd::Zero(12, 12);
  for (System& s : alone) {
    VectorX g;
    energy += s.hessian(x, g);
    gradient += g;
    hessian += Eigen::MatrixXd(s.matrix().to_sparse());
  }
  // The System adds the same terms in the same order: equal up to the round-off of reordered
  // sums (1e-14 relative; the values are O(10)).
  VectorX g = VectorX::Constant(12, 1e3);  // overwritten, not added to
  EXPECT_NEAR(all.energy(x), energy, 1e-14 * std::abs(energy));
  EXPECT_NEAR(all.gradient(x, g), energy, 1e-14 * std::abs(energy));
  EXPECT_LE((g - gradient).norm(), 1e-14 * gradient.norm());
  g.setConstant(1e3);
  EXPECT_NEAR(all.hessian(x, g), energy, 1e-14 * std::abs(energy));
  EXPECT_LE((g - gradient).norm(), 1e-14 * gradient.norm());
  const Eigen::MatrixXd H = Eigen::MatrixXd(all.matrix().to_sparse());
  EXPECT_LE((H - hessian).cwiseAbs().maxCoeff(), 1e-14 * hessian.cwiseAbs().maxCoeff());
  // The pattern is the union of the couplings: the springs' pairs, and nothing else.
  const BlockSparseMatrix& M = all.matrix();
  EXPECT_GE(M.block_index(0, 3), 0);
  EXPECT_GE(M.block_index(2, 1), 0);
  EXPECT_EQ(M.block_index(0, 2), -1);
  EXPECT_EQ(M.num_blocks(), 4 + 2 * 3);
  // A second evaluation after the gradient adds nothing twice (the Hessian is zeroed first).
  all.hessian(x, g);
  EXPECT_LE((Eigen::MatrixXd(all.matrix().to_sparse()) - hessian).cwiseAbs().maxCoeff(),
            1e-14 * hessian.cwiseAbs().maxCoeff());
}

TEST(System, RebuildsThePatternWhenAModulesCouplingsChange) {
  const Points X = reference();
  PhaseTimers timers;
  System system(4, timers);
  system.add(spring());
  Latch& latch = system.add(std::make_unique<Latch>(1, 2, 23.0));
  VectorX g;
  Points x = X;
  system.prepare(x);
  system.hessian(x, g);
  const std::uint64_t first = system.matrix().pattern_version();
  EXPECT_EQ(latch.binds, 1);
  EXPECT_EQ(system.matrix().block_index(1, 2), -1);
  // Nothing changed: the pattern is kept (no new version, no new bind).
  x(3, 2) += 0.1;
  system.prepare(x);
  system.hessian(x, g);
  EXPECT_EQ(system.matrix().pattern_version(), first);
  EXPECT_EQ(latch.binds, 1);
  // Node 1 passes x = 1: the latch couples nodes 1 and 2, and the next Hessian has the block
  // and the spring's value in it (-k I off the diagonal).
  x(1, 0) = 1.2;
  system.prepare(x);
  system.hessian(x, g);
  EXPECT_NE(system.matrix().pattern_version(), first);
  EXPECT_EQ(latch.binds, 2);
  EXPECT_EQ(latch.unbound, 0);
  const Index b12 = system.matrix().block_index(1, 2);
  ASSERT_GE(b12, 0);
  EXPECT_EQ(Mat3(system.matrix().block(b12)), Mat3(-23.0 * Mat3::Identity()));
  // Released again: a new pattern without the block.
  const std::uint64_t second = system.matrix().pattern_version();
  x(1, 0) = 0.9;
  system.prepare(x);
  system.hessian(x, g);
  EXPECT_NE(system.matrix().pattern_version(), second);
  EXPECT_EQ(system.matrix().block_index(1, 2), -1);
  // Adding a module also rebuilds it.
  const std::uint64_t third = system.matrix().pattern_version();
  system.add(pairs());
  system.hessian(x, g);
  EXPECT_NE(system.matrix().pattern_version(), third);
  EXPECT_GE(system.matrix().block_index(0, 3), 0);
}

// Pair springs whose couplings are fixed: bound once, then moved to each new pattern.
class FixedSprings final : public ForceModule {
 public:
  explicit FixedSprings(std::unique_ptr<PairSprings> springs) : springs_(std::move(springs)) {}
  std::string name() const override { return "fixed springs"; }
  bool fixed_couplings() const override { return true; }
  void add_couplings(SparsityBuilder& builder) const override { springs_->add_couplings(builder); }
  void bind(const BlockSparseMatrix& H) override {
    ++binds;
    springs_->bind(H);
  }
  void rebind(const BlockSparseMatrix& H, std::span<const Index> moved) override {
    ++rebinds;
    moved_ = std::vector<Index>(moved.begin(), moved.end());
    springs_->bind(H);  // the reference: indices found anew, compared with the moved ones below
  }
  double evaluate(const Points& x, VectorX* g, BlockSparseMatrix* H) const override {
    return springs_->evaluate(x, g, H);
  }
  int binds = 0, rebinds = 0;
  std::vector<Index> moved_;

 private:
  std::unique_ptr<PairSprings> springs_;
};

// A rebuild for the latch binds the fixed springs once and then moves them: every block of the
// pattern before lands on the same (row, column) in the new one (-1 only for the latch's
// coupling when it goes), and the Hessian equals that of a system built afresh, bit for bit.
TEST(System, FixedCouplingsAreBoundOnceAndMovedToEachNewPattern) {
  PhaseTimers timers;
  System system(4, timers);
  FixedSprings& fixed = system.add(std::make_unique<FixedSprings>(pairs()));
  system.add(std::make_unique<Latch>(1, 2, 23.0));
  VectorX g;
  Points x = reference();
  x(3, 2) += 0.1;
  int rebuilds = 0;
  for (const double x1 : {1.2, 0.9, 1.3}) {  // engage, release, engage
    const BlockSparseMatrix before = system.matrix();
    x(1, 0) = x1;
    system.prepare(x);
    system.hessian(x, g);
    const BlockSparseMatrix& now = system.matrix();
    if (before.num_nodes() == now.num_nodes()) {
      ++rebuilds;
      ASSERT_EQ(fixed.moved_.size(), static_cast<size_t>(before.num_blocks()));
      for (Index i = 0; i < before.num_nodes(); ++i)
        for (Index k = before.row_begin(i); k < before.row_begin(i + 1); ++k)
          EXPECT_EQ(fixed.moved_[k], now.block_index(i, before.block_col(k)));
    }
    PhaseTimers fresh_timers;
    System fresh(4, fresh_timers);
    fresh.add(std::make_unique<FixedSprings>(pairs()));
    fresh.add(std::make_unique<Latch>(1, 2, 23.0));
    VectorX fresh_g;
    fresh.prepare(x);
    fresh.hessian(x, fresh_g);
    EXPECT_EQ(Eigen::MatrixXd(now.to_sparse()), Eigen::MatrixXd(fresh.matrix().to_sparse()));
    EXPECT_EQ(g, fresh_g);
  }
  EXPECT_EQ(fixed.binds, 1);
  EXPECT_EQ(fixed.rebinds, rebuilds);
  EXPECT_EQ(rebuilds, 2);  // the first Hessian built the pattern; two more rebuilt it
}

TEST(System, MaxStepIsTheSmallestOfTheModules) {
  const Points x = reference(), dx = Points::Ones(4, 3);
  PhaseTimers timers;
  System system(4, timers);
  system.add(spring());  // no limit (+infinity)
  EXPECT_EQ(system.max_step(x, dx), kInf);
  system.add(std::make_unique<Constant>(0.0, 0.7));
  system.add(std::make_unique<Constant>(0.0, 0.3));
  system.add(std::make_unique<Constant>(0.0, 0.5));
  EXPECT_EQ(system.max_step(x, dx), 0.3);
}

TEST(System, InfiniteEnergyOfOneModuleIsTheTotal) {
  const Points x = reference();
  // The illegal module first, in the middle or last, among modules of finite (also negative:
  // gravity lifting a mass) energy: every evaluation reports +infinity.
  for (int position = 0; position < 3; ++position) {
    PhaseTimers timers;
    System system(4, timers);
    for (int k = 0; k < 3; ++k) {
      if (k == position) system.add(std::make_unique<Constant>(kInf, kInf));
      system.add(std::make_unique<Constant>(-1e300, kInf));
    }
    system.add(gravity());
    VectorX g;
    EXPECT_EQ(system.energy(x), kInf) << "position " << position;
    EXPECT_EQ(system.gradient(x, g), kInf) << "position " << position;
    EXPECT_EQ(system.hessian(x, g), kInf) << "position " << position;
  }
}

TEST(System, ModuleEnergyIsThatModulesAlone) {
  const Points X = reference(), x = deformed();
  PhaseTimers timers;
  System system(4, timers);
  system.add(spring());
  const PairSprings& springs = system.add(pairs());
  system.add(std::make_unique<Constant>(2.5, kInf));
  // sum k/2 |(x_j - x_i) - (X_j - X_i)|^2 over the three pairs, and nothing of the others.
  double expected = 0;
  for (const auto& [i, j, k] : {std::tuple{0, 1, 13.0}, {1, 2, 17.0}, {0, 3, 19.0}})
    expected += 0.5 * k * (x.row(j) - x.row(i) - X.row(j) + X.row(i)).squaredNorm();
  EXPECT_NEAR(system.module_energy(springs, x), expected, 1e-15 * expected);
  const Constant outside(1.0, kInf);
  EXPECT_THROW(system.module_energy(outside, x), std::logic_error);
}

}  // namespace
}  // namespace depthfem
