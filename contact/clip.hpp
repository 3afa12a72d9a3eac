#pragma once
/// Narrow phase (paper section 5.3, step 3): the convex polygon where a triangle meets a tet,
/// with every vertex labelled by how it arises, so that its position can be re-evaluated as an
/// explicit function of the seven node positions (and differentiated).

#include <array>
#include <cstdint>

#include "core/types.hpp"

namespace depthfem {

/// How a vertex of the clipped polygon arises.
struct ClipVertex {
  enum class Kind : std::uint8_t {
    kTriangleVertex,    ///< triangle corner a inside the tet: R = Q_a
    kTriangleEdgeFace,  ///< triangle edge (a, b) crossing tet face `face` (opposite vertex `face`)
    kTetEdge,           ///< tet edge (a, b) crossing the triangle
  };
  Kind kind = Kind::kTriangleVertex;
  std::int8_t a = 0, b = 0, face = 0;
};

/// A convex polygon of up to 7 vertices (a triangle cut by four planes).
struct ClipPolygon {
  int size = 0;
  std::array<ClipVertex, 8> vertex;
  std::array<Vec3, 8> x;  ///< positions, as computed while clipping
};

/// Corners of the tet faces, face k opposite corner k, ordered so that the right-hand normal
/// points out of a positively oriented tet.
inline constexpr int kTetFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

/// Clips triangle Q by the four face planes of the positively oriented tet P (Sutherland-Hodgman
/// on labelled vertices). Points on a plane (up to rounding) count as inside, except that a
/// polygon lying in a face plane belongs to only one of the two tets sharing that face.
/// size < 3 means no area in common.
ClipPolygon clip_triangle_by_tet(const std::array<Vec3, 4>& P, const std::array<Vec3, 3>& Q);

/// Clips triangle Q to where the linear interpolant of the vertex values g is >= 0 (an
/// obstacle's depth); crossings are kTriangleEdgeFace vertices with face = -1.
ClipPolygon clip_triangle_by_field(const std::array<Vec3, 3>& Q, const std::array<double, 3>& g);

}  // namespace depthfem
