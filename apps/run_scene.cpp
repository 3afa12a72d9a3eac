#include "apps/run_scene.hpp"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "contact/material_depth.hpp"
#include "contact/node_to_surface_contact.hpp"
#include "contact/penetration_depth.hpp"
#include "core/error.hpp"
#include "core/lumped_mass.hpp"
#include "core/results_file.hpp"
#include "integrators/arkode_stepper.hpp"
#include "integrators/gravity.hpp"
#include "integrators/implicit_stepper.hpp"
#include "integrators/residual_scale.hpp"
#include "integrators/stiffness_tether.hpp"
#include "integrators/symplectic_euler.hpp"

namespace depthfem {

namespace {

constexpr const char* kVersion = "0.1.0";

// Newton test: the root mean square over dofs of the residual, each component divided by the
// force of unit strain on a cell of the stiffest material at its node (residual_force_scale), is
// at most the scene's relative tolerance.
void set_newton_tolerance(const Scene& scene, NewtonOptions& newton) {
  newton.force_scale = residual_force_scale(scene.mesh.X, scene.mesh.tets, scene.groups);
  newton.tolerance = scene.tolerance * std::sqrt(3.0 * scene.mesh.num_nodes());
}

std::string format(const char* fmt, auto... args) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, args...);
  return buf;
}

}  // namespace

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
}

