#pragma once
/// Taking the part of a mesh made of some of its element regions.

#include <string>
#include <vector>

#include "core/mesh_file.hpp"

namespace depthfem {

/// The tets of the named regions of `mesh` with the nodes they use, in their original order:
/// region_names becomes `regions` (tet_region renumbered accordingly), node sets keep their
/// nodes that remain (sets left empty are dropped), the source its lines and numbers. The result
/// is one body: check_no_overlap checks it. Throws InputError naming the region and the regions
/// the mesh has for an unknown or repeated name, or when the mesh has no regions, and
/// check_no_overlap's InputError for overlapping tets.
LoadedMesh select_regions(const LoadedMesh& mesh, const std::vector<std::string>& regions);

}  // namespace depthfem
