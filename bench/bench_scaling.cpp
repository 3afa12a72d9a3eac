// Scaling study of the linear solvers: one static run of a scene at one size with one solver,
// appended as a CSV row (run each case in its own process, so that the peak memory is its own;
// bench/scaling.sh runs the whole study).
//
//   build/bench/bench_scaling --scene cantilever|sliding|hertz|knee --size S
//       --solver auto|direct|amg
//       [--threads N] [--ordering best|amd|metis] [--indefinite shift|ldlt] [--reuse TOL]
//       [--out bench/results/scaling.csv] [--set PATH=VALUE ...]
//
// cantilever: cantilever_gravity with S x S/10 x S/10 cells (6 S^3 / 100 tets), bending under
//   its own weight in one increment.
// sliding: sliding_blocks with every cell count scaled by S (4488 S^3 tets), the slider pressed
//   2 cm and moved 2 cm in four increments: material-depth contact between two bodies.
// --reuse sets DirectSolverOptions::reuse_tolerance (0: factor every matrix).
// hertz: the first increment of hertz_sphere alone (the sphere pushed 1 mm into the undeformed
//   block: an indefinite Hessian at first), S core cells per edge (12: the shipped mesh).
// knee: the first 3 degrees of knee_flexion in one increment, on the shipped mesh whatever S
//   (on the mesh before the joint space's curves were protected, contact made the Hessian
//   indefinite after the first Newton step; on the present one both fallbacks run alike).
// Per Newton iteration: wall time of the steps (failed attempts included), of the linear solve
// alone, of force/stiffness, and the CPU time of the run (all threads; less sensitive than wall
// time to other jobs on a shared machine). Peak memory is the process's maximum resident set.
#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "apps/run_scene.hpp"

using namespace depthfem;

namespace {

std::string cells(double a, double b, double c) {
  std::ostringstream s;
  s << "[" << std::lround(a) << "," << std::lround(b) << "," << std::lround(c) << "]";
  return s.str();
}

// Scene file and overrides of one case.
std::pair<std::string, std::vector<std::string>> scene_case(const std::string& name, double S) {
  if (name == "cantilever")
    return {"cantilever_gravity",
            {"bodies.0.mesh.cells=" + cells(S, S / 10, S / 10), "solver.min_increment=1"}};
  if (name == "sliding")
    return {"sliding_blocks",
            {"bodies.0.mesh.cells=" + cells(20 * S, 8 * S, 4 * S),
             "bodies.1.mesh.cells=" + cells(6 * S, 6 * S, 3 * S),
             "boundary.1.displacement=[0.02,0,-0.02]", "solver.initial_increment=0.25",
             "solver.max_increment=0.25"}};
  if (name == "hertz")
    return {
        "hertz_sphere",
        {"bodies.0.mesh.core_cells=" + std::to_string(std::lround(S)),
         "obstacles.0.motion=[0,0,0.001]", "solver.initial_increment=1", "solver.max_increment=1"}};
  if (name == "knee")  // the shipped mesh only: S is ignored
    return {"knee_flexion",
            {"boundary.0.angle_deg=3", "boundary.1.angle_deg=3", "solver.initial_increment=1",
             "solver.max_increment=1"}};
  throw std::invalid_argument("unknown scene '" + name +
                              "' (expected cantilever, sliding, hertz or knee)");
}

// User and system time of the whole process so far [s].
double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

}  // namespace

int main(int argc, char** argv) {
  std::string scene_name, solver = "auto", out = "bench/results/scaling.csv";
  DirectSolverOptions direct;
  double size = 0;
  int threads = 0;
  std::vector<std::string> extra;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--scene" && has_value) {
      scene_name = argv[++i];
    } else if (a == "--size" && has_value) {
      size = std::stod(argv[++i]);
    } else if (a == "--solver" && has_value) {
      solver = argv[++i];
    } else if (a == "--threads" && has_value) {
      threads = std::stoi(argv[++i]);
    } else if (a == "--ordering" && has_value) {
      const std::string v = argv[++i];
      direct.ordering = v == "amd"     ? DirectOrdering::kAmd
                        : v == "metis" ? DirectOrdering::kMetis
                                       : DirectOrdering::kBest;
    } else if (a == "--indefinite" && has_value) {
      direct.indefinite =
          std::string(argv[++i]) == "ldlt" ? IndefiniteFallback::kLdlt : IndefiniteFallback::kShift;
    } else if (a == "--reuse" && has_value) {
      direct.reuse_tolerance = std::stod(argv[++i]);
    } else if (a == "--out" && has_value) {
      out = argv[++i];
    } else if (a == "--set" && has_value) {
      extra.push_back(argv[++i]);
    } else {
      std::cerr << "usage: bench_scaling --scene cantilever|sliding|hertz|knee --size S --solver "
                   "auto|direct|amg [--threads N] [--ordering best|amd|metis] [--indefinite "
                   "shift|ldlt] [--reuse TOL] [--out FILE.csv] [--set PATH=VALUE ...]\n";
      return 2;
    }
  }
  try {
    auto [file, overrides] = scene_case(scene_name, size);
    overrides.push_back("solver.linear_solver=" + solver);
    overrides.insert(overrides.end(), extra.begin(), extra.end());
    std::vector<Override> o;
    for (const std::string& s : overrides) o.push_back(parse_override(s));
    Scene scene =
        load_scene(std::string(DEPTHFEM_SOURCE_DIR) + "/apps/scenes/" + file + ".json", o);
    scene.static_options.newton.linear.direct = direct;
    RunOptions options;
    options.threads = threads;
    std::ostringstream log;
    const double cpu_before = cpu_seconds();
    const RunResult r = run_scene(scene, options, log);
    const double cpu = cpu_seconds() - cpu_before;
    long newton = 0, linear = 0;
    double solve_s = 0;  // the steps' wall time, failed attempts included
    for (const StepRecord& s : r.steps) {
      newton += s.newton_iterations;
      linear += s.linear_iterations;
      solve_s += s.seconds;
    }
    double force = 0;
    for (const auto& [name, sec] : r.timers.phases())
      if (name.rfind("force/stiffness", 0) == 0) force += sec;
    const double per = newton > 0 ? 1.0 / static_cast<double>(newton) : 0.0;
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    const bool fresh = !std::ifstream(out).good();
    std::ofstream csv(out, std::ios::app);
    if (!csv) throw std::runtime_error("cannot write " + out);
    if (fresh)
      csv << "scene,size,tets,dofs,solver,threads,success,steps,newton_iterations,"
             "linear_iterations,steps_s,newton_s_per_it,linear_s_per_it,force_s_per_it,"
             "cpu_s_per_it,peak_mb\n";
    char line[512];
    std::snprintf(line, sizeof line,
                  "%s,%g,%d,%d,%s,%d,%d,%zu,%ld,%ld,%.3f,%.4f,%.4f,%.4f,%.4f,%.0f\n",
                  scene_name.c_str(), size, scene.mesh.num_tets(), 3 * scene.mesh.num_nodes(),
                  solver.c_str(), threads, r.success ? 1 : 0, r.steps.size(), newton, linear,
                  solve_s, solve_s * per, r.timers.seconds("linear solve") * per, force * per,
                  cpu * per, static_cast<double>(usage.ru_maxrss) / 1024.0);
    csv << line;
    std::cout << line;
    if (!r.success) std::cerr << "bench_scaling: " << r.message << "\n";
    return r.success ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "bench_scaling: " << e.what() << "\n";
    return 1;
  }
}
