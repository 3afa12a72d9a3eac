#pragma once
/// How deep boundary triangles have gone into the bodies they cut, measured in the current
/// configuration (the material depth of the penalty is measured in the reference one).

#include <vector>

#include "contact/material_depth_contact.hpp"
#include "core/mesh.hpp"

namespace depthfem {

/// Deepest geometric penetration [m] at positions x (#nodes x 3): over the intersection polygons
/// of `pairs` (clipped at x), the largest distance from a polygon vertex to the current boundary
/// surface of the body whose tet it lies in. For self-contact, the vertex lies on its own
/// triangle's surface, so the triangles that share a node with that triangle and face the same
/// way (its own side of a fold) are skipped; the rest of that side lies at least an edge away.
/// 0 without pairs.
double deepest_penetration(const Mesh& mesh, const Points& x,
                           const std::vector<ContactPair>& pairs);

}  // namespace depthfem
