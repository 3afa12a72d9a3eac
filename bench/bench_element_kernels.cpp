// Element kernel layout study (Mooney-Rivlin, 192,000 tets): the element data as array of
// structures (AoS), structure of arrays (SoA, the TetBlock the library uses) and blocks of W tets
// (AoSoA), each run by the scalar kernel (tet_local, one tet at a time) and the batched kernel
// (tet_batch, W tets in the lanes of a vector register), for energy, + gradient, + Hessian, on 1
// and 2 threads (SoA also with lanes written with std::experimental::simd, and with 4 lanes where
// registers hold 8); then the production path, Elasticity::evaluate, which also scatters the
// Hessian into the block-CSR matrix; and the two ceilings of a roofline: fused multiply-add
// throughput and memory bandwidth.
//
//   build/bench/bench_element_kernels --benchmark_counters_tabular=true
//       --benchmark_out=bench/results/element_kernels.json --benchmark_out_format=json
//   /usr/bin/python3 bench/plot_element_kernels.py bench/results/element_kernels.json
//       --out bench/results/element_kernels.png
//
// Times are the CPU time of the whole process (all threads), so that `per_core`, tets per
// CPU-second, is what a core delivers while it works, however busy a shared machine is (its wall
// clock time is in real_time); `flops_per_tet` the floating-point operations
// of the batched kernel per tet (counted by running it on a counting number type; the scalar
// kernel does the same work, and some more); `bytes_per_tet` the memory traffic a tet cannot
// avoid: its element data, the node data it shares with its neighbours (each node read and, with
// a gradient, written once per sweep) and, in assembly, the matrix (zeroed, read and written once
// per sweep) and the scatter indices.
#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <experimental/simd>
#include <numeric>
#include <random>

#include "core/block_sparse_matrix.hpp"
#include "core/mesh_generators.hpp"
#include "integrators/elements/tet_inputs.hpp"
#include "integrators/forces/elasticity.hpp"

namespace depthfem {
namespace {

const MooneyRivlin kMaterial{4e3, 1e3, 2e4};
constexpr int kOrders = 3;

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
  double nodes_per_tet() const { return double(x.rows()) / double(block.size()); }
};
// The one instance of T, built on first use.
template <class T>
const T& instance() {
  static const T t;
  return t;
}
const Scene& scene() {
  return instance<Scene>();
}

// ---- Layouts. Each gives the scalar kernel one row (input, node) and the batched kernel W rows
// starting at a row of the same chunk (inputs and node indices); rows are those of the TetBlock,
// chunks and colors too.

using BatchNodes = std::array<std::array<Index, kLanes>, 4>;  // [corner][lane]

// SoA: the TetBlock itself (one array per column) and positions with one array per component.
struct SoA {
  static constexpr bool kPadded = false;
  const TetBlock& b = scene().block;
  const Points& x = scene().x;
  Index node(Index, Index e, int a) const { return b.nodes(e, a); }
  TetInput input(Index, Index e) const { return tet_input(b, x, e); }
  template <class V>
  TetBatchInput<V> batch(Index, Index e, BatchNodes& nodes) const {
    for (int a = 0; a < 4; ++a)
      for (int l = 0; l < V::kWidth; ++l) nodes[a][l] = b.nodes(e + l, a);
    return tet_batch_input<V, false>(b, x, e);
  }
};

// AoS: one 96-byte record per tet, xyz together per node.
struct TetRecord {
  Index nodes[4];
  double Dm_inv[9];
  double volume;
};
struct AoSData {
  std::vector<TetRecord> tets;
  std::vector<std::array<double, 3>> x;
  AoSData() {
    const Scene& s = scene();
    for (Index e = 0; e < s.block.size(); ++e) {
      TetRecord r;
      for (int a = 0; a < 4; ++a) r.nodes[a] = s.block.nodes(e, a);
      for (int k = 0; k < 9; ++k) r.Dm_inv[k] = s.block.Dm_inv(e, k);
      r.volume = s.block.volume(e);
      tets.push_back(r);
    }
    for (Index v = 0; v < s.x.rows(); ++v) x.push_back({s.x(v, 0), s.x(v, 1), s.x(v, 2)});
  }
};
struct AoS {
  static constexpr bool kPadded = false;
  const AoSData& d = instance<AoSData>();
  Index node(Index, Index e, int a) const { return d.tets[e].nodes[a]; }
  TetInput input(Index, Index e) const {
    const TetRecord& r = d.tets[e];
    TetInput t;
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) t.Ds(c, a) = d.x[r.nodes[a + 1]][c] - d.x[r.nodes[0]][c];
    t.D = Eigen::Map<const Mat3>(r.Dm_inv);
    t.volume = r.volume;
    return t;
  }
  template <class V>
  TetBatchInput<V> batch(Index k, Index e, BatchNodes& nodes) const {
    TetBatchInput<V> in;
    for (int l = 0; l < V::kWidth; ++l) {
      for (int a = 0; a < 4; ++a) nodes[a][l] = node(k, e + l, a);
      const TetInput t = input(k, e + l);
      for (int k = 0; k < 9; ++k) in.Ds[k].set(l, t.Ds(k)), in.D[k].set(l, t.D(k));
      in.volume.set(l, t.volume);
    }
    return in;
  }
};

