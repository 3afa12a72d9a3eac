#pragma once
/// The per-triangle contact sums of a step (SurfaceContact): what each contact polygon adds to
/// the boundary triangle whose part inside another body or an obstacle it is.

#include <array>

#include "contact/clip.hpp"
#include "core/step_record.hpp"

namespace depthfem {

/// Area and depth integral of a clipped polygon.
struct PolygonMoments {
  double area = 0;            ///< [m^2]
  double depth_integral = 0;  ///< [m^3]: the integral of the penetration depth over the polygon
};

/// Moments of `poly` (positions poly.x, fanned from the first vertex) for a penetration depth that
/// is linear over it with values `depth` [m] at its vertices: each fan triangle of area A adds A
/// and A (G0 + G1 + G2) / 3.
PolygonMoments polygon_moments(const ClipPolygon& poly, const std::array<double, 8>& depth);

/// Adds to boundary triangle `tri` of `surface` (sized already) one contact polygon: the force
/// `on_triangle` [N] its pair exerts on the triangle's body, and the polygon's moments.
void add_to_surface(SurfaceContact& surface, Index tri, const Vec3& on_triangle,
                    const PolygonMoments& moments);

}  // namespace depthfem
