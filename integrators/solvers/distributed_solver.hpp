#pragma once
/// The Newton system of a distributed run, assembled and solved by PETSc across the ranks.

#include <memory>

#include "core/block_sparse_matrix.hpp"
#include "integrators/solvers/amg_solver.hpp"
#include "integrators/solvers/ranks.hpp"

namespace depthfem {

/// How the ranks solve: PETSc's Krylov method and preconditioner.
enum class DistributedMethod {
  kDirect,  ///< MUMPS' parallel sparse LDL^T (PCCHOLESKY, symmetric indefinite allowed)
  kAmg,     ///< CG with GAMG (AmgSolverOptions), MUMPS where CG fails (A indefinite)
  kGmres,   ///< restarted GMRES, Jacobi preconditioning
  kCg,      ///< CG, Jacobi preconditioning
};

/// Settings of a DistributedSolver.
struct DistributedSolverOptions {
  DistributedMethod method = DistributedMethod::kDirect;
  double tolerance = 0.1;  ///< GMRES and CG with Jacobi: |b - A x| <= tolerance |b|
  int max_iterations = 1000;
  int restart = 50;  ///< GMRES
  /// kDirect: CG on the kept factor first (see DirectSolverOptions::reuse_tolerance; 0: always
  /// factor).
  double reuse_tolerance = 1e-3;
  AmgSolverOptions amg{};  ///< kAmg
};

/// What one distributed solve did.
struct DistributedSolveStats {
  int iterations = 0;  ///< Krylov iterations (1 for a direct solve)
  bool converged = false;
  bool factored = false;  ///< kDirect: A was factored (false: CG on the kept factor was enough)
};

/// Solves A x = b where A is the sum over the ranks of each rank's part (a BlockSparseMatrix over
/// all nodes that holds only the couplings of what this rank evaluated) and b and x are whole
/// vectors that every rank holds alike. A is a PETSc parallel AIJ matrix with block size 3 whose
/// block rows follow the partition (the nodes of rank 0 first, Ranks::node_owner); each rank adds
/// its non-zero 3x3 blocks (ADD_VALUES) and PETSc's assembly carries those of other ranks' rows to
/// them. Its layout is preallocated (MATPREALLOCATOR) whenever some rank's pattern changed; the
/// solution is scattered back to every rank (VecScatterCreateToAll). PETSC_OPTIONS overrides
/// the method (-ksp_type, -pc_type, -pc_factor_mat_solver_type). Newton projects each rank's
/// part (Constraints::project), which puts a constrained node's C on its diagonal once per rank
/// whose part touches the node: those directions stay decoupled with a zero right-hand side, so
/// the step is the same, only their diagonal is scaled.
class DistributedSolver {
 public:
  DistributedSolver(Ranks& ranks, DistributedSolverOptions options);
  ~DistributedSolver();
  DistributedSolver(const DistributedSolver&) = delete;
  DistributedSolver& operator=(const DistributedSolver&) = delete;

  /// x = A^-1 b (x from zero); `positions` (#nodes x 3) give GAMG its rigid-body modes. With
  /// kDirect, CG on the kept factor stops at |b - A x| <= tolerance |b| (0: the options'
  /// reuse_tolerance).
  DistributedSolveStats solve(const BlockSparseMatrix& part, const VectorX& b, VectorX& x,
                              const Points* positions, double tolerance = 0);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace depthfem
