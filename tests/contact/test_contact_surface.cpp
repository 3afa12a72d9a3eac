// The per-triangle contact sums the contact modules report (SurfaceContact): where a flat face
// sits at uniform depth d inside a floor or another body, each triangle's force is eps d A along
// the normal, its contact area A and its mean depth d (closed form: W = eps/2 d^2 A per triangle);
// everywhere, the sums over the triangles reproduce the step's contact rows.
#include <gtest/gtest.h>

#include "contact/material_depth.hpp"
#include "contact/material_depth_contact.hpp"
#include "contact/obstacle_contact.hpp"
#include "core/mesh_generators.hpp"

namespace depthfem {
namespace {

constexpr double kPenalty = 1e6, kDepth = 0.01;

// Area of boundary triangle f at x.
double triangle_area(const Mesh& m, const Points& x, Index f) {
  const Vec3 a = x.row(m.tris(f, 0)), b = x.row(m.tris(f, 1)), c = x.row(m.tris(f, 2));
  return 0.5 * (b - a).cross(c - a).norm();
}

// Whether triangle f lies in the plane z = z0 with every corner in [0.28, 0.75] x [0.27, 0.75]:
// where both boxes below are at least 0.25 (their cell height) from their sides, so that each
// one's depth field is the distance to its face in that plane.
bool central_on_plane(const Mesh& m, const Points& x, Index f, double z0) {
  for (int k = 0; k < 3; ++k) {
    const Vec3 p = x.row(m.tris(f, k));
    if (std::abs(p(2) - z0) > 1e-12 || p(0) < 0.28 - 1e-12 || p(0) > 0.75 + 1e-12 ||
        p(1) < 0.27 - 1e-12 || p(1) > 0.75 + 1e-12)
      return false;
  }
  return true;
}

// A triangle at uniform depth d with outward normal n: force -eps d A n on its body, magnitude
// eps d A, area A, depth integral d A. Tolerance: sums over a few clipped polygons, 1e-10.
void expect_uniform_depth(const SurfaceContact& s, Index f, double A, const Vec3& n) {
  const double F = kPenalty * kDepth * A;
  EXPECT_LE((s.force.row(f).transpose() + F * n).norm(), 1e-10 * F) << "triangle " << f;
  EXPECT_NEAR(s.magnitude(f), F, 1e-10 * F);
  EXPECT_NEAR(s.area(f), A, 1e-10 * A);
  EXPECT_NEAR(s.depth_integral(f), kDepth * A, 1e-10 * kDepth * A);
}

// The sums over the triangles of `body` (every body when -1).
struct Totals {
  Vec3 force = Vec3::Zero();
  double magnitude = 0, area = 0;
};
Totals totals(const Mesh& m, const SurfaceContact& s, Index body) {
  Totals t;
  for (Index f = 0; f < m.num_tris(); ++f) {
    if (body >= 0 && m.tri_body(f) != body) continue;
    t.force += s.force.row(f).transpose();
    t.magnitude += s.magnitude(f);
    t.area += s.area(f);
  }
  return t;
}

// A block pressed kDepth into a floor: its bottom triangles carry the closed form, and the
// triangles' sums are the obstacle's row.
TEST(ContactSurface, BlockOnAFloorCarriesTheClosedFormPressure) {
  const Mesh m = single_body_mesh(
      box_mesh({Vec3::Zero(), Vec3(1, 1, 0.5), Eigen::Vector3i(4, 4, 2)}), "block");
  Points x = m.X;
  x.col(2).array() -= kDepth;
  ObstacleContact floor(m, {0}, {{"floor", PlaneObstacle{}, Vec3::Zero(), kPenalty}});
  floor.set_load(0);
  floor.prepare(x);
  StepRecord step;
  floor.report(x, step);
  ASSERT_EQ(step.surface.area.size(), m.num_tris());
  int bottom = 0;
  for (Index f = 0; f < m.num_tris(); ++f)
    if (std::abs(x(m.tris(f, 0), 2) + kDepth) + std::abs(x(m.tris(f, 1), 2) + kDepth) +
            std::abs(x(m.tris(f, 2), 2) + kDepth) <
        1e-12) {
      expect_uniform_depth(step.surface, f, triangle_area(m, x, f), -Vec3::UnitZ());
      ++bottom;
    }
  EXPECT_EQ(bottom, 32);
  const Totals t = totals(m, step.surface, -1);
  const InterfaceForce& row = step.contact.at(0);
  EXPECT_LE((t.force - row.force).norm(), 1e-12 * row.magnitude);
  EXPECT_NEAR(t.magnitude, row.magnitude, 1e-12 * row.magnitude);
  EXPECT_NEAR(t.area, row.area, 1e-12 * row.area);
}

// Two blocks overlapping by kDepth, their meshes shifted sideways so that no triangle edge lies in
// a tet face (where the force is only continuous): each surface lies kDepth deep in the other
// body, so both carry the closed form away from the sides (contact is found from both sides,
// each surface taking its share), and the triangles' sums are the interface's row: the force on
// the first body is its triangles' force minus the second body's, the magnitudes add up, the
// area is the larger of the two surfaces' areas.
TEST(ContactSurface, OverlappingBlocksShareTheContactForce) {
  Mesh m;
  m.add_body("lower", box_mesh({Vec3(0, 0, -0.5), Vec3(1, 1, 0), Eigen::Vector3i(8, 8, 2)}));
  m.add_body("upper", box_mesh({Vec3(0.03, 0.02, -kDepth), Vec3(1.03, 1.02, 0.5 - kDepth),
                                Eigen::Vector3i(8, 8, 2)}));
  MaterialDepthContact contact(m, material_depth(m), {kPenalty, false});
  contact.begin_step(m.X);
  contact.prepare(m.X);
  StepRecord step;
  contact.report(m.X, step);
  ASSERT_EQ(step.surface.area.size(), m.num_tris());
  int lower = 0, upper = 0;
  for (Index f = 0; f < m.num_tris(); ++f) {
    const double A = triangle_area(m, m.X, f);
    if (m.tri_body(f) == 0 && central_on_plane(m, m.X, f, 0.0)) {
      expect_uniform_depth(step.surface, f, A, Vec3::UnitZ());
      ++lower;
    }
    if (m.tri_body(f) == 1 && central_on_plane(m, m.X, f, -kDepth)) {
      expect_uniform_depth(step.surface, f, A, -Vec3::UnitZ());
      ++upper;
    }
  }
  EXPECT_EQ(lower, 18);
  EXPECT_EQ(upper, 18);
  const InterfaceForce& row = step.contact.at(0);
  ASSERT_EQ(row.name, "lower/upper");
  const Totals a = totals(m, step.surface, 0), b = totals(m, step.surface, 1);
  EXPECT_LE((a.force - b.force - row.force).norm(), 1e-12 * row.magnitude);
  EXPECT_NEAR(a.magnitude + b.magnitude, row.magnitude, 1e-12 * row.magnitude);
  EXPECT_NEAR(std::max(a.area, b.area), row.area, 1e-12 * row.area);
}

}  // namespace
}  // namespace depthfem