// AoSoA: each chunk cut into blocks of kLanes tets, every field a run of kLanes values; the last
// block of a chunk is padded with zero lanes (a degenerate tet that the kernel leaves alone).
struct TetLanesRecord {
  Index nodes[4][kLanes];
  double Dm_inv[9][kLanes];
  double volume[kLanes];
};
struct AoSoAData {
  std::vector<TetLanesRecord> blocks;
  std::vector<Index> first_block;  // per chunk
  AoSoAData() {
    const TetBlock& b = scene().block;
    for (size_t k = 0; k + 1 < b.chunk_begin.size(); ++k) {
      first_block.push_back(static_cast<Index>(blocks.size()));
      for (Index e = b.chunk_begin[k]; e < b.chunk_begin[k + 1]; e += kLanes) {
        TetLanesRecord r{};
        for (int l = 0; l < kLanes && e + l < b.chunk_begin[k + 1]; ++l) {
          for (int a = 0; a < 4; ++a) r.nodes[a][l] = b.nodes(e + l, a);
          for (int k9 = 0; k9 < 9; ++k9) r.Dm_inv[k9][l] = b.Dm_inv(e + l, k9);
          r.volume[l] = b.volume(e + l);
        }
        blocks.push_back(r);
      }
    }
  }
};
struct AoSoA {
  static constexpr bool kPadded = true;
  const AoSoAData& d = instance<AoSoAData>();
  const TetBlock& b = scene().block;
  const Points& x = scene().x;
  // Block and lane of row e of chunk k.
  std::pair<const TetLanesRecord*, int> at(Index k, Index e) const {
    const Index i = e - b.chunk_begin[k];
    return {&d.blocks[d.first_block[k] + i / kLanes], static_cast<int>(i % kLanes)};
  }
  Index node(Index k, Index e, int a) const {
    const auto [r, l] = at(k, e);
    return r->nodes[a][l];
  }
  TetInput input(Index k, Index e) const {
    const auto [r, l] = at(k, e);
    TetInput t;
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) t.Ds(c, a) = x(r->nodes[a + 1][l], c) - x(r->nodes[0][l], c);
    for (int k = 0; k < 9; ++k) t.D(k) = r->Dm_inv[k][l];
    t.volume = r->volume[l];
    return t;
  }
  // Row e must start a block (rows are walked block by block from the start of a chunk).
  template <class V>
  TetBatchInput<V> batch(Index k, Index e, BatchNodes& nodes) const {
    static_assert(V::kWidth == kLanes);
    const TetLanesRecord& r = *at(k, e).first;
    for (int a = 0; a < 4; ++a) std::copy_n(r.nodes[a], kLanes, nodes[a].begin());
    TetBatchInput<V> in;
    for (int c = 0; c < 3; ++c) {
      const double* xc = x.col(c).data();
      const V x0 = V::gather(xc, r.nodes[0]);
      for (int a = 1; a < 4; ++a) in.Ds[3 * (a - 1) + c] = V::gather(xc, r.nodes[a]) - x0;
    }
    for (int k = 0; k < 9; ++k) in.D[k] = V::load(r.Dm_inv[k]);
    in.volume = V::load(r.volume);
    return in;
  }
};

// ---- Flops per tet: the batched kernel run on a number type that counts its operations.

