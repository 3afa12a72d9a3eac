#pragma once
/// Linear solvers for the Newton system behind one interface.

#include <memory>
#include <string>

#include "core/block_sparse_matrix.hpp"
#include "integrators/solvers/amg_solver.hpp"
#include "integrators/solvers/direct_solver.hpp"
#include "integrators/solvers/distributed_solver.hpp"

namespace depthfem {

/// Which method solves A x = b.
enum class LinearSolverKind {
  kAuto,    ///< direct or AMG-CG by the predicted cost of the factorisation (see LinearSolver)
  kDirect,  ///< sparse Cholesky (DirectSolver)
  kAmg,     ///< CG with algebraic multigrid through PETSc (AmgSolver); direct where CG fails
  kGmres,   ///< restarted GMRES, Jacobi (diagonal) preconditioning: the paper's choice
  kCg,      ///< conjugate gradients, Jacobi preconditioning
};

/// The scene-file name of a solver kind.
std::string to_string(LinearSolverKind kind);

struct LinearSolverOptions {
  LinearSolverKind kind = LinearSolverKind::kAuto;
  /// Jacobi-preconditioned methods stop when |b - A x| <= tolerance |b| (0.1: the paper's
  /// tenfold reduction).
  double tolerance = 0.1;
  /// Iteration cap of the Jacobi-preconditioned methods (GMRES: inner iterations over restarts).
  int max_iterations = 1000;
  /// GMRES restart length.
  int restart = 50;
  DirectSolverOptions direct{};
  AmgSolverOptions amg{};
  /// kAuto: AMG-CG when a factorisation would take more flops than this per entry of the
  /// matrix's lower triangle (the measured crossover, bench/results/scaling.md).
  double auto_flops_per_entry = 2e4;
};

/// What a solve did.
struct LinearSolveStats {
  int iterations = 0;  ///< iterative: matrix products; direct: factorisations + CG iterations
  double relative_residual = 0;    ///< |b - A x| / |b|
  bool reached_tolerance = false;  ///< iterative: tolerance met; direct: factorisation succeeded
  double shift = 0;                ///< direct: s of the factored A + s diag|A| (A indefinite)
  bool factored = false;           ///< direct: A was factored anew (not CG on a kept factor)
};

/// Solves A x = b with the chosen method (see DirectSolver and AmgSolver). kAuto decides on the
/// first matrix: the graph of its 3x3 blocks predicts the flops F of a factorisation
/// (predicted_factor_flops), which grow with the separators of the mesh (a slender bar factors
/// in few flops per entry, a bulky block in many); a cycle of AMG-CG costs a fixed amount per
/// matrix entry. F above auto_flops_per_entry times the entries of the lower triangle chooses
/// AMG-CG, and PETSc is started only then; otherwise the direct solver analyses the pattern.
/// A matrix that AMG-CG fails on (indefinite) is solved directly.
class LinearSolver {
 public:
  explicit LinearSolver(LinearSolverOptions options = {});
  const LinearSolverOptions& options() const { return options_; }
  /// Nodes whose off-diagonal blocks every matrix to solve holds zero (1 per node; see
  /// DirectSolver::set_decoupled_nodes).
  void set_decoupled_nodes(std::vector<char> nodes);
  /// Solves every later system across `ranks` (DistributedSolver; which must outlive this):
  /// A is then each rank's part, b and x whole on every rank. kDirect takes MUMPS, kAmg CG with
  /// GAMG (MUMPS where CG fails), kGmres and kCg PETSc's Jacobi-preconditioned methods with this
  /// solver's tolerance and caps; kAuto one of the first two by the serial rule, applied to the
  /// pattern of the whole first matrix (gathered from the ranks' parts).
  void distribute(Ranks& ranks);
  /// Starts from x = 0. Returns statistics; x holds the best solution found. `positions`
  /// (#nodes x 3, current) give AMG its rigid-body modes (without them: translations only).
  /// `tolerance` (Newton's forcing term; 0: none) is where the direct solver's CG on a kept
  /// factor stops, |b - A x| <= tolerance |b|, instead of its own reuse tolerance: looser far
  /// from the solution, which saves factorisations, tighter near it, which keeps Newton
  /// quadratic. The iterative methods keep their own tolerances: AMG-CG's cost is its setup,
  /// and a looser solve only cost it Newton iterations (the 160 x 16 x 16 cantilever: 4 instead
  /// of 3, 10 % more time); the Jacobi methods stop at the paper's tenfold reduction.
  LinearSolveStats solve(const BlockSparseMatrix& A, const VectorX& b, VectorX& x,
                         const Points* positions = nullptr, double tolerance = 0);

 private:
  LinearSolveStats gmres(const BlockSparseMatrix& A, const VectorX& b, VectorX& x) const;
  LinearSolveStats cg(const BlockSparseMatrix& A, const VectorX& b, VectorX& x) const;
  LinearSolveStats direct(const BlockSparseMatrix& A, const VectorX& b, VectorX& x,
                          double tolerance);
  LinearSolveStats amg(const BlockSparseMatrix& A, const VectorX& b, VectorX& x,
                       const Points* positions);

  LinearSolverOptions options_;
  std::vector<char> decoupled_;
  std::unique_ptr<DirectSolver> direct_;            // created on first use
  std::unique_ptr<AmgSolver> amg_;                  // created on first use (starts PETSc and MPI)
  std::unique_ptr<DistributedSolver> distributed_;  // a distributed run's
  enum class Choice { kUndecided, kDirect, kAmg } choice_ = Choice::kUndecided;  // kAuto
  Choice choose(const BlockSparseMatrix& A) const;  // kAuto's rule for the whole matrix A
  void start_distributed(LinearSolverKind kind);
  Ranks* ranks_ = nullptr;  // a distributed run's
};

}  // namespace depthfem
