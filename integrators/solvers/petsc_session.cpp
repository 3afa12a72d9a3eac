#include "integrators/solvers/petsc_session.hpp"

#include <petscksp.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace depthfem {

void petsc_check(int code, const char* what) {
  if (code == 0) return;
  const char* text = nullptr;
  PetscErrorMessage(static_cast<PetscErrorCode>(code), &text, nullptr);
  throw std::runtime_error(std::string("PETSc ") + what + " failed: " + (text ? text : "?"));
}

namespace {

// PETSc (and MPI, which starts helper threads) is initialised on first use only and finalised
// at exit. Errors come back as codes (no traceback printed); PETSc installs no signal handlers.
struct PetscSession {
  PetscSession() {
    // Started without mpirun, the process is an MPI singleton, and Open MPI (Debian's MPI)
    // looks for a runtime daemon to join and probes every transport before it settles on one:
    // 0.4 s of wall time (0.1 s of CPU) for each run. A singleton needs neither, so unless the
    // user or mpirun chose, it runs isolated with the self transport: 0.15-0.2 s.
    if (!std::getenv("OMPI_COMM_WORLD_SIZE")) {
      setenv("OMPI_MCA_ess_singleton_isolated", "1", 0);
      setenv("OMPI_MCA_pml", "ob1", 0);
      setenv("OMPI_MCA_btl", "self", 0);
    }
    static char arg0[] = "depthfem", arg1[] = "-no_signal_handler";
    static char* args[] = {arg0, arg1, nullptr};
    int argc = 2;
    char** argv = args;
    petsc_check(PetscInitialize(&argc, &argv, nullptr, nullptr), "initialisation");
    petsc_check(PetscPushErrorHandler(PetscReturnErrorHandler, nullptr), "error handler");
    // GAMG aggregates on the squared graph of the first two levels (PETSc's default: the first
    // only): coarser levels and cheaper Galerkin products. Setup per Newton iteration fell by
    // a fifth on the 1.05 M-tet cantilever (5.67 against 7.00 CPU s per Newton iteration, 43
    // against 33 CG iterations) and on the 178 k-tet sliding blocks (1.69 against 2.09); the
    // 164 k-tet cantilever came out even. PETSc 3.18 reads it from its options database only
    // (PCGAMGSetAggressiveLevels leaves the level count unchanged); a value in PETSC_OPTIONS wins.
    PetscBool given = PETSC_FALSE, given_new_name = PETSC_FALSE;
    petsc_check(PetscOptionsHasName(nullptr, nullptr, "-pc_gamg_square_graph", &given), "options");
    petsc_check(
        PetscOptionsHasName(nullptr, nullptr, "-pc_gamg_aggressive_coarsening", &given_new_name),
        "options");
    if (!given && !given_new_name)
      petsc_check(PetscOptionsSetValue(nullptr, "-pc_gamg_square_graph", "2"), "options");
  }
  ~PetscSession() { PetscFinalize(); }
};

}  // namespace

void configure_amg_cg(KSP ksp, const AmgSolverOptions& options) {
  petsc_check(KSPSetType(ksp, KSPCG), "KSPSetType");
  petsc_check(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType");
  petsc_check(KSPSetTolerances(ksp, options.tolerance, 0.0, PETSC_DEFAULT, options.max_iterations),
              "KSPSetTolerances");
  PC pc;
  petsc_check(KSPGetPC(ksp, &pc), "KSPGetPC");
  if (options.preconditioner == AmgPreconditioner::kGamg) {
    petsc_check(PCSetType(pc, PCGAMG), "PCSetType");
    petsc_check(PCGAMGSetReuseInterpolation(pc, PETSC_TRUE), "PCGAMGSetReuseInterpolation");
    // Dropping graph edges weaker than 2 % of the diagonal from the aggregation and stopping at
    // 1000 coarse unknowns: on the bent cantilever (95 k and 266 k unknowns) CG needs 32 and 33
    // iterations for three Newton steps instead of 52 and 55 (PETSc's defaults 0 and 50).
    PetscReal threshold = 0.02;
    petsc_check(PCGAMGSetThreshold(pc, &threshold, 1), "PCGAMGSetThreshold");
    petsc_check(PCGAMGSetCoarseEqLim(pc, 1000), "PCGAMGSetCoarseEqLim");
  } else {
    petsc_check(PCSetType(pc, PCHYPRE), "PCSetType");
    petsc_check(PCHYPRESetType(pc, "boomeramg"), "PCHYPRESetType");
  }
}

void start_petsc() {
  static PetscSession session;
}

}  // namespace depthfem
