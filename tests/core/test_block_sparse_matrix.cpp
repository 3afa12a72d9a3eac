// Sparse pattern, scatter offsets, element coloring and the colored run against dense /
// brute-force references.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <map>
#include <random>
#include <set>

#include "core/block_sparse_matrix.hpp"
#include "core/element_partition.hpp"
#include "core/mesh_generators.hpp"

namespace depthfem {
namespace {

// The couplings of the tets of a mesh (every tet couples its four nodes).
SparsityBuilder tet_couplings(const TetMesh& m) {
  SparsityBuilder builder(static_cast<Index>(m.X.rows()));
  for (Index t = 0; t < m.tets.rows(); ++t) {
    const Index v[4] = {m.tets(t, 0), m.tets(t, 1), m.tets(t, 2), m.tets(t, 3)};
    builder.add_clique(v);
  }
  return builder;
}

// The pattern of those couplings.
BlockSparseMatrix box_pattern(const TetMesh& m) {
  return BlockSparseMatrix(tet_couplings(m));
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
        if (q > p.row_begin[r]) {
          EXPECT_LT(p.col[q - 1], p.col[q]) << "row " << r;
        }
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

// The union of two patterns is the pattern of both sets of couplings; block_map sends every
// block of a pattern to the same (row, column) of another, -1 where the other lacks it.
// Rows hold every coupled column once, sorted, the diagonal included, however often cliques
// repeat a coupling (contact pairs repeat their nodes' couplings many times): against a set of
// the pairs, over rows enough for both threads' chunks.
TEST(SparsityBuilder, RowsHoldEachCouplingOnceInOrder) {
  const Index n = 3000;
  SparsityBuilder builder(n);
  std::set<std::pair<Index, Index>> reference;
  for (Index i = 0; i < n; ++i) reference.emplace(i, i);
  std::mt19937 rng(11);
  std::uniform_int_distribution<Index> node(0, n - 1), near(0, 20);
  for (int k = 0; k < 20000; ++k) {
    const Index base = node(rng);  // nodes close to each other: many repeated couplings
    std::vector<Index> clique;
    for (int a = 0; a < 7; ++a) clique.push_back(std::min(n - 1, base + near(rng)));
    builder.add_clique(clique);
    for (Index a : clique)
      for (Index b : clique) reference.emplace(a, b);
  }
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  const SparsityBuilder::Rows rows = builder.rows();
  ASSERT_EQ(rows.row_begin.size(), static_cast<size_t>(n) + 1);
  std::set<std::pair<Index, Index>> found;
  for (Index i = 0; i < n; ++i) {
    for (Index k = rows.row_begin[i]; k < rows.row_begin[i + 1]; ++k) {
      if (k > rows.row_begin[i]) {
        EXPECT_LT(rows.col[k - 1], rows.col[k]) << "row " << i;
      }
      found.emplace(i, rows.col[k]);
    }
  }
  EXPECT_EQ(found, reference);
  EXPECT_EQ(rows.col.size(), reference.size()) << "each coupling once";
}

TEST(BlockSparseMatrix, MergedPatternsAndBlockMapsKeepRowsAndColumns) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(3, 2, 2)});
  const Index n = static_cast<Index>(m.X.rows());
  SparsityBuilder tets = tet_couplings(m), extra(n), both = tet_couplings(m);
  std::mt19937 rng(5);
  std::uniform_int_distribution<Index> node(0, n - 1);
  for (int k = 0; k < 40; ++k) {
    const std::vector<Index> clique = {node(rng), node(rng), node(rng)};
    extra.add_clique(clique);
    both.add_clique(clique);
  }
  const SparsityBuilder::Rows merged = SparsityBuilder::merged(tets.rows(), extra.rows());
  EXPECT_EQ(merged.row_begin, both.rows().row_begin);
  EXPECT_EQ(merged.col, both.rows().col);
  const BlockSparseMatrix small(tets), large(merged);
  for (const auto& [from, to] : {std::pair(&small, &large), std::pair(&large, &small)}) {
    const std::vector<Index> map = from->block_map(*to);
    ASSERT_EQ(map.size(), static_cast<size_t>(from->num_blocks()));
    for (Index i = 0; i < n; ++i)
      for (Index k = from->row_begin(i); k < from->row_begin(i + 1); ++k)
        EXPECT_EQ(map[k], to->block_index(i, from->block_col(k)));
  }
  EXPECT_LT(small.num_blocks(), large.num_blocks()) << "the extra cliques must add blocks";
}

