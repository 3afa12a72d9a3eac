#pragma once
/// PETSc (and MPI under it) started once per process on first use, PETSc's error codes as
/// exceptions, and the AMG-CG settings the serial and the distributed solvers share. Included
/// by the solvers' .cpp files only (it brings PETSc's headers).

#include <petscksp.h>

#include "integrators/solvers/amg_solver.hpp"

namespace depthfem {

/// Initialises PETSc (and MPI) on the first call; later calls do nothing. Finalised at exit.
/// Outside mpirun Open MPI starts as an isolated singleton with the self transport (unless the
/// environment says otherwise); under mpirun nothing is changed.
void start_petsc();

/// Throws std::runtime_error "PETSc <what> failed: <PETSc's message>" when `code` is not 0.
void petsc_check(int code, const char* what);

/// Makes `ksp` CG (unpreconditioned residual norm, options.tolerance and max_iterations) with
/// GAMG (reused interpolation, threshold and coarse size as measured) or BoomerAMG.
void configure_amg_cg(KSP ksp, const AmgSolverOptions& options);

}  // namespace depthfem