struct Counted;
struct CountedMask {
  bool m;
  bool any() const { return m; }
};
struct Counted {
  static constexpr int kWidth = 1;
  static inline long flops = 0;
  double v = 0;
  Counted() = default;
  Counted(double x) : v(x) {}  // NOLINT: like Lanes
  double operator[](int) const { return v; }
  void set(int, double x) { v = x; }
  friend Counted operator+(Counted a, Counted b) { return ++flops, a.v + b.v; }
  friend Counted operator-(Counted a, Counted b) { return ++flops, a.v - b.v; }
  friend Counted operator*(Counted a, Counted b) { return ++flops, a.v * b.v; }
  friend Counted operator/(Counted a, Counted b) { return ++flops, a.v / b.v; }
  friend Counted operator-(Counted a) { return -a.v; }
  Counted& operator+=(Counted b) { return *this = *this + b; }
  Counted& operator-=(Counted b) { return *this = *this - b; }
  Counted& operator*=(Counted b) { return *this = *this * b; }
  friend CountedMask operator>(Counted a, Counted b) { return {a.v > b.v}; }
  friend CountedMask operator!=(Counted a, Counted b) { return {a.v != b.v}; }
};
Counted select(CountedMask m, Counted a, Counted b) {
  return m.m ? a : b;
}
Counted multiply_add(Counted a, Counted b, Counted c) {
  Counted::flops += 2;
  return a.v * b.v + c.v;
}
// exp and log as one operation each (Eigen's take some 20 instructions); Mooney-Rivlin uses log.
[[maybe_unused]] Counted exp(Counted a) {
  return ++Counted::flops, std::exp(a.v);
}
Counted log(Counted a) {
  return ++Counted::flops, std::log(a.v);
}

template <int kOrder>
double flops_per_tet() {
  const TetInput t = tet_input(scene().block, scene().x, 0);
  TetBatchInput<Counted> in;
  for (int k = 0; k < 9; ++k) in.Ds[k] = t.Ds(k), in.D[k] = t.D(k);
  in.volume = t.volume;
  TetBatch<Counted> out;
  Counted::flops = 0;
  tet_batch<kOrder>(kMaterial, in, out);
  return static_cast<double>(Counted::flops);
}

// Bytes a tet cannot avoid moving: element data, the positions (and gradient) of its share of
// the nodes.
double kernel_bytes_per_tet(int order) {
  const double element = 4 * sizeof(Index) + 10 * sizeof(double);
  const double node = 3 * sizeof(double) * scene().nodes_per_tet();
  return element + node * (order >= 1 ? 3 : 1);
}

