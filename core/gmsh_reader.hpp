#pragma once
/// Reader for Gmsh MSH files (versions 2.2 and 4.1, ASCII).

#include <string>

#include "core/mesh_file.hpp"

namespace depthfem {

/// Reads the 4-node tetrahedra (element type 4) of a Gmsh MSH 2.2 or 4.1 ASCII file; the version
/// comes from $MeshFormat. Points, lines and triangles are skipped, as are sections other than
/// $MeshFormat, $Nodes and $Elements. Node tags may be arbitrary; nodes keep their file order.
/// Throws InputError naming file, line and element for binary files, other versions, other 3D
/// element types (quadratic tets, hexahedra, prisms, pyramids), undefined node tags, malformed
/// numbers and truncated sections; the mesh is then checked by validate_and_orient.
LoadedMesh read_gmsh(const std::string& path);

}  // namespace depthfem
