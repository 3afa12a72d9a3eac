#pragma once
/// How deep boundary triangles have gone into the bodies they cut, measured in the current
/// configuration (the material depth of the penalty is measured in the reference one).

#include <vector>

#include "contact/material_depth_contact.hpp"
#include "core/mesh.hpp"

namespace depthfem {

/// Deepest geometric penetration [m] at positions x (#nodes x 3): over the intersection polygons
/// of `pairs` (clipped at x), the largest distance from a polygon vertex to the current boundary
/// surface of the body whose tet it lies in. For self-contact the boundary triangles sharing a
/// node with the pair's own triangle are skipped (the vertex lies on them). 0 without pairs.
double deepest_penetration(const Mesh& mesh, const Points& x,
                           const std::vector<ContactPair>& pairs);

}  // namespace depthfem
