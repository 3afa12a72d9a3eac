#include "integrators/solvers/step_lifecycle.hpp"

namespace depthfem {

void StepLifecycle::begin(const Points& x, double load) {
  if (!timing_) {
    start_ = std::chrono::steady_clock::now();
    timing_ = true;
  }
  system_.begin_step(x);
  system_.set_load(load);
}

double StepLifecycle::gradient(const Points& x, VectorX& g) {
  system_.prepare(x);
  return system_.gradient(x, g);
}

void StepLifecycle::complete(double load, const NewtonResult& newton, const Points& x,
                             const Points* v, bool settling, int time_steps) {
  StepRecord step;
  step.index = completed_;
  step.load = load;
  step.settling = settling;
  step.newton_iterations = newton.iterations;
  step.linear_iterations = newton.linear_iterations;
  step.linear_solves = newton.linear_solves;
  step.factorizations = newton.factorizations;
  step.time_steps = time_steps;
  step.residuals = newton.residuals;
  last_energy_ = gradient(x, last_gradient_);
  step.energy = last_energy_;
  for (const Tether* tether : terms_.excluded) step.energy -= system_.module_energy(*tether, x);
  if (v && terms_.mass) step.kinetic_energy = terms_.mass->quadratic_form(*v);
  step.reactions = constraints_.reactions(last_gradient_);
  system_.complete_step(x);
  system_.report(x, step);
  step.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  timing_ = false;
  ++completed_;
  observer_(step, x, v);
}

}  // namespace depthfem
