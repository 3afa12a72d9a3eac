#pragma once
/// The mass of linear tets, in one place: lumped (diagonal) and consistent mass, and per-node
/// size measures of a tet mesh. The force modules that turn mass into inertia and damping
/// (integrators/forces/nodal_spring.hpp, integrators/forces/consistent_mass.hpp) take it from here.

#include "core/block_sparse_matrix.hpp"
#include "core/types.hpp"

namespace depthfem {

/// Mass per node [kg]: each tet gives a quarter of density x volume to each of its nodes.
/// `density` holds one value per tet [kg/m^3].
VectorX lumped_mass(const Points& X, const TetIndices& tets, const VectorX& density);

/// The consistent mass matrix of linear tets times `factor`: blocks M_ab = factor rho V / 20
/// (1 + delta_ab) I per tet corner pair (the integral of rho N_a N_b), on the pattern of the
/// tets' cliques. Its rows sum to the lumped masses. `density` holds one value per tet [kg/m^3].
BlockSparseMatrix consistent_mass(const Points& X, const TetIndices& tets, const VectorX& density,
                                  double factor = 1.0);

/// Volume of the tets around each node [m^3] (each tet counted once per node it has).
VectorX node_volume(const Points& X, const TetIndices& tets);

/// Mean edge length of the tets of a mesh [m] (each tet's six edges counted).
double mean_edge_length(const Points& X, const TetIndices& tets);

}  // namespace depthfem
