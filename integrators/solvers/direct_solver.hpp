#pragma once
/// Sparse direct solver for the symmetric Newton system: CHOLMOD supernodal Cholesky.

#include <cstdint>
#include <memory>

#include "core/block_sparse_matrix.hpp"

namespace depthfem {

/// Fill-reducing ordering of the direct solver, computed on the graph of the 3x3 blocks.
enum class DirectOrdering {
  /// AMD, and METIS too where AMD leaves large fronts; the one with fewer flops. Once METIS
  /// has won, the later patterns of that size are ordered by METIS alone.
  kBest,
  kAmd,    ///< approximate minimum degree
  kMetis,  ///< METIS nested dissection
};

/// What the direct solver does when A is not positive definite (LL^T fails).
enum class IndefiniteFallback {
  kShift,  ///< factor A + s diag|A| by LL^T, s growing until it succeeds: a descent direction
  kLdlt,   ///< factor A itself by simplicial LDL^T: the exact solution of the indefinite system
};

/// The precision of the LL^T factor.
enum class FactorPrecision {
  kDouble,  ///< factor and solve in double
  /// Factor in single precision (twice the flops per second of the dense kernels, half the
  /// bytes) and solve by CG in double preconditioned with it: mixed precision. Where the single
  /// factorisation of an unshifted A fails but the Lanczos estimate finds no negative eigenvalue
  /// (A positive definite beyond single precision's reach), and where CG on the single factor
  /// falls short, A is factored in double.
  kSingle,
};

struct DirectSolverOptions {
  DirectOrdering ordering = DirectOrdering::kBest;
  FactorPrecision precision = FactorPrecision::kDouble;
  IndefiniteFallback indefinite = IndefiniteFallback::kShift;
  /// Solve a new matrix of the same pattern first by CG preconditioned with the kept LL^T factor
  /// of the last one, to |b - A x| <= reuse_tolerance |b|; factor it only when CG needs more
  /// iterations than the factorisation is worth (see DirectSolver). 0: always factor.
  double reuse_tolerance = 1e-3;
};

/// The symbolic analysis of one pattern.
struct DirectAnalysis {
  DirectOrdering ordering = DirectOrdering::kAmd;  ///< the ordering used (kAmd or kMetis)
  double flops = 0;                                ///< of one LL^T factorisation
  double factor_entries = 0;                       ///< nonzeros of L
  /// Patterns since this ordering was computed whose scalar pattern is the analysed one (they
  /// differ from it in couplings of decoupled nodes only): nothing was redone.
  int unchanged = 0;
  /// Patterns since this ordering was computed that fit in its factor (kept it).
  int refitted = 0;
  /// Patterns since this ordering was computed that did not fit in its factor and were
  /// analysed anew under it, their factorisation within 2 % of the flops of the pattern it was
  /// computed for (cheaper than a new ordering: METIS takes several symbolic analyses' time).
  int reanalysed = 0;
  /// The ordering was chosen by computing both AMD and METIS (kBest, large fronts under AMD);
  /// false where one was computed alone.
  bool compared = false;
};

/// The flops of an LL^T factorisation of A predicted from the graph of its 3x3 blocks alone: an
/// AMD ordering and CHOLMOD's column counts of that graph, nine times smaller than the scalar
/// pattern, and no supernodal analysis. A block column of L with c blocks is three scalar
/// columns of about 3c entries, so the scalar flops are about 27 times the block graph's (a
/// slight overestimate, and with AMD where DirectSolver::analyse may find METIS better). This
/// is what LinearSolver's auto compares, before the direct solver is needed. The off-diagonal
/// blocks of `decoupled` nodes are left out, as the direct solver leaves them out.
double predicted_factor_flops(const BlockSparseMatrix& A, std::vector<char> decoupled = {});
/// The scalar entries of A's lower triangle, diagonal included: what flops are counted per (a
/// factorisation's flops per entry are large for a bulky mesh, small for a slender one).
double lower_triangle_entries(const BlockSparseMatrix& A);

/// What one direct solve did.
struct DirectSolveStats {
  bool success = false;   ///< x is finite and solves A x = b (or (A + s diag|A|) x = b)
  bool factored = false;  ///< A was factored (false: CG on the kept factor was enough)
  /// LL^T factorisations that failed (A, or A shifted, not positive definite)
  int failed_factorizations = 0;
  /// Lanczos estimates of the lowest eigenvalue (before LL^T after a shifted factorisation, and
  /// for the shift ladder)
  int estimates = 0;
  /// CG iterations on the kept factor and on a new single-precision factor (also where they
  /// fell short)
  int cg_iterations = 0;
  bool single = false;  ///< the factor that solved (new or kept) is the single-precision one
  double shift = 0;     ///< s of the factored A + s diag|A| (0: A itself)
  bool ldlt = false;    ///< the LDL^T fallback was used
};

/// Solves A x = b for the symmetric block matrix A. The lower triangle is copied into CHOLMOD's
/// compressed-column form through a scalar pattern built once per pattern version; the ordering
/// and symbolic analysis are also done once per pattern version (BlockSparseMatrix::
/// pattern_version()), so that a changed contact pattern with the same number of blocks is
/// analysed anew, or, when all its entries lie in the factor's pattern (new couplings within
/// the fill, or of decoupled nodes), only mapped into the factor analysed before. The fill-reducing
/// ordering is computed on the graph of the 3x3 blocks and expanded to the dofs. A failed LL^T (A
/// indefinite) falls back as the options say. Between Newton iterations the matrix changes little:
/// CG preconditioned by the last LL^T factor converges in a few iterations, each two triangular
/// solves (about 4 nnz(L) flops, memory bound) against a factorisation's F flops (compute bound).
/// CG gets F / (40 nnz(L)) iterations (2 to 50) before the matrix is factored after all. Across
/// Newton iterations and time steps the matrices drift from the factored one and CG needs more
/// iterations: the next matrix is factored (without trying CG) once a solve costs more
/// iterations than the mean over the factor's solves so far, its factorisation counted as those
/// F / (40 nnz(L)) iterations, which keeps that mean near its least.
class DirectSolver {
 public:
  /// Where CG on a new single-precision factor stops when the solve asks for no tolerance (as
  /// exact as the solver makes it): about what a double factor's solve reaches on a stiffness
  /// matrix of condition 1e4.
  static constexpr double kSingleExactTolerance = 1e-12;