RunResult run_scene(const Scene& scene, const RunOptions& options, std::ostream& log) {
  const int threads = options.threads > 0 ? options.threads : tbb::info::default_concurrency();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  const auto start = std::chrono::steady_clock::now();

  RunResult result;
  const Mesh& mesh = scene.mesh;
  System system(mesh.num_nodes(), result.timers);
  const Elasticity& elastic =
      system.add(std::make_unique<Elasticity>(mesh.X, mesh.tets, scene.groups));
  const VectorX mass = lumped_mass(mesh.X, mesh.tets, scene.tet_density);
  if (scene.gravity.norm() > 0) system.add(std::make_unique<Gravity>(mass, scene.gravity));
  // Time-dependent analyses: the implicit schemes carry inertia and damping as tethers.
  const bool time_dependent = scene.analysis != "static";
  const DynamicOptions& dyn_in = scene.dynamic_options;
  ImplicitTerms terms;
  if (time_dependent && (dyn_in.integrator == Integrator::kImplicitEuler ||
                         dyn_in.integrator == Integrator::kNewmark)) {
    if (scene.analysis == "dynamic")
      terms.inertia = &system.add(std::make_unique<NodalSpring>("inertia", mass));
    if (scene.analysis == "quasistatic") {
      terms.damping.push_back(&system.add(std::make_unique<NodalSpring>(
          "viscosity", quasi_viscosity_stiffness(mesh.X, mesh.tets, scene.viscosity))));
    }
    if (dyn_in.damping.mass > 0) {
      terms.damping.push_back(
          &system.add(std::make_unique<NodalSpring>("mass damping", dyn_in.damping.mass * mass)));
    }
    if (dyn_in.damping.stiffness > 0) {
      terms.damping.push_back(&system.add(std::make_unique<StiffnessTether>(
          "stiffness damping", elastic, dyn_in.damping.stiffness)));
    }
  }
  NodalSpring* viscosity = nullptr;
  if (scene.quasi_viscosity > 0) {
    viscosity = &system.add(std::make_unique<NodalSpring>(
        "quasi-viscosity", quasi_viscosity_stiffness(mesh.X, mesh.tets, scene.quasi_viscosity)));
  }
  // Contact is built only when the scene asks for it.
  VectorX depth;
  MaterialDepthContact* contact = nullptr;
  if (scene.contact == ContactModel::kMaterialDepth) {
    PhaseTimers::Scope t(result.timers, "collision detection: material depth");
    depth = material_depth(mesh);
    contact =
        &system.add(std::make_unique<MaterialDepthContact>(mesh, depth, scene.contact_options));
  } else if (scene.contact == ContactModel::kNodeToSurface) {
    system.add(std::make_unique<NodeToSurfaceContact>(mesh, scene.contact_options.penalty));
  }
  ObstacleContact* obstacles = nullptr;
  if (!scene.obstacles.empty()) {
    std::vector<Index> deformable;
    for (size_t b = 0; b < mesh.bodies.size(); ++b)
      if (!scene.rigid[b]) deformable.push_back(static_cast<Index>(b));
    obstacles = &system.add(std::make_unique<ObstacleContact>(mesh, deformable, scene.obstacles));
  }
  const Constraints constraints(mesh.X, scene.constraints);
  StaticOptions opt = scene.static_options;
  set_newton_tolerance(scene, opt.newton);

  std::unique_ptr<ResultsFile> file;
  if (!options.out.empty()) {
    RunInfo info{scene.json_text, kVersion, scene.analysis, threads, {}};
    for (const Constraint& c : scene.constraints) info.constraint_names.push_back(c.name);
    file = std::make_unique<ResultsFile>(options.out, mesh, depth, info);
  }
  log << "scene " << scene.name << ": " << mesh.num_nodes() << " nodes, " << mesh.num_tets()
      << " tets, " << mesh.bodies.size() << " bodies, " << threads << " threads, linear solver "
      << to_string(opt.newton.linear.kind) << ", Newton tolerance "
      << format("%.3g", scene.tolerance) << " x E h^2 per dof" << std::endl;

  result.x = mesh.X;
  // One completed step (static increment or time step): summary, progress line, results file.
  const auto record = [&](Index index, double load, const char* tag, const NewtonResult& newton,
                          double seconds, const Points& x, const Points* v,
                          const VectorX& gradient) {
    StepSummary sum;
    sum.load = load;
    sum.newton_iterations = newton.iterations;
    sum.linear_iterations = newton.linear_iterations;
    sum.energy = newton.energy;
    sum.residual = newton.residuals.back();
    sum.reactions = constraints.reactions(gradient);
    if (contact) {
      sum.contact_area = contact->stats().area;
      sum.contact_force = contact->stats().force;  // the step's gradient was just evaluated at x
      sum.penetration = deepest_penetration(mesh, x, contact->pairs());
    }
    if (obstacles) {
      sum.contact_area = sum.contact_area.value_or(0) + obstacles->contact_area(x);
      sum.contact_force = sum.contact_force.value_or(0) + obstacles->total_force(x).norm();
    }
    log << format("step %4d  %s %.4f%s  newton %2d  linear %5d  residual %.3e  energy % .6e",
                  int(index), v ? "time" : "load", load, tag, sum.newton_iterations,
                  sum.linear_iterations, sum.residual, sum.energy)
        << (sum.penetration ? format("  penetration %.3f mm", 1e3 * *sum.penetration) : "")
        << format("  %.2f s\n", seconds);
    log.flush();  // one line per step even when the log is a file
    if (file) {
      StepRecord rec;
      rec.index = index;
      rec.load = load;
      rec.x = &x;
      rec.v = v;
      rec.newton_iterations = sum.newton_iterations;
      rec.linear_iterations = sum.linear_iterations;
      rec.energy = sum.energy;
      rec.seconds = seconds;
      rec.residuals = newton.residuals;
      rec.reactions = sum.reactions;
      rec.contact_area = sum.contact_area;
      rec.contact_force = sum.contact_force;
      rec.penetration = sum.penetration;
      file->append_step(rec);
      file->write_timing(result.timers.phases());  // a run killed later keeps its timing so far
    }
    result.steps.push_back(std::move(sum));
  };
  try {
    if (time_dependent) {
      DynamicOptions dyn = dyn_in;
      dyn.newton.tolerance = opt.newton.tolerance;
      dyn.newton.force_scale = opt.newton.force_scale;
      Points v = scene.initial_velocity;
      const auto on_step = [&](const DynamicStep& s) {
        NewtonResult newton =
            s.newton;  // report the potential energy, not the incremental potential
        newton.energy = s.potential_energy;
        record(s.index, s.time, "", newton, s.seconds, *s.x, s.v, s.gradient);
        StepSummary& sum = result.steps.back();
        sum.kinetic_energy = 0.5 * (mass.array() * s.v->rowwise().squaredNorm().array()).sum();
        sum.potential_energy = s.potential_energy;
        if (options.observer) options.observer(sum, *s.x);
      };
      switch (dyn.integrator) {
        case Integrator::kImplicitEuler:
        case Integrator::kNewmark:
          ImplicitStepper(system, constraints, terms, dyn).run(result.x, v, on_step);
          break;
        case Integrator::kSymplecticEuler:
          SymplecticEuler(system, constraints, mass, dyn,
                          critical_time_step(mesh.X, mesh.tets, scene.tet_density, scene.groups))
              .run(result.x, v, on_step);
          break;
        case Integrator::kArkode:
          ArkodeStepper(system, constraints, mass, dyn).run(result.x, v, on_step);
          break;
      }
    } else {
      StaticSolver(system, constraints, viscosity, opt).run(result.x, [&](const StaticStep& s) {
        record(s.index, s.load, s.settling ? " (settle)" : "", s.newton, s.seconds, *s.x, nullptr,
               s.gradient);
        if (options.observer) options.observer(result.steps.back(), *s.x);
      });
    }
    result.success = true;
  } catch (const SolveError& e) {
    result.message = e.what();
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (file) {
    file->write_timing(result.timers.phases());
    file->finish(result.success, result.message);
  }
  return result;
}

}  // namespace depthfem
