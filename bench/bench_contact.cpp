// Contact kernels: AABB tree build, refit and query over a two-body scene, and penalty
// integration throughput (pairs per second): energy only, energy + gradient, energy + gradient +
// Hessian (the staged chain rule), and the same by Dual2<21> automatic differentiation through
// the whole energy (the test oracle, which the staged derivatives replaced); then the module's
// assembly (derivatives added into the gradient and the block matrix, 1 and 2 threads) against
// the pair derivatives alone, and the same for a sphere obstacle pressed into the upper box
// (staged derivatives against Dual2<9>, which the obstacle module used before).
//
//   build/bench/bench_contact --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include "contact/material_depth.hpp"
#include "contact/material_depth_contact.hpp"
#include "contact/obstacle_contact.hpp"
#include "contact/penalty.hpp"
#include "core/mesh_generators.hpp"

namespace depthfem {
namespace {

// Two boxes, the upper sunk 30 % into the lower, offset so that no grid planes coincide.
struct Scene {
  Mesh mesh;
  VectorX depth;
  Scene() {
    mesh.add_body("low", box_mesh({Vec3(0, 0, 0), Vec3(1, 1, 0.2), Eigen::Vector3i(40, 40, 8)}));
    mesh.add_body("high", box_mesh({Vec3(0.23, 0.17, 0.14), Vec3(0.83, 0.77, 0.34),
                                    Eigen::Vector3i(28, 28, 8)}));
    depth = material_depth(mesh);
  }
};
const Scene& scene() {
  static const Scene s;
  return s;
}

void BM_TreeBuild(benchmark::State& state) {
  const std::vector<Box3> boxes = tet_boxes(scene().mesh.X, scene().mesh.tets);
  for (auto _ : state) benchmark::DoNotOptimize(AabbTree(boxes));
  state.counters["tets"] = static_cast<double>(boxes.size());
}

void BM_TreeRefit(benchmark::State& state) {
  const std::vector<Box3> boxes = tet_boxes(scene().mesh.X, scene().mesh.tets);
  AabbTree tree(boxes);
  for (auto _ : state) tree.refit(tet_boxes(scene().mesh.X, scene().mesh.tets));
  state.counters["tets"] = static_cast<double>(boxes.size());
}

// prepare(): refit, query every boundary triangle, clip candidates (the collision detection).
void BM_PairSearch(benchmark::State& state) {
  MaterialDepthContact c(scene().mesh, scene().depth, {1e7, true});
  for (auto _ : state) c.prepare(scene().mesh.X);
  state.counters["candidates"] = static_cast<double>(c.stats().candidates);
  state.counters["active_pairs"] = static_cast<double>(c.stats().active);
  state.counters["candidates_per_s"] = benchmark::Counter(
      static_cast<double>(c.stats().candidates), benchmark::Counter::kIsIterationInvariantRate);
}

enum class Evaluation { kEnergy, kGradient, kHessian, kAutodiff };

// Energy, gradient and Hessian of a pair by Dual2<21> through tet_polygon_penalty.
double autodiff_pair(const Points& x, const ContactPair& p) {
  using D = Dual2<21>;
  const Mesh& m = scene().mesh;
  std::array<V3<D>, 4> P;
  std::array<V3<D>, 3> Q;
  std::array<double, 4> g;
  for (int a = 0; a < 4; ++a)
    P[a] = make_point<D>(x.row(m.tets(p.tet, a)), 3 * a), g[a] = scene().depth(m.tets(p.tet, a));
  for (int b = 0; b < 3; ++b) Q[b] = make_point<D>(x.row(m.tris(p.tri, b)), 12 + 3 * b);
  const D W = tet_polygon_penalty(p.polygon, P, Q, g, 1e7, 0.0);
  benchmark::DoNotOptimize(W.h.data());
  return W.v;
}

template <Evaluation kEvaluation>
void BM_PenaltyIntegration(benchmark::State& state) {
  MaterialDepthContact c(scene().mesh, scene().depth, {1e7, true});
  c.prepare(scene().mesh.X);
  const Index n = c.stats().active;
  PairGradient gradient;
  PairHessian hessian;
  for (auto _ : state) {
    for (const ContactPair& p : c.pairs()) {
      if constexpr (kEvaluation == Evaluation::kEnergy) {
        benchmark::DoNotOptimize(c.pair_energy(scene().mesh.X, p));
      } else if constexpr (kEvaluation == Evaluation::kGradient) {
        benchmark::DoNotOptimize(c.pair_derivatives(scene().mesh.X, p, gradient, nullptr));
        benchmark::DoNotOptimize(gradient.data());
      } else if constexpr (kEvaluation == Evaluation::kHessian) {
        benchmark::DoNotOptimize(c.pair_derivatives(scene().mesh.X, p, gradient, &hessian));
        benchmark::DoNotOptimize(hessian.data());
      } else {
        benchmark::DoNotOptimize(autodiff_pair(scene().mesh.X, p));
      }
    }
  }
  state.counters["pairs_per_s"] =
      benchmark::Counter(static_cast<double>(n), benchmark::Counter::kIsIterationInvariantRate);
}

// MaterialDepthContact::evaluate with a gradient (and Hessian) into a matrix over the contact
// couplings: the pair derivatives plus their scatter.
template <bool kHessian>
void BM_ContactAssembly(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  MaterialDepthContact c(scene().mesh, scene().depth, {1e7, true});
  c.prepare(scene().mesh.X);
  SparsityBuilder builder(scene().mesh.num_nodes());
  c.add_couplings(builder);
  BlockSparseMatrix H(builder);
  c.bind(H);
  VectorX g = VectorX::Zero(3 * scene().mesh.num_nodes());
  for (auto _ : state)
    benchmark::DoNotOptimize(c.evaluate(scene().mesh.X, &g, kHessian ? &H : nullptr));
  state.counters["pairs_per_s"] = benchmark::Counter(static_cast<double>(c.stats().active),
                                                     benchmark::Counter::kIsIterationInvariantRate);
}

// A sphere pressed into the top of the upper box: its boundary triangles touching the sphere,
// evaluated by the module (staged derivatives, scattered) or by Dual2<9> alone.
const ObstacleContact& pressed_sphere() {
  static const ObstacleContact o = [] {
    ObstacleContact c(scene().mesh, {1},
                      {{"ball", SphereObstacle{Vec3(0.53, 0.47, 0.64), 0.32}, Vec3::Zero(), 1e7}});
    c.begin_step(scene().mesh.X);
    c.set_load(0);
    c.prepare(scene().mesh.X);
    return c;
  }();
  return o;
}

double sphere_triangles_dual(const Points& x) {
  using D = Dual2<9>;
  const Vec3 centre(0.53, 0.47, 0.64);
  double energy = 0;
  const Mesh& m = scene().mesh;
  for (Index f = m.bodies[1].first_tri; f < m.bodies[1].first_tri + m.bodies[1].num_tris; ++f) {
    std::array<Vec3, 3> Q;
    std::array<V3<D>, 3> Qd;
    std::array<D, 3> G;
    for (int k = 0; k < 3; ++k) {
      Q[k] = x.row(m.tris(f, k));
      Qd[k] = make_point<D>(Q[k], 3 * k);
      const V3<D> d = Qd[k] - make_point<D>(centre, 0) * 1.0;
      G[k] = -sqrt(d.dot(d)) + 0.32;
    }
    if (G[0].v <= 0 && G[1].v <= 0 && G[2].v <= 0) continue;
    const ClipPolygon poly = clip_triangle_by_field(Q, {G[0].v, G[1].v, G[2].v});
    const D W = field_polygon_penalty(poly, Qd, G, 1e7, 0.0);
    benchmark::DoNotOptimize(W.h.data());
    energy += W.v;
  }
  return energy;
}

void BM_ObstacleStaged(benchmark::State& state) {
  ObstacleContact o = pressed_sphere();
  SparsityBuilder builder(scene().mesh.num_nodes());
  o.add_couplings(builder);
  BlockSparseMatrix H(builder);
  o.bind(H);
  VectorX g = VectorX::Zero(3 * scene().mesh.num_nodes());
  for (auto _ : state) benchmark::DoNotOptimize(o.evaluate(scene().mesh.X, &g, &H));
}

void BM_ObstacleDual(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(sphere_triangles_dual(scene().mesh.X));
}

BENCHMARK(BM_TreeBuild)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TreeRefit)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PairSearch)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PenaltyIntegration<Evaluation::kEnergy>)
    ->Name("PenaltyEnergy")
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PenaltyIntegration<Evaluation::kGradient>)
    ->Name("PenaltyEnergyGrad")
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PenaltyIntegration<Evaluation::kHessian>)
    ->Name("PenaltyEnergyGradHess")
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PenaltyIntegration<Evaluation::kAutodiff>)
    ->Name("PenaltyEnergyGradHessAutodiff")
    ->Unit(benchmark::kMillisecond);
// CPU time of the whole process: pairs per CPU-second, comparable with the one-thread rows above.
BENCHMARK(BM_ContactAssembly<false>)
    ->Name("ContactAssembly/Gradient")
    ->Arg(1)
    ->Arg(2)
    ->MeasureProcessCPUTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ContactAssembly<true>)
    ->Name("ContactAssembly/Hessian")
    ->Arg(1)
    ->Arg(2)
    ->MeasureProcessCPUTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ObstacleStaged)->Name("ObstacleHessian/Staged")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ObstacleDual)->Name("ObstacleHessian/Dual2")->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace depthfem

BENCHMARK_MAIN();
