#pragma once
/// A single tetrahedral mesh as produced by generators and readers, and its validation.

#include <map>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

/// One body's tetrahedral mesh in its reference configuration.
struct TetMesh {
  Points X;         ///< #nodes x 3 reference positions [m]
  TetIndices tets;  ///< #tets x 4 node indices, positively oriented after `validate_and_orient`
};

/// Named node sets: name -> sorted node indices without repeats.
using NodeSets = std::map<std::string, std::vector<Index>>;

/// Where a mesh came from, so that validation errors can name the file and line of an entry.
struct MeshSource {
  std::string file = "<generated>";  ///< the file of the tets (a generator: its name)
  std::vector<long> node_line;       ///< line of each node in `node_file` (empty: unknown)
  std::vector<long> tet_line;        ///< line of each tet in `file` (empty: unknown)
  std::string node_file;             ///< the file of the nodes when not `file` (TetGen's .node)
};

/// Signed volume of the tet (a, b, c, d): det[b-a, c-a, d-a] / 6.
double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Checks a mesh and makes every tet positively oriented.
/// Throws InputError naming file, line and element for non-finite coordinates, out-of-range node
/// indices, degenerate tets (|6V| <= 1e-10 * (longest edge)^3), a tet listed twice, tets that
/// overlap across a shared face (both on the same side of it) or a face shared by more than two
/// tets, and nodes that belong to no tet. Tets with negative volume are re-oriented by swapping
/// their last two nodes. Returns how many were re-oriented.
Index validate_and_orient(TetMesh& mesh, const MeshSource& source = {});

}  // namespace depthfem