void set_counters(benchmark::State& state, double tets, double flops, double bytes) {
  state.counters["tets"] = tets;
  state.counters["per_core"] =
      benchmark::Counter(tets, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["flops_per_tet"] = flops;
  state.counters["bytes_per_tet"] = bytes;
}

// ---- The same lanes written with std::experimental::simd (GCC 12's), as the comparison of how
// lanes are written: its arithmetic maps onto the same instructions, its exp and log call the
// scalar functions lane by lane.
namespace stdx = std::experimental;
struct StdLanes;
struct StdMask {
  stdx::simd_mask<double, stdx::simd_abi::deduce_t<double, kLanes>> m;
  bool any() const { return stdx::any_of(m); }
};
struct StdLanes {
  using Simd = stdx::simd<double, stdx::simd_abi::deduce_t<double, kLanes>>;
  static constexpr int kWidth = kLanes;
  Simd v;
  StdLanes() = default;
  StdLanes(double s) : v(s) {}       // NOLINT: like Lanes
  StdLanes(const Simd& s) : v(s) {}  // NOLINT
  static StdLanes load(const double* p) { return Simd(p, stdx::element_aligned); }
  static StdLanes gather(const double* base, const Index* index) {
    return Simd([&](auto l) { return base[index[l]]; });
  }
  double operator[](int l) const { return v[l]; }
  void set(int l, double x) { v[l] = x; }
  friend StdLanes operator+(const StdLanes& a, const StdLanes& b) { return a.v + b.v; }
  friend StdLanes operator-(const StdLanes& a, const StdLanes& b) { return a.v - b.v; }
  friend StdLanes operator*(const StdLanes& a, const StdLanes& b) { return a.v * b.v; }
  friend StdLanes operator/(const StdLanes& a, const StdLanes& b) { return a.v / b.v; }
  friend StdLanes operator-(const StdLanes& a) { return -a.v; }
  StdLanes& operator+=(const StdLanes& b) { return v += b.v, *this; }
  StdLanes& operator-=(const StdLanes& b) { return v -= b.v, *this; }
  StdLanes& operator*=(const StdLanes& b) { return v *= b.v, *this; }
  friend StdMask operator>(const StdLanes& a, const StdLanes& b) { return {a.v > b.v}; }
  friend StdMask operator!=(const StdLanes& a, const StdLanes& b) { return {a.v != b.v}; }
};
StdLanes select(const StdMask& m, const StdLanes& a, const StdLanes& b) {
  StdLanes::Simd r = b.v;
  stdx::where(m.m, r) = a.v;
  return r;
}
StdLanes multiply_add(const StdLanes& a, const StdLanes& b, const StdLanes& c) {
  return stdx::fma(a.v, b.v, c.v);
}
[[maybe_unused]] StdLanes exp(const StdLanes& a) {
  return stdx::exp(a.v);
}
StdLanes log(const StdLanes& a) {
  return stdx::log(a.v);
}

// ---- The kernels over a layout. kOrder 0: energy; 1: + gradient scattered into a 3n vector
// (colors keep it race-free); 2: + the 12x12 Hessian, forced into memory but not scattered (the
// kernel, not the scatter, is measured here; BM_Assembly adds the scatter).

template <int kOrder, class Layout>
struct Sweep {
  const Layout& L;
  VectorX& g;
  // The scalar kernel on row e of chunk k.
  double scalar(Index k, Index e) const {
    TetLocal local;
    const TetInput t = L.input(k, e);
    tet_local<kOrder>(kMaterial, t.Ds, t.D, t.volume, t.fiber, local);
    if constexpr (kOrder >= 1)
      for (int a = 0; a < 4; ++a) g.segment<3>(3 * L.node(k, e, a)) += local.gradient.col(a);
    if constexpr (kOrder == 2) {
      benchmark::DoNotOptimize(local.hessian.data());  // all 144 entries are materialised
      benchmark::ClobberMemory();
    }
    return local.energy;
  }
  // The batched kernel on rows e .. e + count of chunk k (count <= W; padding lanes dropped).
  template <class V>
  double batched(Index k, Index e, int count, TetBatch<V>& t) const {
    BatchNodes nodes;
    tet_batch<kOrder>(kMaterial, L.template batch<V>(k, e, nodes), t);
    double energy = 0;
    for (int l = 0; l < count; ++l) {
      energy += t.energy[l];
      if constexpr (kOrder >= 1)
        for (int a = 0; a < 4; ++a) {
          double* ga = g.data() + 3 * nodes[a][l];
          for (int c = 0; c < 3; ++c) ga[c] += t.gradient[a][c][l];
        }
    }
    if constexpr (kOrder == 2) {
      benchmark::DoNotOptimize(t.hessian.data());
      benchmark::ClobberMemory();
    }
    return energy;
  }
  // The rows of chunk k, V::kWidth at a time (V = double: the scalar kernel).
  template <class V>
  double chunk(const TetBlock& b, Index k) const {
    const Index end = b.chunk_begin[k + 1];
    double energy = 0;
    Index e = b.chunk_begin[k];
    if constexpr (!std::is_same_v<V, double>) {
      constexpr int W = V::kWidth;
      TetBatch<V> t;
      for (; e + W <= end; e += W) energy += batched(k, e, W, t);
      if (Layout::kPadded && e < end) energy += batched(k, e, end - e, t), e = end;
    }
    for (; e < end; ++e) energy += scalar(k, e);
    return energy;
  }
};

template <int kOrder, class Layout, class V>
void BM_Kernel(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  const Layout L;
  const TetBlock& b = scene().block;
  VectorX g(3 * scene().x.rows());
  const Sweep<kOrder, Layout> sweep{L, g};
  std::vector<double> chunk_energy(b.chunk_begin.size());
  for (auto _ : state) {
    g.setZero();
    for (Index c = 0; c < b.num_colors(); ++c) {
      tbb::parallel_for(tbb::blocked_range<Index>(b.color_begin[c], b.color_begin[c + 1], 1),
                        [&](const tbb::blocked_range<Index>& chunks) {
                          for (Index k = chunks.begin(); k < chunks.end(); ++k)
                            chunk_energy[k] = sweep.template chunk<V>(b, k);
                        });
    }
    benchmark::DoNotOptimize(g.data());
    benchmark::DoNotOptimize(chunk_energy.data());
  }
  static const double flops[kOrders] = {flops_per_tet<0>(), flops_per_tet<1>(), flops_per_tet<2>()};
  set_counters(state, b.size(), flops[kOrder], kernel_bytes_per_tet(kOrder));
}

// ---- The production path: Elasticity::evaluate (SoA, batched kernel, colored chunks), gradient
// scattered into the vector and, for the Hessian, 16 blocks per tet into the block-CSR matrix.
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
  const double tets = static_cast<double>(all.size());
  // The matrix is zeroed, read and written back once per sweep; 16 scatter indices per tet.
  const double matrix = kHessian ? (3.0 * 72 * H.num_blocks()) / tets + 16 * sizeof(Index) : 0;
  set_counters(state, tets, kHessian ? flops_per_tet<2>() : flops_per_tet<1>(),
               kernel_bytes_per_tet(kHessian ? 2 : 1) + matrix);
}

