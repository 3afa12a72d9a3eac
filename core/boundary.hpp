#pragma once
/// The faces of a tetrahedral mesh matched up: the boundary surface (faces of one tet only) and
/// the face table that mesh validation reads.

#include <array>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

/// Face k of tet (0,1,2,3) is opposite vertex k, listed so that its right-hand normal points
/// away from that vertex (outward in a positively oriented tet).
inline constexpr int kTetFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

/// One face of one tet: its nodes in increasing order, the tet and which of its faces it is.
struct TetFace {
  std::array<Index, 3> sorted;
  Index tet;
  int local;
};

/// Every face of every tet, ordered by (sorted nodes, tet): the faces a mesh shares are
/// neighbours. Bucketed by the smallest node (a counting sort), each bucket then sorted: about
/// linear in the number of tets.
std::vector<TetFace> face_table(const TetIndices& tets);

/// Boundary triangles with the tet each one belongs to.
struct BoundaryFaces {
  TriIndices tris;  ///< #faces x 3, counter-clockwise seen from outside (normal points outward)
  IndexVector tet;  ///< #faces owning tet
};

/// Extracts the faces used by exactly one tet of a positively oriented mesh, oriented outward.
/// Faces come out sorted by (owning tet, local face) so the result is deterministic.
BoundaryFaces boundary_faces(const TetIndices& tets);

}  // namespace depthfem
