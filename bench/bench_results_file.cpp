// The results file's cost per step. On a 48,000-tet box: what each written field adds to
// ResultsFile::append_step, the stress and strain computation, and, as the yardstick, one
// elastic assembly (energy, gradient and Hessian: what every Newton iteration pays). On a small
// two-body mesh: the cost per step of a 10,000-step run at its start and at its end, for the
// whole append_step and for the sidecar alone (constant: each step is appended to the sidecar,
// not the whole sidecar rewritten).
//
//   build/bench/bench_results_file --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <ctime>
#include <filesystem>
#include <numeric>

#include "core/mesh_generators.hpp"
#include "core/results_file.hpp"
#include "core/xdmf_writer.hpp"
#include "integrators/elements/element_fields.hpp"
#include "integrators/forces/system.hpp"

namespace depthfem {
namespace {

namespace fs = std::filesystem;

const MaterialModel kMaterial = MooneyRivlin{4e3, 1e3, 2e4};

// A 1 x 1 x 1 box of 20^3 cells (9,261 nodes, 48,000 tets, 4,800 boundary triangles) sheared
// by 10 %, one material.
struct Box {
  Mesh mesh = single_body_mesh(box_mesh({Vec3::Zero(), Vec3::Ones(), Eigen::Vector3i(20, 20, 20)}));
  std::vector<ElasticGroup> groups;
  Points x;
  Box() {
    std::vector<Index> all(static_cast<size_t>(mesh.num_tets()));
    std::iota(all.begin(), all.end(), 0);
    groups.push_back({kMaterial, all, Points()});
    x = mesh.X;
    x.col(0) += 0.1 * mesh.X.col(1);
  }
};
const Box& box() {
  static const Box b;
  return b;
}

// A results file in the temporary folder, removed with its sidecars.
struct Scratch {
  fs::path path =
      fs::temp_directory_path() / ("depthfem_bench_results_" + std::to_string(getpid()) + ".h5");
  ~Scratch() {
    fs::remove(path);
    for (const std::string& sidecar : results_sidecars(path)) fs::remove(sidecar);
  }
  double megabytes() const {
    uintmax_t bytes = fs::file_size(path);
    for (const std::string& sidecar : results_sidecars(path)) bytes += fs::file_size(sidecar);
    return double(bytes) / 1e6;
  }
};

// A static step with one contact row and one constraint, as a scene's step would have.
StepRecord record(Index k, Index num_tris, bool contact) {
  StepRecord s;
  s.index = k;
  s.load = (k + 1) / 1000.0;
  s.newton_iterations = 3;
  s.residuals = {1.0, 1e-3, 1e-7, 1e-12};
  s.reactions = Eigen::Matrix<double, 1, 3>(1, 2, 3);
  s.contact = {{"obstacle floor", Vec3(0, 0, 1), 1.0, 0.1}};
  if (contact) {
    s.surface.resize(num_tris);
    s.surface.magnitude.setConstant(0.5);
    s.surface.area.setConstant(1e-3);
  }
  return s;
}

// What each field adds: range(0) selects the fields written besides the positions.
enum Fields { kPositions, kDisplacement, kContact, kStressStrain };
void BM_AppendStep(benchmark::State& state) {
  const Box& b = box();
  const auto fields = static_cast<Fields>(state.range(0));
  RunInfo info{"{}", "bench", "static", 1, {"clamp"}, {"obstacle floor"}, {"mooney_rivlin"},
               {},   {},      {}};
  info.fields.displacement = fields == kDisplacement;
  info.fields.contact = fields == kContact;
  info.fields.stress = info.fields.strain = fields == kStressStrain;
  const ElementFields elements = element_fields(b.mesh.X, b.mesh.tets, b.groups, b.x, {true, true});
  const Scratch scratch;
  ResultsFile file(scratch.path, b.mesh, VectorX(), info);
  const double before = scratch.megabytes();
  Index k = 0;
  for (auto _ : state) {
    file.append_step(record(k++, b.mesh.num_tris(), info.fields.contact), b.x, nullptr, &elements);
  }
  state.counters["MB_per_step"] = (scratch.megabytes() - before) / double(k);
}

// The stress or strain (range(0): 0 stress and von Mises, 1 strain and volume ratio) of every
// tet, on one thread.
void BM_ElementFields(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const Box& b = box();
  const ElementFieldOptions options{state.range(0) == 0, state.range(0) == 1};
  for (auto _ : state)
    benchmark::DoNotOptimize(element_fields(b.mesh.X, b.mesh.tets, b.groups, b.x, options));
  state.counters["tets_per_s"] =
      benchmark::Counter(double(b.mesh.num_tets()), benchmark::Counter::kIsIterationInvariantRate);
}

// The yardstick: one elastic assembly (energy, gradient, Hessian), as a Newton iteration does it
// through the System, on one thread.
void BM_Assembly(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const Box& b = box();
  PhaseTimers timers;
  System system(b.mesh.num_nodes(), timers);
  system.add(std::make_unique<Elasticity>(b.mesh.X, b.mesh.tets, b.groups));
  VectorX g;
  for (auto _ : state) benchmark::DoNotOptimize(system.hessian(b.x, g));
}

// CPU time of the process (user and system: the writes), which other jobs on the machine
// disturb less than wall time [s].
double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// 10,000 steps of two 4 x 2 x 2-cell bodies (90 nodes, 192 tets) with displacement and
// velocities: the mean CPU time per step over the first and the last 100 steps, for append_step
// (HDF5 and both sidecars) and for one sidecar's append alone (same layout), and the sizes
// reached.
void BM_LongRun(benchmark::State& state) {
  constexpr Index kSteps = 10000;
  Mesh mesh;
  mesh.add_body("a", box_mesh({Vec3::Zero(), Vec3(2, 1, 1), Eigen::Vector3i(4, 2, 2)}));
  mesh.add_body("b", box_mesh({Vec3(3, 0, 0), Vec3(5, 1, 1), Eigen::Vector3i(4, 2, 2)}));
  RunInfo info{
      "{}", "bench", "dynamic", 1, {"clamp"}, {"obstacle floor"}, {"neo_hookean", "neo_hookean"},
      {},   {},      {}};
  info.fields.velocity = true;
  info.initial_velocity = Points::Zero(mesh.num_nodes(), 3);
  const auto mean_ms = [](const std::vector<double>& t, size_t from) {
    return 1e3 * std::accumulate(t.begin() + long(from), t.begin() + long(from) + 100, 0.0) / 100;
  };
  for (auto _ : state) {
    std::vector<double> whole, sidecar;
    double h5_mb = 0, xmf_mb = 0;
    {
      const Scratch scratch;
      ResultsFile file(scratch.path, mesh, VectorX(), info);
      for (Index k = 0; k < kSteps; ++k) {
        const double start = cpu_seconds();
        file.append_step(record(k, mesh.num_tris(), false), mesh.X, &mesh.X);
        whole.push_back(cpu_seconds() - start);
      }
      h5_mb = double(fs::file_size(scratch.path)) / 1e6;
      xmf_mb = double(fs::file_size(fs::path(scratch.path).replace_extension(".xmf"))) / 1e6;
    }
    {
      const Scratch scratch;
      const fs::path xmf = fs::path(scratch.path).replace_extension(".xmf");
      SidecarLayout layout{"run.h5",
                           XdmfDialect::kXdmf3,
                           mesh.num_nodes(),
                           mesh.num_tets(),
                           mesh.num_tris(),
                           {{"a", "/mesh/blocks/0/tets", 45, 96, 0, 0},
                            {"b", "/mesh/blocks/1/tets", 45, 96, 45, 96}},
                           false,
                           info.fields};
      XdmfSidecar file(xmf.string(), layout, {-1, 0.0, {}});
      std::vector<StepValue> values(16, {"energy", {1.0}});
      for (Index k = 0; k < kSteps; ++k) {
        const double start = cpu_seconds();
        file.append({k, (k + 1) / 1000.0, values});
        sidecar.push_back(cpu_seconds() - start);
      }
    }
    state.counters["step_first100_ms"] = mean_ms(whole, 0);
    state.counters["step_last100_ms"] = mean_ms(whole, kSteps - 100);
    state.counters["sidecar_first100_ms"] = mean_ms(sidecar, 0);
    state.counters["sidecar_last100_ms"] = mean_ms(sidecar, kSteps - 100);
    state.counters["h5_MB"] = h5_mb;
    state.counters["xmf_MB"] = xmf_mb;
  }
}

BENCHMARK(BM_AppendStep)
    ->ArgName("fields")  // 0 positions, 1 + displacement, 2 + contact, 3 + stress and strain
    ->DenseRange(0, 3)
    ->Iterations(40)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ElementFields)->ArgName("strain")->DenseRange(0, 1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Assembly)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LongRun)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
}  // namespace depthfem

BENCHMARK_MAIN();
