#include "integrators/solvers/distributed_solver.hpp"

#include <petscksp.h>

#include <algorithm>
#include <vector>

#include "integrators/solvers/kept_factor.hpp"
#include "integrators/solvers/petsc_session.hpp"
#include "integrators/solvers/thread_budget.hpp"

namespace depthfem {

struct DistributedSolver::Impl {
  Ranks& ranks;
  DistributedSolverOptions options;
  std::vector<PetscInt> row_of;   // node -> PETSc block row: the nodes of rank 0, of rank 1, ...
  std::vector<Index> node_at;     // PETSc block row -> node
  PetscInt first = 0, count = 0;  // this rank's block rows
  std::uint64_t version = 0;      // pattern version of this rank's part behind A (0: none)
  Mat A = nullptr;
  KSP ksp = nullptr, fallback = nullptr;
  KSP reuse = nullptr;  // CG on the kept MUMPS factor of ksp (kDirect)
  KeptFactor kept;      // ksp's MUMPS factor, kept for the matrices after the factored one
  Vec b = nullptr, x = nullptr, all = nullptr, coords = nullptr;
  VecScatter to_all = nullptr;
  std::vector<PetscInt> cols;      // one block row's columns
  std::vector<PetscScalar> block;  // its values, 3 rows of 3 * cols, by rows

