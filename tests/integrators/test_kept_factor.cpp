// The refactor rule both direct solvers share: a factor is worth F / (40 nnz(L)) CG iterations
// (2-50), and the next matrix is factored once a solve on the kept factor costs more than the
// mean cost of the factor's solves so far.
#include <gtest/gtest.h>

#include "integrators/solvers/kept_factor.hpp"

namespace depthfem {
namespace {

TEST(KeptFactor, NothingIsKeptBeforeAFactorOrAfterADrop) {
  KeptFactor kept;
  EXPECT_FALSE(kept.try_cg());
  kept.start(4000, 10);
  EXPECT_TRUE(kept.try_cg());
  kept.drop();
  EXPECT_FALSE(kept.try_cg());
}

TEST(KeptFactor, AFactorIsWorthItsFlopsOverFortyEntriesClampedToTwoToFifty) {
  KeptFactor kept;
  kept.start(4000, 10);  // 4000 / 400
  EXPECT_EQ(kept.max_iterations(), 10);
  kept.start(1, 1000);
  EXPECT_EQ(kept.max_iterations(), 2);
  kept.start(1e12, 1);
  EXPECT_EQ(kept.max_iterations(), 50);
}

TEST(KeptFactor, RefactorsOnceASolveCostsMoreThanTheCyclesMean) {
  KeptFactor kept;
  kept.start(4000, 10);  // cycle: 1 solve, 10 iterations
  kept.record(5);        // 2 solves, 15: 5 <= 7.5
  EXPECT_TRUE(kept.try_cg());
  kept.record(7);  // 3 solves, 22: 7 <= 7.33
  EXPECT_TRUE(kept.try_cg());
  kept.record(8);  // 4 solves, 30: 8 > 7.5
  EXPECT_FALSE(kept.try_cg());
  kept.start(4000, 10);  // a new factor starts a new cycle
  EXPECT_TRUE(kept.try_cg());
  kept.record(10);  // 2 solves, 20: 10 is the mean, not above it
  EXPECT_TRUE(kept.try_cg());
}

}  // namespace
}  // namespace depthfem
