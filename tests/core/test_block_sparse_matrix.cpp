// Sparse pattern, scatter offsets and element coloring against dense / brute-force references.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "core/block_sparse_matrix.hpp"
#include "core/element_partition.hpp"
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
        const Index k = A.block_index(i, j);
        ASSERT_GE(k, 0);
        A.add_block(k, B);
        dense.block<3, 3>(3 * i, 3 * j) += B;
      }
  EXPECT_EQ((Eigen::MatrixXd(A.to_sparse()) - dense).cwiseAbs().maxCoeff(), 0.0);
  // Uncoupled nodes: opposite corners of the box share no tet.
  EXPECT_EQ(A.block_index(0, n - 1), -1);
  // Product and diagonal against the dense matrix.
  const VectorX x = VectorX::LinSpaced(3 * n, -1, 2);
  VectorX y;
  A.multiply(x, y);
  EXPECT_LE((y - dense * x).cwiseAbs().maxCoeff(), 1e-13 * (dense * x).cwiseAbs().maxCoeff());
  EXPECT_EQ((A.diagonal() - dense.diagonal()).cwiseAbs().maxCoeff(), 0.0);
}

TEST(ElementPartition, ChunksOfAColorShareNoNodeAndEveryElementAppearsOnce) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(6, 5, 4)});
  Points centroids(m.tets.rows(), 3);
  for (Index t = 0; t < m.tets.rows(); ++t) {
    centroids.row(t).setZero();
    for (int a = 0; a < 4; ++a) centroids.row(t) += 0.25 * m.X.row(m.tets(t, a));
  }
  const Index chunk = 16;
  const ElementPartition p =
      partition_elements(m.tets, static_cast<Index>(m.X.rows()), centroids, chunk);
  std::multiset<Index> seen(p.order.begin(), p.order.end());
  ASSERT_EQ(seen.size(), static_cast<size_t>(m.tets.rows()));
  for (Index t = 0; t < m.tets.rows(); ++t) EXPECT_EQ(seen.count(t), 1u);
  ASSERT_EQ(p.color_begin.back(), p.num_chunks());
  for (Index k = 0; k < p.num_chunks(); ++k)
    EXPECT_LE(p.chunk_begin[k + 1] - p.chunk_begin[k], chunk);
  for (Index c = 0; c < p.num_colors(); ++c) {
    std::map<Index, Index> owner;  // node -> chunk that touched it in this color
    for (Index k = p.color_begin[c]; k < p.color_begin[c + 1]; ++k)
      for (Index q = p.chunk_begin[k]; q < p.chunk_begin[k + 1]; ++q)
        for (int a = 0; a < 4; ++a) {
          const auto [it, fresh] = owner.emplace(m.tets(p.order[q], a), k);
          EXPECT_TRUE(fresh || it->second == k) << "color " << c << ": chunks " << it->second
                                                << " and " << k << " share node " << it->first;
        }
  }
  // Compact chunks need few colors (a chunk meets a bounded number of neighbours).
  EXPECT_LE(p.num_colors(), 32);
  EXPECT_GE(p.num_colors(), 2);
}

}  // namespace
}  // namespace depthfem