// The block indices of element cliques, found in bulk, are those of single look-ups, and adding a
// dense element matrix through them adds it block by block.
TEST(BlockSparseMatrix, CliqueBlockIndicesMatchLookUpsAndAddDenseMatrices) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(3, 2, 2)});
  const Index n = static_cast<Index>(m.X.rows());
  const SparsityBuilder builder = tet_couplings(m);
  BlockSparseMatrix A(builder), B(builder);
  const std::vector<Index> off = A.clique_block_indices(m.tets);
  ASSERT_EQ(off.size(), 16 * static_cast<size_t>(m.tets.rows()));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (Index t = 0; t < m.tets.rows(); ++t) {
    Eigen::Matrix<double, 12, 12> K;
    for (Index k = 0; k < K.size(); ++k) K(k) = u(rng);
    A.add_blocks<4>(off.data() + 16 * t, K);
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        EXPECT_EQ(off[16 * t + 4 * a + b], B.block_index(m.tets(t, a), m.tets(t, b)));
        B.add_block(B.block_index(m.tets(t, a), m.tets(t, b)), K.block<3, 3>(3 * a, 3 * b));
      }
  }
  EXPECT_EQ((Eigen::MatrixXd(A.to_sparse()) - Eigen::MatrixXd(B.to_sparse())).cwiseAbs().maxCoeff(),
            0.0);
  // Seven-node cliques (as contact pairs') in any order, nodes repeated: one look-up per pair.
  Eigen::Matrix<Index, Eigen::Dynamic, 7> sevens(m.tets.rows(), 7);
  std::uniform_int_distribution<int> corner(0, 3);
  for (Index t = 0; t < m.tets.rows(); ++t)
    for (int a = 0; a < 7; ++a) sevens(t, a) = m.tets(t, a < 4 ? 3 - a : corner(rng));
  const std::vector<Index> off7 = A.clique_block_indices(sevens);
  ASSERT_EQ(off7.size(), 49 * static_cast<size_t>(m.tets.rows()));
  for (Index t = 0; t < m.tets.rows(); ++t)
    for (int a = 0; a < 7; ++a)
      for (int b = 0; b < 7; ++b)
        EXPECT_EQ(off7[49 * t + 7 * a + b], A.block_index(sevens(t, a), sevens(t, b)));
  // A clique of uncoupled nodes has no block indices at all.
  Eigen::Matrix<Index, 1, 2> far;
  far << 0, n - 1;
  EXPECT_TRUE(A.clique_block_indices(far).empty());
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

// Chunks that all share a node need a color each: 100 of them, more than one 64-bit word of
// colors per node holds.
TEST(ElementPartition, ChunksSharingANodeGetAColorEach) {
  const Index n = 100;
  Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic> elements(n, 2);
  Points centroids(n, 3);
  for (Index e = 0; e < n; ++e) {
    elements.row(e) << 0, e + 1;
    centroids.row(e) << e, 0, 0;
  }
  const ElementPartition p = partition_elements(elements, n + 1, centroids, 1);
  EXPECT_EQ(p.num_colors(), n);
  for (Index c = 0; c < p.num_colors(); ++c) EXPECT_EQ(p.color_begin[c + 1] - p.color_begin[c], 1);
}

// run_by_color calls every chunk once, starts a chunk only after every chunk of the earlier colors
// has finished, and returns the same sum (bit for bit) on any number of threads.
TEST(ElementPartition, RunByColorVisitsChunksOnceColorAfterColor) {
  const std::vector<Index> color_begin = {0, 5, 6, 40, 41, 90};
  const int colors = static_cast<int>(color_begin.size()) - 1, chunks = 90;
  std::vector<int> color_of(chunks);
  for (int c = 0; c < colors; ++c)
    for (Index k = color_begin[c]; k < color_begin[c + 1]; ++k) color_of[k] = c;
  const auto run = [&](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    tbb::task_arena arena(threads);
    std::vector<std::atomic<int>> calls(chunks), finished(colors);
    double sum = 0;
    arena.execute([&] {
      sum = run_by_color(color_begin, 0.0, [&](Index k) {
        ++calls[k];
        for (int c = 0; c < color_of[k]; ++c)
          EXPECT_EQ(finished[c].load(), color_begin[c + 1] - color_begin[c]) << "chunk " << k;
        double v = 0;
        for (int i = 1; i <= 1000; ++i) v += 1.0 / (i + k);  // inexact: a new order would show
        ++finished[color_of[k]];
        return v;
      });
    });
    for (int k = 0; k < chunks; ++k) EXPECT_EQ(calls[k].load(), 1) << "chunk " << k;
    return sum;
  };
  const double one = run(1);
  EXPECT_EQ(run(2), one);
  EXPECT_EQ(run(4), one);
}

}  // namespace
}  // namespace depthfem
