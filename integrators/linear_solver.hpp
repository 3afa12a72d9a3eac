#pragma once
/// Linear solvers for the Newton system behind one interface.

#include <Eigen/CholmodSupport>
#include <memory>
#include <string>

#include "core/block_sparse_matrix.hpp"

namespace depthfem {

/// Which method solves A x = b.
enum class LinearSolverKind {
  kGmres,   ///< restarted GMRES, Jacobi (diagonal) preconditioning: the paper's choice
  kCg,      ///< conjugate gradients, Jacobi preconditioning
  kDirect,  ///< sparse Cholesky (CHOLMOD supernodal LL^T; simplicial LDL^T if indefinite)
};

/// The scene-file name of a solver kind.
std::string to_string(LinearSolverKind kind);

struct LinearSolverOptions {
  LinearSolverKind kind = LinearSolverKind::kDirect;
  /// Iterative methods stop when |b - A x| <= tolerance |b| (0.1: the paper's tenfold reduction).
  double tolerance = 0.1;
  /// Iteration cap of the iterative methods (GMRES counts inner iterations over restarts).
  int max_iterations = 1000;
  /// GMRES restart length.
  int restart = 50;
};

/// What a solve did.
struct LinearSolveStats {
  int iterations = 0;              ///< iterative: matrix products; direct: 1
  double relative_residual = 0;    ///< |b - A x| / |b|
  bool reached_tolerance = false;  ///< iterative: tolerance met; direct: factorisation succeeded
};

/// Solves A x = b with the chosen method. The direct method reuses its symbolic analysis while
/// the matrix pattern (number of blocks) is unchanged. A matrix that is not positive definite
/// (past a bifurcation) fails the supernodal LL^T; the solver then factors it as LDL^T, which
/// takes indefinite matrices with nonzero pivots.
class LinearSolver {
 public:
  explicit LinearSolver(LinearSolverOptions options = {});
  const LinearSolverOptions& options() const { return options_; }
  /// Starts from x = 0. Returns statistics; x holds the best solution found.
  LinearSolveStats solve(const BlockSparseMatrix& A, const VectorX& b, VectorX& x);

 private:
  LinearSolveStats gmres(const BlockSparseMatrix& A, const VectorX& b, VectorX& x) const;
  LinearSolveStats cg(const BlockSparseMatrix& A, const VectorX& b, VectorX& x) const;
  LinearSolveStats direct(const BlockSparseMatrix& A, const VectorX& b, VectorX& x);

  LinearSolverOptions options_;
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt_;
  Eigen::CholmodSimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt_;
  Index analysed_blocks_ = -1;
};

}  // namespace depthfem
