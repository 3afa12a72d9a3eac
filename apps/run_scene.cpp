#include "apps/run_scene.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <new>
#include <optional>
#include <utility>

#include "apps/scene_model.hpp"
#include "contact/penetration_depth.hpp"
#include "core/error.hpp"
#include "core/results_file.hpp"
#include "integrators/elements/element_fields.hpp"
#include "integrators/solvers/implicit_stepper.hpp"
#include "integrators/solvers/static_solver.hpp"
#include "integrators/solvers/sundials_stepper.hpp"
#include "integrators/solvers/symplectic_euler.hpp"
#include "integrators/solvers/thread_budget.hpp"

namespace depthfem {

namespace {

constexpr const char* kVersion = "0.1.0";

std::string format(const char* fmt, auto... args) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, args...);
  return buf;
}

/// The static solver's settings after a preset and the keys beside it, in one line.
std::string solver_summary(const Scene& scene) {
  const StaticOptions& o = scene.static_options;
  const LinearSolverOptions& lin = o.newton.linear;
  const auto on = [](bool b) { return b ? "on" : "off"; };
  return "solver preset " + scene.solver_preset + ": linear solver " + to_string(lin.kind) +
         format(" (tolerance %.3g, at most %d iterations, GMRES restart %d)", lin.tolerance,
                lin.max_iterations, lin.restart) +
         ", line search " +
         (o.newton.line_search == LineSearchRule::kResidual ? "residual" : "energy") + " from " +
         (o.newton.full_step_first ? "the full step" : "the legal step") + ", gradient fallback " +
         on(o.newton.gradient_fallback) + ", predictor " + on(o.predictor) + ", linearised start " +
         on(o.linearised_start) + format(", quasi-viscosity %.3g Pa", scene.quasi_viscosity) +
         format(", contact candidate list margin %.3g", scene.contact_options.list_margin);
}

/// What the results file writes per step: the scene's output section, velocities for
/// time-dependent analyses, contact fields where material-depth or obstacle contact fills them.
ResultFields result_fields(const Scene& scene) {
  ResultFields fields = scene.output;
  fields.velocity = scene.analysis != Analysis::kStatic;
  fields.contact =
      fields.contact && (scene.contact == ContactModel::kMaterialDepth || !scene.obstacles.empty());
  fields.viscous = fields.velocity && std::ranges::any_of(scene.groups, [](const ElasticGroup& g) {
                     return !g.viscoelastic.empty();
                   });
  return fields;
}

/// Whether the scene's integrator can go on from a completed step of a results file: every one
/// but SUNDIALS' (ARKODE, CVODE), whose adaptive step size and error history (and CVODE's order
/// and Nordsieck history) no results file holds.
bool restartable(const Scene& scene) {
  const Integrator integrator = scene.dynamic_options.integrator;
  return scene.analysis == Analysis::kStatic ||
         (integrator != Integrator::kArkode && integrator != Integrator::kArkodeDirk &&
          integrator != Integrator::kCvodeBdf);
}

/// What the restart record of every step holds: the acceleration Newmark and generalized-alpha
/// carry, the force symplectic Euler carries, the viscoelastic history; nothing for a static run
/// or one that cannot restart.
RestartLayout restart_layout(const Scene& scene, const SceneModel& model) {
  if (scene.analysis == Analysis::kStatic || !restartable(scene)) return {};
  const Integrator integrator = scene.dynamic_options.integrator;
  return {.acceleration =
              integrator == Integrator::kNewmark || integrator == Integrator::kGeneralizedAlpha,
          .history_columns = model.elasticity ? model.elasticity->history_columns() : 0,
          .force = integrator == Integrator::kSymplecticEuler};
}

