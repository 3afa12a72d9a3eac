// AABB tree queries equal brute force, before and after refitting.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "contact/aabb_tree.hpp"

namespace depthfem {
namespace {

std::vector<Box3> random_boxes(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> pos(0, 10), size(0.01, 0.8);
  std::vector<Box3> boxes;
  for (int i = 0; i < n; ++i) {
    const Vec3 lo(pos(rng), pos(rng), pos(rng));
    boxes.emplace_back(lo, lo + Vec3(size(rng), size(rng), size(rng)));
  }
  return boxes;
}

std::set<Index> brute(const std::vector<Box3>& boxes, const Box3& q) {
  std::set<Index> out;
  for (size_t i = 0; i < boxes.size(); ++i)
    if (boxes[i].intersects(q)) out.insert(static_cast<Index>(i));
  return out;
}

TEST(AabbTree, QueriesEqualBruteForceBeforeAndAfterRefit) {
  std::mt19937 rng(4);
  std::vector<Box3> boxes = random_boxes(3000, rng);
  AabbTree tree(boxes);
  for (int pass = 0; pass < 2; ++pass) {
    const std::vector<Box3> queries = random_boxes(300, rng);
    for (const Box3& q : queries) {
      std::set<Index> found;
      tree.query(q, [&](Index i) { EXPECT_TRUE(found.insert(i).second) << "reported twice"; });
      EXPECT_EQ(found, brute(boxes, q));
    }
    // Move every box randomly and refit (the topology stays, the answers must not).
    std::normal_distribution<double> jitter(0, 0.5);
    for (Box3& b : boxes) {
      const Vec3 d(jitter(rng), jitter(rng), jitter(rng));
      b = Box3(b.min() + d, b.max() + d);
    }
    tree.refit(boxes);
  }
}

// Every query, before and after a refit, visits its boxes in the order of walk_order(), which
// holds each primitive once: what lets a list of query results be kept sorted without querying.
TEST(AabbTree, QueriesVisitInWalkOrder) {
  std::mt19937 rng(5);
  std::vector<Box3> boxes = random_boxes(2000, rng);
  AabbTree tree(boxes);
  const std::vector<Index> order = tree.walk_order();
  std::vector<Index> rank(order.size(), -1);
  for (size_t k = 0; k < order.size(); ++k) rank[static_cast<size_t>(order[k])] = k;
  EXPECT_EQ(std::ranges::count(rank, -1), 0) << "walk_order() is a permutation";
  Index visited = 0;
  for (int pass = 0; pass < 2; ++pass) {
    for (const Box3& q : random_boxes(200, rng)) {
      Index last = -1;
      tree.query(q, [&](Index i) {
        EXPECT_GT(rank[static_cast<size_t>(i)], last);
        last = rank[static_cast<size_t>(i)];
        ++visited;
      });
    }
    for (Box3& b : boxes) b.translate(Vec3(0.3, -0.2, 0.1) * (pass + 1));
    std::ranges::shuffle(boxes, rng);  // the same tree over other boxes
    tree.refit(boxes);
  }
  EXPECT_GT(visited, 200) << "the queries must meet boxes";
}

TEST(AabbTree, NearestFindsTheClosestBox) {
  std::mt19937 rng(9);
  const std::vector<Box3> boxes = random_boxes(2000, rng);
  const AabbTree tree(boxes);
  std::uniform_real_distribution<double> pos(-2, 12);
  for (int k = 0; k < 200; ++k) {
    const Vec3 p(pos(rng), pos(rng), pos(rng));
    double best = std::numeric_limits<double>::infinity();
    tree.nearest(p, best, [&](Index i, double) {
      best = std::min(best, boxes[i].squaredExteriorDistance(p));
      return best;
    });
    double expected = std::numeric_limits<double>::infinity();
    for (const Box3& b : boxes) expected = std::min(expected, b.squaredExteriorDistance(p));
    EXPECT_EQ(best, expected);
  }
}

}  // namespace
}  // namespace depthfem
