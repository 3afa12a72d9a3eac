// Linear solvers on a clamped elastic block: each reaches what it promises.
#include <gtest/gtest.h>
#include <petscsys.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/mesh_generators.hpp"
#include "integrators/forces/constraints.hpp"
#include "integrators/forces/elasticity.hpp"
#include "integrators/solvers/amg_solver.hpp"
#include "integrators/solvers/direct_solver.hpp"
#include "integrators/solvers/linear_solver.hpp"
#include "integrators/solvers/thread_budget.hpp"

namespace depthfem {
namespace {

// Stiffness of a 6 x 3 x 3 (or `cells`) Mooney-Rivlin block clamped at x = 0, at a deformed
// state, with a right-hand side of random forces; `shift` subtracts a multiple of the identity.
struct Problem {
  BlockSparseMatrix A;
  VectorX b;
};
Problem clamped_block(double shift, const Eigen::Vector3i& cells = {6, 3, 3}) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3(2, 1, 1), cells});
  std::vector<Index> all(m.tets.rows());
  std::iota(all.begin(), all.end(), 0);
  Elasticity e(m.X, m.tets, {{MooneyRivlin{4e3, 1e3, 2e4}, all, Points()}});
  SparsityBuilder builder(static_cast<Index>(m.X.rows()));
  e.add_couplings(builder);
  Problem p{BlockSparseMatrix(builder), VectorX::Zero(3 * m.X.rows())};
  e.bind(p.A);
  Points x = m.X;
  x.col(0) *= 1.1;
  e.evaluate(x, &p.b, &p.A);
  std::vector<Index> clamp;
  for (Index i = 0; i < m.X.rows(); ++i)
    if (m.X(i, 0) == 0) clamp.push_back(i);
  const Constraints c(m.X, {{"clamp", clamp, Fixed{}}});
  c.project(p.A);
  for (Index i = 0; i < p.A.num_nodes(); ++i)
    p.A.block(p.A.block_index(i, i)).diagonal().array() -= shift;
  p.b = VectorX::LinSpaced(p.b.size(), -1, 1);
  c.project(p.b);
  return p;
}

double residual(const BlockSparseMatrix& A, const VectorX& x, const VectorX& b) {
  VectorX Ax;
  A.multiply(x, Ax);
  return (b - Ax).norm() / b.norm();
}

TEST(LinearSolver, EachMethodMeetsItsTolerance) {
  const Problem p = clamped_block(0.0);
  for (double tol : {0.1, 1e-8}) {
    for (LinearSolverKind kind : {LinearSolverKind::kGmres, LinearSolverKind::kCg}) {
      LinearSolver s({kind, tol, 5000, 30});
      VectorX x;
      const LinearSolveStats st = s.solve(p.A, p.b, x);
      EXPECT_TRUE(st.reached_tolerance) << to_string(kind) << " tol " << tol;
      EXPECT_LE(residual(p.A, x, p.b), tol) << to_string(kind);
      EXPECT_NEAR(st.relative_residual, residual(p.A, x, p.b), 1e-6 * tol);
      EXPECT_GT(st.iterations, 0);
    }
  }
  LinearSolver direct({LinearSolverKind::kDirect});
  VectorX x;
  EXPECT_TRUE(direct.solve(p.A, p.b, x).reached_tolerance);
  EXPECT_LE(residual(p.A, x, p.b), 1e-10);
}

// Newton's forcing term reaches the direct solver's CG on the kept factor: two solvers factor
// the same matrix, its diagonal is then raised by 1 % of its mean, and each solves the changed
// system, one to 0.1 and one to 1e-6: each meets its tolerance, the loose one by CG on its kept
// factor alone, the tight one with more CG iterations or (on this small block, whose CG is
// allowed two iterations before a factorisation) with a new factorisation.
TEST(LinearSolver, DirectKeptFactorStopsAtTheGivenTolerance) {
  Problem p = clamped_block(0.0);
  DirectSolver loose_solver, tight_solver;
  VectorX x;
  EXPECT_TRUE(loose_solver.solve(p.A, p.b, x).factored);
  EXPECT_TRUE(tight_solver.solve(p.A, p.b, x).factored);
  const double raise = 0.01 * p.A.diagonal().mean();
  for (Index i = 0; i < p.A.num_nodes(); ++i)
    p.A.block(p.A.block_index(i, i)).diagonal().array() += raise;
  const DirectSolveStats loose = loose_solver.solve(p.A, p.b, x, 0.1);
  EXPECT_FALSE(loose.factored);
  EXPECT_LE(residual(p.A, x, p.b), 0.1);
  const DirectSolveStats tight = tight_solver.solve(p.A, p.b, x, 1e-6);
  EXPECT_LE(residual(p.A, x, p.b), 1e-6);
  EXPECT_TRUE(tight.factored || tight.cg_iterations > loose.cg_iterations);
}

