#pragma once
/// Reading a tetrahedral mesh from a file, whatever its format.

#include <string>
#include <vector>

#include "core/tet_mesh.hpp"

namespace depthfem {

/// A mesh read from a file, how many of its tets were re-oriented, and its named groups.
struct LoadedMesh {
  TetMesh mesh;          ///< validated, every tet positively oriented
  Index reoriented = 0;  ///< tets whose last two nodes were swapped to make their volume positive
  /// Element regions (Gmsh physical volumes, by name), in order of their first physical tag;
  /// empty when the file defines none.
  std::vector<std::string> region_names;
  /// #tets index into region_names; empty when the file defines no regions.
  std::vector<Index> tet_region;
  /// Every named group of the file (Gmsh physical groups of any dimension) as the nodes of its
  /// elements.
  NodeSets node_sets;
  /// The file, line and the file's own number of each node and tet, for messages.
  MeshSource source;
  /// #tets x 4: the tet across each face of the mesh as read, -1 on the boundary (see
  /// validate_and_orient); empty for a generated mesh.
  TetIndices neighbours;
};

/// Reads a mesh, choosing the reader by extension: ".msh" (Gmsh 2.2 or 4.1 ASCII) or
/// ".node"/".ele" (TetGen pair). Throws InputError for an unknown extension, a file that cannot be
/// opened, or any malformed content, naming the file and line. A mesh without element regions is
/// one body and is checked for overlapping tets here (check_no_overlap); a mesh with regions is
/// checked when a body is made of it (select_regions, or check_no_overlap on all of it).
LoadedMesh read_tet_mesh(const std::string& path);

/// Last step of every reader but for its groups: builds the mesh from row-major `xyz` (x0 y0 z0
/// x1 ...) and `tets` (4 0-based node indices per tet), throws InputError "FILE: contains no 4-node
/// tetrahedra" when there are none, then runs validate_and_orient with the lines and numbers in
/// `source`, which it keeps. The reader then checks a mesh without regions by check_no_overlap.
LoadedMesh finish_loaded_mesh(const std::vector<double>& xyz, const std::vector<Index>& tets,
                              const MeshSource& source);

}  // namespace depthfem
