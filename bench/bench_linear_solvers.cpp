// Linear solvers on the stiffness matrix of the clamped cantilever (neo-Hookean, E = 100 MPa,
// nu = 0.3, box 1 x 0.1 x 0.1 m with n x n/10 x n/10 cells, Kuhn split: 6 n^3 / 100 tets):
// the direct solver's analysis (ordering) and factorisation with each ordering and thread count,
// and AMG-CG to a relative residual of 1e-6 with each preconditioner.
//
//   build/bench/bench_linear_solvers --benchmark_counters_tabular=true
//
// Arguments: cells along the bar n; ordering (0 best of the two, 1 AMD, 2 METIS) or
// preconditioner (0 GAMG, 1 BoomerAMG with PETSc's defaults; PETSC_OPTIONS sets others);
// threads; for the repeated solve, the factor's precision. Counters: unknowns, flops of one
// factorisation and entries of L (direct), CG iterations (AMG).
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <numeric>

#include "core/mesh_generators.hpp"
#include "integrators/forces/constraints.hpp"
#include "integrators/forces/elasticity.hpp"
#include "integrators/solvers/amg_solver.hpp"
#include "integrators/solvers/direct_solver.hpp"
#include "integrators/solvers/thread_budget.hpp"

namespace depthfem {
namespace {

struct Problem {
  Points X;
  BlockSparseMatrix A;
  VectorX b;
};

// The Newton matrix at the reference state (linear elasticity) and a load along -z.
const Problem& cantilever(int n) {
  static std::map<int, std::unique_ptr<Problem>> cache;
  auto& p = cache[n];
  if (p) return *p;
  const TetMesh m = box_mesh({Vec3(0, -0.05, -0.05), Vec3(1, 0.05, 0.05),
                              Eigen::Vector3i(n, std::max(1, n / 10), std::max(1, n / 10))});
  std::vector<Index> all(m.tets.rows());
  std::iota(all.begin(), all.end(), 0);
  const double E = 1e8, nu = 0.3;
  Elasticity e(m.X, m.tets,
               {{NeoHookean{E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))}, all, {}}});
  SparsityBuilder builder(static_cast<Index>(m.X.rows()));
  e.add_couplings(builder);
  p = std::make_unique<Problem>(Problem{m.X, BlockSparseMatrix(builder), VectorX()});
  e.bind(p->A);
  VectorX g = VectorX::Zero(3 * m.X.rows());
  e.evaluate(m.X, &g, &p->A);
  std::vector<Index> clamp;
  for (Index i = 0; i < m.X.rows(); ++i)
    if (m.X(i, 0) == 0) clamp.push_back(i);
  const Constraints c(m.X, {{"clamp", clamp, Fixed{}}});
  c.project(p->A);
  p->b = VectorX::Zero(3 * m.X.rows());
  for (Index i = 0; i < m.X.rows(); ++i) p->b(3 * i + 2) = -1.0;
  c.project(p->b);
  return *p;
}

void set_counters(benchmark::State& state, const Problem& p) {
  state.counters["dofs"] = static_cast<double>(p.b.size());
}

DirectSolverOptions direct_options(const benchmark::State& state) {
  DirectSolverOptions o;
  o.ordering = static_cast<DirectOrdering>(state.range(1));
  o.reuse_tolerance = 0;  // every solve factors
  return o;
}

// Ordering and symbolic analysis: what a new pattern costs before its first factorisation.
void BM_DirectAnalysis(benchmark::State& state) {
  const Problem& p = cantilever(static_cast<int>(state.range(0)));
  const ThreadBudget budget(static_cast<int>(state.range(2)));
  DirectAnalysis a;
  for (auto _ : state) {
    DirectSolver s(direct_options(state));
    benchmark::DoNotOptimize(a = s.analyse(p.A));
  }
  state.counters["flops"] = a.flops;
  state.counters["L_entries"] = a.factor_entries;
  state.counters["flops_per_entry"] = a.flops / lower_triangle_entries(p.A);
  state.counters["metis"] = a.ordering == DirectOrdering::kMetis;
  set_counters(state, p);
}

// The prediction from the block graph alone (predicted_factor_flops): what auto compares with
// auto_flops_per_entry, before any analysis of the scalar pattern.
void BM_PredictedFlops(benchmark::State& state) {
  const Problem& p = cantilever(static_cast<int>(state.range(0)));
  double flops = 0;
  for (auto _ : state) benchmark::DoNotOptimize(flops = predicted_factor_flops(p.A));
  state.counters["predicted_flops"] = flops;
  state.counters["flops_per_entry"] = flops / lower_triangle_entries(p.A);
  set_counters(state, p);
}

// Factorisation and solve with the analysis kept: what a Newton iteration costs; the fourth
// argument the factor's precision (0 double; 1 single, CG to kSingleExactTolerance; 2 single, CG
// to 0.1, Newton's loosest forcing term). Counters: the relative residual |b - A x| / |b|
// reached and the CG iterations on the single factor.
void BM_DirectRepeatSolve(benchmark::State& state) {
  const Problem& p = cantilever(static_cast<int>(state.range(0)));
  const ThreadBudget budget(static_cast<int>(state.range(2)));
  DirectSolverOptions o = direct_options(state);
  o.precision = state.range(3) ? FactorPrecision::kSingle : FactorPrecision::kDouble;
  DirectSolver s(o);
  VectorX x, Ax;
  const double tolerance = state.range(3) == 2 ? 0.1 : 0;
  DirectSolveStats st = s.solve(p.A, p.b, x, tolerance);  // the analysis, outside the timing
  for (auto _ : state) benchmark::DoNotOptimize(st = s.solve(p.A, p.b, x, tolerance));
  p.A.multiply(x, Ax);
  state.counters["residual"] = (p.b - Ax).norm() / p.b.norm();
  state.counters["cg_iterations"] = st.cg_iterations;
  state.counters["single"] = st.single;
  set_counters(state, p);
}

// AMG-CG with the hierarchy kept (GAMG: interpolation reused, coarse operators recomputed).
void BM_AmgRepeatSolve(benchmark::State& state) {
  const Problem& p = cantilever(static_cast<int>(state.range(0)));
  const ThreadBudget budget(static_cast<int>(state.range(2)));
  AmgSolver s({static_cast<AmgPreconditioner>(state.range(1)), 1e-6, 1000});
  VectorX x;
  s.solve(p.A, p.b, x, &p.X);
  AmgSolveStats st;
  for (auto _ : state) benchmark::DoNotOptimize(st = s.solve(p.A, p.b, x, &p.X));
  state.counters["iterations"] = st.iterations;
  state.counters["converged"] = st.converged;
  set_counters(state, p);
}

BENCHMARK(BM_DirectAnalysis)
    ->ArgsProduct({{40, 70, 80, 100, 140, 160, 200, 260}, {0, 1, 2}, {1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_PredictedFlops)
    ->ArgsProduct({{40, 70, 80, 100, 140, 160, 200, 260}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_DirectRepeatSolve)
    ->ArgsProduct({{40, 80, 160}, {1, 2}, {1, 2}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_AmgRepeatSolve)
    ->ArgsProduct({{40, 80, 160}, {0, 1}, {1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace depthfem

BENCHMARK_MAIN();
