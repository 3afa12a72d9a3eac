// Generators and boundary extraction: exact volumes, closed outward surfaces, sphere nodes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "core/boundary.hpp"
#include "core/error.hpp"
#include "core/mesh.hpp"
#include "core/mesh_generators.hpp"

namespace depthfem {
namespace {

double total_volume(const TetMesh& m) {
  double v = 0;
  for (Index t = 0; t < m.tets.rows(); ++t) {
    const double vt = signed_volume(m.X.row(m.tets(t, 0)), m.X.row(m.tets(t, 1)),
                                    m.X.row(m.tets(t, 2)), m.X.row(m.tets(t, 3)));
    EXPECT_GT(vt, 0) << "tet " << t;
    v += vt;
  }
  return v;
}

// Volume enclosed by a triangle surface by the divergence theorem: sum over faces of
// (x0 . ((x1 - x0) x (x2 - x0))) / 6. Equals the mesh volume only for a closed, outward surface.
double enclosed_volume(const Points& X, const TriIndices& F) {
  double v = 0;
  for (Index f = 0; f < F.rows(); ++f) {
    const Vec3 a = X.row(F(f, 0)), b = X.row(F(f, 1)), c = X.row(F(f, 2));
    v += a.dot((b - a).cross(c - a)) / 6;
  }
  return v;
}

// Every directed edge of a closed, consistently oriented surface appears once, its twin once.
void expect_closed_oriented(const TriIndices& F) {
  std::map<std::pair<Index, Index>, int> directed;
  for (Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++directed[{F(f, k), F(f, (k + 1) % 3)}];
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1) << "edge " << edge.first << "-" << edge.second
                        << " used twice in one direction";
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << "edge without twin";
  }
}

TEST(BoxMesh, CountsVolumeAndBoundary) {
  const TetMesh m = box_mesh({Vec3(0, 0, 0), Vec3(2, 1, 0.5), Eigen::Vector3i(4, 3, 2)});
  EXPECT_EQ(m.X.rows(), 5 * 4 * 3);
  EXPECT_EQ(m.tets.rows(), 6 * 4 * 3 * 2);
  EXPECT_NEAR(total_volume(m), 1.0, 1e-14);
  const BoundaryFaces b = boundary_faces(m.tets);
  // 2 triangles per boundary quad: 2 (4*3 + 4*2 + 3*2) quads.
  EXPECT_EQ(b.tris.rows(), 2 * 2 * (12 + 8 + 6));
  EXPECT_NEAR(enclosed_volume(m.X, b.tris), 1.0, 1e-14);
  expect_closed_oriented(b.tris);
  for (Index f = 0; f < b.tris.rows(); ++f) {  // each face belongs to its tet
    for (int k = 0; k < 3; ++k) EXPECT_TRUE((m.tets.row(b.tet(f)).array() == b.tris(f, k)).any());
  }
}

// The core and the three shell blocks must share their faces node for node and diagonal for
// diagonal: a mismatch would leave inner faces on the boundary (not closed, wrong volume).
TEST(CornerMesh, ConformingCubeWithShellsGrowingGeometrically) {
  const int m = 3;
  const TetMesh mesh = corner_mesh({2.0, 0.1, m, 1.5});
  const int shells = static_cast<int>(std::ceil(std::log(20.0) / std::log(1.5)));  // 0.1 -> 2
  EXPECT_EQ(mesh.X.rows(),
            (m + 1) * (m + 1) * (m + 1) + shells * ((m + 1) * (m + 1) * (m + 1) - m * m * m));
  EXPECT_EQ(mesh.tets.rows(), 6 * m * m * m + 18 * m * m * shells);
  EXPECT_NEAR(total_volume(mesh), 8.0, 1e-12);
  const BoundaryFaces b = boundary_faces(mesh.tets);
  EXPECT_NEAR(enclosed_volume(mesh.X, b.tris), 8.0, 1e-12);
  expect_closed_oriented(b.tris);
  for (Index f = 0; f < b.tris.rows(); ++f)  // every boundary triangle lies on a face of the cube
    for (int k = 0; k < 3; ++k) {
      const Vec3 x = mesh.X.row(b.tris(f, k));
      EXPECT_TRUE(x.minCoeff() == 0 || x.maxCoeff() == 2.0) << x.transpose();
    }
  EXPECT_NEAR(mesh.X.col(0).cwiseAbs().maxCoeff(), 2.0, 0);
  // Smallest cells at the corner: the core's, 0.1 / 3.
  double shortest = 1e300;
  for (Index t = 0; t < mesh.tets.rows(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int c = a + 1; c < 4; ++c)
        shortest =
            std::min(shortest, (mesh.X.row(mesh.tets(t, a)) - mesh.X.row(mesh.tets(t, c))).norm());
  EXPECT_NEAR(shortest, 0.1 / m, 1e-12);
}

TEST(TubeMesh, VolumeIsThatOfThePolygonalShell) {
  const TubeParams p{0.3, 0.5, 2.0, 2, 12, 5};
  const TetMesh m = tube_mesh(p);
  EXPECT_EQ(m.X.rows(), 3 * 12 * 6);
  // A regular n-gon of circumradius r has area n/2 r^2 sin(2 pi / n).
  const double n = 12, expected = n / 2 * std::sin(2 * std::numbers::pi / n) * (0.25 - 0.09) * 2.0;
  EXPECT_NEAR(total_volume(m), expected, 1e-12);
  const BoundaryFaces b = boundary_faces(m.tets);
  expect_closed_oriented(b.tris);
  EXPECT_NEAR(enclosed_volume(m.X, b.tris), expected, 1e-12);
  for (Index v = 0; v < m.X.rows(); ++v) {
    const double r = std::hypot(m.X(v, 0), m.X(v, 1));
    EXPECT_TRUE(r > 0.3 - 1e-12 && r < 0.5 + 1e-12);
  }
}

TEST(BallMesh, BoundaryNodesOnSphereAndVolumeConverges) {
  double previous_error = 1;
  for (int n : {2, 4, 8}) {
    const TetMesh m = ball_mesh({Vec3(1, 2, 3), 0.5, n});
    const BoundaryFaces b = boundary_faces(m.tets);
    expect_closed_oriented(b.tris);
    for (Index f = 0; f < b.tris.rows(); ++f)
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR((m.X.row(b.tris(f, k)) - Eigen::RowVector3d(1, 2, 3)).norm(), 0.5, 1e-14);
    const double exact = 4.0 / 3 * std::numbers::pi * 0.125;
    const double error = std::abs(total_volume(m) - exact) / exact;
    EXPECT_LT(error, previous_error / 3) << "inscribed polyhedron volume error must drop ~h^2";
    previous_error = error;
  }
  EXPECT_LT(previous_error, 0.02);
}

TEST(Generators, RejectBadParameters) {
  EXPECT_THROW(box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(0, 1, 1)}), InputError);
  EXPECT_THROW(box_mesh({Vec3::Ones(), Vec3::Zero(), Eigen::Vector3i(1, 1, 1)}), InputError);
  EXPECT_THROW(tube_mesh({0.5, 0.4, 1, 1, 8, 1}), InputError);
  EXPECT_THROW(tube_mesh({0.0, 0.4, 1, 1, 8, 1}), InputError);
  EXPECT_THROW(tube_mesh({0.1, 0.4, 1, 1, 2, 1}), InputError);
  EXPECT_THROW(ball_mesh({Vec3::Zero(), -1, 2}), InputError);
  EXPECT_THROW(corner_mesh({1.0, 2.0, 4, 1.2}), InputError);
  EXPECT_THROW(corner_mesh({1.0, 0.1, 0, 1.2}), InputError);
  EXPECT_THROW(corner_mesh({1.0, 0.1, 4, 1.0}), InputError);
}