// Matrices drifting from the factored one (the diagonal raised a little more each time, as
// the Newton matrices of a dynamic run drift over its steps): CG on the kept factor needs more
// iterations each time, and the next matrix is factored once a solve costs more than the mean
// over the factor's solves, its factorisation counted as F / (40 nnz(L)) iterations. Every
// solve meets its tolerance; the rule is replayed from the statistics and must have fired.
TEST(LinearSolver, DirectRefactorsOnceASolveCostsMoreThanTheMean) {
  Problem p = clamped_block(0.0, {24, 8, 8});
  DirectSolver solver;
  const DirectAnalysis& analysis = solver.analyse(p.A);
  const double factor_cost = std::clamp(analysis.flops / (40 * analysis.factor_entries), 2.0, 50.0);
  ASSERT_GT(factor_cost, 4);  // a block bulky enough for several CG iterations per factorisation
  const double raise = 0.003 * p.A.diagonal().mean();
  int solves = 0, rule_refactors = 0;
  double cost = 0;
  bool refactor = false;
  VectorX x;
  for (int j = 0; j < 40; ++j) {
    const DirectSolveStats s = solver.solve(p.A, p.b, x, 1e-6);
    ASSERT_TRUE(s.success);
    EXPECT_LE(residual(p.A, x, p.b), 1e-6) << "solve " << j;
    if (refactor) {
      EXPECT_TRUE(s.factored && s.cg_iterations == 0) << "solve " << j;
      ++rule_refactors;
    }
    if (s.factored) {
      solves = 1;
      cost = factor_cost;
      refactor = false;
    } else {
      ++solves;
      cost += s.cg_iterations;
      refactor = s.cg_iterations * solves > cost;
    }
    for (Index i = 0; i < p.A.num_nodes(); ++i)
      p.A.block(p.A.block_index(i, i)).diagonal().array() += raise;
  }
  EXPECT_GE(rule_refactors, 2);
}

TEST(LinearSolver, IterationCapIsHonoured) {
  const Problem p = clamped_block(0.0);
  LinearSolver s({LinearSolverKind::kGmres, 1e-12, 7, 5});
  VectorX x;
  const LinearSolveStats st = s.solve(p.A, p.b, x);
  EXPECT_EQ(st.iterations, 7);
  EXPECT_FALSE(st.reached_tolerance);
  EXPECT_LT(st.relative_residual, 1.0);  // GMRES never increases the residual
}

TEST(LinearSolver, DirectSolvesIndefiniteSystemsExactlyWithLdlt) {
  // Shifting the spectrum makes the matrix indefinite (as past a bifurcation): LL^T fails and
  // the LDL^T fallback must still solve it.
  const Problem p = clamped_block(2e3);
  LinearSolverOptions o{LinearSolverKind::kDirect};
  o.direct.indefinite = IndefiniteFallback::kLdlt;
  LinearSolver direct(o);
  VectorX x;
  const LinearSolveStats st = direct.solve(p.A, p.b, x);
  EXPECT_TRUE(st.reached_tolerance);
  EXPECT_EQ(st.shift, 0.0);
  EXPECT_LE(residual(p.A, x, p.b), 1e-8);
}

// D = diag|A|: the weights of the shifted fallback A + s D.
VectorX shift_weights(const BlockSparseMatrix& A) {
  return A.diagonal().cwiseAbs();
}

TEST(LinearSolver, DirectShiftsIndefiniteSystemsToADescentDirection) {
  // The shifted fallback solves (A + s D) x = b with A + s D positive definite, so x is a
  // descent direction for the quadratic with gradient -b: b.x = x^T (A + s D) x > 0.
  const Problem p = clamped_block(2e3);
  LinearSolver direct({LinearSolverKind::kDirect});
  ASSERT_EQ(direct.options().direct.indefinite, IndefiniteFallback::kShift);
  VectorX x;
  const LinearSolveStats st = direct.solve(p.A, p.b, x);
  ASSERT_GT(st.shift, 0.0);
  EXPECT_GT(p.b.dot(x), 0.0);
  VectorX Ax;
  p.A.multiply(x, Ax);
  const VectorX D = shift_weights(p.A);
  EXPECT_LE((p.b - Ax - st.shift * D.cwiseProduct(x)).norm(), 1e-10 * p.b.norm());
  // The shift is less than ten times the least that works: a tenth of it leaves A + s D
  // indefinite.
  BlockSparseMatrix shifted = p.A;
  for (Index i = 0; i < shifted.num_nodes(); ++i)
    shifted.block(shifted.block_index(i, i)).diagonal() += 0.1 * st.shift * D.segment<3>(3 * i);
  LinearSolver probe({LinearSolverKind::kDirect});
  EXPECT_GT(probe.solve(shifted, p.b, x).shift, 0.0);
}

