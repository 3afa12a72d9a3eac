// Overlapping tets of one body: valid meshes pass (cavities, bodies touching along a face, an
// edge or a vertex, nesting), and every way of overlapping without sharing a face is rejected
// with the elements named.
#include <gtest/gtest.h>

#include <array>
#include <random>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/mesh_edits.hpp"
#include "core/mesh_generators.hpp"
#include "core/overlap_check.hpp"

namespace depthfem {
namespace {

using testing::box;
using testing::joined;
using testing::small_tet;
using testing::tet;
using testing::without_tets_in;

// check_no_overlap's message, or "" when it accepts the mesh (validated and oriented first).
std::string overlap_error(TetMesh mesh, const MeshSource& source = {}) {
  validate_and_orient(mesh, source);
  try {
    check_no_overlap(mesh, source);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// ---- Valid meshes ------------------------------------------------------------------------------

TEST(OverlapCheck, GeneratedMeshesPass) {
  EXPECT_EQ(overlap_error(box(Vec3::Zero(), Vec3(2, 1, 0.5), 3)), "");
  EXPECT_EQ(overlap_error(tube_mesh({0.5, 1.0, 2.0, 2, 12, 4})), "");  // a hole: genus 1
  EXPECT_EQ(overlap_error(ball_mesh({Vec3::Zero(), 1.0, 4})), "");
  EXPECT_EQ(overlap_error(corner_mesh({1.0, 0.1, 2, 1.5})), "");
}

TEST(OverlapCheck, CavityPasses) {
  // The middle cell of 3 x 3 x 3 left out: a second boundary surface, facing inwards.
  const TetMesh hollow = without_tets_in(box(Vec3::Zero(), Vec3::Ones(), 3),
                                         Vec3::Constant(1.0 / 3), Vec3::Constant(2.0 / 3));
  EXPECT_EQ(hollow.tets.rows(), 26 * 6);
  EXPECT_EQ(overlap_error(hollow), "");
  // A body floating in the cavity, touching nothing, is still one layer deep everywhere.
  EXPECT_EQ(overlap_error(joined(hollow, box(Vec3::Constant(0.4), Vec3::Constant(0.6), 1))), "");
}

TEST(OverlapCheck, PartsTouchingAlongAFaceAnEdgeOrAVertexPass) {
  const TetMesh a = box(Vec3::Zero(), Vec3::Ones(), 2);
  // Face to face, nodes shared (one conforming mesh) and nodes doubled (a crack).
  EXPECT_EQ(overlap_error(joined(a, box(Vec3(1, 0, 0), Vec3(2, 1, 1), 2), true)), "");
  EXPECT_EQ(overlap_error(joined(a, box(Vec3(1, 0, 0), Vec3(2, 1, 1), 2), false)), "");
  // Face to face with the other mesh's nodes on the face in between (not conforming).
  EXPECT_EQ(overlap_error(joined(a, box(Vec3(1, 0, 0), Vec3(2, 1, 1), 3), false)), "");
  // Along an edge, its nodes shared: four boundary triangles at each of its edges.
  EXPECT_EQ(overlap_error(joined(a, box(Vec3(1, 1, 0), Vec3(2, 2, 1), 2), true)), "");
  // At one vertex.
  EXPECT_EQ(overlap_error(joined(a, box(Vec3::Ones(), Vec3::Constant(2), 2), true)), "");
  // Apart.
  EXPECT_EQ(overlap_error(joined(a, box(Vec3::Constant(3), Vec3::Constant(4), 1))), "");
}

TEST(OverlapCheck, FlatSurfaceFarFromTheOriginPasses) {
  // Coordinates near 1e6 with cells of 1e-3: rounding must not read as crossing.
  EXPECT_EQ(overlap_error(box(Vec3::Constant(1e6), Vec3::Constant(1e6 + 3e-3), 3)), "");
}

// ---- Overlaps ----------------------------------------------------------------------------------

TEST(OverlapCheck, TetFloatingInsideOthersIsAnError) {
  // Four new nodes inside the box: no face shared with anything, the mesh two layers deep there.
  const TetMesh a = box(Vec3::Zero(), Vec3::Ones(), 2);
  const std::string message = overlap_error(joined(a, small_tet(Vec3(0.3, 0.2, 0.15), 0.05)));
  EXPECT_TRUE(contains(message, "element 48 overlaps element ")) << message;
  EXPECT_TRUE(contains(message, "is covered by 2 elements")) << message;
}

TEST(OverlapCheck, TetOfExistingNodesInsideIsAnError) {
  // The corner tet of a Kuhn-split unit cube: inside the cube, three faces on the cube's faces.
  const TetMesh a = box(Vec3::Zero(), Vec3::Ones(), 1);
  const std::string message = overlap_error(
      joined(a, tet(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)), true));
  EXPECT_TRUE(contains(message, "element 6 overlaps element ")) << message;
}

TEST(OverlapCheck, TetStickingOutIsAnError) {
  const TetMesh a = box(Vec3::Zero(), Vec3::Ones(), 2);
  const std::string message = overlap_error(joined(
      a, tet(Vec3(0.4, 0.4, 0.8), Vec3(0.6, 0.4, 0.8), Vec3(0.5, 0.6, 0.8), Vec3(0.5, 0.5, 1.3))));
  EXPECT_TRUE(contains(message, "element 48 overlaps element ")) << message;
  EXPECT_TRUE(contains(message, "cross")) << message;
}

TEST(OverlapCheck, TetsSharingAnEdgeAndOverlappingAroundItAreAnError) {
  // Two tets on the z axis, the second turned 30 degrees about it: they overlap in a wedge.
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  const TetMesh a = tet(Vec3::Zero(), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1));
  const TetMesh b = tet(Vec3::Zero(), Vec3(c, s, 0), Vec3(-s, c, 0), Vec3(0, 0, 1));
  EXPECT_TRUE(contains(overlap_error(joined(a, b, true)), "element 1 overlaps element 0"));
  // Sharing a vertex only, the second turned 30 degrees about the diagonal through it.
  const TetMesh d = tet(Vec3::Zero(), Vec3(c, s, 0), Vec3(-s, c, 0), Vec3(0, 0, 1.2));
  EXPECT_TRUE(contains(overlap_error(joined(a, d, true)), "element 1 overlaps element 0"));
}

TEST(OverlapCheck, TetRepeatedOnDoubledNodesIsAnError) {
  // The same tet twice, each with nodes of its own: nothing shared, the same space covered.
  const TetMesh a = tet(Vec3::Zero(), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1));
  EXPECT_TRUE(contains(overlap_error(joined(a, a)), "element 1 overlaps element 0"));
}

TEST(OverlapCheck, BoxesOverlappingAsOneBodyAreAnError) {
  const TetMesh a = box(Vec3::Zero(), Vec3::Ones(), 2);
  EXPECT_TRUE(contains(overlap_error(joined(a, box(Vec3::Constant(0.55), Vec3::Constant(1.55), 2))),
                       "cross"));
  // With the grids aligned, the boundaries only touch (along edges and in planes); the space they
  // share is covered twice.
  EXPECT_TRUE(contains(overlap_error(joined(a, box(Vec3::Constant(0.5), Vec3::Constant(1.5), 2))),
                       "is covered by 2 elements"));
  // The same cube again on nodes of its own, split otherwise: faces in one plane, both on the
  // same side.
  EXPECT_TRUE(
      contains(overlap_error(joined(a, box(Vec3::Zero(), Vec3::Ones(), 1))), "overlaps element"));
}

TEST(OverlapCheck, MessagesUseTheFilesNumbersAndLines) {
  const TetMesh a = tet(Vec3::Zero(), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1));
  MeshSource source;
  source.file = "m.msh";
  source.tet_line = {20, 21};
  source.tet_number = {7, 49};
  source.node_number = {10, 11, 12, 13, 14, 15, 16, 17};
  const std::string message = overlap_error(joined(a, a), source);
  EXPECT_TRUE(contains(message, "m.msh:21: element 49 (line 21) overlaps element 7 (line 20)"))
      << message;
}