TEST(Mesh, BodiesAreAppendedWithOffsets) {
  Mesh scene;
  const TetMesh a = box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(1, 1, 1)});
  const TetMesh b = ball_mesh({Vec3(3, 0, 0), 1, 2});
  EXPECT_EQ(scene.add_body("a", a), 0);
  EXPECT_EQ(scene.add_body("b", b), 1);
  ASSERT_EQ(scene.bodies.size(), 2u);
  const Body& bb = scene.bodies[1];
  EXPECT_EQ(bb.first_node, a.X.rows());
  EXPECT_EQ(bb.first_tet, a.tets.rows());
  EXPECT_EQ(scene.num_nodes(), a.X.rows() + b.X.rows());
  for (Index t = bb.first_tet; t < bb.first_tet + bb.num_tets; ++t) {
    EXPECT_EQ(scene.tet_body(t), 1);
    EXPECT_GE(scene.tets.row(t).minCoeff(), bb.first_node);
  }
  for (Index f = bb.first_tri; f < bb.first_tri + bb.num_tris; ++f) {
    EXPECT_EQ(scene.tri_body(f), 1);
    EXPECT_EQ(scene.tet_body(scene.tri_tet(f)), 1);
  }
  expect_closed_oriented(scene.tris);
}

// Tets of a body with regions are stored region after region, regions in the order of their
// first tets, each region's tets in their given order; the boundary follows the stored tets.
// Regions interleaved as a checkerboard of the cells of a 2 x 2 x 1 box (6 tets per cell), listed
// so that the first tet's region is the second name; the body comes after another one.
TEST(Mesh, RegionsAreStoredContiguouslyInTheirGivenOrder) {
  const TetMesh a = box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(1, 1, 1)});
  const TetMesh b = box_mesh({Vec3(3, 0, 0), Vec3(5, 2, 1), Eigen::Vector3i(2, 2, 1)});
  std::vector<Index> tet_region;
  std::vector<std::vector<Index>> tets_of(2);  // original tets of "odd" (0) and "even" (1)
  for (Index t = 0; t < b.tets.rows(); ++t) {
    Vec3 c = Vec3::Zero();
    for (int k = 0; k < 4; ++k) c += b.X.row(b.tets(t, k)).transpose() / 4;
    const Index region = (int(std::floor(c.x() - 3)) + int(std::floor(c.y()))) % 2 == 0 ? 1 : 0;
    tet_region.push_back(region);
    tets_of[region].push_back(t);
  }
  ASSERT_EQ(tet_region[0], 1);
  ASSERT_EQ(tet_region[6], 0) << "the regions must interleave";
  Mesh scene;
  scene.add_body("a", a);
  scene.add_body("b", b, {}, {"odd", "even"}, tet_region);
  const Body& body = scene.bodies[1];
  EXPECT_TRUE(scene.bodies[0].regions.empty());
  ASSERT_EQ(body.regions.size(), 2u);
  const Index first = a.tets.rows();
  EXPECT_EQ(body.regions[0].name, "even");
  EXPECT_EQ(body.regions[0].first_tet, first);
  EXPECT_EQ(body.regions[0].num_tets, 12);
  EXPECT_EQ(body.regions[1].name, "odd");
  EXPECT_EQ(body.regions[1].first_tet, first + 12);
  EXPECT_EQ(body.regions[1].num_tets, 12);
  for (int r = 0; r < 2; ++r) {
    const std::vector<Index>& original = tets_of[r == 0 ? 1 : 0];
    for (size_t k = 0; k < original.size(); ++k)
      EXPECT_EQ(scene.tets.row(body.regions[r].first_tet + Index(k)),
                (b.tets.row(original[k]).array() + body.first_node).matrix())
          << body.regions[r].name << " tet " << k;
  }
  // Every boundary triangle is a face of the tet recorded as its owner.
  for (Index f = body.first_tri; f < body.first_tri + body.num_tris; ++f)
    for (int c = 0; c < 3; ++c)
      EXPECT_TRUE((scene.tets.row(scene.tri_tet(f)).array() == scene.tris(f, c)).any())
          << "triangle " << f;
  EXPECT_EQ(body.num_tris, boundary_faces(b.tets).tris.rows());
  expect_closed_oriented(scene.tris);
}

