#include "integrators/solvers/amg_solver.hpp"

#include <petscksp.h>

#include <stdexcept>
#include <string>
#include <type_traits>

#include "integrators/solvers/petsc_session.hpp"
#include "integrators/solvers/thread_budget.hpp"

namespace depthfem {

namespace {

static_assert(std::is_same_v<PetscInt, Index>, "PETSc's index type must be depthfem's Index");
static_assert(std::is_same_v<PetscScalar, double>, "PETSc must be built for real doubles");

}  // namespace

struct AmgSolver::Impl {
  AmgSolverOptions options;
  std::uint64_t version = 0;   // pattern version of the PETSc matrix and hierarchy (0: none)
  ScalarPattern pattern;       // all entries, by rows
  std::vector<double> values;  // for MPIAIJ (a sequential A holds its values itself)
  VectorX coordinates;         // interleaved positions for the rigid-body modes
  Mat A = nullptr;
  KSP ksp = nullptr;
  Vec b = nullptr, x = nullptr, coords = nullptr;

  ~Impl() { release(); }
  void release() {
    KSPDestroy(&ksp);
    MatDestroy(&A);
    VecDestroy(&b);
    VecDestroy(&x);
    VecDestroy(&coords);
    version = 0;
    lag_ok = false;
  }
  bool in_place = false;     // A is sequential AIJ: values are written into its array
  bool lag_ok = false;       // the current preconditioner may serve the next matrix
  int setup_iterations = 0;  // CG iterations of the solve that built it

