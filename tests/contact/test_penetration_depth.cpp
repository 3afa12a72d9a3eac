// Deepest geometric penetration: how far boundary points have gone inside another body (or a
// non-adjacent part of their own), measured to that body's current surface.
#include <gtest/gtest.h>

#include "contact/material_depth.hpp"
#include "contact/penetration_depth.hpp"
#include "core/mesh_generators.hpp"

namespace depthfem {
namespace {

// The pairs of a contact module at x.
std::vector<ContactPair> pairs_at(const Mesh& m, const Points& x, bool self_contact) {
  MaterialDepthContact c(m, material_depth(m), {1e6, self_contact});
  c.begin_step(x);
  c.prepare(x);
  return c.pairs();
}

// A narrower box pushed d into a wider one: its bottom face lies d below the lower box's top
// face and more than d from its sides, so the deepest penetration is d exactly; the lower box's
// top face inside the upper box lies d above the upper box's bottom face.
TEST(PenetrationDepth, BoxPushedIntoABoxPenetratesByItsDisplacement) {
  Mesh m;
  m.add_body("low", box_mesh({Vec3(0, 0, 0), Vec3(1, 1, 0.4), Eigen::Vector3i(5, 5, 2)}));
  m.add_body("high",
             box_mesh({Vec3(0.1, 0.1, 0.4), Vec3(0.9, 0.9, 0.8), Eigen::Vector3i(4, 4, 2)}));
  EXPECT_LT(deepest_penetration(m, m.X, pairs_at(m, m.X, true)), 1e-12);
  for (const double d : {0.001, 0.013}) {
    Points x = m.X;
    const Body& high = m.bodies[1];
    x.col(2).segment(high.first_node, high.num_nodes).array() -= d;
    EXPECT_NEAR(deepest_penetration(m, x, pairs_at(m, x, true)), d, 1e-12) << d;
  }
}

// A slab folded back onto itself through its own material: the upper arm's lower face is pushed
// d into the lower arm. Self-contact must measure d to the lower arm's top face, not the zero
// distance to the face the penetrating point lies on.
TEST(PenetrationDepth, SelfContactMeasuresToTheOtherSideOfTheFold) {
  // A U-shaped body: two arms (z in [0, 0.1] and [0.3, 0.4], two cells thick, so that their
  // middle nodes have depth) joined at x in [0.8, 1].
  TetMesh slab = box_mesh({Vec3(0, 0, 0), Vec3(1, 0.2, 0.4), Eigen::Vector3i(10, 2, 8)});
  // Keep the tets outside the gap x < 0.8, 0.1 < z < 0.3.
  std::vector<Index> keep;
  for (Index t = 0; t < slab.tets.rows(); ++t) {
    Vec3 c = Vec3::Zero();
    for (int k = 0; k < 4; ++k) c += slab.X.row(slab.tets(t, k)).transpose() / 4;
    if (!(c.x() < 0.8 && c.z() > 0.1 && c.z() < 0.3)) keep.push_back(t);
  }
  TetMesh u;
  u.X = slab.X;
  u.tets.resize(static_cast<Index>(keep.size()), 4);
  for (size_t k = 0; k < keep.size(); ++k)
    u.tets.row(static_cast<Index>(k)) = slab.tets.row(keep[k]);
  const Mesh m = single_body_mesh(u);
  // Close the gap and press on: the upper arm's lower face (z = 0.3) moves to 0.1 - d for x < 0.5.
  const double d = 0.004;
  Points x = m.X;
  for (Index i = 0; i < x.rows(); ++i)
    if (m.X(i, 2) >= 0.3 - 1e-12 && m.X(i, 0) < 0.5 + 1e-12) x(i, 2) -= 0.2 + d;
  EXPECT_NEAR(deepest_penetration(m, x, pairs_at(m, x, true)), d, 1e-12);
  EXPECT_EQ(deepest_penetration(m, x, pairs_at(m, x, false)), 0.0)
      << "no pairs without self-contact";
}

}  // namespace
}  // namespace depthfem