// A mesh without regions, with one region, or with regions already contiguous keeps its tets,
// boundary triangles and their owners exactly.
TEST(Mesh, ContiguousRegionsKeepTheTetOrder) {
  const TetMesh ball = ball_mesh({Vec3::Zero(), 1, 3});
  const Index n = ball.tets.rows();
  Mesh plain, one, two;
  plain.add_body("ball", ball);
  one.add_body("ball", ball, {}, {"all"}, std::vector<Index>(size_t(n), 0));
  std::vector<Index> halves(size_t(n), 1);
  std::fill(halves.begin(), halves.begin() + n / 2, 0);
  two.add_body("ball", ball, {}, {"first", "second"}, halves);
  EXPECT_TRUE(plain.bodies[0].regions.empty());
  ASSERT_EQ(one.bodies[0].regions.size(), 1u);
  EXPECT_EQ(one.bodies[0].regions[0].num_tets, n);
  ASSERT_EQ(two.bodies[0].regions.size(), 2u);
  EXPECT_EQ(two.bodies[0].regions[1].first_tet, n / 2);
  for (const Mesh* m : {&one, &two}) {
    EXPECT_EQ(m->tets, plain.tets);
    EXPECT_EQ(m->tris, plain.tris);
    EXPECT_EQ(m->tri_tet, plain.tri_tet);
  }
}

TEST(Mesh, RegionsThatDoNotMatchTheTetsAreRejected) {
  const TetMesh box = box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(1, 1, 1)});
  Mesh scene;
  EXPECT_THROW(scene.add_body("short", box, {}, {"a"}, {0, 0}), std::invalid_argument);
  EXPECT_THROW(scene.add_body("unknown", box, {}, {"a"}, {0, 0, 0, 1, 0, 0}),
               std::invalid_argument);
}

}  // namespace
}  // namespace depthfem