  void set_up(const BlockSparseMatrix& M);
  void update_values(const BlockSparseMatrix& M);
  AmgSolveStats run(const VectorX& rhs, VectorX& sol);
};

void AmgSolver::Impl::set_up(const BlockSparseMatrix& M) {
  release();
  pattern = M.scalar_pattern(Triangle::kFull);
  values.resize(pattern.col.size());
  M.scalar_values(pattern, values.data());
  const PetscInt n = static_cast<PetscInt>(pattern.row_begin.size()) - 1;
  petsc_check(MatCreate(PETSC_COMM_WORLD, &A), "MatCreate");
  petsc_check(MatSetSizes(A, n, n, n, n), "MatSetSizes");
  petsc_check(MatSetBlockSize(A, 3), "MatSetBlockSize");
  // AIJ: PETSc's sequential type on one process, MPIAIJ on several (PETSC_OPTIONS' -mat_type
  // mpiaij forces the latter on one). On one process the sequential kernels are the faster:
  // the 1.05 M-tet cantilever's multigrid set-up took 6.9 s against 9.8 s (its sparse matrix
  // products 5.9 against 8.4 s), the run 1.57 against 2.20 GB. Of the two preallocations only
  // the one for A's type acts.
  petsc_check(MatSetType(A, MATAIJ), "MatSetType");
  petsc_check(MatSetFromOptions(A), "MatSetFromOptions");
  const PetscInt* rows = pattern.row_begin.data();
  petsc_check(MatSeqAIJSetPreallocationCSR(A, rows, pattern.col.data(), values.data()),
              "hand-over");
  petsc_check(MatMPIAIJSetPreallocationCSR(A, rows, pattern.col.data(), values.data()),
              "hand-over");
  PetscBool sequential = PETSC_FALSE;
  petsc_check(PetscObjectTypeCompare(reinterpret_cast<PetscObject>(A), MATSEQAIJ, &sequential),
              "type");
  in_place = sequential;
  MatInfo info;
  petsc_check(MatGetInfo(A, MAT_LOCAL, &info), "MatGetInfo");
  if (info.nz_used != static_cast<PetscLogDouble>(pattern.col.size()))  // A's array is ours
    throw std::logic_error("PETSc's matrix does not hold the pattern's entries");
  if (in_place) values = {};  // later values go straight into A's own array
  petsc_check(MatSetOption(A, MAT_SPD, PETSC_TRUE), "MatSetOption");
  petsc_check(MatCreateVecs(A, &x, &b), "MatCreateVecs");
  petsc_check(VecDuplicate(x, &coords), "VecDuplicate");

  petsc_check(KSPCreate(PETSC_COMM_WORLD, &ksp), "KSPCreate");
  configure_amg_cg(ksp, options);
  petsc_check(KSPSetFromOptions(ksp), "KSPSetFromOptions");
  version = M.pattern_version();
}

void AmgSolver::Impl::update_values(const BlockSparseMatrix& M) {
  if (in_place) {
    PetscScalar* a = nullptr;
    petsc_check(MatSeqAIJGetArrayWrite(A, &a), "MatSeqAIJGetArrayWrite");
    M.scalar_values(pattern, a);
    petsc_check(MatSeqAIJRestoreArrayWrite(A, &a), "MatSeqAIJRestoreArrayWrite");
    return;
  }
  M.scalar_values(pattern, values.data());
  const PetscInt n = static_cast<PetscInt>(pattern.row_begin.size()) - 1;
  petsc_check(MatUpdateMPIAIJWithArrays(A, n, n, n, n, pattern.row_begin.data(), pattern.col.data(),
                                        values.data()),
              "matrix update");
}

AmgSolver::AmgSolver(AmgSolverOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->options = options;
  start_petsc();
}
AmgSolver::~AmgSolver() = default;

AmgSolveStats AmgSolver::solve(const BlockSparseMatrix& M, const VectorX& rhs, VectorX& sol,
                               const Points* positions) {
  // PETSc's vector operations call BLAS, whose threads would change the sums with their count.
  const SerialBlas serial;
  Impl& s = *impl_;
  if (s.version != M.pattern_version()) {
    s.set_up(M);
  } else {
    s.update_values(M);
  }
  if (positions) {  // rigid-body modes at the current positions: 3 translations, 3 rotations
    s.coordinates = as_dofs(*positions);
    petsc_check(VecPlaceArray(s.coords, s.coordinates.data()), "VecPlaceArray");
    MatNullSpace modes;
    petsc_check(MatNullSpaceCreateRigidBody(s.coords, &modes), "MatNullSpaceCreateRigidBody");
    petsc_check(MatSetNearNullSpace(s.A, modes), "MatSetNearNullSpace");
    petsc_check(MatNullSpaceDestroy(&modes), "MatNullSpaceDestroy");
    petsc_check(VecResetArray(s.coords), "VecResetArray");
  }

  // A preconditioner from an earlier matrix of this pattern serves while CG needs at most
  // twice the iterations it needed when it was built; a failed solve with it is repeated with
  // a fresh one.
  AmgSolveStats stats;
  bool reuse = s.lag_ok && s.options.lag_preconditioner;
  for (;;) {
    petsc_check(KSPSetReusePreconditioner(s.ksp, reuse ? PETSC_TRUE : PETSC_FALSE), "reuse");
    petsc_check(KSPSetOperators(s.ksp, s.A, s.A), "KSPSetOperators");
    const AmgSolveStats one = s.run(rhs, sol);
    stats.iterations += one.iterations;
    stats.converged = one.converged;
    if (!reuse) {
      s.setup_iterations = one.iterations;
      s.lag_ok = one.converged;
      break;
    }
    if (one.converged) {
      s.lag_ok = one.iterations <= 2 * s.setup_iterations;
      break;
    }
    reuse = false;
  }
  return stats;
}

AmgSolveStats AmgSolver::Impl::run(const VectorX& rhs, VectorX& sol) {
  sol.setZero(rhs.size());
  petsc_check(VecPlaceArray(b, rhs.data()), "VecPlaceArray");
  petsc_check(VecPlaceArray(x, sol.data()), "VecPlaceArray");
  const PetscErrorCode code = KSPSolve(ksp, b, x);
  VecResetArray(b);
  VecResetArray(x);
  petsc_check(code, "KSPSolve");
  AmgSolveStats stats;
  KSPConvergedReason reason;
  petsc_check(KSPGetIterationNumber(ksp, &stats.iterations), "KSPGetIterationNumber");
  petsc_check(KSPGetConvergedReason(ksp, &reason), "KSPGetConvergedReason");
  stats.converged = reason > 0;
  return stats;
}

}  // namespace depthfem
