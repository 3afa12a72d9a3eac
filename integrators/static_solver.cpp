#include "integrators/static_solver.hpp"

#include <chrono>
#include <cmath>

#include "core/error.hpp"

namespace depthfem {

namespace {
double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}
}  // namespace

void StaticSolver::run(Points& x, const std::function<void(const StaticStep&)>& on_step) {
  // Converged solutions at the last two load factors feed the predictor.
  double load = 0, previous_load = 0;
  Points previous = x;
  double increment = std::min(options_.initial_increment, options_.max_increment);
  int successes = 0;
  Index index = 0;
  auto start = std::chrono::steady_clock::now();
  std::string last_failure;

  const auto attempt = [&](double target, bool settling) -> bool {
    Points trial = x;
    if (options_.predictor && index >= 1 && !settling && load > previous_load) {
      trial = x + (target - load) / (load - previous_load) * (x - previous);
    }
    constraints_.impose(target, trial);
    if (viscosity_) viscosity_->set_anchor(x);
    system_.begin_step(x, target);
    system_.prepare(trial);
    // An illegal trial (the predictor, or the prescribed motion alone, inverts a tet): carry
    // the prescribed motion into the body by the stiffness at x, else give up on the increment.
    if (!std::isfinite(system_.energy(trial))) {
      Points moved = x;
      constraints_.impose(target, moved);
      trial = newton_.linearised_step(x, moved - x);
      constraints_.impose(target, trial);
      system_.prepare(trial);
      if (!std::isfinite(system_.energy(trial))) {
        trial = moved;
        system_.prepare(trial);
        if (!std::isfinite(system_.energy(trial))) {
          last_failure = "prescribed motion inverts an element";
          return false;
        }
      }
    }
    NewtonResult r = newton_.solve(trial);
    if (!r.converged) {
      last_failure = r.failure;
      return false;
    }
    previous = x;
    previous_load = load;
    x = trial;
    load = target;
    StaticStep step;
    step.index = index++;
    step.load = load;
    step.settling = settling;
    step.newton = std::move(r);
    step.seconds = seconds_since(start);
    step.x = &x;
    system_.gradient(x, step.gradient);
    on_step(step);
    start = std::chrono::steady_clock::now();
    return true;
  };

  while (load < 1.0) {
    const double target = std::min(1.0, load + increment);
    if (attempt(target, false)) {
      if (++successes >= 2)
        increment = std::min(options_.max_increment, increment * options_.growth);
      continue;
    }
    successes = 0;
    increment *= 0.5;
    if (increment < options_.min_increment) {
      throw SolveError("load increment fell below min_increment " +
                       std::to_string(options_.min_increment) + " at load factor " +
                       std::to_string(load) + ": " + last_failure);
    }
  }
  if (!viscosity_) return;
  // Settle at full load by pseudo-transient continuation: each step is a viscous (proximal)
  // step from the last one; the viscosity is halved after every success and raised fourfold after
  // a failure, so the body first creeps off unstable equilibria, then the steps approach plain
  // Newton solves. At rest the motion of a step at the base viscosity exerts no force worth the
  // Newton tolerance.
  double scale = 1.0;
  for (int k = 0; k < options_.max_settle_steps; ++k) {
    const Points before = x;
    viscosity_->set_scale(scale);
    if (!attempt(1.0, true)) {
      scale *= 4;
      if (scale > 1e6) throw SolveError("settling step failed at full load: " + last_failure);
      continue;
    }
    VectorX viscous = VectorX::Zero(3 * x.rows());
    viscosity_->set_scale(1.0);
    viscosity_->set_anchor(before);
    viscosity_->evaluate(x, &viscous, nullptr);
    constraints_.project(viscous);
    if (scaled_residual(options_.newton, viscous) <= options_.newton.tolerance) return;
    scale = std::max(scale / 2, 1e-12);
  }
  throw SolveError("the body did not come to rest in " + std::to_string(options_.max_settle_steps) +
                   " quasi-viscous steps at full load");
}

}  // namespace depthfem
