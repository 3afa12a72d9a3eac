#pragma once
/// Reader for Gmsh MSH files (versions 2.2 and 4.1, ASCII).

#include <string>

#include "core/mesh_file.hpp"

namespace depthfem {

/// Reads the 4-node tetrahedra (element type 4) of a Gmsh MSH 2.2 or 4.1 ASCII file; the version
/// comes from $MeshFormat. Node tags may be arbitrary; nodes keep their file order.
/// Physical groups (named by $PhysicalNames, else by their tag; in MSH 4.1 an element's groups
/// are those of its entity in $Entities): physical volumes become regions (LoadedMesh::
/// region_names, tet_region), and every physical group of any dimension becomes a node set of
/// the nodes of its elements. Points, lines and triangles serve only for node sets; sections
/// other than $MeshFormat, $PhysicalNames, $Entities, $Nodes and $Elements are skipped.
/// Throws InputError naming file, line and element (by its tag) for binary files, other versions,
/// other 3D element types (quadratic tets, hexahedra, prisms, pyramids), undefined node tags,
/// malformed numbers and truncated sections, a tet in two regions, a file where some tets have a
/// region and others none, two physical groups with elements and the same name (a surface and a
/// volume "fixed", or unnamed ones of the same tag: their node sets would be one) or names the
/// results file stores as one (stored_set_name), and a physical name that is empty or given
/// twice. The mesh is then checked by validate_and_orient and, without regions (one body), by
/// check_no_overlap; a mesh with regions is checked as bodies are made of it.
LoadedMesh read_gmsh(const std::string& path);

}  // namespace depthfem