// ---- Roofline ceilings, per thread.

// Fused multiply-adds on 8 independent chains of registers: the arithmetic peak.
void BM_PeakFlops(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  constexpr long kSteps = 1 << 20;
  for (auto _ : state) {
    tbb::parallel_for(0, threads, [](int) {
      using V = Lanes<kLanes>;
      std::array<V, 8> acc;
      for (int k = 0; k < 8; ++k) acc[k] = V(1.0 + k);
      const V a(0.999999), b(1e-7);
      for (long s = 0; s < kSteps; ++s)
        for (int k = 0; k < 8; ++k) acc[k] = multiply_add(acc[k], a, b);
      benchmark::DoNotOptimize(acc);
    });
  }
  state.counters["flops_per_s_per_core"] = benchmark::Counter(
      2.0 * 8 * kLanes * kSteps * threads, benchmark::Counter::kIsIterationInvariantRate);
}

// a = b + s c over arrays of 2^range(1) entries each (STREAM's triad, 24 bytes per entry): 2^22
// (32 MiB) as the kernels' ceiling, 2^27 (1 GiB, beyond any last-level cache) for main memory.
void BM_Bandwidth(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  const size_t n = size_t(1) << state.range(1);
  std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);
  for (auto _ : state) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 16),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t i = r.begin(); i < r.end(); ++i) a[i] = b[i] + 0.5 * c[i];
                      });
    benchmark::DoNotOptimize(a.data());
  }
  state.counters["bytes_per_s_per_core"] =
      benchmark::Counter(24.0 * n, benchmark::Counter::kIsIterationInvariantRate);
}

template <int kOrder, class Layout, class V>
void register_kernel(const std::string& layout, const std::string& kernel) {
  static const char* order[kOrders] = {"Energy", "Gradient", "Hessian"};
  benchmark::RegisterBenchmark(("Kernel/" + layout + "/" + kernel + "/" + order[kOrder]).c_str(),
                               BM_Kernel<kOrder, Layout, V>)
      ->Arg(1)
      ->Arg(2)
      ->MeasureProcessCPUTime()
      ->Unit(benchmark::kMillisecond);
}

template <class Layout, class V>
void register_orders(const std::string& layout, const std::string& kernel) {
  register_kernel<0, Layout, V>(layout, kernel);
  register_kernel<1, Layout, V>(layout, kernel);
  register_kernel<2, Layout, V>(layout, kernel);
}

const bool registered = [] {
  register_orders<AoS, double>("AoS", "scalar");
  register_orders<AoS, Lanes<kLanes>>("AoS", "batched");
  register_orders<SoA, double>("SoA", "scalar");
  register_orders<SoA, Lanes<kLanes>>("SoA", "batched");
  register_orders<AoSoA, double>("AoSoA", "scalar");
  register_orders<AoSoA, Lanes<kLanes>>("AoSoA", "batched");
  register_orders<SoA, StdLanes>("SoA", "batched_stdsimd");
  if constexpr (kLanes == 8) register_orders<SoA, Lanes<4>>("SoA", "batched_w4");
  benchmark::RegisterBenchmark("Assembly/Gradient", BM_Assembly<false>)
      ->Arg(1)
      ->Arg(2)
      ->MeasureProcessCPUTime()
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("Assembly/Hessian", BM_Assembly<true>)
      ->Arg(1)
      ->Arg(2)
      ->MeasureProcessCPUTime()
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("Ceiling/PeakFlops", BM_PeakFlops)
      ->Arg(1)
      ->Arg(2)
      ->MeasureProcessCPUTime();
  benchmark::RegisterBenchmark("Ceiling/Bandwidth", BM_Bandwidth)
      ->Args({1, 22})
      ->Args({2, 22})
      ->Args({1, 27})
      ->MeasureProcessCPUTime();
  return true;
}();

}  // namespace
}  // namespace depthfem

BENCHMARK_MAIN();