TEST(LinearSolver, DirectSolvesAfterAShiftAsAFreshSolverWould) {
  // After a shifted factorisation the solver estimates the lowest eigenvalue before trying LL^T
  // and skips LL^T where the estimate is negative: the next indefinite matrix must get the shift
  // and solution a fresh solver gives it (to the estimate's rounding: the kept solver's Lanczos
  // steps start from its last Ritz vector, a fresh one's from a random vector), and a positive
  // definite one after it its exact, unshifted solution.
  const Problem first = clamped_block(2e3), second = clamped_block(2.5e3),
                definite = clamped_block(0);
  DirectSolverOptions factor_always;
  factor_always.reuse_tolerance = 0;  // no CG on the kept factor: every matrix is factored
  DirectSolver kept(factor_always);
  VectorX x;
  ASSERT_GT(kept.solve(first.A, first.b, x).shift, 0.0);
  for (const Problem* p : {&second, &definite}) {
    DirectSolver fresh(factor_always);
    VectorX y;
    const DirectSolveStats a = kept.solve(p->A, p->b, x), b = fresh.solve(p->A, p->b, y);
    ASSERT_TRUE(a.success);
    EXPECT_NEAR(a.shift, b.shift, 1e-12 * b.shift);
    EXPECT_LE((x - y).norm(), 1e-10 * y.norm());
  }
  EXPECT_LE(residual(definite.A, x, definite.b), 1e-10);  // shift 0: the exact solution
}

TEST(LinearSolver, DirectShiftIsInvariantUnderRescalingTheDofs) {
  // A stiff region beside a soft one (a bone beside soft tissue, a penalty beside both): the
  // congruence S A S with S = diag(1000 on half the nodes, 1 on the rest) has the same inertia,
  // and with the shift weighted by the diagonal, (S A S + s S D S) y = S b is solved by
  // y = S^-1 x with the same s. A shift s I would instead be set by the stiff half and freeze
  // the soft one.
  const Problem p = clamped_block(2e3);
  VectorX scale = VectorX::Ones(p.b.size());
  scale.head(p.b.size() / 2).setConstant(1e3);
  BlockSparseMatrix scaled = p.A;
  for (Index i = 0; i < scaled.num_nodes(); ++i)
    for (Index k = scaled.row_begin(i); k < scaled.row_begin(i + 1); ++k) {
      const Index j = scaled.block_col(k);
      scaled.block(k) = scale.segment<3>(3 * i).asDiagonal() * scaled.block(k) *
                        scale.segment<3>(3 * j).asDiagonal();
    }
  LinearSolver plain({LinearSolverKind::kDirect}), rescaled({LinearSolverKind::kDirect});
  VectorX x, y;
  const LinearSolveStats a = plain.solve(p.A, p.b, x);
  const LinearSolveStats b = rescaled.solve(scaled, scale.cwiseProduct(p.b), y);
  ASSERT_GT(a.shift, 0.0);
  // The Lanczos estimate sees the same scaled matrix up to round-off.
  EXPECT_NEAR(b.shift, a.shift, 1e-6 * a.shift);
  EXPECT_LE((scale.cwiseProduct(y) - x).norm(), 1e-6 * x.norm());
}

// A chain of nodes coupled to the next (pattern 1) or to the one after next (pattern 2), both
// closed into a ring: the same number of blocks, different blocks. Symmetric, diagonally dominant.
BlockSparseMatrix ring(Index nodes, Index stride) {
  SparsityBuilder builder(nodes);
  for (Index i = 0; i < nodes; ++i) builder.add_clique(std::vector<Index>{i, (i + stride) % nodes});
  BlockSparseMatrix A(builder);
  for (Index i = 0; i < nodes; ++i)
    for (Index k = A.row_begin(i); k < A.row_begin(i + 1); ++k) {
      const Index j = A.block_col(k);
      Mat3 B;
      for (int e = 0; e < 9; ++e) B(e / 3, e % 3) = std::sin(1.0 + std::min(i, j) + 0.1 * e);
      A.block(k) = i == j ? Mat3(10 * Mat3::Identity()) : (i < j ? B : Mat3(B.transpose()));
    }
  return A;
}

TEST(LinearSolver, DirectAnalysesEveryNewPatternEvenWithTheSameBlockCount) {
  const BlockSparseMatrix A1 = ring(20, 1), A2 = ring(20, 2);
  ASSERT_EQ(A1.num_blocks(), A2.num_blocks());
  const VectorX b = VectorX::LinSpaced(60, -1, 1);
  LinearSolver direct({LinearSolverKind::kDirect});
  VectorX x;
  for (const BlockSparseMatrix* A : {&A1, &A2, &A1}) {
    const LinearSolveStats st = direct.solve(*A, b, x);
    EXPECT_TRUE(st.reached_tolerance);
    EXPECT_LE(residual(*A, x, b), 1e-12);
  }
}

