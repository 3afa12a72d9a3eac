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

// The pattern of the tets of a mesh (every tet couples its four nodes).
BlockSparseMatrix box_pattern(const TetMesh& m) {
  SparsityBuilder builder(static_cast<Index>(m.X.rows()));
  for (Index t = 0; t < m.tets.rows(); ++t) {
    const Index v[4] = {m.tets(t, 0), m.tets(t, 1), m.tets(t, 2), m.tets(t, 3)};
    builder.add_clique(v);
  }
  return BlockSparseMatrix(builder);
}

TEST(BlockSparseMatrix, ScatteredBlocksEqualDenseAssembly) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(2, 2, 1)});
  const Index n = static_cast<Index>(m.X.rows());
  BlockSparseMatrix A = box_pattern(m);
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

// The scalar views (what CHOLMOD and PETSc receive) against the triplet-built reference, on a
// matrix with distinct values in every entry (not symmetric, so that a transposed read shows).
TEST(BlockSparseMatrix, ScalarViewsEqualTheReferenceMatrix) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(2, 1, 2)});
  const Index n = static_cast<Index>(m.X.rows());
  BlockSparseMatrix A = box_pattern(m);
  for (Index k = 0; k < A.num_blocks(); ++k)
    for (int e = 0; e < 9; ++e) A.block(k)(e / 3, e % 3) = 9 * k + e + 1;
  const Eigen::MatrixXd dense(A.to_sparse());
  for (Triangle t : {Triangle::kFull, Triangle::kUpper}) {
    const ScalarPattern p = A.scalar_pattern(t);
    ASSERT_EQ(p.row_begin.size(), static_cast<size_t>(3 * n + 1));
    std::vector<double> v(p.col.size());
    A.scalar_values(p, v.data());
    Eigen::MatrixXd rebuilt = Eigen::MatrixXd::Zero(3 * n, 3 * n);
    for (Index r = 0; r < 3 * n; ++r)
      for (Index q = p.row_begin[r]; q < p.row_begin[r + 1]; ++q) {
        if (q > p.row_begin[r]) EXPECT_LT(p.col[q - 1], p.col[q]) << "row " << r;
        rebuilt(r, p.col[q]) = v[q];
      }
    const Eigen::MatrixXd expected =
        t == Triangle::kFull ? dense : Eigen::MatrixXd(dense.triangularView<Eigen::Upper>());
    EXPECT_EQ((rebuilt - expected).cwiseAbs().maxCoeff(), 0.0);
  }
}

// Every pattern built gets its own version, also one with as many blocks; copies keep it.
TEST(BlockSparseMatrix, EveryNewPatternGetsANewVersion) {
  SparsityBuilder a(3), b(3);
  a.add_clique(std::vector<Index>{0, 1});
  b.add_clique(std::vector<Index>{1, 2});
  const BlockSparseMatrix A(a), B(b), A2(a);
  ASSERT_EQ(A.num_blocks(), B.num_blocks());
  EXPECT_NE(A.pattern_version(), B.pattern_version());
  EXPECT_NE(A.pattern_version(), A2.pattern_version());
  const BlockSparseMatrix copy = A;
  EXPECT_EQ(copy.pattern_version(), A.pattern_version());
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
