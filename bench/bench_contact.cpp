// Contact kernels: AABB tree build, refit and query over a two-body scene, and penalty
// integration throughput (pairs per second): energy only, energy + gradient, energy + gradient +
// Hessian (the staged chain rule), and the same by Dual2<21> automatic differentiation through
// the whole energy (the test oracle, which the staged derivatives replaced).
//
//   build/bench/bench_contact --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include "contact/material_depth.hpp"
#include "contact/material_depth_contact.hpp"
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

}  // namespace
}  // namespace depthfem

BENCHMARK_MAIN();
