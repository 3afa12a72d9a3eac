#include "contact/contact_surface.hpp"

namespace depthfem {

PolygonMoments polygon_moments(const ClipPolygon& poly, const std::array<double, 8>& depth) {
  PolygonMoments m;
  for (int k = 1; k + 1 < poly.size; ++k) {
    const double a = 0.5 * (poly.x[k] - poly.x[0]).cross(poly.x[k + 1] - poly.x[0]).norm();
    m.area += a;
    m.depth_integral += a * (depth[0] + depth[k] + depth[k + 1]) / 3;
  }
  return m;
}

void add_to_surface(SurfaceContact& surface, Index tri, const Vec3& on_triangle,
                    const PolygonMoments& moments) {
  surface.force.row(tri) += on_triangle.transpose();
  surface.magnitude(tri) += on_triangle.norm();
  surface.area(tri) += moments.area;
  surface.depth_integral(tri) += moments.depth_integral;
}

}  // namespace depthfem