  explicit DirectSolver(DirectSolverOptions options = {});
  ~DirectSolver();
  DirectSolver(const DirectSolver&) = delete;
  DirectSolver& operator=(const DirectSolver&) = delete;

  /// Nodes (1 per node, or empty) whose off-diagonal blocks every later A holds zero: the fully
  /// prescribed ones, after Constraints::project. Their couplings are left out of the pattern
  /// that is ordered and factored (which the factor does not change), so that contact with a
  /// prescribed body, coming and going, does not change it.
  void set_decoupled_nodes(std::vector<char> nodes);
  /// Orders and analyses the pattern of A unless it was already (the solve then reuses it). A
  /// new pattern of A whose entries all lie in the pattern of the factor analysed before keeps
  /// that factor's ordering and symbolic analysis.
  const DirectAnalysis& analyse(const BlockSparseMatrix& A);
  /// x = A^-1 b (or (A + s diag|A|)^-1 b, see DirectSolveStats::shift). CG on a kept factor
  /// stops at |b - A x| <= tolerance |b| (0: the options' reuse_tolerance); CG on a new single-
  /// precision factor at tolerance (0: kSingleExactTolerance).
  DirectSolveStats solve(const BlockSparseMatrix& A, const VectorX& b, VectorX& x,
                         double tolerance = 0);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace depthfem
