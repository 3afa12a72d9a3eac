// The thread budget: with one thread, assembly, the direct solve and matrix products run on
// the calling thread alone (threads counted in /proc/self/task); every pool gets the budget.
#include <gtest/gtest.h>
#include <omp.h>
#include <tbb/global_control.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iterator>
#include <numeric>

#include "core/mesh_generators.hpp"
#include "integrators/forces/constraints.hpp"
#include "integrators/forces/elasticity.hpp"
#include "integrators/solvers/linear_solver.hpp"
#include "integrators/solvers/thread_budget.hpp"

namespace depthfem {
namespace {

// Threads of this process now.
size_t thread_count() {
  const std::filesystem::directory_iterator tasks("/proc/self/task");
  return static_cast<size_t>(std::distance(begin(tasks), end(tasks)));
}

// Assembly of the stiffness of a clamped 80 x 8 x 8 bar (30,720 tets), a direct solve of it
// (positive definite: the undeformed state) with a made-up right-hand side (the supernodal
// factorisation, whose BLAS calls OpenBLAS would share with its pool, and the solves) and
// products: every parallel part of a Newton iteration with the direct solver.
double newton_work() {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3(1, 0.1, 0.1), Eigen::Vector3i(80, 8, 8)});
  std::vector<Index> all(m.tets.rows());
  std::iota(all.begin(), all.end(), 0);
  Elasticity e(m.X, m.tets, {{NeoHookean{4e4, 6e4}, all, Points()}});
  SparsityBuilder builder(static_cast<Index>(m.X.rows()));
  e.add_couplings(builder);
  BlockSparseMatrix A(builder);
  e.bind(A);
  VectorX g = VectorX::Zero(3 * m.X.rows());
  e.evaluate(m.X, &g, &A);
  g = VectorX::LinSpaced(g.size(), -1, 1);
  std::vector<Index> clamp;
  for (Index i = 0; i < m.X.rows(); ++i)
    if (m.X(i, 0) == 0) clamp.push_back(i);
  const Constraints c(m.X, {{"clamp", clamp, Fixed{}}});
  c.project(A);
  c.project(g);
  LinearSolver direct({LinearSolverKind::kDirect});
  VectorX dx, Adx;
  direct.solve(A, -g, dx);
  A.multiply(dx, Adx);
  return (Adx + g).norm() / g.norm();
}

// In a fresh process (the test binary run again for this statement alone, so that no earlier
// test has started a pool): OpenBLAS has started its pool on loading; with a budget of one the
// work must leave this thread the only one. Every pool keeps its threads once started, so none
// can have run and gone.
TEST(ThreadBudget, OneThreadRunsAlone) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        const size_t at_start = thread_count();
        const ThreadBudget budget(1);
        const double residual = newton_work();
        const size_t at_end = thread_count();
        std::fprintf(stderr, "threads at start %zu, after the work %zu; residual %g\n", at_start,
                     at_end, residual);
        std::exit(at_end == 1 && residual < 1e-8 ? 0 : 1);
      },
      testing::ExitedWithCode(0), "");
}

TEST(ThreadBudget, EveryPoolGetsTheBudget) {
  for (int n : {1, 2, 3}) {
    const ThreadBudget budget(n);
    EXPECT_EQ(budget.threads(), n);
    EXPECT_EQ(static_cast<int>(
                  tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism)),
              n);
    EXPECT_EQ(omp_get_max_threads(), n);
    EXPECT_EQ(omp_get_max_active_levels(), 0);  // CHOLMOD's loops stay on the calling thread
  }
}

}  // namespace
}  // namespace depthfem
