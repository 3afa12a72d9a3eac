// Selecting regions of a mesh keeps their tets, the nodes they use and what remains of the sets.
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/mesh_regions.hpp"

namespace depthfem {
namespace {

// Three tets in a row along x, regions a, b, a; nodes 0..5 with tet t = (t, t+1, t+2, t+3).
LoadedMesh three_tets() {
  LoadedMesh m;
  m.mesh.X.resize(6, 3);
  for (Index i = 0; i < 6; ++i) m.mesh.X.row(i) = Vec3(i, i * i, i * i * i);
  m.mesh.tets.resize(3, 4);
  for (Index t = 0; t < 3; ++t) m.mesh.tets.row(t) << t, t + 1, t + 2, t + 3;
  m.region_names = {"a", "b"};
  m.tet_region = {0, 1, 0};
  m.node_sets = {{"first", {0}}, {"last", {5}}, {"middle", {2, 3}}};
  return m;
}

TEST(MeshRegions, KeepsTheTetsOfTheRegionsAndTheirNodesInOrder) {
  const LoadedMesh b = select_regions(three_tets(), {"b"});
  ASSERT_EQ(b.mesh.X.rows(), 4);
  EXPECT_TRUE(b.mesh.X.row(0) == Vec3(1, 1, 1).transpose());
  EXPECT_TRUE(b.mesh.X.row(3) == Vec3(4, 16, 64).transpose());
  ASSERT_EQ(b.mesh.tets.rows(), 1);
  EXPECT_TRUE(b.mesh.tets.row(0) == Eigen::RowVector4i(0, 1, 2, 3));
  EXPECT_EQ(b.region_names, (std::vector<std::string>{"b"}));
  EXPECT_EQ(b.tet_region, (std::vector<Index>{0}));
  // "first" and "last" lie outside tet 1 and are dropped; "middle" is renumbered.
  EXPECT_EQ(b.node_sets, (NodeSets{{"middle", {1, 2}}}));
}

TEST(MeshRegions, RegionsAreNumberedInTheOrderAsked) {
  const LoadedMesh all = select_regions(three_tets(), {"b", "a"});
  EXPECT_EQ(all.mesh.X.rows(), 6);
  EXPECT_EQ(all.tet_region, (std::vector<Index>{1, 0, 1}));
  EXPECT_EQ(all.node_sets, three_tets().node_sets);
}

TEST(MeshRegions, UnknownOrRepeatedRegionIsAnError) {
  try {
    select_regions(three_tets(), {"c"});
    FAIL() << "an unknown region must throw";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "no region 'c' (the mesh has 'a', 'b')");
  }
  EXPECT_THROW(select_regions(three_tets(), {"a", "a"}), InputError);
  LoadedMesh no_regions;
  no_regions.mesh = three_tets().mesh;
  EXPECT_THROW(select_regions(no_regions, {"a"}), InputError);
}

}  // namespace
}  // namespace depthfem
