// Element kernel throughput: structure-of-arrays vs array-of-structures, 1 and 2 threads,
// energy + gradient + 12x12 Hessian and gradient only, and full assembly into the block-CSR matrix.
//
//   build/bench/bench_element_kernels --benchmark_counters_tabular=true
//       (add --benchmark_out=kernels.json --benchmark_out_format=json for a file)
//
// Counter `tets_per_s` is tets per second over all threads; `per_core` divides by threads.
#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <numeric>
#include <random>

#include "core/block_sparse_matrix.hpp"
#include "core/mesh_generators.hpp"
#include "core/tet_block.hpp"
#include "integrators/elasticity.hpp"
#include "integrators/tet_kernel.hpp"

namespace depthfem {
namespace {

const MooneyRivlin kMaterial{4e3, 1e3, 2e4};

// A 40 x 40 x 20 box: 192,000 tets, 35,301 nodes, moved by a smooth non-affine map.
struct Scene {
  TetMesh mesh = box_mesh({Vec3::Zero(), Vec3(2, 2, 1), Eigen::Vector3i(40, 40, 20)});
  Points x;
  TetBlock block;
  Scene() {
    x = mesh.X;
    for (Index v = 0; v < x.rows(); ++v) {
      x(v, 0) += 0.05 * std::sin(mesh.X(v, 1) * 3);
      x(v, 2) += 0.05 * std::cos(mesh.X(v, 0) * 2);
    }
    std::vector<Index> all(mesh.tets.rows());
    std::iota(all.begin(), all.end(), 0);
    block = make_tet_block(mesh.X, mesh.tets, all);
  }
};
const Scene& scene() {
  static const Scene s;
  return s;
}

// The same data as an array of structures: one record per tet, xyz interleaved per node.
struct TetRecord {
  Index nodes[4];
  double Dm_inv[9];
  double volume;
};
struct AoSData {
  std::vector<TetRecord> tets;
  std::vector<Vec3> x;
  AoSData() {
    const Scene& s = scene();
    for (Index e = 0; e < s.block.size(); ++e) {
      TetRecord r;
      for (int a = 0; a < 4; ++a) r.nodes[a] = s.block.nodes(e, a);
      for (int k = 0; k < 9; ++k) r.Dm_inv[k] = s.block.Dm_inv(e, k);
      r.volume = s.block.volume(e);
      tets.push_back(r);
    }
    for (Index v = 0; v < s.x.rows(); ++v) x.push_back(s.x.row(v).transpose());
  }
};
const AoSData& aos() {
  static const AoSData d;
  return d;
}

// Layout accessors: both feed the same tet_local math.
struct SoA {
  const TetBlock& b = scene().block;
  const Points& x = scene().x;
  Index node(Index e, int a) const { return b.nodes(e, a); }
  Mat3 Ds(Index e) const {
    Mat3 D;
    const Index n0 = b.nodes(e, 0);
    for (int a = 0; a < 3; ++a) {
      const Index n = b.nodes(e, a + 1);
      D.col(a) = Vec3(x(n, 0) - x(n0, 0), x(n, 1) - x(n0, 1), x(n, 2) - x(n0, 2));
    }
    return D;
  }
  Mat3 D(Index e) const { return b.dm_inv(e); }
  double volume(Index e) const { return b.volume(e); }
};
struct AoS {
  const AoSData& d = aos();
  Index node(Index e, int a) const { return d.tets[e].nodes[a]; }
  Mat3 Ds(Index e) const {
    const TetRecord& r = d.tets[e];
    Mat3 D;
    for (int a = 0; a < 3; ++a) D.col(a) = d.x[r.nodes[a + 1]] - d.x[r.nodes[0]];
    return D;
  }
  Mat3 D(Index e) const { return Mat3(Eigen::Map<const Mat3>(d.tets[e].Dm_inv)); }
  double volume(Index e) const { return d.tets[e].volume; }
};

// kOrder 1: gradient scattered into a 3n vector (colors keep it race-free).
// kOrder 2: energy, gradient and Hessian per tet; the 12x12 is forced into memory but not
// scattered (so that the kernel, not the scatter, is measured; BM_Assembly adds the scatter).
template <int kOrder, class Layout>
void BM_Kernel(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  const Layout L;
  const TetBlock& b = scene().block;
  VectorX g(3 * scene().x.rows());
  std::vector<double> sink(b.size());
  for (auto _ : state) {
    g.setZero();
    for (Index c = 0; c < b.num_colors(); ++c) {
      tbb::parallel_for(
          tbb::blocked_range<Index>(b.color_begin[c], b.color_begin[c + 1], 1),
          [&](const tbb::blocked_range<Index>& chunks) {
            TetLocal local;
            for (Index k = chunks.begin(); k < chunks.end(); ++k)
              for (Index e = b.chunk_begin[k]; e < b.chunk_begin[k + 1]; ++e) {
                tet_local<kOrder>(kMaterial, L.Ds(e), L.D(e), L.volume(e), Vec3::UnitX(), local);
                for (int a = 0; a < 4; ++a) g.segment<3>(3 * L.node(e, a)) += local.gradient.col(a);
                if constexpr (kOrder == 2) {
                  sink[e] = local.energy;
                  benchmark::DoNotOptimize(local.hessian.data());  // all 144 entries are
                  benchmark::ClobberMemory();                      // materialised
                }
              }
          });
    }
    benchmark::DoNotOptimize(g.data());
    benchmark::DoNotOptimize(sink.data());
  }
  state.counters["tets_per_s"] =
      benchmark::Counter(b.size(), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["per_core"] =
      benchmark::Counter(double(b.size()) / threads, benchmark::Counter::kIsIterationInvariantRate);
}

// The production path: Elasticity::evaluate with scatter into the global CSR matrix.
template <bool kHessian>
void BM_Assembly(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  const Scene& s = scene();
  std::vector<Index> all(s.mesh.tets.rows());
  std::iota(all.begin(), all.end(), 0);
  Elasticity e(s.mesh.X, s.mesh.tets, {{kMaterial, all, Points()}});
  SparsityBuilder builder(static_cast<Index>(s.x.rows()));
  e.add_couplings(builder);
  BlockSparseMatrix H(builder);
  e.bind(H);
  VectorX g(3 * s.x.rows());
  for (auto _ : state) {
    g.setZero();
    if (kHessian) H.set_zero();
    benchmark::DoNotOptimize(e.evaluate(s.x, &g, kHessian ? &H : nullptr));
  }
  state.counters["tets_per_s"] =
      benchmark::Counter(all.size(), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["per_core"] = benchmark::Counter(double(all.size()) / threads,
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

BENCHMARK(BM_Kernel<2, SoA>)
    ->Name("EnergyGradHess/SoA")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Kernel<2, AoS>)
    ->Name("EnergyGradHess/AoS")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Kernel<1, SoA>)
    ->Name("Gradient/SoA")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Kernel<1, AoS>)
    ->Name("Gradient/AoS")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Assembly<true>)
    ->Name("AssembleBSR/EnergyGradHess")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Assembly<false>)
    ->Name("AssembleBSR/EnergyGrad")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace depthfem

BENCHMARK_MAIN();
