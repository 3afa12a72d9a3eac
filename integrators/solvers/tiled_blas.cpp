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
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha,
            const double* A, const int* lda, const double* beta, double* C, const int* ldc);
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m,
            const int* n, const double* alpha, const double* A, const int* lda, double* B,
            const int* ldb);
void dpotrf_(const char* uplo, const int* n, double* A, const int* lda, int* info);
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

}  // namespace

void lower_product(int m, int n, int k, double alpha, const double* A, int lda, double beta,
                   double* C, int ldc) {
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
    double* out = C + r0 + std::size_t(c0) * ldc;
    if (I == J) {
      dsyrk_("L", "N", &nc, &k, &alpha, A + c0, &lda, &beta, out, &ldc);
    } else {
      dgemm_("N", "T", &mr, &nc, &k, &alpha, A + r0, &lda, A + c0, &lda, &beta, out, &ldc);
    }
  };
  if (tiles.size() <= 2) {
    for (size_t t = 0; t < tiles.size(); ++t) tile(t);
  } else {
    tbb::parallel_for(size_t(0), tiles.size(), tile);
  }
}

void solve_right_lower_transposed(int m, int n, const double* L, int ldl, double* B, int ldb) {
  if (m <= 0 || n <= 0) return;
  const double one = 1;
  // Each row of B is solved on its own: parts of rows.
  std::vector<int> rows;
  if (double(m) * n * n < 2 * kBlasTiledWork) {
    rows = {0, m};
  } else {
    cut(0, m, rows);
  }
  const auto part = [&](int I) {
    const int mr = rows[I + 1] - rows[I];
    dtrsm_("R", "L", "T", "N", &mr, &n, &one, L, &ldl, B + rows[I], &ldb);
  };
  if (rows.size() == 2) {
    part(0);
  } else {
    tbb::parallel_for(0, int(rows.size()) - 1, part);
  }
}

int cholesky_lower(int n, double* A, int lda) {
  int info = 0;
  if (n <= kBlasTile) {
    dpotrf_("L", &n, A, &lda, &info);
    return info;
  }
  // Recursively by halves (LAPACK's recursive scheme): factor the leading block, solve the
  // rows below it, update the trailing block by them (the bulk of the work: one large product,
  // in tiles), factor that.
  const int n1 = n / 2 / 8 * 8, n2 = n - n1;
  info = cholesky_lower(n1, A, lda);
  if (info != 0) return info;
  double* below = A + n1;
  solve_right_lower_transposed(n2, n1, A, lda, below, lda);
  double* trailing = below + std::size_t(n1) * lda;
  lower_product(n2, n2, n1, -1.0, below, lda, 1.0, trailing, lda);
  info = cholesky_lower(n2, trailing, lda);
  return info != 0 ? n1 + info : 0;
}

}  // namespace depthfem
