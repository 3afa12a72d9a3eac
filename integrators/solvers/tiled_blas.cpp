#include "integrators/solvers/tiled_blas.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

// BLAS and LAPACK (Fortran calling convention; the hidden lengths of the one-letter arguments
// are left out, as CHOLMOD does).
extern "C" {
void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k,
            const double* alpha, const double* A, const int* lda, const double* B, const int* ldb,
            const double* beta, double* C, const int* ldc);
void sgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k,
            const float* alpha, const float* A, const int* lda, const float* B, const int* ldb,
            const float* beta, float* C, const int* ldc);
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha,
            const double* A, const int* lda, const double* beta, double* C, const int* ldc);
void ssyrk_(const char* uplo, const char* trans, const int* n, const int* k, const float* alpha,
            const float* A, const int* lda, const float* beta, float* C, const int* ldc);
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m,
            const int* n, const double* alpha, const double* A, const int* lda, double* B,
            const int* ldb);
void strsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m,
            const int* n, const float* alpha, const float* A, const int* lda, float* B,
            const int* ldb);
void dpotrf_(const char* uplo, const int* n, double* A, const int* lda, int* info);
void spotrf_(const char* uplo, const int* n, float* A, const int* lda, int* info);
}

namespace depthfem {

namespace {

// Cuts [begin, end) into parts of at most about kBlasTile, as equal as multiples of 8 (the
// register blocks of the BLAS kernels) allow: the boundaries, first and last included.
void cut(int begin, int end, std::vector<int>& bounds) {
  const int size = end - begin, parts = std::max(1, (size + kBlasTile - 1) / kBlasTile);
  for (int p = 0; p < parts; ++p)
    bounds.push_back(begin + int(std::int64_t(size) * p / parts / 8 * 8));
  bounds.push_back(end);
}

// The BLAS routine of each precision under one name.
void gemm_nt(int m, int n, int k, double alpha, const double* A, int lda, const double* B, int ldb,
             double beta, double* C, int ldc) {
  dgemm_("N", "T", &m, &n, &k, &alpha, A, &lda, B, &ldb, &beta, C, &ldc);
}
void gemm_nt(int m, int n, int k, float alpha, const float* A, int lda, const float* B, int ldb,
             float beta, float* C, int ldc) {
  sgemm_("N", "T", &m, &n, &k, &alpha, A, &lda, B, &ldb, &beta, C, &ldc);
}
void syrk_ln(int n, int k, double alpha, const double* A, int lda, double beta, double* C,
             int ldc) {
  dsyrk_("L", "N", &n, &k, &alpha, A, &lda, &beta, C, &ldc);
}
void syrk_ln(int n, int k, float alpha, const float* A, int lda, float beta, float* C, int ldc) {
  ssyrk_("L", "N", &n, &k, &alpha, A, &lda, &beta, C, &ldc);
}
void trsm_rltn(int m, int n, const double* L, int ldl, double* B, int ldb) {
  const double one = 1;
  dtrsm_("R", "L", "T", "N", &m, &n, &one, L, &ldl, B, &ldb);
}
void trsm_rltn(int m, int n, const float* L, int ldl, float* B, int ldb) {
  const float one = 1;
  strsm_("R", "L", "T", "N", &m, &n, &one, L, &ldl, B, &ldb);
}
int potrf_l(int n, double* A, int lda) {
  int info = 0;
  dpotrf_("L", &n, A, &lda, &info);
  return info;
}
int potrf_l(int n, float* A, int lda) {
  int info = 0;
  spotrf_("L", &n, A, &lda, &info);
  return info;
}

}  // namespace

template <class T>
void lower_product(int m, int n, int k, T alpha, const T* A, int lda, T beta, T* C, int ldc) {
  if (m <= 0 || n <= 0) return;
  // Rows cut at the columns' cuts down to n, then below; tile (I, J) for row part I >= column
  // part J: a square of the diagonal (dsyrk) for I = J, else a rectangle (dgemm).
  std::vector<int> rows;
  // Work of the trapezoid: n (n + 1) / 2 + (m - n) n entries of k multiply-adds each.
  if ((double(m) - 0.5 * n) * n * k < kBlasTiledWork) {
    rows = {0, n, m};
  } else {
    cut(0, n, rows);
    rows.pop_back();
    cut(n, m, rows);
  }
  const int columns = static_cast<int>(std::upper_bound(rows.begin(), rows.end(), n - 1) -
                                       rows.begin());  // column parts: rows[0 .. columns]
  std::vector<std::pair<int, int>> tiles;
  for (int J = 0; J < columns; ++J)
    for (int I = J; I + 1 < int(rows.size()); ++I)
      if (rows[I + 1] > rows[I]) tiles.emplace_back(I, J);
  const auto tile = [&](size_t t) {
    const auto [I, J] = tiles[t];
    const int r0 = rows[I], mr = rows[I + 1] - r0, c0 = rows[J], nc = rows[J + 1] - c0;
    T* out = C + r0 + std::size_t(c0) * ldc;
    if (I == J) {
      syrk_ln(nc, k, alpha, A + c0, lda, beta, out, ldc);
    } else {
      gemm_nt(mr, nc, k, alpha, A + r0, lda, A + c0, lda, beta, out, ldc);
    }
  };
  if (tiles.size() <= 2) {
    for (size_t t = 0; t < tiles.size(); ++t) tile(t);
  } else {
    tbb::parallel_for(size_t(0), tiles.size(), tile);
  }
}

template <class T>
void solve_right_lower_transposed(int m, int n, const T* L, int ldl, T* B, int ldb) {
  if (m <= 0 || n <= 0) return;
  // Each row of B is solved on its own: parts of rows.
  std::vector<int> rows;
  if (double(m) * n * n < 2 * kBlasTiledWork) {
    rows = {0, m};
  } else {
    cut(0, m, rows);
  }
  const auto part = [&](int I) { trsm_rltn(rows[I + 1] - rows[I], n, L, ldl, B + rows[I], ldb); };
  if (rows.size() == 2) {
    part(0);
  } else {
    tbb::parallel_for(0, int(rows.size()) - 1, part);
  }
}

template <class T>
int cholesky_lower(int n, T* A, int lda) {
  if (n <= kBlasTile) return potrf_l(n, A, lda);
  // Recursively by halves (LAPACK's recursive scheme): factor the leading block, solve the
  // rows below it, update the trailing block by them (the bulk of the work: one large product,
  // in tiles), factor that.
  const int n1 = n / 2 / 8 * 8, n2 = n - n1;
  int info = cholesky_lower(n1, A, lda);
  if (info != 0) return info;
  T* below = A + n1;
  solve_right_lower_transposed(n2, n1, A, lda, below, lda);
  T* trailing = below + std::size_t(n1) * lda;
  lower_product<T>(n2, n2, n1, -1, below, lda, 1, trailing, lda);
  info = cholesky_lower(n2, trailing, lda);
  return info != 0 ? n1 + info : 0;
}

template void lower_product(int, int, int, double, const double*, int, double, double*, int);
template void lower_product(int, int, int, float, const float*, int, float, float*, int);
template void solve_right_lower_transposed(int, int, const double*, int, double*, int);
template void solve_right_lower_transposed(int, int, const float*, int, float*, int);
template int cholesky_lower(int, double*, int);
template int cholesky_lower(int, float*, int);

}  // namespace depthfem
