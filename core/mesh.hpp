#pragma once
/// The mesh of a whole scene: several bodies stored in one set of structure-of-arrays.

#include <string>
#include <vector>

#include "core/tet_mesh.hpp"

namespace depthfem {

/// An element region of a body (a Gmsh physical volume): a contiguous range of the scene's tets.
struct Region {
  std::string name;
  Index first_tet = 0, num_tets = 0;
};

/// Contiguous ranges of one body inside the scene arrays.
struct Body {
  std::string name;
  Index first_node = 0, num_nodes = 0;
  Index first_tet = 0, num_tets = 0;
  Index first_tri = 0, num_tris = 0;
  /// The body's element regions, one after the other over its tets, in the order in which their
  /// first tets appear in the body's mesh; empty when the mesh has none.
  std::vector<Region> regions;
  /// Moved only by prescribed motion: its nodes are no unknowns and it has no material.
  bool rigid = false;
};

/// Reference nodes, tets and outward boundary triangles of every body of a scene.
struct Mesh {
  Points X;              ///< #nodes x 3 reference positions [m]
  TetIndices tets;       ///< #tets x 4, positively oriented
  TriIndices tris;       ///< #tris x 3 boundary triangles, outward
  IndexVector tri_tet;   ///< #tris owning tet
  IndexVector tet_body;  ///< #tets body id
  IndexVector tri_body;  ///< #tris body id
  std::vector<Body> bodies;
  /// Named node sets of all bodies (scene node indices); a name several bodies use holds the
  /// nodes of each.
  NodeSets node_sets;

  Index num_nodes() const { return static_cast<Index>(X.rows()); }
  Index num_tets() const { return static_cast<Index>(tets.rows()); }
  Index num_tris() const { return static_cast<Index>(tris.rows()); }

  /// Appends a body (nodes, tets, its boundary triangles) with its node sets (body node indices)
  /// and returns its id. The mesh must already be validated (positive tets). With element
  /// regions (`tet_region`: #tets index into `region_names`, both empty for a mesh without), the
  /// tets are stored region after region, each region's tets in their given order, so that a mesh
  /// whose regions are already contiguous (one region, say) keeps its tet order; Body::regions
  /// records the ranges. Throws std::invalid_argument when tet_region does not match the tets or
  /// names a region that region_names lacks.
  Index add_body(const std::string& name, const TetMesh& body, const NodeSets& sets = {},
                 const std::vector<std::string>& region_names = {},
                 const std::vector<Index>& tet_region = {});
};

/// A scene mesh holding one body.
Mesh single_body_mesh(const TetMesh& body, const std::string& name = "body");

}  // namespace depthfem
