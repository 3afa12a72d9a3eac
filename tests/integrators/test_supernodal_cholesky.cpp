// The supernodal factorisation into a CHOLMOD factor: the factor of CHOLMOD's own
// cholmod_factorize to rounding (of the analysed pattern and of a sparser one fitted to it), the
// same first failing column on an indefinite matrix and its failed pivot, the subtree where the
// last factorisation failed factored first, and bitwise the same factor on one, two and three
// threads.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "integrators/solvers/supernodal_cholesky.hpp"
#include "integrators/solvers/thread_budget.hpp"
#include "integrators/solvers/tiled_blas.hpp"

namespace depthfem {
namespace {

// CHOLMOD's workspace for one test.
struct Common {
  cholmod_common c;
  Common() {
    cholmod_start(&c);
    c.print = 0;
  }
  ~Common() { cholmod_finish(&c); }
};

// The 7-point Laplacian of a q x q x q grid plus `shift` on the diagonal, its lower triangle by
// columns (stype -1): positive definite for shift > 0. Nested dissection gives a top separator
// of q^2 columns, a supernode large enough for the tiled kernels (q = 30: 900 columns).
cholmod_sparse* grid_laplacian(int q, double shift, cholmod_common& c) {
  const int n = q * q * q;
  cholmod_sparse* A = cholmod_allocate_sparse(n, n, 4 * size_t(n), 1, 1, -1, CHOLMOD_REAL, &c);
  int* p = static_cast<int*>(A->p);
  int* row = static_cast<int*>(A->i);
  double* x = static_cast<double*>(A->x);
  int k = 0;
  for (int j = 0; j < n; ++j) {
    p[j] = k;
    row[k] = j;
    x[k++] = 6 + shift;
    for (const int step : {1, q, q * q}) {  // the neighbours after j along x, y, z
      const int along = (j / step) % q;
      if (along + 1 < q) {
        row[k] = j + step;
        x[k++] = -1;
      }
    }
  }
  p[n] = k;
  return A;
}

// CHOLMOD's supernodal analysis of A with nested dissection (METIS).
cholmod_factor* analyse(cholmod_sparse* A, cholmod_common& c) {
  c.supernodal = CHOLMOD_SUPERNODAL;
  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_METIS;
  c.postorder = 1;
  return cholmod_analyze(A, &c);
}

std::vector<double> values(const cholmod_factor& L) {
  const double* x = static_cast<const double*>(L.x);
  return std::vector<double>(x, x + L.xsize);
}

// The largest supernode (columns) of L.
int widest_supernode(const cholmod_factor& L) {
  const int* super = static_cast<const int*>(L.super);
  int widest = 0;
  for (size_t s = 0; s < L.nsuper; ++s) widest = std::max(widest, super[s + 1] - super[s]);
  return widest;
}

// A with every third off-diagonal entry dropped: a pattern within A's.
cholmod_sparse* sparser(cholmod_sparse* A, cholmod_common& c) {
  cholmod_sparse* B = cholmod_copy_sparse(A, &c);
  int* p = static_cast<int*>(B->p);
  int* row = static_cast<int*>(B->i);
  double* x = static_cast<double*>(B->x);
  int kept = 0;
  for (size_t j = 0, k = 0; j < B->ncol; ++j) {
    const int end = p[j + 1];
    p[j] = kept;
    for (; static_cast<int>(k) < end; ++k)
      if (row[k] == static_cast<int>(j) || k % 3 != 0) {
        row[kept] = row[k];
        x[kept++] = x[k];
      }
  }
  p[B->ncol] = kept;
  return B;
}

// A itself and a sparser pattern fitted to A's analysis (as a contact pattern that lost
// couplings is fitted to the kept factor): each factors as CHOLMOD factors it with that analysis.
TEST(SupernodalCholesky, EqualsCholmodsFactorToRounding) {
  Common common;
  cholmod_common& c = common.c;
  cholmod_sparse* A = grid_laplacian(30, 0.01, c);
  cholmod_factor* reference = analyse(A, c);
  cholmod_factor* L = cholmod_copy_factor(reference, &c);
  ASSERT_TRUE(reference && L);
  ASSERT_GT(widest_supernode(*L), kBlasTile);  // the Cholesky recursion and the tiles are used
  cholmod_sparse* B = sparser(A, c);
  ASSERT_LT(cholmod_nnz(B, &c), cholmod_nnz(A, &c) * 4 / 5);
  for (cholmod_sparse* M : {A, B}) {
    cholmod_factorize(M, reference, &c);
    ASSERT_EQ(reference->minor, reference->n);
    const std::unique_ptr<SupernodalCholesky> cholesky = SupernodalCholesky::fitted(*M, *L, c);
    ASSERT_TRUE(cholesky);
    {
      const SerialBlas serial;
      ASSERT_TRUE(cholesky->factorize(*M, *L));
    }
    EXPECT_EQ(L->minor, L->n);
    // Entries of L are at most sqrt(6.01) in size, and each sums at most a few thousand
    // products: its rounding stays far below 1e-11 (measured: about 1e-14).
    const std::vector<double> ours = values(*L), theirs = values(*reference);
    double worst = 0;
    for (size_t k = 0; k < ours.size(); ++k) worst = std::max(worst, std::abs(ours[k] - theirs[k]));
    EXPECT_LT(worst, 1e-11);
    // And CHOLMOD solves with it: M x = b to rounding.
    cholmod_dense* b = cholmod_ones(M->nrow, 1, CHOLMOD_REAL, &c);
    cholmod_dense* x = cholmod_solve(CHOLMOD_A, L, b, &c);
    cholmod_dense* r = cholmod_copy_dense(b, &c);
    double minus_one[2] = {-1, 0}, one[2] = {1, 0};
    cholmod_sdmult(M, 0, minus_one, one, x, r, &c);  // r = b - M x
    EXPECT_LT(cholmod_norm_dense(r, 0, &c), 1e-10 * cholmod_norm_dense(b, 0, &c));
    for (cholmod_dense* d : {b, x, r}) cholmod_free_dense(&d, &c);
  }
  cholmod_free_factor(&L, &c);
  cholmod_free_factor(&reference, &c);
  cholmod_free_sparse(&B, &c);
  cholmod_free_sparse(&A, &c);
}

// Runs f in an arena of `threads` threads, no more allowed.
template <class F>
void on_threads(int threads, F&& f) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  tbb::task_arena arena(threads);
  arena.execute(f);
}

// A - 0.6 I has a few negative eigenvalues (the Laplacian's lowest are near 0.07): both
// factorisations stop at the same first pivot that is not positive, on any number of threads
// (the subtrees after the failing supernode may fail first).
TEST(SupernodalCholesky, StopsWhereCholmodStopsOnAnIndefiniteMatrix) {
  Common common;
  cholmod_common& c = common.c;
  cholmod_sparse* A = grid_laplacian(20, -0.6, c);
  cholmod_factor* reference = analyse(A, c);
  cholmod_factor* L = cholmod_copy_factor(reference, &c);
  cholmod_factorize(A, reference, &c);
  ASSERT_LT(reference->minor, reference->n);
  SupernodalCholesky cholesky(*A, *L, c);
  const SerialBlas serial;
  for (const int threads : {1, 2, 3}) {
    bool ok = true;
    on_threads(threads, [&] { ok = cholesky.factorize(*A, *L); });
    EXPECT_FALSE(ok);
    EXPECT_EQ(L->minor, reference->minor) << threads << " threads";
  }
  cholmod_free_factor(&L, &c);
  cholmod_free_factor(&reference, &c);
  cholmod_free_sparse(&A, &c);
}

// A copy of A whose diagonal entry at column k of L (permuted) is -1: its first failing pivot.
cholmod_sparse* failing_at(const cholmod_sparse* A, const cholmod_factor& L, int k,
                           cholmod_common& c) {
  cholmod_sparse* out = cholmod_copy_sparse(const_cast<cholmod_sparse*>(A), &c);
  const int column = static_cast<const int*>(L.Perm)[k];
  static_cast<double*>(out->x)[static_cast<const int*>(out->p)[column]] = -1;  // stored first
  return out;
}

// After a failed factorisation the subtree of the supernode that failed is factored first. A
// matrix that fails there again costs that subtree only; one that fails elsewhere fails at the
// first failing column of the sequential loop, as without that history; a positive definite one
// gets bitwise the factor of a factorisation without it; on one and on two threads.
TEST(SupernodalCholesky, FactorsFirstWhereTheLastFactorisationFailed) {
  Common common;
  cholmod_common& c = common.c;
  cholmod_sparse* definite = grid_laplacian(20, 0.01, c);
  cholmod_sparse* indefinite = grid_laplacian(20, -0.6, c);  // fails at a separator
  cholmod_factor* L = analyse(definite, c);
  // The last leaf of the supernodal tree (no supernode's first row below its columns is in it):
  // nearly every other leaf comes before it.
  const int* super = static_cast<const int*>(L->super);
  const int* pi = static_cast<const int*>(L->pi);
  const int* rows = static_cast<const int*>(L->s);
  std::vector<char> has_child(L->nsuper, 0);
  for (size_t s = 0; s < L->nsuper; ++s) {
    const int ncol = super[s + 1] - super[s];
    if (pi[s + 1] - pi[s] > ncol)
      has_child[std::upper_bound(super, super + L->nsuper + 1, rows[pi[s] + ncol]) - super - 1] = 1;
  }
  int last_leaf = static_cast<int>(L->nsuper) - 1;
  while (has_child[last_leaf]) --last_leaf;
  cholmod_sparse* late = failing_at(definite, *L, super[last_leaf], c);
  cholmod_sparse* early = failing_at(definite, *L, 0, c);
  const SerialBlas serial;
  for (const int threads : {1, 2}) {
    SupernodalCholesky fresh(*definite, *L, c), probing(*definite, *L, c);
    const auto factor = [&](SupernodalCholesky& s, cholmod_sparse* A) {
      bool ok = false;
      on_threads(threads, [&] { ok = s.factorize(*A, *L); });
      return ok;
    };
    ASSERT_TRUE(factor(fresh, definite));
    const std::vector<double> reference = values(*L);
    ASSERT_FALSE(factor(fresh, indefinite));
    const size_t indefinite_minor = L->minor;

    ASSERT_FALSE(factor(probing, late));
    EXPECT_EQ(L->minor, size_t(super[last_leaf]));
    const int unprobed = probing.last_factored();
    EXPECT_FALSE(factor(probing, late));
    EXPECT_EQ(L->minor, size_t(super[last_leaf]));
    EXPECT_EQ(probing.last_factored(), 1) << "the failing leaf alone";
    EXPECT_GT(unprobed, 10) << "the leaves before it";

    EXPECT_FALSE(factor(probing, early));  // the leaf probed passes, supernode 0 fails
    EXPECT_EQ(L->minor, 0u);
    EXPECT_FALSE(factor(probing, indefinite));
    EXPECT_EQ(L->minor, indefinite_minor) << threads << " threads";

    EXPECT_TRUE(factor(probing, definite));
    EXPECT_EQ(L->minor, L->n);
    EXPECT_EQ(probing.last_factored(), static_cast<int>(L->nsuper));
    EXPECT_TRUE(values(*L) == reference) << threads << " threads";
  }
  cholmod_free_factor(&L, &c);
  for (cholmod_sparse* A : {definite, indefinite, late, early}) cholmod_free_sparse(&A, &c);
}

// The failed pivot over its diagonal entry, against the pivot of the dense leading block of
// P A P^T up to the failing column k (its last diagonal entry minus b^T B^-1 b, B the block
// before k and b the column k above the diagonal): to rounding in double; in single precision
// (failing at the same column) to 1e-3 of it (measured 1.4e-4: b^T B^-1 b is 1.5 times the
// pivot, and B is nearly singular, its eigenvalue nearest zero being what turns the pivot
// negative, so that single precision's rounding grows with B's condition). 0 after a
// factorisation that succeeded.
TEST(SupernodalCholesky, ReportsTheFailedPivotOverItsDiagonalEntry) {
  Common common;
  cholmod_common& c = common.c;
  cholmod_sparse* A = grid_laplacian(10, -0.6, c);  // the lowest eigenvalue 0.245 - 0.6
  cholmod_factor* L = analyse(A, c);
  SupernodalCholesky cholesky(*A, *L, c);
  const SerialBlas serial;
  ASSERT_FALSE(cholesky.factorize(*A, *L));
  const int k = static_cast<int>(L->minor);
  const int n = static_cast<int>(A->nrow);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(n, n);
  const int* p = static_cast<const int*>(A->p);
  const int* row = static_cast<const int*>(A->i);
  const double* x = static_cast<const double*>(A->x);
  for (int j = 0; j < n; ++j)
    for (int e = p[j]; e < p[j + 1]; ++e) dense(row[e], j) = dense(j, row[e]) = x[e];
  const int* perm = static_cast<const int*>(L->Perm);
  Eigen::MatrixXd B(k, k);
  Eigen::VectorXd b(k);
  for (int i = 0; i < k; ++i) {
    b(i) = dense(perm[i], perm[k]);
    for (int j = 0; j < k; ++j) B(i, j) = dense(perm[i], perm[j]);
  }
  const Eigen::LLT<Eigen::MatrixXd> leading(B);
  ASSERT_EQ(leading.info(), Eigen::Success) << "the pivots before k are positive";
  const double diagonal = dense(perm[k], perm[k]);
  const double expected = (diagonal - b.dot(leading.solve(b))) / diagonal;
  ASSERT_LT(expected, -1e-2);
  EXPECT_NEAR(cholesky.failed_pivot(), expected, 1e-12);

  std::vector<float> single;
  ASSERT_FALSE(cholesky.factorize(*A, *L, single));
  EXPECT_EQ(static_cast<int>(L->minor), k);
  EXPECT_NEAR(cholesky.failed_pivot(), expected, 1e-3 * std::abs(expected));

  cholmod_sparse* definite = grid_laplacian(10, 0.01, c);
  EXPECT_TRUE(cholesky.factorize(*definite, *L));
  EXPECT_EQ(cholesky.failed_pivot(), 0.0);
  cholmod_free_factor(&L, &c);
  cholmod_free_sparse(&definite, &c);
  cholmod_free_sparse(&A, &c);
}

// Each supernode's updates summed in CHOLMOD's order whichever thread runs it, its dense blocks
// in tiles cut by their sizes alone: the factor does not depend on the number of threads.
// (CHOLMOD's own, through a threaded OpenBLAS, does.)
TEST(SupernodalCholesky, BitwiseTheSameFactorOnOneTwoAndThreeThreads) {
  Common common;
  cholmod_common& c = common.c;
  cholmod_sparse* A = grid_laplacian(30, 0.01, c);
  cholmod_factor* L = analyse(A, c);
  SupernodalCholesky cholesky(*A, *L, c);
  const auto factor_on = [&](int threads) {
    const SerialBlas serial;
    bool ok = false;
    on_threads(threads, [&] { ok = cholesky.factorize(*A, *L); });
    EXPECT_TRUE(ok);
    return values(*L);
  };
  const std::vector<double> one = factor_on(1);
  EXPECT_TRUE(factor_on(2) == one);
  EXPECT_TRUE(factor_on(3) == one);
  cholmod_free_factor(&L, &c);
  cholmod_free_sparse(&A, &c);
}

}  // namespace
}  // namespace depthfem
