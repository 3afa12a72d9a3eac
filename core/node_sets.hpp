#pragma once
/// Selecting nodes by region: axis-aligned box, plane, explicit list, or body.

#include <vector>

#include "core/mesh.hpp"

namespace depthfem {

/// Nodes whose reference position lies in the closed box [lo - tol, hi + tol].
std::vector<Index> nodes_in_box(const Points& X, const Vec3& lo, const Vec3& hi, double tol = 1e-9);

/// Nodes within `tol` of the plane n . X = offset (n need not be unit; it is normalised).
std::vector<Index> nodes_on_plane(const Points& X, const Vec3& normal, double offset,
                                  double tol = 1e-9);

/// All nodes of body `body`.
std::vector<Index> nodes_of_body(const Mesh& mesh, Index body);

}  // namespace depthfem
