// Contact kernels: AABB tree build, refit and query over a two-body scene, and penalty
// integration throughput (pairs per second) for energy only and energy + gradient + Hessian.
//
//   build/bench/bench_contact --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include "contact/material_depth.hpp"
#include "contact/material_depth_contact.hpp"
#include "core/mesh_generators.hpp"

namespace depthfem {
namespace {

// Two boxes, the upper sunk 30 % into the lower, offset so that no grid planes coincide.
struct Scene {
  Mesh mesh;
  VectorX depth;
  Scene() {
    mesh.add_body("low", box_mesh({Vec3(0, 0, 0), Vec3(1, 1, 0.2), Eigen::Vector3i(40, 40, 8)}));
    mesh.add_body("high", box_mesh({Vec3(0.23, 0.17, 0.14), Vec3(0.83, 0.77, 0.34), Eigen::Vector3i(28, 28, 8)}));
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
  state.counters["candidates_per_s"] =
      benchmark::Counter(static_cast<double>(c.stats().candidates), benchmark::Counter::kIsIterationInvariantRate);
}

template <bool kDerivatives>
void BM_PenaltyIntegration(benchmark::State& state) {
  MaterialDepthContact c(scene().mesh, scene().depth, {1e7, true});
  c.prepare(scene().mesh.X);
  const Index n = c.stats().active;
  for (auto _ : state) {
    for (const ContactPair& p : c.pairs()) {
      if constexpr (kDerivatives) {
        auto d = c.pair_derivatives(scene().mesh.X, p);
        benchmark::DoNotOptimize(d.hessian.data());
      } else {
        benchmark::DoNotOptimize(c.pair_energy(scene().mesh.X, p));
      }
    }
  }
  state.counters["pairs_per_s"] = benchmark::Counter(static_cast<double>(n), benchmark::Counter::kIsIterationInvariantRate);
}

BENCHMARK(BM_TreeBuild)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TreeRefit)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PairSearch)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PenaltyIntegration<false>)->Name("PenaltyEnergy")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PenaltyIntegration<true>)->Name("PenaltyEnergyGradHess")->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace depthfem

BENCHMARK_MAIN();
