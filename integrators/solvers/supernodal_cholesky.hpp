#pragma once
/// Numeric supernodal LL^T factorisation into a CHOLMOD factor, bitwise the same for any number
/// of threads.

#include <cholmod.h>
#include <tbb/enumerable_thread_specific.h>

#include <cstddef>
#include <memory>
#include <vector>

namespace depthfem {

/// Fills a supernodal CHOLMOD factor L = chol(P A P^T) by CHOLMOD's own left-looking supernodal
/// scheme (each supernode gathers the updates of its descendants, factors its diagonal block and
/// solves the rows below it), with the dense work done by the tiled kernels of tiled_blas.hpp.
/// Supernodes in separate subtrees of the elimination tree run on separate threads; each one sums
/// its updates in the order of CHOLMOD's sequential loop. CHOLMOD's cholmod_factorize hands the
/// same dense blocks to a threaded BLAS, whose results change with its thread count; these do
/// not (run under SerialBlas). The factor is CHOLMOD's in every other respect: cholmod_solve2
/// solves with it.
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
  /// L->minor is the first column whose pivot is not positive and L is not usable. The subtrees
  /// of the supernodes where the last kProbes failed factorisations failed (the probes) are
  /// factored first (each a principal submatrix of A: where one is not positive definite,
  /// neither is A), and the factorisation stops there when they fail; L->minor is then the first
  /// failing column of those subtrees. A matrix that fails where a recent one failed (the rungs
  /// of a shift ladder, a failed single-precision factorisation retried in double, the next
  /// Newton iteration's matrix) costs those subtrees, not every supernode before the failing
  /// column. The factor and the outcome are bitwise those of one pass in the sequential order.
  bool factorize(const cholmod_sparse& A, cholmod_factor& L);
  /// The same in single precision: the factor's values, in L's layout (L->x's positions), go
  /// to `values` instead of L->x. Half the bytes and about twice the flops per second of the
  /// double factor, and about 1e-7 of its accuracy relative to A's condition number
  /// (DirectSolver uses it as CG's preconditioner).
  bool factorize(const cholmod_sparse& A, cholmod_factor& L, std::vector<float>& values);
  /// x = A^-1 b (n values each) with the single-precision factor `values` of L, summed in double.
  void solve(const cholmod_factor& L, const std::vector<float>& values, const double* b, double* x);
  /// The supernodes the last factorisation computed (all of them where it succeeded).
  int last_factored() const { return last_factored_; }
  /// Where the last factorisation failed, its failed pivot (the diagonal entry of the Schur
  /// complement at L->minor, not positive) over A's diagonal entry there; 0 where it succeeded
  /// or where that entry is not positive. Rounding alone takes the pivots of a positive definite
  /// A below zero by a small multiple of the precision's unit roundoff times this scale (the
  /// squares that column's L row sums equal A's entry); a pivot far below that proves A itself
  /// indefinite, not only beyond the precision's reach.
  double failed_pivot() const { return failed_pivot_; }
  /// Probes first where `before`, of the same L, failed (a fitted pattern keeps L's supernodes).
  void keep_probes_of(const SupernodalCholesky& before);

  static constexpr size_t kProbes = 8;

 private:
  // Maps A into L; `fits` tells whether every entry of A found its place.
  SupernodalCholesky(const cholmod_sparse& A, cholmod_factor& L, cholmod_common& common,
                     bool& fits);

  // One descendant's update of a supernode: rows first .. past-1 of the descendant are the
  // supernode's columns it updates, the rows from first on those the update touches.
  struct Update {
    int descendant, first, past;
  };
  // What one thread needs for one supernode at a time, kept between factorisations.
  struct Workspace {
    std::vector<int> row_map, relative_map;  // of L's rows (n): in the supernode, in the update
    std::vector<double> update;
    std::vector<float> update_single;
    int failed_column = 0;
  };
  // Finds the updates of every supernode and the supernodal elimination tree.
  void schedule(const cholmod_factor& L);
  // Supernode s of L (values Lx, in L's layout) from A and its descendants' final columns:
  // false when a pivot is not positive (w.failed_column).
  template <class T>
  bool factorize_supernode(int s, const cholmod_sparse& A, const cholmod_factor& L, T* Lx,
                           Workspace& w) const;
  // The whole factorisation into Lx; sets L.minor.
  template <class T>
  bool factorize_into(const cholmod_sparse& A, cholmod_factor& L, T* Lx);
  // failed_pivot() of a factorisation into Lx that failed at `column`.
  template <class T>
  double failed_pivot_ratio(const cholmod_sparse& A, const cholmod_factor& L, const T* Lx,
                            int column) const;

  std::vector<int> super_of_column_;       // supernode of every column of L
  std::vector<size_t> entry_begin_;        // entries of A per supernode, nsuper + 1
  std::vector<int> entry_source_;          // position in A->x, grouped by supernode
  std::vector<size_t> entry_destination_;  // position in L->x
  std::vector<size_t> update_begin_;       // updates per supernode, nsuper + 1
  std::vector<Update> updates_;            // in the order each supernode sums them
  std::vector<int> parent_;                // in the supernodal elimination tree (-1: a root)
  std::vector<int> children_;              // in that tree
  tbb::enumerable_thread_specific<Workspace> workspaces_;
  std::vector<int> probes_;  // supernodes where the last failed factorisations failed, latest first
  int last_factored_ = 0;
  double failed_pivot_ = 0;         // failed_pivot()
  std::vector<double> solve_work_;  // solve(): the permuted vector
  std::vector<double> solve_rows_;  // solve(): one supernode's rows
};

}  // namespace depthfem