  Impl(Ranks& r, DistributedSolverOptions o) : ranks(r), options(o) {}
  ~Impl() { release(); }
  void release() {
    KSPDestroy(&reuse);
    kept.drop();
    KSPDestroy(&fallback);
    KSPDestroy(&ksp);
    VecScatterDestroy(&to_all);
    VecDestroy(&all);
    VecDestroy(&coords);
    VecDestroy(&b);
    VecDestroy(&x);
    MatDestroy(&A);
    version = 0;
  }
  // Calls insert(row, columns, values) for every block row of `part` with the blocks of it
  // that `keep` takes, in PETSc's numbering.
  template <class Keep>
  void add_rows(Mat M, const BlockSparseMatrix& part, Keep keep, InsertMode mode);
  void set_up(const BlockSparseMatrix& part);
  KSP make_ksp(DistributedMethod method) const;
  bool run(KSP solver, int& iterations);
  bool run_direct(KSP solver, int& iterations);
  bool reuse_factor(double tolerance, int& iterations);
  void keep_factor();
};

template <class Keep>
void DistributedSolver::Impl::add_rows(Mat M, const BlockSparseMatrix& part, Keep keep,
                                       InsertMode mode) {
  for (Index i = 0; i < part.num_nodes(); ++i) {
    cols.clear();
    block.clear();
    const Index n = part.row_begin(i + 1) - part.row_begin(i);
    block.resize(static_cast<size_t>(9 * n));
    for (Index k = part.row_begin(i); k < part.row_begin(i + 1); ++k) {
      if (!keep(k)) continue;
      const Index c = static_cast<Index>(cols.size());
      cols.push_back(row_of[static_cast<size_t>(part.block_col(k))]);
      const auto B = part.block(k);
      for (int r = 0; r < 3; ++r)
        for (int s = 0; s < 3; ++s) block[static_cast<size_t>((r * n + c) * 3 + s)] = B(r, s);
    }
    if (cols.empty()) continue;
    // The rows of `block` are 3 n long; PETSc reads them 3 * cols.size() long.
    const Index m = static_cast<Index>(cols.size());
    for (int r = 1; r < 3; ++r)
      std::copy_n(block.begin() + r * 3 * n, 3 * m, block.begin() + r * 3 * m);
    const PetscInt row = row_of[static_cast<size_t>(i)];
    petsc_check(
        MatSetValuesBlocked(M, 1, &row, static_cast<PetscInt>(m), cols.data(), block.data(), mode),
        "MatSetValuesBlocked");
  }
}

KSP DistributedSolver::Impl::make_ksp(DistributedMethod method) const {
  KSP solver = nullptr;
  PC pc = nullptr;
  petsc_check(KSPCreate(PETSC_COMM_WORLD, &solver), "KSPCreate");
  petsc_check(KSPGetPC(solver, &pc), "KSPGetPC");
  switch (method) {
    case DistributedMethod::kDirect:
      petsc_check(KSPSetType(solver, KSPPREONLY), "KSPSetType");
      petsc_check(PCSetType(pc, PCCHOLESKY), "PCSetType");
      petsc_check(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS), "PCFactorSetMatSolverType");
      {
        // MUMPS sizes its workspace from the analysis plus ICNTL(14) percent (20); the pivots
        // an indefinite contact matrix delays outgrew that in 3 of 5 sliding
        // blocks runs on two ranks (INFOG(1) = -9); with 100 % more, none of 4.
        Mat factor = nullptr;
        petsc_check(KSPSetOperators(solver, A, A), "KSPSetOperators");
        petsc_check(PCFactorSetUpMatSolverType(pc), "PCFactorSetUpMatSolverType");
        petsc_check(PCFactorGetMatrix(pc, &factor), "PCFactorGetMatrix");
        petsc_check(MatMumpsSetIcntl(factor, 14, 100), "MatMumpsSetIcntl");
        // The root node factored by MUMPS itself, not ScaLAPACK, so that INFOG(12) counts all
        // negative pivots (run_direct reads the inertia from it).
        petsc_check(MatMumpsSetIcntl(factor, 13, 1), "MatMumpsSetIcntl");
      }
      break;
    case DistributedMethod::kAmg:
      configure_amg_cg(solver, options.amg);
      break;
    case DistributedMethod::kGmres:
    case DistributedMethod::kCg:
      // As the serial Jacobi methods: the true residual, |b - A x| <= tolerance |b|.
      if (method == DistributedMethod::kGmres) {
        petsc_check(KSPSetType(solver, KSPGMRES), "KSPSetType");
        petsc_check(KSPGMRESSetRestart(solver, options.restart), "KSPGMRESSetRestart");
        petsc_check(KSPSetPCSide(solver, PC_RIGHT), "KSPSetPCSide");
      } else {
        petsc_check(KSPSetType(solver, KSPCG), "KSPSetType");
      }
      petsc_check(KSPSetNormType(solver, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType");
      petsc_check(PCSetType(pc, PCJACOBI), "PCSetType");
      petsc_check(
          KSPSetTolerances(solver, options.tolerance, 0.0, PETSC_DEFAULT, options.max_iterations),
          "KSPSetTolerances");
      break;
  }
  petsc_check(KSPSetFromOptions(solver), "KSPSetFromOptions");
  return solver;
}

void DistributedSolver::Impl::set_up(const BlockSparseMatrix& part) {
  // A collective rebuild: every rank takes part when any rank's pattern changed.
  const bool changed = ranks.sum(part.pattern_version() != version ? 1.0 : 0.0) > 0;
  if (changed) {
    release();
    const PetscInt n = 3 * static_cast<PetscInt>(row_of.size()), local = 3 * count;
    Mat layout = nullptr;
    petsc_check(MatCreate(PETSC_COMM_WORLD, &layout), "MatCreate");
    petsc_check(MatSetType(layout, MATPREALLOCATOR), "MatSetType");
    petsc_check(MatSetSizes(layout, local, local, n, n), "MatSetSizes");
    petsc_check(MatSetBlockSize(layout, 3), "MatSetBlockSize");
    petsc_check(MatSetUp(layout), "MatSetUp");
    add_rows(
        layout, part, [](Index) { return true; }, INSERT_VALUES);
    petsc_check(MatAssemblyBegin(layout, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
    petsc_check(MatAssemblyEnd(layout, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
    petsc_check(MatCreate(PETSC_COMM_WORLD, &A), "MatCreate");
    petsc_check(MatSetType(A, MATAIJ), "MatSetType");
    petsc_check(MatSetSizes(A, local, local, n, n), "MatSetSizes");
    petsc_check(MatSetBlockSize(A, 3), "MatSetBlockSize");
    petsc_check(MatSetFromOptions(A), "MatSetFromOptions");
    petsc_check(MatPreallocatorPreallocate(layout, PETSC_TRUE, A), "MatPreallocatorPreallocate");
    MatDestroy(&layout);
    petsc_check(MatCreateVecs(A, &x, &b), "MatCreateVecs");
    petsc_check(VecDuplicate(x, &coords), "VecDuplicate");
    petsc_check(VecScatterCreateToAll(x, &to_all, &all), "VecScatterCreateToAll");
    ksp = make_ksp(options.method);
    version = part.pattern_version();
  }
  petsc_check(MatZeroEntries(A), "MatZeroEntries");
  // A rank's part holds zero blocks where its pattern has room for couplings another rank
  // evaluates (contact pairs of tets it does not own): only the others travel.
  add_rows(
      A, part, [&](Index k) { return !part.block(k).isZero(0); }, ADD_VALUES);
  petsc_check(MatAssemblyBegin(A, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
  petsc_check(MatAssemblyEnd(A, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
}

bool DistributedSolver::Impl::run(KSP solver, int& iterations) {
  petsc_check(KSPSetOperators(solver, A, A), "KSPSetOperators");
  petsc_check(VecSet(x, 0.0), "VecSet");
  petsc_check(KSPSolve(solver, b, x), "KSPSolve");
  PetscInt its = 0;
  KSPConvergedReason reason;
  petsc_check(KSPGetIterationNumber(solver, &its), "KSPGetIterationNumber");
  petsc_check(KSPGetConvergedReason(solver, &reason), "KSPGetConvergedReason");
  iterations += std::max<int>(1, static_cast<int>(its));
  return reason > 0;
}

namespace {

// The negative pivots of MUMPS' last LDL^T factorisation by `solver`: the matrix's negative
// eigenvalues (Sylvester's law of inertia).
PetscInt negative_pivots(KSP solver) {
  PC pc = nullptr;
  Mat factor = nullptr;
  PetscInt count = 0;
  petsc_check(KSPGetPC(solver, &pc), "KSPGetPC");
  petsc_check(PCFactorGetMatrix(pc, &factor), "PCFactorGetMatrix");
  petsc_check(MatMumpsGetInfog(factor, 12, &count), "MatMumpsGetInfog");
  return count;
}

}  // namespace

bool DistributedSolver::Impl::run_direct(KSP solver, int& iterations) {
  if (run(solver, iterations) && negative_pivots(solver) == 0) return true;
  // MUMPS' LDL^T solves an indefinite matrix (deep contact, buckling) exactly, where the serial
  // direct solver's LL^T fails and it factors A + s D instead, D the diagonal of |A| floored at
  // 1e-12 of its largest entry: so does this, with s from 1e-3 raised fourfold until the
  // factorisation has no negative pivot (the serial solver starts from an eigenvalue estimate;
  // the same rule otherwise, so that a distributed run takes the serial run's Newton path
  // through indefinite systems instead of the exact Newton step). A is rebuilt for the next
  // solve anyway.
  Vec d = nullptr, step = nullptr;
  petsc_check(MatCreateVecs(A, &d, nullptr), "MatCreateVecs");
  petsc_check(VecDuplicate(d, &step), "VecDuplicate");
  petsc_check(MatGetDiagonal(A, d), "MatGetDiagonal");
  petsc_check(VecAbs(d), "VecAbs");
  PetscReal largest = 0;
  petsc_check(VecMax(d, nullptr, &largest), "VecMax");
  PetscScalar* entry = nullptr;
  PetscInt length = 0;
  petsc_check(VecGetLocalSize(d, &length), "VecGetLocalSize");
  petsc_check(VecGetArray(d, &entry), "VecGetArray");
  for (PetscInt i = 0; i < length; ++i) entry[i] = std::max(entry[i], 1e-12 * largest);
  VecRestoreArray(d, &entry);
  bool solved = false;
  for (double s = 1e-3, applied = 0; s < 1e3 && !solved; applied = s, s *= 4) {
    petsc_check(VecAXPBY(step, s - applied, 0.0, d), "VecAXPBY");
    petsc_check(MatDiagonalSet(A, step, ADD_VALUES), "MatDiagonalSet");
    solved = run(solver, iterations) && negative_pivots(solver) == 0;
  }
  VecDestroy(&step);
  VecDestroy(&d);
  return solved;
}

// CG preconditioned by the kept factor of ksp (of an earlier matrix of this pattern, shifted or
// not), to |b - A x| <= tolerance |b| in at most kept.max_iterations(); false when it falls
// short or meets negative curvature.
bool DistributedSolver::Impl::reuse_factor(double tolerance, int& iterations) {
  PC pc = nullptr;
  petsc_check(KSPGetPC(ksp, &pc), "KSPGetPC");
  if (!reuse) {
    petsc_check(KSPCreate(PETSC_COMM_WORLD, &reuse), "KSPCreate");
    petsc_check(KSPSetType(reuse, KSPCG), "KSPSetType");
    petsc_check(KSPSetPC(reuse, pc), "KSPSetPC");
    petsc_check(KSPSetNormType(reuse, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType");
  }
  const int cap = kept.max_iterations();
  petsc_check(KSPSetTolerances(reuse, tolerance, 0.0, PETSC_DEFAULT, cap), "KSPSetTolerances");
  // The shared preconditioner keeps its factor while CG runs on the new A.
  petsc_check(PCSetReusePreconditioner(pc, PETSC_TRUE), "PCSetReusePreconditioner");
  petsc_check(KSPSetOperators(reuse, A, A), "KSPSetOperators");
  petsc_check(VecSet(x, 0.0), "VecSet");
  petsc_check(KSPSolve(reuse, b, x), "KSPSolve");
  petsc_check(PCSetReusePreconditioner(pc, PETSC_FALSE), "PCSetReusePreconditioner");
  PetscInt its = 0;
  KSPConvergedReason reason;
  petsc_check(KSPGetIterationNumber(reuse, &its), "KSPGetIterationNumber");
  petsc_check(KSPGetConvergedReason(reuse, &reason), "KSPGetConvergedReason");
  iterations += static_cast<int>(its);
  if (reason <= 0) return false;
  kept.record(static_cast<int>(its));
  return true;
}

// Keeps a new factor, with MUMPS' flops (RINFOG(3)) and entries (INFOG(29), negative: millions).
void DistributedSolver::Impl::keep_factor() {
  PC pc = nullptr;
  Mat factor = nullptr;
  PetscReal flops = 0;
  PetscInt entries = 0;
  petsc_check(KSPGetPC(ksp, &pc), "KSPGetPC");
  petsc_check(PCFactorGetMatrix(pc, &factor), "PCFactorGetMatrix");
  petsc_check(MatMumpsGetRinfog(factor, 3, &flops), "MatMumpsGetRinfog");
  petsc_check(MatMumpsGetInfog(factor, 29, &entries), "MatMumpsGetInfog");
  kept.start(flops, entries < 0 ? -1e6 * double(entries) : double(entries));
}

DistributedSolver::DistributedSolver(Ranks& ranks, DistributedSolverOptions options)
    : impl_(std::make_unique<Impl>(ranks, options)) {
  Impl& s = *impl_;
  const std::vector<int>& owner = ranks.node_owner();
  std::vector<PetscInt> next(static_cast<size_t>(ranks.size()) + 1, 0);
  for (const int o : owner) ++next[static_cast<size_t>(o) + 1];
  for (size_t r = 1; r < next.size(); ++r) next[r] += next[r - 1];
  s.first = next[static_cast<size_t>(ranks.rank())];
  s.count = next[static_cast<size_t>(ranks.rank()) + 1] - s.first;
  s.row_of.resize(owner.size());
  s.node_at.resize(owner.size());
  for (size_t i = 0; i < owner.size(); ++i) {
    const PetscInt row = next[static_cast<size_t>(owner[i])]++;
    s.row_of[i] = row;
    s.node_at[static_cast<size_t>(row)] = static_cast<Index>(i);
  }
}

DistributedSolver::~DistributedSolver() = default;

DistributedSolveStats DistributedSolver::solve(const BlockSparseMatrix& part, const VectorX& rhs,
                                               VectorX& sol, const Points* positions,
                                               double tolerance) {
  const SerialBlas serial;  // PETSc's vector operations call BLAS
  Impl& s = *impl_;
  s.set_up(part);
  PetscScalar* local = nullptr;
  petsc_check(VecGetArray(s.b, &local), "VecGetArray");
  for (PetscInt k = 0; k < s.count; ++k)
    for (int c = 0; c < 3; ++c) local[3 * k + c] = rhs(3 * s.node_at[s.first + k] + c);
  VecRestoreArray(s.b, &local);
  if (positions && s.options.method == DistributedMethod::kAmg) {
    petsc_check(VecGetArray(s.coords, &local), "VecGetArray");
    for (PetscInt k = 0; k < s.count; ++k)
      for (int c = 0; c < 3; ++c) local[3 * k + c] = (*positions)(s.node_at[s.first + k], c);
    VecRestoreArray(s.coords, &local);
    MatNullSpace modes;
    petsc_check(MatNullSpaceCreateRigidBody(s.coords, &modes), "MatNullSpaceCreateRigidBody");
    petsc_check(MatSetNearNullSpace(s.A, modes), "MatSetNearNullSpace");
    MatNullSpaceDestroy(&modes);
  }
  DistributedSolveStats stats;
  if (s.options.method == DistributedMethod::kDirect) {
    // As DirectSolver: CG on the kept factor first, the matrix factored once CG costs more than
    // the mean over the factor's solves.
    if (s.options.reuse_tolerance > 0 && s.kept.try_cg() &&
        s.reuse_factor(tolerance > 0 ? tolerance : s.options.reuse_tolerance, stats.iterations)) {
      stats.converged = true;
    } else {
      stats.converged = s.run_direct(s.ksp, stats.iterations);
      stats.factored = true;
      if (stats.converged)
        s.keep_factor();
      else
        s.kept.drop();
    }
  } else {
    stats.converged = s.run(s.ksp, stats.iterations);
  }
  if (!stats.converged && s.options.method == DistributedMethod::kAmg) {
    // CG stops on an indefinite matrix (deep contact, buckling): MUMPS' LDL^T solves it.
    if (!s.fallback) s.fallback = s.make_ksp(DistributedMethod::kDirect);
    stats.converged = s.run_direct(s.fallback, stats.iterations);
  }
  petsc_check(VecScatterBegin(s.to_all, s.x, s.all, INSERT_VALUES, SCATTER_FORWARD),
              "VecScatterBegin");
  petsc_check(VecScatterEnd(s.to_all, s.x, s.all, INSERT_VALUES, SCATTER_FORWARD), "VecScatterEnd");
  const PetscScalar* whole = nullptr;
  petsc_check(VecGetArrayRead(s.all, &whole), "VecGetArrayRead");
  sol.resize(rhs.size());
  for (size_t i = 0; i < s.row_of.size(); ++i)
    for (int c = 0; c < 3; ++c) sol(3 * static_cast<Index>(i) + c) = whole[3 * s.row_of[i] + c];
  VecRestoreArrayRead(s.all, &whole);
  return stats;
}

}  // namespace depthfem