// The clamped nodes of clamped_block, 1 per node.
std::vector<char> clamped_nodes(const BlockSparseMatrix& A) {
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3(2, 1, 1), Eigen::Vector3i(6, 3, 3)});
  std::vector<char> out(static_cast<size_t>(A.num_nodes()), 0);
  for (Index i = 0; i < m.X.rows(); ++i) out[size_t(i)] = m.X(i, 0) == 0;
  return out;
}

// Leaving the couplings of the clamped nodes (zero after Constraints::project) out of the
// factored pattern gives the same solution to rounding, with fewer flops.
TEST(LinearSolver, DirectLeavesOutTheCouplingsOfDecoupledNodes) {
  const Problem p = clamped_block(0.0);
  DirectSolver whole({DirectOrdering::kAmd}), reduced({DirectOrdering::kAmd});
  reduced.set_decoupled_nodes(clamped_nodes(p.A));
  EXPECT_LT(reduced.analyse(p.A).flops, whole.analyse(p.A).flops);
  VectorX x_whole, x_reduced;
  ASSERT_TRUE(whole.solve(p.A, p.b, x_whole).success);
  ASSERT_TRUE(reduced.solve(p.A, p.b, x_reduced).success);
  EXPECT_LE((x_reduced - x_whole).norm(), 1e-12 * x_whole.norm());
  EXPECT_LE(residual(p.A, x_reduced, p.b), 1e-12);
}

// The block matrix `A` with extra couplings (i, j) for the given node pairs, holding
// `value` I in them (and the values of A elsewhere).
BlockSparseMatrix with_couplings(const BlockSparseMatrix& A,
                                 const std::vector<std::pair<Index, Index>>& pairs, double value) {
  SparsityBuilder builder(A.num_nodes());
  for (Index i = 0; i < A.num_nodes(); ++i)
    for (Index k = A.row_begin(i); k < A.row_begin(i + 1); ++k)
      builder.add_clique(std::vector<Index>{i, A.block_col(k)});
  for (const auto& [i, j] : pairs) builder.add_clique(std::vector<Index>{i, j});
  BlockSparseMatrix B(builder);
  for (Index i = 0; i < A.num_nodes(); ++i)
    for (Index k = A.row_begin(i); k < A.row_begin(i + 1); ++k)
      B.block(B.block_index(i, A.block_col(k))) = A.block(k);
  for (const auto& [i, j] : pairs) {
    B.block(B.block_index(i, j)) = value * Mat3::Identity();
    B.block(B.block_index(j, i)) = value * Mat3::Identity();
  }
  return B;
}

// A new pattern that adds only a coupling of a decoupled node (zero in the matrix) leaves the
// factor's pattern as it is: nothing is redone; one that adds an entry outside the factor is
// analysed anew; one whose entries lie in that factor (the first pattern again, a part of the
// larger one) keeps its analysis and is fitted to it. Each solve is exact.
TEST(LinearSolver, DirectKeepsItsAnalysisForAPatternThatFitsTheFactor) {
  const Problem p = clamped_block(0.0);
  const std::vector<char> clamped = clamped_nodes(p.A);
  const Index clamped_node = Index(std::find(clamped.begin(), clamped.end(), 1) - clamped.begin());
  const Index last = p.A.num_nodes() - 1;  // free, at the far end from the clamp
  ASSERT_EQ(clamped[size_t(last)], 0);
  DirectSolver solver({DirectOrdering::kAmd});
  solver.set_decoupled_nodes(clamped);
  VectorX x;
  ASSERT_TRUE(solver.solve(p.A, p.b, x).success);
  EXPECT_EQ(solver.analyse(p.A).refitted, 0);
  EXPECT_EQ(solver.analyse(p.A).unchanged, 0);
  const BlockSparseMatrix same = with_couplings(p.A, {{clamped_node, last}}, 0.0);
  ASSERT_TRUE(solver.solve(same, p.b, x).success);
  EXPECT_EQ(solver.analyse(same).unchanged, 1) << "a decoupled node's coupling adds no entry";
  EXPECT_EQ(solver.analyse(same).refitted, 0);
  EXPECT_LE(residual(same, x, p.b), 1e-12);
  // Free nodes at the two ends of the block are not coupled in the factor of an AMD ordering
  // of a 6 x 3 x 3 block (its fill stays within a few layers).
  const Index first_free = Index(std::find(clamped.begin(), clamped.end(), 0) - clamped.begin());
  const BlockSparseMatrix grows = with_couplings(p.A, {{first_free, last}}, 1e-3);
  ASSERT_TRUE(solver.solve(grows, p.b, x).success);
  EXPECT_EQ(solver.analyse(grows).refitted, 0) << "an entry outside the factor needs an analysis";
  EXPECT_EQ(solver.analyse(grows).unchanged, 0);
  EXPECT_LE(residual(grows, x, p.b), 1e-12);
  ASSERT_TRUE(solver.solve(p.A, p.b, x).success);
  EXPECT_EQ(solver.analyse(p.A).refitted, 1) << "a part of the analysed pattern fits its factor";
  EXPECT_LE(residual(p.A, x, p.b), 1e-12);
}