/// The names of the materials of each body, and of each element region of each body (regions
/// body after body, as RunInfo::region_materials); "rigid" for a rigid body and its regions.
struct MaterialNames {
  std::vector<std::string> bodies, regions;
};
MaterialNames material_names(const Scene& scene) {
  MaterialNames out;
  out.bodies.resize(scene.mesh.bodies.size());
  for (const ElasticGroup& g : scene.groups) {
    if (g.tets.empty()) continue;
    std::string& names = out.bodies[static_cast<size_t>(scene.mesh.tet_body(g.tets.front()))];
    const std::string name = material_name(g.material);
    if (names.find(name) == std::string::npos) names += (names.empty() ? "" : ", ") + name;
  }
  for (size_t b = 0; b < out.bodies.size(); ++b) {
    if (scene.mesh.bodies[b].rigid) out.bodies[b] = "rigid";
    for (const Region& r : scene.mesh.bodies[b].regions) {
      const auto group = std::ranges::find_if(scene.groups, [&](const ElasticGroup& g) {
        return std::ranges::find(g.tets, r.first_tet) != g.tets.end();
      });
      out.regions.push_back(scene.mesh.bodies[b].rigid    ? "rigid"
                            : group != scene.groups.end() ? material_name(group->material)
                                                          : "");
    }
  }
  return out;
}

// Throws when `out`, or a file written beside it, is one of `inputs` (the same file under any
// name).
void refuse_overwriting_inputs(const std::string& out, const std::vector<std::string>& inputs) {
  std::vector<std::string> written = results_sidecars(out);
  written.push_back(out);
  written.push_back(results_lock_path(out));
  for (const std::string& path : written) {
    for (const std::string& input : inputs) {
      std::error_code error;
      if (std::filesystem::equivalent(path, input, error)) {
        throw InputError(located(
            out, 0, "--out would overwrite the input " + input + "; choose another results path"));
      }
    }
  }
}

// The modules the scene asks for; errors the scene reader could not see (a conflict found by a
// module) name the scene.
std::unique_ptr<SceneModel> build_scene_model(const Scene& scene, PhaseTimers& timers,
                                              Ranks* ranks) {
  try {
    return build_model(scene, timers, ranks);
  } catch (const InputError& e) {
    throw InputError(scene.file + ": " + e.what());
  }
}

// The results file of the run (none without --out), refusing to overwrite an input.
std::unique_ptr<ResultsFile> open_results(const Scene& scene, const RunOptions& options,
                                          const SceneModel& model, int threads, int ranks) {
  if (options.out.empty()) return nullptr;
  std::vector<std::string> inputs = scene.inputs;
  if (!options.restart.empty()) inputs.push_back(options.restart);
  refuse_overwriting_inputs(options.out, inputs);
  MaterialNames materials = material_names(scene);
  const ResultFields fields = result_fields(scene);
  RunInfo info{.scene_json = scene.json_text,
               .version = kVersion,
               .analysis = to_string(scene.analysis),
               .threads = threads,
               .constraint_names = {},
               .contact_names = model.system.interface_names(),
               .body_materials = std::move(materials.bodies),
               .region_materials = std::move(materials.regions),
               .fields = fields,
               .initial_velocity = fields.velocity ? scene.initial_velocity : Points(),
               .restart = restart_layout(scene, model),
               .ranks = ranks};
  for (const Constraint& c : scene.constraints) info.constraint_names.push_back(c.name);
  return std::make_unique<ResultsFile>(options.out, scene.mesh, model.depth, info);
}

// Where a run starts besides its positions: at rest, or where a completed step of an earlier
// run left off (--restart).
struct Start {
  double load = 0;       // static: the load factor
  Points v;              // time-dependent: the velocities
  DynamicStart dynamic;  // time-dependent: the time and the acceleration carried
};

