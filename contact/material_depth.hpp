#pragma once
/// Material depth (paper section 5.2): each node's distance to its body's boundary surface in
/// the reference configuration (0 on the boundary), the gap function of the contact penalty.

#include "core/mesh.hpp"

namespace depthfem {

/// Closest point on the triangle (a, b, c) to p (Ericson, Real-Time Collision Detection 5.1.5:
/// Voronoi regions of vertices, edges and face).
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

/// Depth of every node [m]: exact Euclidean distance from its reference position to the
/// boundary triangles of its own body, found with an AABB tree over those triangles.
VectorX material_depth(const Mesh& mesh);

}  // namespace depthfem
