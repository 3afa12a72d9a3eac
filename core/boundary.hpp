#pragma once
/// Boundary surface of a tetrahedral mesh: the faces that belong to exactly one tet.

#include "core/types.hpp"

namespace depthfem {

/// Boundary triangles with the tet each one belongs to.
struct BoundaryFaces {
  TriIndices tris;  ///< #faces x 3, counter-clockwise seen from outside (normal points outward)
  IndexVector tet;  ///< #faces owning tet
};

/// Extracts the faces used by exactly one tet of a positively oriented mesh, oriented outward.
/// Faces come out sorted by (owning tet, local face) so the result is deterministic.
BoundaryFaces boundary_faces(const TetIndices& tets);

}  // namespace depthfem
