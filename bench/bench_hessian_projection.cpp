// Scene benchmark of the ways a static solve gets past unstable or indefinite states: plain
// Newton, the element Hessians projected to positive semi-definite (solver.hessian_projection),
// quasi-viscosity (solver.quasi_viscosity), and both, on buckling_column, twist_bar and fold_slab.
// One CSV row per scene and method.
//
//   build/bench/bench_hessian_projection [--out bench/results/hessian_projection.csv]
//       [--threads N] [--scene NAME]
//
// Quasi-viscosity is 1 % of the small-strain Young's modulus of the scene's body (buckling_column
// ships with 1e4 Pa = 1 % of 1e6 Pa); "plain" and "projection" run without it, so buckling_column
// is changed from its shipped setting there. Per run: whether it completed, increments completed
// and tried (each failed try halves the increment), Newton iterations of the completed increments,
// Hessian assemblies of all tries (one per Newton iteration plus one at each try's final iterate),
// wall and CPU seconds, the load factor reached, the potential energy there and the largest
// displacement per axis, which tell the branches apart.
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "apps/scene_model.hpp"
#include "core/error.hpp"
#include "integrators/solvers/static_solver.hpp"
#include "integrators/solvers/thread_budget.hpp"

using namespace depthfem;

namespace {

// Adds nothing to the energy; counts the increments tried (begin_step) and the Hessian
// assemblies (evaluate with a Hessian) of the System it belongs to.
class Counter final : public ForceModule {
 public:
  std::string name() const override { return "counter"; }
  void begin_step(const Points& /*x*/) override { ++tries; }
  void add_couplings(SparsityBuilder& /*builder*/) const override {}
  double evaluate(const Points& /*x*/, VectorX* /*gradient*/,
                  BlockSparseMatrix* hessian) const override {
    if (hessian) ++hessians;
    return 0;
  }
  long tries = 0;
  mutable long hessians = 0;
};

// User and system time of the whole process so far [s].
double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Method {
  const char* name;
  bool projection, viscosity;
};

// One static run of `file` with `method`; returns its CSV row.
std::string run(const std::string& file, const std::string& scene_name, const Method& method) {
  Scene scene = load_scene(file);
  scene.elasticity.project_hessian = method.projection;
  scene.quasi_viscosity =
      method.viscosity ? 0.01 * material_moduli(scene.groups.at(0).material).youngs() : 0.0;
  PhaseTimers timers;
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = cpu_seconds();
  const std::unique_ptr<SceneModel> model = build_model(scene, timers);
  const Counter& counter = model->system.add(std::make_unique<Counter>());
  long steps = 0, newton = 0;
  double load = 0, energy = 0;
  const auto on_step = [&](const StepRecord& s, const Points& /*x*/, const Points* /*v*/) {
    ++steps;
    newton += s.newton_iterations;
    load = s.load;
    energy = s.energy;
  };
  StepLifecycle lifecycle(model->system, model->constraints, model->lifecycle_terms(), on_step);
  Points x = scene.mesh.X;
  std::string status = "completed";
  try {
    StaticSolver(lifecycle, model->quasi_viscosity, model->static_options).run(x);
  } catch (const SolveError& e) {
    status = "failed";
    std::cerr << scene_name << " " << method.name << ": " << e.what() << "\n";
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cpu = cpu_seconds() - cpu_start;
  const Vec3 max_u = (x - scene.mesh.X).cwiseAbs().colwise().maxCoeff();
  char line[512];
  std::snprintf(
      line, sizeof line, "%s,%s,%.4g,%s,%ld,%ld,%ld,%ld,%.2f,%.2f,%.6g,%.6g,%.4g,%.4g,%.4g\n",
      scene_name.c_str(), method.name, scene.quasi_viscosity, status.c_str(), steps, counter.tries,
      newton, counter.hessians, wall, cpu, load, energy, max_u.x(), max_u.y(), max_u.z());
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  std::string out = "bench/results/hessian_projection.csv", only;
  int threads = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) {
      out = argv[++i];
    } else if (a == "--threads" && i + 1 < argc) {
      threads = std::stoi(argv[++i]);
    } else if (a == "--scene" && i + 1 < argc) {
      only = argv[++i];
    } else {
      std::cerr
          << "usage: bench_hessian_projection [--out FILE.csv] [--threads N] [--scene NAME]\n";
      return 2;
    }
  }
  std::ofstream csv(out);
  if (!csv) {
    std::cerr << "bench_hessian_projection: cannot write " << out << "\n";
    return 1;
  }
  const ThreadBudget budget(threads);
  const std::string header =
      "scene,method,quasi_viscosity_pa,status,steps,tries,newton_iterations,hessian_assemblies,"
      "wall_s,cpu_s,final_load,final_energy_j,max_ux_m,max_uy_m,max_uz_m\n";
  csv << header;
  std::cout << header;
  const Method methods[] = {{"plain", false, false},
                            {"projection", true, false},
                            {"quasi_viscosity", false, true},
                            {"projection+quasi_viscosity", true, true}};
  try {
    for (const char* scene : {"buckling_column", "twist_bar", "fold_slab"}) {
      if (!only.empty() && only != scene) continue;
      const std::string file = std::string(DEPTHFEM_SOURCE_DIR) + "/apps/scenes/" + scene + ".json";
      for (const Method& m : methods) {
        const std::string row = run(file, scene, m);
        csv << row << std::flush;
        std::cout << row << std::flush;
      }
    }
  } catch (const std::exception& e) {
    std::cerr << "bench_hessian_projection: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