// ---- Randomised: valid unions of grid tets, and tets added on grid nodes ------------------------

// The Kuhn tets of a 4 x 4 x 4 grid: random subsets (whole cells or single tets) make meshes with
// cavities, tunnels and parts touching along faces, edges and vertices; some tets get nodes of
// their own (cracks: coincident faces from opposite sides). All are valid.
TEST(OverlapCheck, RandomUnionsOfGridTetsPass) {
  std::mt19937 random(11);
  const TetMesh grid = box(Vec3::Zero(), Vec3::Ones(), 4);
  for (int trial = 0; trial < 300; ++trial) {
    std::bernoulli_distribution keep(std::uniform_real_distribution<double>(0.1, 0.9)(random));
    std::bernoulli_distribution own_nodes(trial % 3 == 0 ? 0.3 : 0.0);
    std::vector<bool> cell(64);
    for (size_t c = 0; c < cell.size(); ++c) cell[c] = keep(random);
    TetMesh m;
    std::vector<Vec3> X;
    std::vector<Index> shared(static_cast<size_t>(grid.X.rows()), -1);
    std::vector<std::array<Index, 4>> tets;
    for (Index t = 0; t < grid.tets.rows(); ++t) {
      Vec3 c = Vec3::Zero();
      for (int k = 0; k < 4; ++k) c += grid.X.row(grid.tets(t, k)).transpose() / 4;
      const Eigen::Vector3i ijk = (4 * c).cast<int>();
      if (!(trial % 2 ? keep(random) : cell[ijk(0) + 4 * (ijk(1) + 4 * ijk(2))])) continue;
      const bool own = own_nodes(random);
      std::array<Index, 4> nodes;
      for (int k = 0; k < 4; ++k) {
        const Index v = grid.tets(t, k);
        if (own || shared[v] < 0) {
          if (!own) shared[v] = static_cast<Index>(X.size());
          nodes[k] = static_cast<Index>(X.size());
          X.push_back(grid.X.row(v));
        } else {
          nodes[k] = shared[v];
        }
      }
      tets.push_back(nodes);
    }
    if (tets.empty()) continue;
    m.X.resize(static_cast<Index>(X.size()), 3);
    for (size_t i = 0; i < X.size(); ++i) m.X.row(static_cast<Index>(i)) = X[i].transpose();
    m.tets.resize(static_cast<Index>(tets.size()), 4);
    for (size_t t = 0; t < tets.size(); ++t)
      for (int k = 0; k < 4; ++k) m.tets(static_cast<Index>(t), k) = tets[t][k];
    if (trial % 4 == 1) {  // turned, so that the planes are no longer exact
      const Mat3 turn = Eigen::Quaterniond(0.9, 0.2, -0.3, 0.25).normalized().toRotationMatrix();
      m.X = (m.X * turn.transpose()).eval();
    }
    EXPECT_EQ(overlap_error(m), "") << "trial " << trial;
  }
}

