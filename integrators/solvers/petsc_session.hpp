#pragma once
/// PETSc (and MPI under it) started once per process on first use, and PETSc's error codes as
/// exceptions.

namespace depthfem {

/// Initialises PETSc (and MPI) on the first call; later calls do nothing. Finalised at exit.
/// Outside mpirun Open MPI starts as an isolated singleton with the self transport (unless the
/// environment says otherwise); under mpirun nothing is changed.
void start_petsc();

/// Throws std::runtime_error "PETSc <what> failed: <PETSc's message>" when `code` is not 0.
void petsc_check(int code, const char* what);

}  // namespace depthfem