// The node of m at (x, y, z) (-1: none).
Index node_at(const TetMesh& m, double x, double y, double z) {
  for (Index i = 0; i < m.X.rows(); ++i)
    if ((m.X.row(i) - Eigen::RowVector3d(x, y, z)).norm() < 1e-9) return i;
  return -1;
}

// A pattern that does not fit the factor but whose factorisation under the same ordering costs
// at most 2 % more flops keeps the ordering (only the symbolic analysis is redone); one that
// costs more is ordered anew. Either way the solve is exact.
TEST(LinearSolver, DirectKeepsItsOrderingWhereTheFlopsBarelyGrow) {
  const Eigen::Vector3i cells(12, 4, 4);
  const Problem p = clamped_block(0.0, cells);
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3(2, 1, 1), cells});
  // Two nodes a cell or two apart, not coupled by a tet nor in the factor (found by a search:
  // 0.05 % more flops under METIS's ordering), and the block's two ends (7.7 % more).
  const Index a = node_at(m, 1.5, 0.0, 0.25), b = node_at(m, 1.0 + 2.0 / 3, 0.5, 0.75);
  const Index first = node_at(m, 2.0 / 12, 0.5, 0.5), last = node_at(m, 2.0, 0.5, 0.5);
  ASSERT_TRUE(a >= 0 && b >= 0 && first >= 0 && last >= 0);
  for (const auto& [i, j, kept] : {std::tuple{a, b, true}, std::tuple{first, last, false}}) {
    DirectSolver solver({DirectOrdering::kMetis});
    VectorX x;
    ASSERT_TRUE(solver.solve(p.A, p.b, x).success);
    const double flops = solver.analyse(p.A).flops;
    const BlockSparseMatrix grown = with_couplings(p.A, {{i, j}}, 1e-3);
    ASSERT_TRUE(solver.solve(grown, p.b, x).success);
    const DirectAnalysis& after = solver.analyse(grown);
    EXPECT_EQ(after.refitted, 0) << "the coupling lies outside the factor";
    EXPECT_EQ(after.reanalysed, kept ? 1 : 0);
    if (kept) {
      EXPECT_LE(after.flops, 1.02 * flops);
    }
    EXPECT_LE(residual(grown, x, p.b), 1e-12);
  }
}

// With the best ordering, a block whose AMD ordering leaves large fronts is ordered by METIS
// (both computed, METIS with fewer flops); a later pattern of that size that needs a new ordering
// (the block's two ends coupled: more than 2 % more flops under the kept one) is ordered by METIS
// alone, into the analysis that comparing both gives it.
TEST(LinearSolver, DirectOrdersByMetisAloneOnceMetisHasWon) {
  const Eigen::Vector3i cells(24, 12, 12);
  const Problem p = clamped_block(0.0, cells);
  const TetMesh m = box_mesh({Vec3::Zero(), Vec3(2, 1, 1), cells});
  const Index first = node_at(m, 2.0 / 24, 0.5, 0.5), last = node_at(m, 2.0, 0.5, 0.5);
  ASSERT_TRUE(first >= 0 && last >= 0);
  const BlockSparseMatrix grown = with_couplings(p.A, {{first, last}}, 1e-3);
  DirectSolver solver, fresh;
  VectorX x;
  ASSERT_TRUE(solver.solve(p.A, p.b, x).success);
  const DirectAnalysis before = solver.analyse(p.A);
  ASSERT_EQ(before.ordering, DirectOrdering::kMetis);
  ASSERT_TRUE(before.compared);
  ASSERT_TRUE(solver.solve(grown, p.b, x).success);
  const DirectAnalysis after = solver.analyse(grown);
  EXPECT_EQ(after.reanalysed, 0) << "ordered anew";
  EXPECT_EQ(after.ordering, DirectOrdering::kMetis);
  EXPECT_FALSE(after.compared);
  EXPECT_LE(residual(grown, x, p.b), 1e-12);
  const DirectAnalysis compared = fresh.analyse(grown);
  EXPECT_TRUE(compared.compared);
  EXPECT_EQ(compared.ordering, DirectOrdering::kMetis);
  EXPECT_EQ(after.flops, compared.flops);
  EXPECT_EQ(after.factor_entries, compared.factor_entries);
}

DirectSolverOptions single_precision() {
  DirectSolverOptions o;
  o.precision = FactorPrecision::kSingle;
  return o;
}

