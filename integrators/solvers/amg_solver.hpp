#pragma once
/// Conjugate gradients preconditioned by algebraic multigrid, through PETSc.

#include <cstdint>
#include <memory>

#include "core/block_sparse_matrix.hpp"

namespace depthfem {

/// The multigrid preconditioner.
enum class AmgPreconditioner {
  kGamg,       ///< PETSc's smoothed aggregation (GAMG), rigid-body modes as near-null space
  kBoomerAmg,  ///< hypre's BoomerAMG (classical), nodal coarsening
};

struct AmgSolverOptions {
  AmgPreconditioner preconditioner = AmgPreconditioner::kGamg;
  /// Stop when |b - A x| <= tolerance |b|. Newton then needs as many steps as with exact
  /// solves on the benchmark scenes, and a third fewer CG iterations than at 1e-6.
  double tolerance = 1e-3;
  int max_iterations = 500;
  /// Keep the preconditioner across matrices of one pattern while CG needs at most twice the
  /// iterations it needed when the preconditioner was built.
  bool lag_preconditioner = true;
};

/// What one AMG-CG solve did.
struct AmgSolveStats {
  int iterations = 0;
  bool converged = false;  ///< tolerance met (false also on negative curvature: A indefinite)
};

/// Solves A x = b for the symmetric positive definite block matrix A by PETSc's CG with an
/// algebraic multigrid preconditioner. The matrix goes to PETSc as AIJ with block size 3: the
/// sequential type on one process (values then written straight into its array), MPIAIJ, the
/// type a multi-process run distributes, on several; its scalar pattern is built once per
/// pattern version and only the values are copied afterwards. The multigrid hierarchy is rebuilt
/// for a new pattern; for new values of the same pattern GAMG keeps its interpolation and only
/// recomputes the coarse operators. PETSc (and MPI) are initialised on first construction and
/// finalised at exit; PETSC_OPTIONS in the environment can override every setting.
class AmgSolver {
 public:
  explicit AmgSolver(AmgSolverOptions options = {});
  ~AmgSolver();
  AmgSolver(const AmgSolver&) = delete;
  AmgSolver& operator=(const AmgSolver&) = delete;

  /// x = A^-1 b from x = 0. `positions` (#nodes x 3, current) span the rigid-body modes;
  /// without them GAMG takes the translations only.
  AmgSolveStats solve(const BlockSparseMatrix& A, const VectorX& b, VectorX& x,
                      const Points* positions);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace depthfem