// Runs the scene's analysis from (result.x, start) through the lifecycle; a failure (a solve
// that cannot go on, a step the results file refused, memory) is the result's message.
void drive(const Scene& scene, SceneModel& model, StepLifecycle& lifecycle, Start start,
           RunResult& result, std::ostream& log) {
  const DynamicOptions& dyn = model.dynamic_options;
  // A failed attempt completes no step: one line each, so that a long one shows where the time
  // goes.
  const auto on_failure = [&log](const FailedAttempt& f) {
    log << format("attempt  load %.4f -> %.4f%s  failed", f.from, f.target,
                  f.settling ? " (settle)" : "")
        << (f.newton ? format("  newton %2d  linear %5d", f.newton->iterations,
                              f.newton->linear_iterations)
                     : "")
        << ": " << f.why << format("  %.2f s\n", f.seconds);
    log.flush();
  };
  try {
    if (scene.analysis == Analysis::kStatic) {
      StaticSolver(lifecycle, model.quasi_viscosity, model.static_options, on_failure)
          .run(result.x, start.load);
    } else {
      Points& v = start.v;
      switch (dyn.integrator) {
        case Integrator::kImplicitEuler:
        case Integrator::kNewmark:
        case Integrator::kGeneralizedAlpha:
          ImplicitStepper(lifecycle, model.implicit, dyn).run(result.x, v, start.dynamic);
          break;
        case Integrator::kArkodeDirk:
        case Integrator::kCvodeBdf:
          SundialsStepper(lifecycle, model.lumped_mass, dyn, model.implicit).run(result.x, v);
          break;
        case Integrator::kSymplecticEuler:
          SymplecticEuler(
              lifecycle, model.lumped_mass, dyn,
              critical_time_step(scene.mesh.X, scene.mesh.tets, scene.tet_density, scene.groups))
              .run(result.x, v, start.dynamic);
          break;
        case Integrator::kArkode:
          SundialsStepper(lifecycle, model.lumped_mass, dyn).run(result.x, v);
          break;
      }
    }
    result.success = true;
  } catch (const SolveError& e) {
    result.message = e.what();
  } catch (const InputError& e) {  // a step the results file refused, a stepper's input check
    result.message = e.what();
  } catch (const std::bad_alloc&) {
    if (Ranks::running()) throw;  // this rank alone: the run ends at once (command_line)
    result.message = "out of memory";
  }
}

// The processes of a distributed run (mpirun -n N, N > 1), its tets partitioned among them, or
// null for a serial run.
std::unique_ptr<Ranks> start_ranks(const Scene& scene, PhaseTimers& timers) {
  if (Ranks::launched() == 1) return nullptr;
  auto ranks = std::make_unique<Ranks>();
  PhaseTimers::Scope t(timers, "partition");
  ranks->partition(scene.mesh.tets, scene.mesh.num_nodes());
  return ranks;
}

// Writes the timing and the outcome. A file that can no longer grow (a full disk, a file-size
// limit) keeps its last flushed state, and still takes the outcome: the status and message
// overwrite space they own.
void finish_results(ResultsFile& file, RunResult& result) {
  const auto write = [&](const auto& what) {
    try {
      what();
    } catch (const InputError& e) {
      result.message += (result.message.empty() ? "" : "; then ") + std::string(e.what());
      result.success = false;
    }
  };
  write([&] { file.write_timing(result.timers.phases()); });
  write([&] { file.finish(result.success, result.message); });
}

}  // namespace

