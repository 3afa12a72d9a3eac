// The pair schedule's pattern with room: pairs that come back need no new pattern, and the kept
// cliques start afresh once they outnumber the current pairs twice.
#include <gtest/gtest.h>

#include "contact/pair_schedule.hpp"

namespace depthfem {
namespace {

// Pairs (cliques of two nodes) k -- k + 1 for k in [first, first + count) on a line of nodes.
struct Pairs {
  PairSchedule::Nodes nodes;
  Points centres;
};
Pairs chain(Index first, Index count) {
  Pairs p{PairSchedule::Nodes(count, 2), Points(count, 3)};
  for (Index k = 0; k < count; ++k) {
    p.nodes.row(k) << first + k, first + k + 1;
    p.centres.row(k) << double(first + k) + 0.5, 0, 0;
  }
  return p;
}

constexpr Index kNodes = 40;

// A pattern of the schedule's couplings (and the diagonal of every node), bound to it.
BlockSparseMatrix bound_pattern(PairSchedule& s) {
  SparsityBuilder builder(kNodes);
  for (Index i = 0; i < kNodes; ++i) builder.add_clique(std::vector<Index>{i});
  s.add_couplings(builder);
  BlockSparseMatrix H(builder);
  s.bind(H, "test");
  return H;
}

TEST(PairSchedule, PairsThatComeBackFindTheirBlocksInThePattern) {
  PairSchedule s;
  const Pairs a = chain(0, 10), b = chain(5, 10);
  s.arrange(a.nodes, a.centres, kNodes, nullptr);
  BlockSparseMatrix H = bound_pattern(s);
  s.arrange(b.nodes, b.centres, kNodes, &H);
  EXPECT_FALSE(s.has_blocks()) << "pairs 10..14 are new";
  H = bound_pattern(s);
  EXPECT_EQ(H.num_blocks(), kNodes + 2 * 15) << "the union of both sets: pairs 0..14";
  s.arrange(a.nodes, a.centres, kNodes, &H);
  EXPECT_TRUE(s.has_blocks()) << "the first set is still in the pattern";
}

TEST(PairSchedule, KeptCliquesStartAfreshWhenTheyOutnumberTheCurrentPairsTwice) {
  PairSchedule s;
  const Pairs a = chain(0, 10), b = chain(20, 5);
  s.arrange(a.nodes, a.centres, kNodes, nullptr);
  BlockSparseMatrix H = bound_pattern(s);
  s.arrange(b.nodes, b.centres, kNodes, &H);  // 15 kept, more than twice 5: only b stays
  ASSERT_FALSE(s.has_blocks());
  H = bound_pattern(s);
  EXPECT_EQ(H.num_blocks(), kNodes + 2 * 5);
  s.arrange(a.nodes, a.centres, kNodes, &H);
  EXPECT_FALSE(s.has_blocks()) << "the first set was dropped";
}

}  // namespace
}  // namespace depthfem
