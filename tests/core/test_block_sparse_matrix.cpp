// Sparse pattern, scatter offsets and element coloring against dense / brute-force references.
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "core/block_sparse_matrix.hpp"
#include "core/element_coloring.hpp"
#include "core/mesh_generators.hpp"

namespace depthfem {
namespace {

TEST(BlockSparseMatrix, ScatteredBlocksEqualDenseAssembly) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(2, 2, 1)});
  const Index n = static_cast<Index>(m.X.rows());
  SparsityBuilder builder(n);
  for (Index t = 0; t < m.tets.rows(); ++t) {
    const Index v[4] = {m.tets(t, 0), m.tets(t, 1), m.tets(t, 2), m.tets(t, 3)};
    builder.add_clique(v);
  }
  BlockSparseMatrix A(builder);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (Index t = 0; t < m.tets.rows(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        Mat3 B;
        for (int k = 0; k < 9; ++k) B(k) = u(rng);
        const Index i = m.tets(t, a), j = m.tets(t, b);
        const Index off = A.block_offset(i, j);
        ASSERT_GE(off, 0);
        A.add_block(off, i, B);
        dense.block<3, 3>(3 * i, 3 * j) += B;
      }
  EXPECT_EQ((Eigen::MatrixXd(A.matrix()) - dense).cwiseAbs().maxCoeff(), 0.0);
  // Uncoupled nodes: opposite corners of the box share no tet.
  EXPECT_EQ(A.block_offset(0, n - 1), -1);
  // Each row of node i holds 3 entries per coupled node, the diagonal included.
  for (Index i = 0; i < n; ++i) EXPECT_EQ(A.row_stride(i) % 3, 0);
}

TEST(ElementColoring, NoTwoElementsOfAColorShareANode) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(4, 3, 3)});
  const ElementColoring c = color_elements(m.tets, static_cast<Index>(m.X.rows()));
  std::multiset<Index> seen(c.order.begin(), c.order.end());
  ASSERT_EQ(seen.size(), static_cast<size_t>(m.tets.rows()));
  for (Index t = 0; t < m.tets.rows(); ++t) EXPECT_EQ(seen.count(t), 1u);
  for (Index k = 0; k < c.num_colors(); ++k) {
    std::set<Index> nodes;
    size_t expected = 0;
    for (Index p = c.begin[k]; p < c.begin[k + 1]; ++p) {
      for (int a = 0; a < 4; ++a) nodes.insert(m.tets(c.order[p], a));
      expected += 4;
      if (p > c.begin[k]) EXPECT_LT(c.order[p - 1], c.order[p]);  // original order kept
    }
    EXPECT_EQ(nodes.size(), expected) << "color " << k << " has elements sharing a node";
  }
  EXPECT_LE(c.num_colors(), 64);
}

}  // namespace
}  // namespace depthfem