// A single-precision factor solves by CG in double to the asked tolerance: an exact solve
// (tolerance 0) to kSingleExactTolerance, agreeing with the double factor's solution to the
// condition number (below 1e4 here) times that; a loose one to its tolerance in fewer
// iterations.
TEST(LinearSolver, DirectSingleFactorSolvesToTheAskedTolerance) {
  const Problem p = clamped_block(0.0, {12, 4, 4});
  DirectSolver double_solver, exact(single_precision()), loose(single_precision());
  VectorX reference, x, y;
  ASSERT_TRUE(double_solver.solve(p.A, p.b, reference).success);
  const DirectSolveStats e = exact.solve(p.A, p.b, x);
  ASSERT_TRUE(e.success && e.factored && e.single);
  EXPECT_LE(residual(p.A, x, p.b), DirectSolver::kSingleExactTolerance);
  EXPECT_LE((x - reference).norm(), 1e-8 * reference.norm());
  const DirectSolveStats l = loose.solve(p.A, p.b, y, 1e-3);
  ASSERT_TRUE(l.success && l.single);
  EXPECT_LE(residual(p.A, y, p.b), 1e-3);
  EXPECT_LT(l.cg_iterations, e.cg_iterations);
}

// An indefinite matrix: the single-precision LL^T fails where the double one does, and the
// shifted matrix gets the same shift (the same estimate and ladder) and its solution to the
// tolerance.
TEST(LinearSolver, DirectSingleFactorShiftsAsTheDoubleOne) {
  const Problem p = clamped_block(2e3);
  DirectSolver double_solver, single_solver(single_precision());
  VectorX reference, x;
  const DirectSolveStats d = double_solver.solve(p.A, p.b, reference);
  const DirectSolveStats s = single_solver.solve(p.A, p.b, x);
  ASSERT_GT(d.shift, 0.0);
  ASSERT_TRUE(s.success && s.single);
  EXPECT_EQ(s.shift, d.shift);
  EXPECT_EQ(s.failed_factorizations, d.failed_factorizations);
  EXPECT_LE((x - reference).norm(), 1e-8 * reference.norm());
}

// The clamped block with its free part's diagonal shifted so that its lowest eigenvalue is
// `lowest` times its largest.
Problem block_with_lowest_eigenvalue(double lowest) {
  Problem p = clamped_block(0.0);
  const std::vector<char> clamped = clamped_nodes(p.A);
  std::vector<Index> free_dofs;
  for (Index i = 0; i < p.A.num_nodes(); ++i)
    if (!clamped[static_cast<size_t>(i)])
      for (Index d = 0; d < 3; ++d) free_dofs.push_back(3 * i + d);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(p.b.size(), p.b.size());
  for (Index i = 0; i < p.A.num_nodes(); ++i)
    for (Index k = p.A.row_begin(i); k < p.A.row_begin(i + 1); ++k)
      dense.block<3, 3>(3 * i, 3 * p.A.block_col(k)) = p.A.block(k);
  Eigen::MatrixXd free(free_dofs.size(), free_dofs.size());
  for (size_t a = 0; a < free_dofs.size(); ++a)
    for (size_t b = 0; b < free_dofs.size(); ++b) free(a, b) = dense(free_dofs[a], free_dofs[b]);
  const VectorX eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(free).eigenvalues();
  const double shift = eigenvalues(0) - lowest * eigenvalues(eigenvalues.size() - 1);
  for (Index i = 0; i < p.A.num_nodes(); ++i)
    if (!clamped[static_cast<size_t>(i)])
      p.A.block(p.A.block_index(i, i)).diagonal().array() -= shift;
  return p;
}

// The lowest eigenvalue of D^-1/2 A D^-1/2, D = |diag(A)|: the scaled spectrum the direct
// solver's shifts are measured in (dense, for small blocks).
double lowest_scaled_eigenvalue(const BlockSparseMatrix& A) {
  const Eigen::MatrixXd dense = Eigen::MatrixXd(A.to_sparse());
  const VectorX inv_sqrt = dense.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = inv_sqrt.asDiagonal() * dense * inv_sqrt.asDiagonal();
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(scaled, Eigen::EigenvaluesOnly)
      .eigenvalues()(0);
}

// A positive definite matrix of condition about 1e9 (the block's free part shifted down to 1e-9
// of its largest eigenvalue), beyond single precision's reach: the single-precision LL^T fails
// (at a pivot of about -2e-6 of its diagonal entry), and the solver falls back to the double
// factor and solves A itself, unshifted.
TEST(LinearSolver, DirectSingleFactorFallsBackToDoubleBeyondItsReach) {
  const Problem p = block_with_lowest_eigenvalue(1e-9);
  DirectSolver solver(single_precision());
  VectorX x;
  const DirectSolveStats s = solver.solve(p.A, p.b, x);
  ASSERT_TRUE(s.success);
  EXPECT_FALSE(s.single);
  EXPECT_EQ(s.shift, 0.0);
  EXPECT_EQ(s.failed_factorizations, 1) << "the single-precision one";
  EXPECT_LE(residual(p.A, x, p.b), 1e-6);
}

