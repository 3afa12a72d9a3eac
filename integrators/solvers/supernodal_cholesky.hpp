#pragma once
/// Numeric supernodal LL^T factorisation into a CHOLMOD factor, bitwise the same for any number
/// of threads.

#include <cholmod.h>

#include <cstddef>
#include <memory>
#include <vector>

namespace depthfem {

/// Fills a supernodal CHOLMOD factor L = chol(P A P^T) by CHOLMOD's own left-looking supernodal
/// scheme (supernodes in order; each one gathers the updates of its descendants, factors its
/// diagonal block and solves the rows below it), with the dense work done by the tiled kernels
/// of tiled_blas.hpp. CHOLMOD's cholmod_factorize hands the same dense blocks to a threaded BLAS,
/// whose results change with its thread count; these do not (run under SerialBlas). The
/// factor is CHOLMOD's in every other respect: cholmod_solve2 solves with it.
class SupernodalCholesky {
 public:
  /// For the lower triangle A (stype -1, n x n, real) and L, CHOLMOD's supernodal symbolic
  /// analysis of it (cholmod_analyze_p: its permutation, supernodes and row patterns): where
  /// every entry of A lands in L. L becomes a numeric LL^T factor (values allocated, undefined
  /// until factorize); L and the pattern of A must not change while this is used.
  SupernodalCholesky(const cholmod_sparse& A, cholmod_factor& L, cholmod_common& common);

  /// The same for an A whose pattern may differ from the one L was analysed for: null when an
  /// entry of A falls outside L's pattern (a new analysis is needed), else the mapping, with
  /// which L factors A under L's permutation and supernodes as if analysed for it.
  static std::unique_ptr<SupernodalCholesky> fitted(const cholmod_sparse& A, cholmod_factor& L,
                                                    cholmod_common& common);

  /// L = chol(P A P^T) with A's current values. False when A is not positive definite: then
  /// L->minor is the first column whose pivot is not positive and L is not usable.
  bool factorize(const cholmod_sparse& A, cholmod_factor& L);

 private:
  // Maps A into L; `fits` tells whether every entry of A found its place.
  SupernodalCholesky(const cholmod_sparse& A, cholmod_factor& L, cholmod_common& common,
                     bool& fits);

  std::vector<int> super_of_column_;       // supernode of every column of L
  std::vector<size_t> entry_begin_;        // entries of A per supernode, nsuper + 1
  std::vector<int> entry_source_;          // position in A->x, grouped by supernode
  std::vector<size_t> entry_destination_;  // position in L->x
  // workspace of factorize
  std::vector<int> head_, next_, position_, row_map_, relative_map_;
  std::vector<double> update_;
};

}  // namespace depthfem