// A tet on four random nodes of a 2 x 2 x 2 or 3 x 3 x 3 grid lies inside the grid's cube, so it
// overlaps tets of the grid; every one is refused (by validate_and_orient when it shares a face).
TEST(OverlapCheck, RandomTetsOnGridNodesAreFound) {
  std::mt19937 random(7);
  int found = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    TetMesh m = box(Vec3::Zero(), Vec3::Ones(), 2 + trial % 2);
    std::uniform_int_distribution<Index> node(0, static_cast<Index>(m.X.rows()) - 1);
    std::array<Index, 4> n;
    for (Index& i : n) i = node(random);
    if (std::abs(signed_volume(m.X.row(n[0]), m.X.row(n[1]), m.X.row(n[2]), m.X.row(n[3]))) < 1e-9)
      continue;
    m.tets.conservativeResize(m.tets.rows() + 1, Eigen::NoChange);
    m.tets.bottomRows(1) << n[0], n[1], n[2], n[3];
    bool refused = false;
    try {
      validate_and_orient(m);
      check_no_overlap(m);
    } catch (const InputError&) {
      refused = true;
    }
    EXPECT_TRUE(refused) << "tet " << n[0] << " " << n[1] << " " << n[2] << " " << n[3];
    found += refused;
  }
  EXPECT_GT(found, 1000);
}

}  // namespace
}  // namespace depthfem
