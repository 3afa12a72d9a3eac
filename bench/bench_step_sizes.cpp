// The step-size history of SUNDIALS' error-controlled steppers through a scene: every internal
// step's time and size, and per output interval the Newton work and the contact force, as two
// CSV files. Shows what the onset of contact does to the step-size control (bars_drop).
//
//   build/bench/bench_step_sizes SCENE.json --out PREFIX [--set PATH=VALUE ...]
//
// writes PREFIX_steps.csv (time_s, step_s) and PREFIX_intervals.csv (time_s, newton_iterations,
// linear_solves, factorizations, contact_force_n, wall_s). The scene must choose integrator
// arkode, arkode_dirk or cvode_bdf (--set dynamic.integrator=arkode_dirk). Plot with
// bench/plot_step_sizes.py.
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "apps/scene.hpp"
#include "apps/scene_model.hpp"
#include "core/error.hpp"
#include "integrators/solvers/sundials_stepper.hpp"
#include "integrators/solvers/thread_budget.hpp"

using namespace depthfem;

int main(int argc, char** argv) {
  std::string scene_path, prefix;
  std::vector<Override> overrides;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) {
      prefix = argv[++i];
    } else if (a == "--set" && i + 1 < argc) {
      overrides.push_back(parse_override(argv[++i]));
    } else if (scene_path.empty() && a.rfind("--", 0) != 0) {
      scene_path = a;
    } else {
      scene_path.clear();
      break;
    }
  }
  if (scene_path.empty() || prefix.empty()) {
    std::cerr << "usage: bench_step_sizes SCENE.json --out PREFIX [--set PATH=VALUE ...]\n";
    return 2;
  }
  try {
    const ThreadBudget budget(1);
    const Scene scene = load_scene(scene_path, overrides);
    const Integrator integrator = scene.dynamic_options.integrator;
    if (integrator != Integrator::kArkode && integrator != Integrator::kArkodeDirk &&
        integrator != Integrator::kCvodeBdf) {
      throw InputError(scene_path +
                       ": dynamic.integrator must be arkode, arkode_dirk or cvode_bdf");
    }
    PhaseTimers timers;
    const std::unique_ptr<SceneModel> model = build_model(scene, timers);
    std::ofstream intervals(prefix + "_intervals.csv");
    intervals << "time_s,newton_iterations,linear_solves,factorizations,contact_force_n,wall_s\n";
    StepLifecycle lifecycle(model->system, model->constraints, model->lifecycle_terms(),
                            [&](const StepRecord& s, const Points&, const Points*) {
                              double force = 0;
                              for (const InterfaceForce& f : s.contact) force += f.magnitude;
                              intervals << s.load << "," << s.newton_iterations << ","
                                        << s.linear_solves << "," << s.factorizations << ","
                                        << force << "," << s.seconds << "\n";
                            });
    SundialsStepper stepper(lifecycle, model->lumped_mass, model->dynamic_options, model->implicit);
    Points x = scene.mesh.X, v = scene.initial_velocity;
    std::string failure;
    try {
      stepper.run(x, v);
    } catch (const SolveError& e) {
      failure = e.what();
    }
    std::ofstream steps(prefix + "_steps.csv");
    steps << "time_s,step_s\n";
    for (const SundialsInternalStep& s : stepper.history())
      steps << s.time << "," << s.size << "\n";
    std::cout << stepper.history().size() << " internal steps, " << lifecycle.completed()
              << " output intervals" << (failure.empty() ? "" : "; failed: " + failure) << "\n";
    return failure.empty() ? 0 : 1;
  } catch (const InputError& e) {
    std::cerr << "bench_step_sizes: " << e.what() << "\n";
    return 1;
  }
}
