// The tiled dense kernels of the supernodal factorisation: each against a plain loop (to the
// rounding of a sum of k products), and bitwise the same on one, two and three threads.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include "integrators/solvers/thread_budget.hpp"
#include "integrators/solvers/tiled_blas.hpp"

namespace depthfem {
namespace {

std::vector<double> random_matrix(int rows, int cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> a(size_t(rows) * cols);
  for (double& v : a) v = u(rng);
  return a;
}

// A symmetric positive definite n x n matrix (column-major): B B^T / k + I, B n x k.
std::vector<double> spd_matrix(int n, int k, unsigned seed) {
  const std::vector<double> B = random_matrix(n, k, seed);
  std::vector<double> A(size_t(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      double s = 0;
      for (int l = 0; l < k; ++l) s += B[i + size_t(l) * n] * B[j + size_t(l) * n];
      A[i + size_t(j) * n] = s / k + (i == j);
    }
  return A;
}

// `work` run on `threads` threads (an arena of that many; the BLAS of every tile on its thread).
void on_threads(int threads, const std::function<void()>& work) {
  const SerialBlas serial;
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  tbb::task_arena arena(threads);
  arena.execute(work);
}

// Sizes on both sides of the tiling (kBlasTiledWork multiply-adds): one call, and a trapezoid
// cut in two column parts by three row parts, the last below the square.
TEST(TiledBlas, LowerProductMatchesALoopAndLeavesTheUpperTriangle) {
  struct Size {
    int m, n, k;
  };
  constexpr int t = kBlasTile;
  for (const Size s : {Size{90, 40, 7}, Size{2 * t + 100, t + 200, 40}}) {
    const std::vector<double> A = random_matrix(s.m, s.k, 1), C0 = random_matrix(s.m, s.n, 2);
    const bool tiled = (s.m - 0.5 * s.n) * s.n * s.k >= kBlasTiledWork;
    EXPECT_EQ(tiled, s.m > 100);
    for (const double beta : {0.0, 1.0}) {
      std::vector<double> C = C0;
      on_threads(2,
                 [&] { lower_product(s.m, s.n, s.k, -2.0, A.data(), s.m, beta, C.data(), s.m); });
      double worst = 0;
      for (int j = 0; j < s.n; ++j)
        for (int i = 0; i < s.m; ++i) {
          const size_t at = i + size_t(j) * s.m;
          if (i < j) {
            ASSERT_EQ(C[at], C0[at]) << "above the diagonal: " << i << ", " << j;
            continue;
          }
          double sum = 0;
          for (int l = 0; l < s.k; ++l) sum += A[i + size_t(l) * s.m] * A[j + size_t(l) * s.m];
          worst = std::max(worst, std::abs(C[at] - (beta * C0[at] - 2 * sum)));
        }
      // Each entry sums k products of entries below 1 in size (rounding at most k eps times
      // their sum, under k), doubled, then adds beta C0.
      EXPECT_LT(worst, 2 * (s.k + 1) * s.k * std::numeric_limits<double>::epsilon());
    }
  }
}

TEST(TiledBlas, SolveAndCholeskyMatchTheirDefinitions) {
  // n > 2 kBlasTile: the Cholesky recursion splits twice, the solves and products below it are
  // tiled.
  const int n = 2 * kBlasTile + 100, m = 2 * kBlasTile + 400;
  const std::vector<double> A = spd_matrix(n, 60, 3);
  std::vector<double> L = A;
  int info = -1;
  on_threads(2, [&] { info = cholesky_lower(n, L.data(), n); });
  ASSERT_EQ(info, 0);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < j; ++i) L[i + size_t(j) * n] = 0;  // the upper triangle is A's
  double worst = 0;  // L L^T against A, entries of size about 1 to 2
  for (int j = 0; j < n; j += 7)
    for (int i = j; i < n; ++i) {
      double s = 0;
      for (int l = 0; l <= j; ++l) s += L[i + size_t(l) * n] * L[j + size_t(l) * n];
      worst = std::max(worst, std::abs(s - A[i + size_t(j) * n]));
    }
  EXPECT_LT(worst, 1e-12);

  // X L^T = B, B m x n.
  const std::vector<double> B = random_matrix(m, n, 4);
  std::vector<double> X = B;
  on_threads(2, [&] { solve_right_lower_transposed(m, n, L.data(), n, X.data(), m); });
  worst = 0;
  for (int i = 0; i < m; i += 11)
    for (int j = 0; j < n; ++j) {
      double s = 0;
      for (int l = 0; l <= j; ++l) s += X[i + size_t(l) * m] * L[j + size_t(l) * n];
      worst = std::max(worst, std::abs(s - B[i + size_t(j) * m]));
    }
  EXPECT_LT(worst, 1e-10);
}

// A pivot that is not positive is reported at its column, 1-based as LAPACK's info, also when
// the recursion meets it in its second half.
TEST(TiledBlas, CholeskyReportsTheFirstColumnThatIsNotPositive) {
  const int n = 2 * kBlasTile + 100;
  for (const int bad : {5, n / 2 + 100}) {
    std::vector<double> A = spd_matrix(n, 20, 5);
    for (int i = 0; i < n; ++i) A[i + size_t(bad) * n] = A[bad + size_t(i) * n] = 0;
    A[bad + size_t(bad) * n] = -1;
    int info = 0;
    on_threads(2, [&] { info = cholesky_lower(n, A.data(), n); });
    EXPECT_EQ(info, bad + 1);
  }
}

// The tiles are cut by the sizes alone and each is one call on one thread: the results do not
// depend on how many threads share them.
TEST(TiledBlas, BitwiseTheSameOnOneTwoAndThreeThreads) {
  const int n = 2 * kBlasTile + 250, m = 3 * kBlasTile + 100, k = 300;
  const std::vector<double> A = spd_matrix(n, 40, 6), P = random_matrix(m, k, 7);
  struct Out {
    std::vector<double> product, factor, solved;
  };
  const auto compute = [&](int threads) {
    Out o;
    on_threads(threads, [&] {
      o.product.assign(size_t(m) * n, 0.0);
      lower_product(m, n, k, 1.0, P.data(), m, 0.0, o.product.data(), m);
      o.factor = A;
      EXPECT_EQ(cholesky_lower(n, o.factor.data(), n), 0);
      o.solved = random_matrix(m, n, 8);
      solve_right_lower_transposed(m, n, o.factor.data(), n, o.solved.data(), m);
    });
    return o;
  };
  const Out one = compute(1);
  for (const int threads : {2, 3}) {
    const Out more = compute(threads);
    EXPECT_TRUE(more.product == one.product) << threads << " threads";
    EXPECT_TRUE(more.factor == one.factor) << threads << " threads";
    EXPECT_TRUE(more.solved == one.solved) << threads << " threads";
  }
}

}  // namespace
}  // namespace depthfem
