// The contact force modules: no forces at rest, exact derivatives of the assembled energy,
// continuity of material-depth forces against the node-to-surface baseline.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "contact/material_depth.hpp"
#include "contact/material_depth_contact.hpp"
#include "contact/node_to_surface_contact.hpp"
#include "contact/obstacle_contact.hpp"
#include "core/mesh_generators.hpp"
#include "finite_differences.hpp"

namespace depthfem {
namespace {

struct Evaluated {
  double energy = 0;
  VectorX gradient;
  Eigen::SparseMatrix<double> hessian;
  BlockSparseMatrix pattern;  // stays bound to the module for its later prepare() calls
};

// Energy, gradient and Hessian of a module at x, with a pattern built for the pairs at x.
void evaluate(ForceModule& m, const Points& x, Evaluated& out) {
  m.prepare(x);
  SparsityBuilder b(static_cast<Index>(x.rows()));
  m.add_couplings(b);
  out.pattern = BlockSparseMatrix(b);
  m.bind(out.pattern);
  out.gradient = VectorX::Zero(3 * x.rows());
  out.energy = m.evaluate(x, &out.gradient, &out.pattern);
  out.hessian = out.pattern.to_sparse();
}

TEST(MaterialDepthContact, UndeformedBodiesWithSelfContactHaveNoContactForces) {
  Mesh m;
  m.add_body("ball", ball_mesh({Vec3::Zero(), 0.5, 6}));
  m.add_body("box", box_mesh({Vec3(1, 0, 0), Vec3(2, 0.5, 0.3), Eigen::Vector3i(6, 3, 2)}));
  MaterialDepthContact c(m, material_depth(m), {1e6, true});
  c.begin_step(m.X);
  Evaluated r;
  evaluate(c, m.X, r);
  EXPECT_EQ(r.energy, 0.0);
  EXPECT_EQ(r.gradient.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(r.hessian.coeffs().size() ? r.hessian.coeffs().cwiseAbs().maxCoeff() : 0.0, 0.0);
  EXPECT_GT(c.stats().candidates, 0) << "neighbouring elements must have been examined";
}

// The gradient of a contact module as a function of the interleaved dofs, its pairs found anew
// at every point.
auto module_gradient(ForceModule& module) {
  return [&module](const VectorX& z) {
    const Points y = as_points(z);
    module.prepare(y);
    VectorX g = VectorX::Zero(z.size());
    module.evaluate(y, &g, nullptr);
    return g;
  };
}

// A box resting on a wider one: the faces touch with zero depth, which is no contact area.
// Pressed 1 mm in, the upper box's bottom face (0.4 x 0.4 m, at least a cell from the lower box's
// sides, so inside tets with positive depth) counts in full; the lower box's top face inside the
// upper box counts where the upper box's tets have depth (not in its edge tets, all of whose
// nodes lie on its surface), so at most as much again.
TEST(MaterialDepthContact, TouchingAtRestIsNoContactArea) {
  Mesh m;
  m.add_body("low", box_mesh({Vec3(0, 0, 0), Vec3(1, 1, 0.4), Eigen::Vector3i(10, 10, 2)}));
  m.add_body("high",
             box_mesh({Vec3(0.3, 0.3, 0.4), Vec3(0.7, 0.7, 0.8), Eigen::Vector3i(4, 4, 4)}));
  MaterialDepthContact c(m, material_depth(m), {1e6, false});
  c.begin_step(m.X);
  Evaluated rest;
  evaluate(c, m.X, rest);
  EXPECT_GT(c.stats().active, 0) << "the faces touch";
  StepRecord at_rest;
  c.report(m.X, at_rest);
  EXPECT_EQ(at_rest.contact_area(), 0.0);
  EXPECT_EQ(rest.energy, 0.0);
  Points x = m.X;
  const Body& high = m.bodies[1];
  x.col(2).segment(high.first_node, high.num_nodes).array() -= 0.001;
  Evaluated pressed;
  evaluate(c, x, pressed);
  StepRecord step;
  c.report(x, step);
  EXPECT_GE(step.contact_area(), 0.16 - 1e-9);
  EXPECT_LE(step.contact_area(), 0.32 + 1e-9);
}

// Two boxes overlapping by a third of the upper one's height, with self-contact on; random
// perturbations make every clip case appear. Finite differences re-run the pair search.
TEST(MaterialDepthContact, AssembledDerivativesMatchFiniteDifferences) {
  Mesh m;
  m.add_body("low", box_mesh({Vec3(0, 0, 0), Vec3(1, 1, 0.4), Eigen::Vector3i(4, 4, 2)}));
  m.add_body("high",
             box_mesh({Vec3(0.23, 0.17, 0.3), Vec3(0.83, 0.77, 0.6), Eigen::Vector3i(3, 3, 2)}));
  MaterialDepthContact c(m, material_depth(m), {1e5, true});
  c.begin_step(m.X);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  Points x = m.X;
  for (Index i = 0; i < x.size(); ++i) x(i) += u(rng);
  Evaluated r;
  evaluate(c, x, r);
  ASSERT_GT(r.energy, 0);
  ASSERT_GT(c.stats().active, 20);
  const double h = 1e-7;
  const VectorX fd = testing::central_gradient_dofs(
      [&](const Points& y) {
        c.prepare(y);
        return c.evaluate(y, nullptr, nullptr);
      },
      x, h);
  EXPECT_LE((r.gradient - fd).cwiseAbs().maxCoeff(), 1e-6 * r.gradient.cwiseAbs().maxCoeff());
  std::normal_distribution<double> n;
  VectorX v(x.size());
  for (Index i = 0; i < v.size(); ++i) v(i) = n(rng);
  const VectorX Hv = r.hessian * v;
  const VectorX Hv_fd = testing::central_directional(module_gradient(c), as_dofs(x), v, h);
  EXPECT_LE((Hv - Hv_fd).cwiseAbs().maxCoeff(), 1e-5 * Hv.cwiseAbs().maxCoeff());
}

// The (triangle, tet) pairs a module finds at the reference configuration.
std::set<std::pair<Index, Index>> found_pairs(const Mesh& mesh, ContactOptions options) {
  MaterialDepthContact c(mesh, material_depth(mesh), std::move(options));
  c.begin_step(mesh.X);
  c.prepare(mesh.X);
  std::set<std::pair<Index, Index>> out;
  for (const ContactPair& p : c.pairs()) out.insert({p.tri, p.tet});
  return out;
}

// A search that leaves out the pairs where `left_out(tri, tet)` found `searched`: exactly the
// pairs of `all` not left out (more than 10 of them, and more than 10 left out).
void expect_all_but(const std::set<std::pair<Index, Index>>& all,
                    const std::set<std::pair<Index, Index>>& searched, const auto& left_out) {
  std::set<std::pair<Index, Index>> expected;
  Index dropped = 0;
  for (const auto& [tri, tet] : all) {
    if (left_out(tri, tet))
      ++dropped;
    else
      expected.insert({tri, tet});
  }
  EXPECT_GT(dropped, 10) << "the pairs left out must exist";
  EXPECT_GT(expected.size(), 10u);
  EXPECT_EQ(searched, expected);
}

// Three overlapping boxes.
Mesh three_boxes() {
  Mesh m;
  m.add_body("a", box_mesh({Vec3(0, 0, 0), Vec3(1, 1, 0.4), Eigen::Vector3i(4, 4, 2)}));
  m.add_body("b", box_mesh({Vec3(0.2, 0.1, 0.3), Vec3(0.8, 0.7, 0.6), Eigen::Vector3i(3, 3, 2)}));
  m.add_body("c", box_mesh({Vec3(0.1, 0.2, 0.25), Vec3(0.9, 0.6, 0.65), Eigen::Vector3i(4, 2, 2)}));
  return m;
}

// Pairs of two rigid bodies, whose nodes are all prescribed, are not searched; every other pair
// is found as without rigid bodies: three overlapping boxes, the outer two rigid.
TEST(MaterialDepthContact, PairsOfTwoRigidBodiesAreNotSearched) {
  Mesh m = three_boxes();
  const auto all = found_pairs(m, {.penalty = 1e5});
  m.bodies[0].rigid = m.bodies[2].rigid = true;
  const auto searched = found_pairs(m, {.penalty = 1e5});
  expect_all_but(all, searched, [&](Index tri, Index tet) {
    return m.bodies[m.tri_body(tri)].rigid && m.bodies[m.tet_body(tet)].rigid;
  });
}

// An excluded interface loses its pairs from both sides (a's triangles in c's tets and c's in
// a's) and nothing else; an excluded self-contact only the body's own pairs.
TEST(MaterialDepthContact, ExcludedInterfacesAreNotSearched) {
  const Mesh m = three_boxes();
  const auto all = found_pairs(m, {.penalty = 1e5});
  const auto searched = found_pairs(m, {.penalty = 1e5, .excluded = {{0, 2}, {1, 1}}});
  expect_all_but(all, searched, [&](Index tri, Index tet) {
    const std::set<Index> bodies = {m.tri_body(tri), m.tet_body(tet)};
    return bodies == std::set<Index>{0, 2} || bodies == std::set<Index>{1};
  });
}

// The candidate list: after moves within its margin the module keeps its list; after a few
// nodes move beyond it, it searches the trees again for those nodes' triangles and looks up
// their tets among the other triangles; after many do, it makes a new list. Either way it finds
// the pairs, polygons and order that a module searching its trees at those positions finds.
TEST(MaterialDepthContact, TheCandidateListFindsWhatASearchAtThePositionsFinds) {
  const Mesh m = three_boxes();
  const Index num_tris = static_cast<Index>(m.tris.rows());
  MaterialDepthContact kept(m, material_depth(m), {.penalty = 1e5});
  kept.begin_step(m.X);
  kept.prepare(m.X);
  ASSERT_EQ(kept.stats().searched_triangles, num_tris);
  const double margin = kept.list_margin();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto moved = [&](const Points& from, double per_axis) {
    Points y = from;
    for (Index i = 0; i < y.size(); ++i) y.data()[i] += per_axis * u(rng);
    return y;
  };
  // The nodes of two pairs (tet and triangle) sent two to three margins away, the rest kept.
  const auto few_far = [&](const Points& from) {
    Points y = from;
    for (size_t k = 0; k < 2; ++k) {
      const ContactPair& p = kept.pairs()[k * kept.pairs().size() / 2];
      for (int a = 0; a < 4; ++a)
        y.row(m.tets(p.tet, a)) += Vec3(u(rng), u(rng), 2 + u(rng)).transpose() * margin;
      for (int b = 0; b < 3; ++b)
        y.row(m.tris(p.tri, b)) += Vec3(2 + u(rng), u(rng), u(rng)).transpose() * margin;
    }
    return y;
  };
  // Each move is measured from where the list took each node: within the margin (a node moves
  // at most sqrt(3) per_axis), then far for all, within again, far for 14 nodes (twice), and
  // within again from there (0.4 + 0.4 of the margin at most for the nodes listed at `far`).
  enum Search { kNone, kFew, kAll };
  const double w = margin / std::sqrt(3.0);
  const Points far = moved(m.X, 3 * margin);
  const Points within_far = moved(far, 0.4 * w);
  const Points few = few_far(within_far);
  const Points few_again = few_far(few);
  const std::vector<std::pair<Points, Search>> moves = {{moved(m.X, 0.5 * w), kNone},
                                                        {moved(m.X, 0.9 * w), kNone},
                                                        {far, kAll},
                                                        {within_far, kNone},
                                                        {few, kFew},
                                                        {few_again, kFew},
                                                        {moved(few_again, 0.4 * w), kNone}};
  Index compared = 0, ordered = 0;
  for (const auto& [x, search] : moves) {
    kept.prepare(x);
    const Index searched = kept.stats().searched_triangles;
    EXPECT_EQ(kept.stats().relisted, search != kNone);
    if (search == kFew) {
      EXPECT_GT(searched, 0);
      EXPECT_LT(searched, num_tris / 4);
    } else {
      EXPECT_EQ(searched, search == kAll ? num_tris : 0);
    }
    MaterialDepthContact fresh(m, material_depth(m), {.penalty = 1e5});
    fresh.prepare(x);
    ASSERT_EQ(kept.pairs().size(), fresh.pairs().size());
    EXPECT_EQ(kept.stats().candidates, fresh.stats().candidates);
    for (size_t k = 0; k < fresh.pairs().size(); ++k) {
      const ContactPair &a = kept.pairs()[k], &b = fresh.pairs()[k];
      ASSERT_EQ(std::tie(a.tri, a.tet, a.polygon.size), std::tie(b.tri, b.tet, b.polygon.size));
      for (int v = 0; v < a.polygon.size; ++v) EXPECT_EQ(a.polygon.x[v], b.polygon.x[v]);
    }
    compared += static_cast<Index>(fresh.pairs().size());
    // The tets both lists hold for a triangle come in the same order (the search's).
    for (Index f = 0; f < num_tris; ++f) {
      const auto in = [](std::span<const Index> list, Index t) {
        return std::ranges::find(list, t) != list.end();
      };
      std::vector<Index> a, b;
      for (Index t : kept.candidates(f))
        if (in(fresh.candidates(f), t)) a.push_back(t);
      for (Index t : fresh.candidates(f))
        if (in(kept.candidates(f), t)) b.push_back(t);
      EXPECT_EQ(a, b) << "triangle " << f;
      ordered += a.size() >= 2;
    }
  }
  EXPECT_GT(compared, 100) << "the boxes must overlap";
  EXPECT_GT(ordered, 100);
}

// A distributed run's ranks: each module clips only the pairs of the tets it owns, so two
// modules owning complementary halves hold together the whole module's pairs and energy, and
// each reports the whole surface (the forces, areas and depth integrals of every triangle).
// Two halves of the tets, as two ranks hold them: each half's trees, pairs and energy are its
// own tets', and the two halves' report shares, merged, give the report of the whole.
TEST(MaterialDepthContact, OwnedTetsSplitThePairsAndTheirSharesMakeTheReport) {
  const Mesh m = three_boxes();
  const ContactOptions options{.penalty = 1e5};
  MaterialDepthContact whole(m, material_depth(m), options);
  whole.begin_step(m.X);
  whole.prepare(m.X);
  StepRecord expected;
  whole.report(m.X, expected);
  std::set<std::pair<Index, Index>> all, split;
  for (const ContactPair& p : whole.pairs()) all.insert({p.tri, p.tet});
  double energy = 0;
  std::vector<ContactShare> concatenated;
  size_t first_half = 0;  // shares in concatenated
  for (const int half : {0, 1}) {
    ContactPart owned;
    owned.owned.resize(static_cast<size_t>(m.num_tets()));
    for (Index t = 0; t < m.num_tets(); ++t) owned.owned[static_cast<size_t>(t)] = t % 2 == half;
    MaterialDepthContact part(m, material_depth(m), options, owned);
    part.begin_step(m.X);
    part.prepare(m.X);
    EXPECT_LT(part.stats().listed, whole.stats().listed);
    for (const ContactPair& p : part.pairs()) {
      EXPECT_EQ(p.tet % 2, half);
      EXPECT_TRUE(split.insert({p.tri, p.tet}).second) << "a pair on both halves";
    }
    energy += part.evaluate(m.X, nullptr, nullptr);
    const std::vector<ContactShare> shares = part.shares(m.X);
    concatenated.insert(concatenated.end(), shares.begin(), shares.end());
    if (half == 0) first_half = concatenated.size();
  }
  EXPECT_GT(all.size(), 100u) << "the boxes must overlap";
  EXPECT_EQ(split, all);
  const double total = whole.evaluate(m.X, nullptr, nullptr);
  EXPECT_GT(total, 0);
  EXPECT_NEAR(energy, total, 1e-12 * total);

  const std::vector<ContactShare> merged = MaterialDepthContact::merge(concatenated);
  EXPECT_LT(merged.size(), concatenated.size()) << "no triangle has pairs on both halves";
  StepRecord reported;
  whole.report_shares(merged, reported);
  const auto close = [](const auto& a, const auto& b) {
    return (a - b).cwiseAbs().maxCoeff() <= 1e-12 * b.cwiseAbs().maxCoeff();
  };
  EXPECT_TRUE(close(reported.surface.force, expected.surface.force));
  EXPECT_TRUE(close(reported.surface.magnitude, expected.surface.magnitude));
  EXPECT_TRUE(close(reported.surface.area, expected.surface.area));
  EXPECT_TRUE(close(reported.surface.depth_integral, expected.surface.depth_integral));
  ASSERT_EQ(reported.contact.size(), expected.contact.size());
  for (size_t r = 0; r < expected.contact.size(); ++r) {
    const InterfaceForce &a = reported.contact[r], &b = expected.contact[r];
    EXPECT_LE((a.force - b.force).norm(), 1e-12 * b.force.norm()) << "row " << r;
    EXPECT_NEAR(a.magnitude, b.magnitude, 1e-12 * b.magnitude) << "row " << r;
    EXPECT_NEAR(a.area, b.area, 1e-12 * b.area) << "row " << r;
  }
  // The first half's shares alone miss the other half's pairs.
  StepRecord half;
  whole.report_shares(MaterialDepthContact::merge(std::span(concatenated).first(first_half)), half);
  EXPECT_FALSE(close(half.surface.area, expected.surface.area));
}

// Energy, gradient and Hessian of a module at x on `threads` threads, into a matrix bound to it.
struct Assembly {
  double energy = 0;
  VectorX gradient;
  Eigen::MatrixXd hessian;
};
Assembly assemble_on(int threads, ForceModule& m, const Points& x, BlockSparseMatrix& H) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  tbb::task_arena arena(threads);
  Assembly a;
  a.gradient = VectorX::Zero(3 * x.rows());
  H.set_zero();
  arena.execute([&] { a.energy = m.evaluate(x, &a.gradient, &H); });
  a.hessian = Eigen::MatrixXd(H.to_sparse());
  return a;
}

// Every gradient entry and matrix block receives its terms in the module's pair order, whatever
// the number of threads: the colored chunks scatter concurrently into disjoint nodes. The serial
// reference adds pair by pair in pairs() order, finding each block by search.
TEST(MaterialDepthContact, ParallelScatterEqualsTheSerialOneBitForBit) {
  Mesh m;
  m.add_body("low", box_mesh({Vec3(0, 0, 0), Vec3(1, 1, 0.2), Eigen::Vector3i(16, 16, 3)}));
  m.add_body("high", box_mesh({Vec3(0.23, 0.17, 0.14), Vec3(0.83, 0.77, 0.34),
                               Eigen::Vector3i(10, 10, 3)}));
  MaterialDepthContact c(m, material_depth(m), {1e6, true});
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-0.004, 0.004);
  Points x = m.X;
  for (Index i = 0; i < x.size(); ++i) x(i) += u(rng);
  c.begin_step(x);
  c.prepare(x);
  ASSERT_GT(c.stats().active, 2000) << "want many chunks of 256 pairs";
  SparsityBuilder builder(m.num_nodes());
  c.add_couplings(builder);
  BlockSparseMatrix H(builder), reference(builder);
  c.bind(H);
  VectorX g_ref = VectorX::Zero(3 * x.rows());
  PairGradient grad;
  PairHessian hess;
  for (const ContactPair& p : c.pairs()) {
    c.pair_derivatives(x, p, grad, &hess);
    const Index v[7] = {m.tets(p.tet, 0), m.tets(p.tet, 1), m.tets(p.tet, 2), m.tets(p.tet, 3),
                        m.tris(p.tri, 0), m.tris(p.tri, 1), m.tris(p.tri, 2)};
    for (int a = 0; a < 7; ++a) {
      g_ref.segment<3>(3 * v[a]) += grad.segment<3>(3 * a);
      for (int b = 0; b < 7; ++b)
        reference.add_block(reference.block_index(v[a], v[b]), hess.block<3, 3>(3 * a, 3 * b));
    }
  }
  const Eigen::MatrixXd H_ref(reference.to_sparse());
  const Assembly one = assemble_on(1, c, x, H);
  for (int threads : {1, 2, 4}) {
    const Assembly r = assemble_on(threads, c, x, H);
    EXPECT_EQ(r.energy, one.energy) << threads << " threads";
    EXPECT_EQ((r.gradient - g_ref).cwiseAbs().maxCoeff(), 0.0) << threads << " threads";
    EXPECT_EQ((r.hessian - H_ref).cwiseAbs().maxCoeff(), 0.0) << threads << " threads";
  }
  EXPECT_GT(H_ref.cwiseAbs().maxCoeff(), 0);
}

// The obstacle and node-to-surface modules scatter the same way: the same result, bit for bit,
// on 1, 2 and 4 threads.
TEST(ContactModules, ObstacleAndNodeToSurfaceScattersDoNotDependOnTheThreadCount) {
  Mesh m;
  m.add_body("low", box_mesh({Vec3(0, 0, 0), Vec3(1, 1, 0.2), Eigen::Vector3i(16, 16, 3)}));
  m.add_body("high", box_mesh({Vec3(0.23, 0.17, 0.14), Vec3(0.83, 0.77, 0.34),
                               Eigen::Vector3i(10, 10, 3)}));
  ObstacleContact obstacles(
      m, {0, 1},
      {{"ball", SphereObstacle{Vec3(0.5, 0.5, -2.9), 3.0}, Vec3::Zero(), 1e6},
       {"floor", PlaneObstacle{Vec3(0, 0, 0.05), Vec3::UnitZ()}, Vec3::Zero(), 1e6}});
  NodeToSurfaceContact baseline(m, 1e6);
  for (ForceModule* module : std::initializer_list<ForceModule*>{&obstacles, &baseline}) {
    module->begin_step(m.X);
    module->prepare(m.X);
    SparsityBuilder builder(m.num_nodes());
    module->add_couplings(builder);
    BlockSparseMatrix H(builder);
    module->bind(H);
    const Assembly one = assemble_on(1, *module, m.X, H);
    EXPECT_GT(one.energy, 0) << module->name();
    for (int threads : {2, 4}) {
      const Assembly r = assemble_on(threads, *module, m.X, H);
      EXPECT_EQ(r.energy, one.energy) << module->name();
      EXPECT_EQ((r.gradient - one.gradient).cwiseAbs().maxCoeff(), 0.0) << module->name();
      EXPECT_EQ((r.hessian - one.hessian).cwiseAbs().maxCoeff(), 0.0) << module->name();
    }
  }
}

// A flat plate sliding over a faceted ball at constant penetration, in N and 2N steps. The
// material-depth force is a continuous function of the position: its largest change between
// steps halves with the step. The node-to-surface force jumps whenever a node's nearest
// triangle changes: its largest change does not shrink.
double largest_jump(ForceModule& m, const Mesh& mesh, Index plate_first_node, int steps) {
  double jump = 0;
  VectorX previous;
  for (int k = 0; k <= steps; ++k) {
    Points x = mesh.X;
    x.bottomRows(mesh.num_nodes() - plate_first_node).col(0).array() += -0.2 + 0.4 * k / steps;
    m.begin_step(x);
    m.prepare(x);
    VectorX g = VectorX::Zero(3 * x.rows());
    m.evaluate(x, &g, nullptr);
    if (k > 0) jump = std::max(jump, (g - previous).cwiseAbs().maxCoeff());
    previous = g;
  }
  return jump;
}

TEST(ContactContinuity, MaterialDepthForcesAreContinuousAndNodeToSurfaceForcesJump) {
  Mesh m;
  m.add_body("ball", ball_mesh({Vec3::Zero(), 0.5, 6}));
  m.add_body("plate", box_mesh({Vec3(-0.25, -0.25, 0.46), Vec3(0.25, 0.25, 0.6),
                                Eigen::Vector3i(10, 10, 2)}));
  const Index first = m.bodies[1].first_node;
  MaterialDepthContact depth(m, material_depth(m), {1e5, false});
  NodeToSurfaceContact baseline(m, 1e5);
  const double d1 = largest_jump(depth, m, first, 40), d2 = largest_jump(depth, m, first, 80);
  const double b1 = largest_jump(baseline, m, first, 40), b2 = largest_jump(baseline, m, first, 80);
  RecordProperty("material_depth_jumps", std::to_string(d1) + " " + std::to_string(d2));
  RecordProperty("node_to_surface_jumps", std::to_string(b1) + " " + std::to_string(b2));
  EXPECT_GT(d1, 0);
  EXPECT_LT(d2 / d1, 0.6) << "material depth: " << d1 << " -> " << d2;
  EXPECT_GT(b2 / b1, 0.8) << "node to surface: " << b1 << " -> " << b2;
}

TEST(ObstacleContact, PlaneForceMatchesClosedForm) {
  // A 1 x 1 plate whose bottom face is d = 0.01 below the plane z = 0. The obstacle depth is
  // linear, so clipping and integration are exact: the bottom carries pressure eps d on unit
  // area, and the four side walls (perimeter 4) dip into the obstacle with depth falling from d
  // to 0: energy eps/2 (d^2 + 4 d^3 / 3), upward force eps (d + 4 d^2 / 2), area 1 + 4 d.
  const double eps = 1e6, d = 0.01;
  const Mesh m =
      single_body_mesh(box_mesh({Vec3(0, 0, -d), Vec3(1, 1, 0.2), Eigen::Vector3i(4, 4, 2)}));
  ObstacleContact o(m, {0},
                    {{"floor", PlaneObstacle{Vec3::Zero(), Vec3::UnitZ()}, Vec3::Zero(), eps}});
  o.set_load(0);
  o.prepare(m.X);
  StepRecord step;
  o.report(m.X, step);
  ASSERT_EQ(step.contact.size(), 1u);
  EXPECT_EQ(step.contact[0].name, "obstacle floor");
  EXPECT_LE((step.contact[0].force - Vec3(0, 0, eps * (d + 2 * d * d))).norm(), 1e-8);
  EXPECT_NEAR(step.contact[0].area, 1 + 4 * d, 1e-12);
  EXPECT_NEAR(o.evaluate(m.X, nullptr, nullptr), eps / 2 * (d * d + 4 * d * d * d / 3), 1e-9);
  // The obstacle moves with the load factor: at load 1 the plane has risen by d, doubling depths.
  ObstacleContact moving(
      m, {0}, {{"floor", PlaneObstacle{Vec3::Zero(), Vec3::UnitZ()}, Vec3(0, 0, d), eps}});
  moving.set_load(1.0);
  moving.prepare(m.X);
  StepRecord moved;
  moving.report(m.X, moved);
  EXPECT_NEAR(moved.contact[0].force(2), eps * (2 * d + 2 * 4 * d * d), 1e-8);
}

// One tet inside a sphere obstacle: each boundary face carries eps A / 12 (sum G_i^2 + sum G_i G_j)
// with G_i = R - |q_i - c| at its corners (the linear interpolant of the depth, integrated
// exactly); the force is checked against finite differences of that energy, the sphere moved
// by the load factor.
TEST(ObstacleContact, SphereEnergyAndForceMatchTheLinearDepthIntegral) {
  TetMesh t;
  t.X.resize(4, 3);
  t.X << 0.1, 0.0, 0.0, 0.3, 0.05, 0.0, 0.15, 0.25, 0.02, 0.12, 0.08, 0.2;
  t.tets.resize(1, 4);
  t.tets << 0, 1, 2, 3;
  validate_and_orient(t);
  const Mesh m = single_body_mesh(t);
  const double eps = 1e5, R = 0.8;  // all four corners inside at loads 0 and 1
  const Vec3 c(0.1, 0.1, -0.4), motion(0, 0, 0.1);
  ObstacleContact o(m, {0}, {{"ball", SphereObstacle{c, R}, motion, eps}});
  const auto energy = [&](const Points& x, double load) {
    double W = 0;
    for (Index f = 0; f < m.num_tris(); ++f) {
      double G[3];
      for (int k = 0; k < 3; ++k)
        G[k] = R - (x.row(m.tris(f, k)).transpose() - c - load * motion).norm();
      const Vec3 a = x.row(m.tris(f, 0)), b = x.row(m.tris(f, 1)), d = x.row(m.tris(f, 2));
      const double area = 0.5 * (b - a).cross(d - a).norm();
      W += eps * area / 12 *
           (G[0] * G[0] + G[1] * G[1] + G[2] * G[2] + G[0] * G[1] + G[0] * G[2] + G[1] * G[2]);
    }
    return W;
  };
  for (double load : {0.0, 1.0}) {
    o.set_load(load);
    o.prepare(m.X);
    VectorX g = VectorX::Zero(12);
    const double W = o.evaluate(m.X, &g, nullptr);
    EXPECT_NEAR(W, energy(m.X, load), 1e-12 * W);
    for (Index i = 0; i < 12; ++i) {
      Points xp = m.X, xm = m.X;
      xp(i / 3, i % 3) += 1e-7;
      xm(i / 3, i % 3) -= 1e-7;
      EXPECT_NEAR(g(i), (energy(xp, load) - energy(xm, load)) / 2e-7,
                  1e-6 * g.cwiseAbs().maxCoeff());
    }
  }
}

// The assembled obstacle Hessian (staged derivatives) against central differences of the
// gradient, on a plate whose bottom is partly inside a sphere, so that triangles are whole,
// cut to a corner and cut to a quadrilateral. Step 1e-7 on coordinates of order 1: agreement to
// about 1e-7 relative, asserted at 1e-5.
TEST(ObstacleContact, HessianMatchesFiniteDifferencesOfTheGradient) {
  const Mesh m = single_body_mesh(
      box_mesh({Vec3(-0.3, -0.3, -0.02), Vec3(0.3, 0.3, 0.1), Eigen::Vector3i(8, 8, 2)}));
  ObstacleContact o(m, {0}, {{"ball", SphereObstacle{Vec3(0.05, 0, -1), 1}, Vec3::Zero(), 1e6}});
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(-0.003, 0.003);
  Points x = m.X;
  for (Index i = 0; i < x.size(); ++i) x(i) += u(rng);
  o.begin_step(x);
  o.set_load(0);
  Evaluated r;
  evaluate(o, x, r);
  ASSERT_GT(r.energy, 0);
  std::normal_distribution<double> n;
  const double h = 1e-7;
  for (int trial = 0; trial < 3; ++trial) {
    VectorX v(x.size());
    for (Index i = 0; i < v.size(); ++i) v(i) = n(rng);
    const VectorX Hv = r.hessian * v;
    const VectorX Hv_fd = testing::central_directional(module_gradient(o), as_dofs(x), v, h);
    EXPECT_LE((Hv - Hv_fd).cwiseAbs().maxCoeff(), 1e-5 * Hv.cwiseAbs().maxCoeff());
  }
}

}  // namespace
}  // namespace depthfem