// Slightly indefinite matrices (the lowest eigenvalue -1e-5 and -1e-6 of the largest), which
// the 30 Lanczos steps do not see (the shift is the ladder's first, 1e-3): where the single-
// precision LL^T fails at a pivot below -1e-3 of its diagonal entry (-6e-3 at -1e-5) A is not
// factored in double, and the solver fails as often as the double one and shifts as it does;
// where the pivot lies above (-5e-4 at -1e-6) LL^T in double decides, one failure more.
TEST(LinearSolver, DirectSingleFactorSkipsTheDoubleOneWhereItsPivotProvesAIndefinite) {
  for (const double lowest : {-1e-5, -1e-6}) {
    const Problem p = block_with_lowest_eigenvalue(lowest);
    DirectSolver double_solver, single_solver(single_precision());
    VectorX reference, x;
    const DirectSolveStats d = double_solver.solve(p.A, p.b, reference);
    const DirectSolveStats s = single_solver.solve(p.A, p.b, x);
    ASSERT_TRUE(d.success && s.success && s.single);
    EXPECT_EQ(d.shift, 1e-3) << lowest;
    EXPECT_EQ(s.shift, d.shift) << lowest;
    EXPECT_EQ(d.failed_factorizations, 1) << lowest;
    EXPECT_EQ(s.failed_factorizations, lowest == -1e-5 ? 1 : 2) << lowest;
    EXPECT_LE((x - reference).norm(), 1e-6 * reference.norm()) << lowest;
  }
}

// A chain of n nodes, each direction a 1D Laplacian (2 on the diagonal, -1 beside it, the ends
// held), its diagonal lowered by its lowest eigenvalue plus three times the gap to the next: the
// lowest eigenvalue negative, the soft modes above it close together.
BlockSparseMatrix lowered_chain(Index n) {
  SparsityBuilder builder(n);
  for (Index i = 0; i + 1 < n; ++i) builder.add_clique(std::vector<Index>{i, i + 1});
  BlockSparseMatrix A(builder);
  const double h = std::acos(-1.0) / static_cast<double>(n + 1);
  const double first = 2 - 2 * std::cos(h), second = 2 - 2 * std::cos(2 * h);
  const double lowered = first + 3 * (second - first);
  for (Index i = 0; i < n; ++i)
    for (Index k = A.row_begin(i); k < A.row_begin(i + 1); ++k)
      A.block(k) = (A.block_col(k) == i ? 2 - lowered : -1.0) * Mat3::Identity();
  return A;
}

// The lowest eigenvalue of the 200-node lowered chain, -1.1e-3 on the solver's scale, lies among
// soft modes that 30 Lanczos steps from a random start do not resolve: the first solve's
// estimate falls short of it, and the shift ladder climbs from its lowest rung (LL^T of A and
// the shift 1e-3 fail, 4e-3 succeeds). Each later estimate starts from the last one's Ritz
// vector, a restarted Lanczos run that gets closer with each restart (the second solve's
// estimate still falls short: one failed rung; from the third solve on each finds it): once an
// estimate is below zero, LL^T of A is not tried and the first shift, 1.5 times the estimate,
// lies between |lowest| and 1.5 |lowest|. With estimates from a random start every solve would
// repeat the first one's failed factorisations.
TEST(LinearSolver, DirectEstimateStartsFromTheLastRitzVector) {
  const BlockSparseMatrix A = lowered_chain(200);
  const double lowest = lowest_scaled_eigenvalue(A);
  ASSERT_LT(lowest, -1e-3);
  const VectorX b = VectorX::LinSpaced(A.num_nodes() * 3, -1, 1);
  DirectSolver solver;
  VectorX x;
  const DirectSolveStats first = solver.solve(A, b, x);
  ASSERT_TRUE(first.success);
  EXPECT_EQ(first.estimates, 1);
  EXPECT_EQ(first.failed_factorizations, 2) << "the estimate from a random start missed";
  EXPECT_EQ(first.shift, 4e-3);
  int found = 0;  // solves whose estimate was below zero
  for (int k = 0; k < 6; ++k) {
    const DirectSolveStats later = solver.solve(A, b, x);
    ASSERT_TRUE(later.success);
    EXPECT_EQ(later.estimates, 1) << k;
    VectorX Ax;
    A.multiply(x, Ax);
    Ax += later.shift * A.diagonal().cwiseAbs().cwiseProduct(x);
    EXPECT_LE((Ax - b).norm(), 1e-8 * b.norm()) << k;
    if (later.failed_factorizations > 0) {
      EXPECT_EQ(found, 0) << k << ": an estimate that was found again lost";
      continue;
    }
    ++found;
    EXPECT_GT(later.shift, -lowest) << k;
    EXPECT_LE(later.shift, -1.5 * lowest) << k;
  }
  EXPECT_GE(found, 5) << "the warm-started estimates found the eigenvalue from the third solve on";
}

