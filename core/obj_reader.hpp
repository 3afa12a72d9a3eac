#pragma once
/// Reader for triangle surfaces in Wavefront OBJ files.

#include <string>

#include "core/types.hpp"

namespace depthfem {

/// A triangle surface: vertices and 0-based triangles.
struct TriSurface {
  Points V;      ///< #V x 3 vertex positions
  TriIndices F;  ///< #F x 3 vertex indices (0-based), in the file's winding order
};

/// Reads `v x y z [w]` and `f` statements of an OBJ file. Face corners may be written `a`, `a/t`,
/// `a//n` or `a/t/n`; negative indices count back from the last vertex defined so far; polygons
/// with more than 3 corners are split into a fan (a b c d -> a b c, a c d). Comments and the
/// statements vn, vt, vp, o, g, s, usemtl, mtllib and l are ignored. The surface must bound a
/// solid: closed, manifold (every edge in two faces, the faces around each vertex one fan),
/// consistently oriented, no degenerate face (2 area <= 1e-10 (longest edge)^2); self-intersection
/// is not checked. Throws InputError naming file, line and face for malformed or non-finite
/// numbers, index 0 or out of range, faces with fewer than 3 corners, unknown statements, files
/// without faces and surfaces that break these rules.
TriSurface read_obj(const std::string& path);

}  // namespace depthfem