StepState restart_state(const std::string& path, Index step, const Mesh& mesh, Analysis analysis) {
  const auto refuse = [&](const std::string& why) {
    throw InputError(located(path, 0, "cannot restart from it: " + why));
  };
  const ResultsSummary previous = read_results_summary(path);
  if (previous.num_nodes != mesh.num_nodes() || previous.num_tets != mesh.num_tets()) {
    refuse("it has " + std::to_string(previous.num_nodes) + " nodes and " +
           std::to_string(previous.num_tets) + " tets, the scene " +
           std::to_string(mesh.num_nodes()) + " and " + std::to_string(mesh.num_tets()));
  }
  if (previous.analysis != to_string(analysis))
    refuse("its /run attribute analysis is " + previous.analysis + ", the scene's " +
           to_string(analysis));
  check_results_mesh(path, mesh);
  const StepState state = read_step_state(path, step);
  const std::string of_step = "step " + std::to_string(state.index);
  if (state.x.rows() != mesh.num_nodes() || !state.x.allFinite())
    refuse(of_step + " has no finite #nodes x 3 positions");
  if (analysis == Analysis::kStatic && !(state.load >= 0 && state.load <= 1))
    refuse(of_step + " has load " + std::to_string(state.load) + ", not a load factor in [0, 1]");
  if (analysis != Analysis::kStatic && !(state.load >= 0))
    refuse(of_step + " has time " + std::to_string(state.load) + " s, not a time >= 0");
  if (analysis != Analysis::kStatic && state.v.rows() != mesh.num_nodes())
    refuse(of_step + " has no velocities (/steps/v)");
  return state;
}

void print_timing(const PhaseTimers& timers, double total, std::ostream& out) {
  out << "timing (s, share of " << format("%.3f", total) << " s wall):\n";
  double grouped[3] = {0, 0, 0};
  const char* groups[3] = {"force/stiffness", "collision detection", "linear solve"};
  for (const auto& [name, sec] : timers.phases()) {
    out << format("  %-36s %10.3f  %5.1f %%\n", name.c_str(), sec,
                  total > 0 ? 100 * sec / total : 0.0);
    for (int k = 0; k < 3; ++k)
      if (name.rfind(groups[k], 0) == 0) grouped[k] += sec;
  }
  double rest = total;
  for (int k = 0; k < 3; ++k) {
    out << format("  = %-34s %10.3f  %5.1f %%\n", groups[k], grouped[k],
                  total > 0 ? 100 * grouped[k] / total : 0.0);
    rest -= grouped[k];
  }
  out << format("  = %-34s %10.3f  %5.1f %%\n", "other", rest,
                total > 0 ? 100 * rest / total : 0.0);
  // Threads busy on average in each phase: where a second thread idles.
  out << "CPU time (s, all threads; CPU / wall):\n";
  double cpu_grouped[3] = {0, 0, 0};
  for (const auto& [name, sec] : timers.phases()) {
    const double cpu = timers.cpu_seconds(name);
    out << format("  %-36s %10.3f  %5.2f\n", name.c_str(), cpu, sec > 0 ? cpu / sec : 0.0);
    for (int k = 0; k < 3; ++k)
      if (name.rfind(groups[k], 0) == 0) cpu_grouped[k] += cpu;
  }
  for (int k = 0; k < 3; ++k)
    out << format("  = %-34s %10.3f  %5.2f\n", groups[k], cpu_grouped[k],
                  grouped[k] > 0 ? cpu_grouped[k] / grouped[k] : 0.0);
}

namespace {

// The starting state, positions into x: the reference at rest, or a completed step of an
// earlier run of this scene (--restart) with, for a time-dependent run, its time, velocities and
// restart record (the acceleration carried, the viscoelastic history, restored into the model).
Start starting_state(const Scene& scene, SceneModel& model, const RunOptions& options,
                     std::ostream& log, Points& x) {
  x = scene.mesh.X;
  Start start{.load = 0, .v = scene.initial_velocity, .dynamic = {}};
  if (options.restart.empty()) return start;
  const auto refuse = [&](const std::string& why) {
    throw InputError(located(options.restart, 0, "cannot restart from it: " + why));
  };
  if (!restartable(scene))
    refuse(
        "the scene's integrator (arkode, arkode_dirk or cvode_bdf) keeps an adaptive step size "
        "and error history that no results file holds; restart with implicit_euler, newmark, "
        "generalized_alpha or symplectic_euler");
  const StepState state =
      restart_state(options.restart, options.restart_step, scene.mesh, scene.analysis);
  x = state.x;
  if (scene.analysis == Analysis::kStatic) {
    log << "restart from step " << state.index << " of " << options.restart << " at load "
        << format("%.6g", state.load) << std::endl;
    start.load = state.load;
    return start;
  }
  const double duration = model.dynamic_options.duration;
  if (!(state.load < duration))
    refuse("step " + std::to_string(state.index) + " ends at t = " + format("%.12g", state.load) +
           " s, the scene's duration is " + format("%.12g", duration) + " s: nothing is left");
  RestartRecord record =
      read_restart_record(options.restart, state.index, restart_layout(scene, model));
  start.v = state.v;
  start.dynamic = {.time = state.load,
                   .acceleration = std::move(record.acceleration),
                   .force = std::move(record.force)};
  // The history as the step left it, at the time (as a fraction of the duration) the step set.
  if (record.history.size() > 0)
    model.elasticity->restore_history(record.history, state.load / duration);
  log << "restart from step " << state.index << " of " << options.restart
      << " at t = " << format("%.6g", state.load) << " s" << std::endl;
  return start;
}

}  // namespace

