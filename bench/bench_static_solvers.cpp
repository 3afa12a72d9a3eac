// Scene benchmark: Newton iterations, linear iterations and wall time to solution of every
// linear solver (and both line-search rules) on the static scenes that stress them.
//
//   build/bench/bench_static_solvers [--out bench/results/static_solvers.csv] [--quick]
//
// --quick uses the 80 x 8 x 8 cantilever instead of the 160 x 16 x 16 one.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "apps/run_scene.hpp"

using namespace depthfem;

int main(int argc, char** argv) {
  std::string out = "bench/results/static_solvers.csv";
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) {
      out = argv[++i];
    } else if (a == "--quick") {
      quick = true;
    } else {
      std::cerr << "usage: bench_static_solvers [--out FILE.csv] [--quick]\n";
      return 2;
    }
  }
  const std::string dir = std::string(DEPTHFEM_SOURCE_DIR) + "/apps/scenes/";
  struct Case {
    std::string scene;
    std::vector<std::string> overrides;
  };
  const std::vector<Case> cases = {
      // Gravity is not ramped, so a smaller increment would only repeat the same solve: one try.
      {"cantilever_gravity",
       {std::string("bodies.0.mesh.cells=") + (quick ? "[80,8,8]" : "[160,16,16]"),
        "solver.min_increment=1"}},
      {"twist_bar", {}},
  };
  std::ofstream csv(out);
  if (!csv) {
    std::cerr << "bench_static_solvers: cannot write " << out << "\n";
    return 1;
  }
  csv << "scene,dofs,linear_solver,line_search,success,steps,newton_iterations,linear_iterations,"
         "seconds,force_stiffness_s,linear_solve_s,final_energy\n";
  for (const Case& c : cases) {
    for (const char* solver : {"auto", "direct", "amg", "gmres", "cg"}) {
      for (const char* rule : {"energy", "residual"}) {
        std::vector<Override> o;
        for (const std::string& s : c.overrides) o.push_back(parse_override(s));
        o.push_back(parse_override(std::string("solver.linear_solver=") + solver));
        o.push_back(parse_override(std::string("solver.line_search=") + rule));
        const Scene scene = load_scene(dir + c.scene + ".json", o);
        std::ostringstream log;
        const RunResult r = run_scene(scene, RunOptions(), log);
        long newton = 0, linear = 0;
        for (const StepRecord& s : r.steps) {
          newton += s.newton_iterations;
          linear += s.linear_iterations;
        }
        double force = 0;
        for (const auto& [name, sec] : r.timers.phases())
          if (name.rfind("force/stiffness", 0) == 0) force += sec;
        char line[512];
        std::snprintf(line, sizeof line, "%s,%d,%s,%s,%d,%zu,%ld,%ld,%.3f,%.3f,%.3f,%.9g\n",
                      c.scene.c_str(), 3 * scene.mesh.num_nodes(), solver, rule, r.success ? 1 : 0,
                      r.steps.size(), newton, linear, r.seconds, force,
                      r.timers.seconds("linear solve"),
                      r.steps.empty() ? 0.0 : r.steps.back().energy);
        csv << line << std::flush;
        std::cout << line << std::flush;
      }
    }
  }
  return 0;
}
