#pragma once
/// Dense kernels of a Cholesky factorisation (column-major, LAPACK's conventions) whose results
/// do not depend on the number of threads: a block large enough to share is cut into tiles of
/// about kBlasTile rows or columns, a cut fixed by its sizes alone; each tile is one BLAS call on
/// the calling thread (run them under SerialBlas), and TBB runs the tiles in any order on any
/// threads. A threaded BLAS cuts its blocks by its thread count instead: OpenBLAS 0.3.21's
/// dgemm, dsyrk, dtrsm and dpotrf (and ddot) give other bits on two threads than on one.

namespace depthfem {

/// Rows or columns of a tile. Each tile packs its operands anew, so small tiles cost time: on one
/// thread the factorisation of hertz_sphere's matrix (1.0e11 flops) took 0.95-1.00 times the CPU
/// time of CHOLMOD's own with tiles of 768 or 1024, 1.03-1.06 times with 512 (paired runs).
inline constexpr int kBlasTile = 768;

/// Multiply-adds under which a kernel is one BLAS call, untiled (a tile's worth).
inline constexpr double kBlasTiledWork = double(kBlasTile) * kBlasTile * 32;

/// C(i, j) = beta C(i, j) + alpha sum_l A(i, l) A(j, l) for i >= j: the lower trapezoid of the
/// m x n block C (m >= n, leading dimension ldc); A is m x k (lda), its first n rows are the
/// columns' factors. (dsyrk on the top n x n, dgemm below it; nothing above the diagonal.)
/// T is double or float (a single-precision factor, DirectSolverOptions::precision).
template <class T>
void lower_product(int m, int n, int k, T alpha, const T* A, int lda, T beta, T* C, int ldc);

/// B = B L^-T: L is n x n lower triangular (ldl), B is m x n (ldb). (dtrsm "R", "L", "T", "N".)
template <class T>
void solve_right_lower_transposed(int m, int n, const T* L, int ldl, T* B, int ldb);

/// The lower triangle of the n x n symmetric A (lda) is overwritten by L, A = L L^T. Returns 0,
/// or as LAPACK's dpotrf the 1-based column whose pivot is not positive (L is then partial).
template <class T>
int cholesky_lower(int n, T* A, int lda);

}  // namespace depthfem
