// Dirichlet conditions: targets, combination of planes, projected Newton matrix, reactions.
#include <gtest/gtest.h>

#include <numbers>

#include "core/error.hpp"
#include "integrators/forces/constraints.hpp"

namespace depthfem {
namespace {

Points four_points() {
  Points X(4, 3);
  X << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 2, 3;
  return X;
}

TEST(Constraints, TargetsOfEachKind) {
  const Points X = four_points();
  const Constraints c(
      X, {{"fix", {0}, Fixed{}},
          {"move", {1}, Displaced{Vec3(0.1, 0.2, 0.3)}},
          {"turn", {2}, Rotated{Vec3::UnitZ(), Vec3::Zero(), std::numbers::pi / 2, Vec3(0, 0, 1)}},
          {"slide", {3}, InPlane{Vec3(0, 0, 2), 0.5}}});
  Points x = X.array() + 7.0;  // garbage everywhere
  c.impose(0.5, x);
  EXPECT_LE((x.row(0) - X.row(0)).norm(), 1e-15);
  EXPECT_LE((x.row(1) - Eigen::RowVector3d(1.05, 0.1, 0.15)).norm(), 1e-15);
  // (0,1,0) turned by 45 degrees about z, raised by 0.5.
  EXPECT_LE((x.row(2) - Eigen::RowVector3d(-std::sqrt(0.5), std::sqrt(0.5), 0.5)).norm(), 1e-15);
  // In-plane node: z = 3 + 0.5 * 0.5, x and y untouched.
  EXPECT_LE((x.row(3) - Eigen::RowVector3d(8, 9, 3.25)).norm(), 1e-15);
}

TEST(Constraints, PlanesCombineIntoLinesAndPoints) {
  const Points X = four_points();
  const Constraints c(X, {{"a", {0, 1, 3}, InPlane{Vec3::UnitX(), 0.2}},
                          {"b", {0, 1}, InPlane{Vec3(1, 1, 0), 0.0}},
                          {"c", {0}, InPlane{Vec3::UnitZ(), -0.1}}});
  Points x = X.array() + 1.0;
  c.impose(1.0, x);
  // Node 0: three independent planes fix it at the point solving all three offsets.
  EXPECT_LE((x.row(0) - Eigen::RowVector3d(0.2, -0.2, -0.1)).norm(), 1e-14);
  // Node 1: two planes leave a line along z; x = 1.2, x + y = 1.
  EXPECT_NEAR(x(1, 0), 1.2, 1e-14);
  EXPECT_NEAR(x(1, 0) + x(1, 1), 1.0, 1e-14);
  EXPECT_NEAR(x(1, 2), 1.0, 1e-14);  // free direction untouched
  VectorX g = VectorX::Ones(12);
  c.project(g);
  EXPECT_NEAR(g.segment<3>(0).norm(), 0.0, 1e-15);
  EXPECT_NEAR(g(5), 1.0, 1e-15);  // node 1, z free
  EXPECT_NEAR(g(3) + g(4), 0.0, 1e-15);
  EXPECT_THROW(Constraints(X, {{"p", {2}, InPlane{Vec3::UnitX(), 0.1}},
                               {"q", {2}, InPlane{Vec3::UnitX(), 0.3}}}),
               InputError);
}

TEST(Constraints, ProjectedMatrixIsIdentityOnConstrainedDirections) {
  const Points X = four_points();
  SparsityBuilder b(4);
  const Index all[4] = {0, 1, 2, 3};
  b.add_clique(all);
  BlockSparseMatrix H(b);
  for (Index k = 0; k < H.num_blocks(); ++k) H.block(k).setConstant(2.0);
  const Constraints c(X, {{"fix", {0}, Fixed{}}, {"line", {1}, OnLine{Vec3::UnitY()}}});
  c.project(H);
  const Eigen::MatrixXd D = Eigen::MatrixXd(H.to_sparse());
  EXPECT_TRUE((D.block<3, 3>(0, 0).isIdentity(1e-15)));
  EXPECT_LE((D.block<3, 9>(0, 3).cwiseAbs().maxCoeff()), 1e-15);
  // Node 1 on a line along y: x and z rows are identity rows, y keeps its coupling.
  EXPECT_NEAR(D(3, 3), 1.0, 1e-15);
  EXPECT_NEAR(D(3, 4), 0.0, 1e-15);
  EXPECT_NEAR(D(4, 4), 2.0, 1e-15);
  EXPECT_NEAR(D(4, 6), 2.0, 1e-15);
  EXPECT_LE((D - D.transpose()).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(Constraints, ReactionsSumConstrainedGradientComponents) {
  const Points X = four_points();
  const Constraints c(X, {{"fix", {0, 1}, Fixed{}}, {"slide", {3}, InPlane{Vec3::UnitZ(), 0}}});
  VectorX g(12);
  for (Index i = 0; i < 12; ++i) g(i) = i + 1;
  const auto R = c.reactions(g);
  EXPECT_LE((R.row(0) - Eigen::RowVector3d(1 + 4, 2 + 5, 3 + 6)).norm(), 1e-15);
  EXPECT_LE((R.row(1) - Eigen::RowVector3d(0, 0, 12)).norm(), 1e-15);
}

// A node in two conditions counts once: a full prescription owns the whole node, and of two
// planes each owns the direction it added (Gram-Schmidt in list order). The rows then sum to the
// constrained components of g, each once.
TEST(Constraints, EveryConstrainedDirectionBelongsToOneCondition) {
  const Points X = four_points();
  const Constraints c(X, {{"symmetry", {0, 1, 2}, InPlane{Vec3::UnitX(), 0}},
                          {"base", {0}, Fixed{}},
                          {"floor", {1}, InPlane{Vec3(1, 0, 1), 0}}});
  VectorX g(12);
  for (Index i = 0; i < 12; ++i) g(i) = i + 1;
  const auto R = c.reactions(g);
  // symmetry: x of nodes 1 and 2 (node 0 belongs to base); floor: what (1, 0, 1) adds beyond
  // x at node 1, which is z.
  EXPECT_LE((R.row(0) - Eigen::RowVector3d(4 + 7, 0, 0)).norm(), 1e-14);
  EXPECT_LE((R.row(1) - Eigen::RowVector3d(1, 2, 3)).norm(), 1e-14);
  EXPECT_LE((R.row(2) - Eigen::RowVector3d(0, 0, 6)).norm(), 1e-14);
  VectorX free = g;
  c.project(free);
  const VectorX constrained = g - free;
  const Vec3 total(constrained(Eigen::seq(0, 11, 3)).sum(), constrained(Eigen::seq(1, 11, 3)).sum(),
                   constrained(Eigen::seq(2, 11, 3)).sum());
  EXPECT_LE((R.colwise().sum().transpose() - total).norm(), 1e-14);
}

TEST(Constraints, RejectsBadInput) {
  const Points X = four_points();
  EXPECT_THROW(Constraints(X, {{"a", {9}, Fixed{}}}), InputError);
  EXPECT_THROW(Constraints(X, {{"a", {}, Fixed{}}}), InputError);
  EXPECT_THROW(Constraints(X, {{"a", {0}, InPlane{Vec3::Zero(), 0}}}), InputError);
  EXPECT_THROW(Constraints(X, {{"a", {0}, Rotated{Vec3::Zero(), Vec3::Zero(), 1, Vec3::Zero()}}}),
               InputError);
}

}  // namespace
}  // namespace depthfem
