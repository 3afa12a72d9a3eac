#pragma once
/// Lumped (diagonal) mass and per-node size measures from a tet mesh.

#include "core/types.hpp"

namespace depthfem {

/// Mass per node [kg]: each tet gives a quarter of density x volume to each of its nodes.
/// `density` holds one value per tet [kg/m^3].
VectorX lumped_mass(const Points& X, const TetIndices& tets, const VectorX& density);

/// Volume of the tets around each node [m^3] (each tet counted once per node it has).
VectorX node_volume(const Points& X, const TetIndices& tets);

/// Mean edge length of the tets of a mesh [m] (each tet's six edges counted).
double mean_edge_length(const Points& X, const TetIndices& tets);

}  // namespace depthfem
