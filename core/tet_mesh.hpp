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

/// How the results file names the dataset of a node set: '/', which would open a subgroup,
/// becomes '_'. Two names that differ only there would be stored as one.
std::string stored_set_name(std::string name);

/// Where a mesh came from, so that validation errors can name the file and line of an entry, and
/// the node or element as the file numbers it.
struct MeshSource {
  std::string file = "<generated>";  ///< the file of the tets (a generator: its name)
  std::vector<long> node_line;       ///< line of each node in `node_file` (empty: unknown)
  std::vector<long> tet_line;        ///< line of each tet in `file` (empty: unknown)
  std::string node_file;             ///< the file of the nodes when not `file` (TetGen's .node)
  /// The file's own number of each node (a Gmsh node tag, a TetGen point number; empty: the
  /// 0-based index) and of each tet (a Gmsh element tag, a TetGen tetrahedron number).
  std::vector<long long> node_number, tet_number;

  /// The file's number of node `i`, and of tet `t`.
  long long file_node(Index i) const;
  long long file_element(Index t) const;
  /// "node N" with the file's number of node `i`.
  std::string node_name(Index i) const;
  /// "element N (line L)" with the file's number of tet `t`; without the line when unknown.
  std::string element_name(Index t) const;
  /// The line of tet `t` in `file` (0: unknown).
  long line_of_tet(Index t) const;
  /// The line of node `i` in its file (0: unknown).
  long line_of_node(Index i) const;
  /// The file that lists the nodes.
  const std::string& nodes_file() const { return node_file.empty() ? file : node_file; }
  /// The part of this source that describes the tets `tets` (in that order) and the nodes
  /// `nodes` (new node k is old node nodes[k]).
  MeshSource subset(const std::vector<Index>& tets, const std::vector<Index>& nodes) const;
};

/// Signed volume of the tet (a, b, c, d): det[b-a, c-a, d-a] / 6.
double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Checks a mesh and makes every tet positively oriented.
/// Throws InputError naming file, line and element (in the file's numbering) for non-finite
/// coordinates, out-of-range node indices, degenerate tets (|6V| <= 1e-10 * (longest edge)^3), a
/// tet listed twice, tets that overlap across a shared face (both on the same side of it) or a
/// face shared by more than two tets, and nodes that belong to no tet. Tets with negative volume
/// are re-oriented by swapping their last two nodes. Returns how many were re-oriented; with
/// `neighbours`, sets it to #tets x 4: the tet across face k of each tet (the face opposite its
/// corner k, as in kTetFace), -1 on the boundary.
/// Tets that overlap without sharing a face are found by check_no_overlap (overlap_check.hpp),
/// which a body's mesh needs as well.
Index validate_and_orient(TetMesh& mesh, const MeshSource& source = {},
                          TetIndices* neighbours = nullptr);

}  // namespace depthfem