RunResult run_scene(const Scene& scene, const RunOptions& options, std::ostream& log_stream) {
  const ThreadBudget budget(options.threads);
  const int threads = budget.threads();
  const auto start = std::chrono::steady_clock::now();
  RunResult result;
  const std::unique_ptr<Ranks> ranks = start_ranks(scene, result.timers);
  const int num_ranks = ranks ? ranks->size() : 1;
  // A distributed run: rank 0 alone prints and writes the results file.
  const bool writer = !ranks || ranks->rank() == 0;
  std::ostream silent(nullptr);
  std::ostream& log = writer ? log_stream : silent;
  const std::unique_ptr<SceneModel> model = build_scene_model(scene, result.timers, ranks.get());
  const Mesh& mesh = scene.mesh;
  const Start from = starting_state(scene, *model, options, log, result.x);
  const std::unique_ptr<ResultsFile> file =
      writer ? open_results(scene, options, *model, threads, num_ranks) : nullptr;
  const ResultFields fields = result_fields(scene);
  log << "scene " << scene.name << ": " << mesh.num_nodes() << " nodes, " << mesh.num_tets()
      << " tets, " << mesh.bodies.size() << " bodies, "
      << (ranks ? std::to_string(num_ranks) + " ranks of " : "") << threads
      << " threads, linear solver " << to_string(model->static_options.newton.linear.kind)
      << ", Newton tolerance " << format("%.3g", scene.tolerance) << " x E h^2 per dof"
      << std::endl;
  if (!scene.solver_preset.empty()) log << solver_summary(scene) << std::endl;

  // Writes a completed step into the results file, with the restart record of the model's
  // state: the last completed step is the one written (or the pending one, written at the end:
  // no step completed after it, and a failed attempt leaves the acceleration and the history
  // as the last completed step left them).
  const RestartLayout layout = restart_layout(scene, *model);
  const StepLifecycle* running = nullptr;  // the run's lifecycle, set before the run
  // The viscoelastic history's fields of a step, per tet: each rank holds its own tets' rows
  // (zero elsewhere), summed over the ranks into the whole field on every rank. Every rank
  // calls it for every step written, rank 0 alone writes.
  struct HistoryFields {
    SymmetricColumns viscous_stress;
    Eigen::MatrixXd history;
  };
  const auto history_fields = [&](const Points& x) {
    HistoryFields out;
    const auto whole = [&](auto& rows) {
      if (!ranks) return;
      VectorX v = rows.reshaped();
      ranks->sum(v);
      rows = v.reshaped(rows.rows(), rows.cols());
    };
    if (fields.viscous) {
      PhaseTimers::Scope t(result.timers, "output: element fields");
      out.viscous_stress = model->elasticity->viscous_stress(x);
      whole(out.viscous_stress);
    }
    if (layout.history_columns > 0) {
      out.history = model->elasticity->history_state();
      whole(out.history);
    }
    return out;
  };
  const auto write = [&](const StepRecord& step, const Points& x, const Points* v,
                         HistoryFields history) {
    ElementFields elements;
    if (fields.stress || fields.strain) {
      PhaseTimers::Scope t(result.timers, "output: element fields");
      const VectorX pressure =
          model->patch_volume ? model->patch_volume->tet_pressures(x) : VectorX();
      elements = element_fields(mesh.X, mesh.tets, scene.groups, x, {fields.stress, fields.strain},
                                &pressure);
    }
    elements.viscous_stress = std::move(history.viscous_stress);
    RestartRecord record;
    if (layout.acceleration) record.acceleration = running->acceleration();
    if (layout.force) record.force = as_points(running->last_gradient());
    record.history = std::move(history.history);
    PhaseTimers::Scope t(result.timers, "output: results file");
    file->append_step(step, x, v, &elements, layout.empty() ? nullptr : &record);
    file->write_timing(result.timers.phases());  // a run killed later keeps its timing so far
  };
  // The last completed step not written (output every N > 1 steps), written when the run ends;
  // kept on every rank of a distributed run (each adds its part of the history fields).
  struct Pending {
    StepRecord step;
    Points x, v;
    bool has_v = false;
  };
  std::optional<Pending> pending;
  // Drive: every N-th completed step is written (every one by default), then every step is
  // printed (so a printed step of a run writing every step is on disk) and kept.
  const auto on_step = [&](const StepRecord& done, const Points& x, const Points* v) {
    StepRecord step = done;
    if (model->contact) {
      PhaseTimers::Scope t(result.timers, "output: penetration");
      // A distributed run's ranks each hold the pairs of their own tets: the deepest of all.
      const double deepest = deepest_penetration(mesh, x, model->contact->pairs());
      step.penetration = ranks ? -ranks->min(-deepest) : deepest;
    }
    // Each rank's viscoelastic history dissipates in its own tets.
    if (ranks && step.dissipated_energy)
      step.dissipated_energy = ranks->sum(*step.dissipated_energy);
    if (!options.out.empty() && (step.index + 1) % scene.output_every == 0) {
      // In a distributed run every rank learns whether rank 0 could write the step, so that
      // all stop together.
      std::string failure;
      HistoryFields history = history_fields(x);
      try {
        if (file) write(step, x, v, std::move(history));
      } catch (const InputError& e) {
        if (!ranks) throw;
        failure = e.what();
      }
      if (ranks && ranks->sum(failure.empty() ? 0.0 : 1.0) > 0)
        throw InputError(failure.empty() ? "rank 0 could not write the results file" : failure);
      pending.reset();
    } else if (!options.out.empty()) {
      pending = Pending{step, x, v ? *v : Points(), v != nullptr};
    }
    log << format("step %4d  %s %.4f%s  newton %2d  linear %5d  residual %.3e  energy % .6e",
                  int(step.index), v ? "time" : "load", step.load, step.settling ? " (settle)" : "",
                  step.newton_iterations, step.linear_iterations, step.residuals.back(),
                  step.energy)
        << (step.penetration ? format("  penetration %.3f mm", 1e3 * *step.penetration) : "")
        << format("  %.2f s\n", step.seconds);
    log.flush();  // one line per step even when the log is a file
    result.steps.push_back(step);
    if (options.observer) options.observer(step, x);
  };
  StepLifecycle lifecycle(model->system, model->constraints, model->lifecycle_terms(), on_step);
  running = &lifecycle;
  drive(scene, *model, lifecycle, from, result, log);
  if (pending) {
    HistoryFields history = history_fields(pending->x);
    try {
      if (file)
        write(pending->step, pending->x, pending->has_v ? &pending->v : nullptr,
              std::move(history));
    } catch (const InputError& e) {  // a full disk, a file-size limit
      result.message += (result.message.empty() ? "" : "; then ") + std::string(e.what());
      result.success = false;
    }
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (file) finish_results(*file, result);
  return result;
}

}  // namespace depthfem
