// Material depth against closed forms: a box (distance to the nearest face) and a ball.
#include <gtest/gtest.h>

#include <random>

#include "contact/material_depth.hpp"
#include "core/mesh_generators.hpp"

namespace depthfem {
namespace {

TEST(MaterialDepth, BoxDepthIsDistanceToNearestFace) {
  const Vec3 lo(0, 0, 0), hi(2, 1, 0.6);
  const Mesh m = single_body_mesh(box_mesh({lo, hi, Eigen::Vector3i(10, 5, 6)}));
  const VectorX d = material_depth(m);
  for (Index i = 0; i < m.num_nodes(); ++i) {
    const Vec3 p = m.X.row(i);
    const double expected = std::min((p - lo).minCoeff(), (hi - p).minCoeff());
    EXPECT_NEAR(d(i), expected, 1e-14) << "node " << i;
  }
  EXPECT_NEAR(d.maxCoeff(), 0.3, 1e-14);
}

// The boundary is a polyhedron inscribed in the sphere (vertices on it), so it lies inside the
// ball and contains the ball of radius min over facets of their plane distance from the centre.
// A facet's vertices lie on the sphere, so its circumcircle is the plane's cut of the sphere and
// the plane distance is sqrt(R^2 - rho^2), rho the facet circumradius (a b c / (4 area)). Hence
// R - |X - c| - gap <= depth <= R - |X - c| with gap = R - min sqrt(R^2 - rho^2).
TEST(MaterialDepth, BallDepthApproachesRadiusMinusDistance) {
  const double R = 0.5;
  const Vec3 c(1, 2, 3);
  for (int n : {4, 8}) {
    const Mesh m = single_body_mesh(ball_mesh({c, R, n}));
    const VectorX d = material_depth(m);
    double rho = 0;
    for (Index f = 0; f < m.num_tris(); ++f) {
      const Vec3 a = m.X.row(m.tris(f, 0)), b = m.X.row(m.tris(f, 1)), e = m.X.row(m.tris(f, 2));
      const double area2 = (b - a).cross(e - a).norm();  // twice the area
      rho = std::max(rho, (a - b).norm() * (b - e).norm() * (e - a).norm() / (2 * area2));
    }
    const double gap = R - std::sqrt(R * R - rho * rho);
    for (Index i = 0; i < m.num_nodes(); ++i) {
      const double expected = R - (m.X.row(i).transpose() - c).norm();
      EXPECT_LE(d(i), expected + 1e-12) << "n " << n << " node " << i;
      EXPECT_GE(d(i), expected - gap - 1e-12) << "n " << n << " node " << i;
    }
  }
}

TEST(MaterialDepth, EachBodyMeasuresItsOwnBoundary) {
  Mesh m;
  m.add_body("a", box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(4, 4, 4)}));
  m.add_body("b",
             box_mesh({Vec3(0.25, 0.25, 0.25), Vec3(0.75, 0.75, 0.75), Eigen::Vector3i(2, 2, 2)}));
  const VectorX d = material_depth(m);
  const Body& b = m.bodies[1];
  // The centre node of b is 0.25 deep in b (not 0.5 as it would be in a).
  for (Index i = b.first_node; i < b.first_node + b.num_nodes; ++i) {
    if ((m.X.row(i) - Eigen::RowVector3d(0.5, 0.5, 0.5)).norm() < 1e-12) {
      EXPECT_NEAR(d(i), 0.25, 1e-14);
    }
  }
}

}  // namespace
}  // namespace depthfem
