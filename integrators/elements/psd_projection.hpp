#pragma once
/// Projection of a tet's 12x12 Hessian onto the positive semi-definite matrices: the nearest one in
/// the Frobenius norm keeps the eigenvectors and clamps negative eigenvalues to zero.

#include "integrators/elements/tet_kernel.hpp"

namespace depthfem {

/// Replaces the Hessian `h` [N/m] of a tet by V max(Lambda, 0) V^T from its eigen-decomposition
/// h = V Lambda V^T. `h` must be translation invariant, as tet_local makes it (rows and columns
/// of node 0 minus the sums over nodes 1..3): then h = A^T K A with K its node 1..3 block and A of
/// full rank, so h is PSD exactly when K is, and a successful Cholesky factorisation of K (9x9,
/// far cheaper than the 12x12 eigen-decomposition) leaves `h` untouched. So does an entry that is
/// not finite (a tet with det F <= 0, whose energy is already infinite). Returns whether `h`
/// changed.
bool project_to_psd(Mat12& h);

}  // namespace depthfem