// The prediction from the block graph against CHOLMOD's analysis of the scalar pattern with the
// same (AMD) ordering, an independent count: a block column of c blocks expands into three
// columns of about 3c entries, so 27 times the block graph's flops, slightly above the scalar
// count (measured 1.006 to 1.02 on the cantilever from 40 to 80 cells; 1.10 allowed).
TEST(LinearSolver, PredictedFactorFlopsMatchTheScalarAnalysis) {
  const Problem p = clamped_block(0.0);
  DirectSolver direct({DirectOrdering::kAmd});
  const double scalar = direct.analyse(p.A).flops, predicted = predicted_factor_flops(p.A);
  EXPECT_GE(predicted, scalar);
  EXPECT_LE(predicted, 1.10 * scalar);
}

// auto takes AMG-CG exactly when the predicted flops exceed auto_flops_per_entry times the
// entries of the lower triangle; the direct solve takes one iteration, AMG-CG several.
TEST(LinearSolver, AutoChoosesByThePredictedFlopsPerEntry) {
  const Problem p = clamped_block(0.0);
  const double per_entry = predicted_factor_flops(p.A) / lower_triangle_entries(p.A);
  for (const double factor : {0.5, 2.0}) {
    LinearSolverOptions o;
    o.auto_flops_per_entry = factor * per_entry;
    o.amg.tolerance = 1e-8;
    LinearSolver s(o);
    VectorX x;
    const LinearSolveStats st = s.solve(p.A, p.b, x);
    EXPECT_TRUE(st.reached_tolerance);
    EXPECT_LE(residual(p.A, x, p.b), 1e-8);
    if (factor < 1)
      EXPECT_GT(st.iterations, 1) << "the threshold below the prediction must choose AMG-CG";
    else
      EXPECT_EQ(st.iterations, 1) << "the threshold above the prediction must choose direct";
  }
}

// AMG-CG hands the matrix to PETSc once per pattern and only its values afterwards: written
// into the array of PETSc's sequential matrix on one process, or through MPIAIJ's update (the
// multi-process type, forced on one by -mat_type). Both must solve the system as it is after
// its values changed, to the tolerance, measured by depthfem's own product.
TEST(LinearSolver, AmgSolvesTheUpdatedMatrixWithEitherPetscType) {
  for (const bool distributed : {false, true}) {
    Problem p = clamped_block(0.0);
    AmgSolver amg({AmgPreconditioner::kGamg, 1e-10, 500, false});
    if (distributed) {
      ASSERT_EQ(PetscOptionsSetValue(nullptr, "-mat_type", "mpiaij"), 0);
    }
    VectorX x;
    EXPECT_TRUE(amg.solve(p.A, p.b, x, nullptr).converged);
    EXPECT_LE(residual(p.A, x, p.b), 1e-10);
    if (distributed) {
      PetscBool used = PETSC_FALSE;
      ASSERT_EQ(PetscOptionsUsed(nullptr, "mat_type", &used), 0);
      EXPECT_TRUE(used) << "the matrix type was not read from the options";
      ASSERT_EQ(PetscOptionsClearValue(nullptr, "-mat_type"), 0);
    }
    for (Index i = 0; i < p.A.num_nodes(); ++i)  // new values, every block row different
      p.A.block(p.A.block_index(i, i)).diagonal().array() *= 1.0 + 0.5 * (i % 3);
    EXPECT_TRUE(amg.solve(p.A, p.b, x, nullptr).converged);
    EXPECT_LE(residual(p.A, x, p.b), 1e-10) << (distributed ? "MPIAIJ" : "sequential AIJ");
  }
}

// PETSc's vector operations call BLAS, which OpenBLAS shares among its threads over more than
// 10,000 entries (its dot products then sum per thread): under a budget of one thread and of
// two, AMG-CG on 11,907 rows must give the same bits.
TEST(LinearSolver, AmgGivesTheSameBitsOnOneAndTwoThreads) {
  const Problem p = clamped_block(0.0, {48, 8, 8});
  ASSERT_GT(p.b.size(), 10000);
  VectorX x[2];
  for (const int threads : {1, 2}) {
    const ThreadBudget budget(threads);
    AmgSolver amg({AmgPreconditioner::kGamg, 1e-10, 500, false});
    EXPECT_TRUE(amg.solve(p.A, p.b, x[threads - 1], nullptr).converged);
  }
  EXPECT_TRUE(x[0] == x[1]) << "apart by up to " << (x[0] - x[1]).cwiseAbs().maxCoeff();
}

}  // namespace
}  // namespace depthfem
