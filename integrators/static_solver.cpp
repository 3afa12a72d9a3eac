#include "integrators/static_solver.hpp"

#include <cmath>

#include "core/decimal.hpp"
#include "core/error.hpp"

namespace depthfem {

void StaticSolver::run(Points& x, double start_load) {
  const Constraints& constraints = lifecycle_.constraints();
  System& system = lifecycle_.system();
  // Converged solutions at the last two load factors feed the predictor.
  double load = start_load, previous_load = start_load;
  Points previous = x;
  double increment = std::min(options_.initial_increment, options_.max_increment);
  // Load factors are base + k increment within a run of equal increments, so that ten steps of
  // 0.1 end exactly at 1 instead of accumulating round-off, rounded to the decimal they stand
  // for (0.44, not 0.44000000000000006).
  double base = start_load;
  int count = 0, successes = 0;
  std::string last_failure;

  const auto attempt = [&](double target, bool settling) -> bool {
    Points trial = x;
    if (options_.predictor && lifecycle_.completed() >= 1 && !settling && load > previous_load) {
      trial = x + (target - load) / (load - previous_load) * (x - previous);
    }
    constraints.impose(target, trial);
    if (viscosity_) viscosity_->set_anchor(x);
    lifecycle_.begin(x, target);
    system.prepare(trial);
    // An illegal trial (the predictor, or the prescribed motion alone, inverts a tet): carry
    // the prescribed motion into the body by the stiffness at x, else give up on the increment.
    if (!std::isfinite(system.energy(trial))) {
      Points moved = x;
      constraints.impose(target, moved);
      trial = newton_.linearised_step(x, moved - x);
      constraints.impose(target, trial);
      system.prepare(trial);
      if (!std::isfinite(system.energy(trial))) {
        trial = moved;
        system.prepare(trial);
        if (!std::isfinite(system.energy(trial))) {
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
    lifecycle_.complete(load, r, x, nullptr, settling);
    return true;
  };
  const auto restart_run = [&](double new_increment) {
    increment = new_increment;
    base = load;
    count = 0;
  };

  while (load < 1.0) {
    double target = round_to_decimal(base + (count + 1) * increment);
    if (target > 1.0 || 1.0 - target <= 1e-9 * increment) target = 1.0;
    // Every attempt must move the load: an increment below the resolution of the rounded load
    // factors would land on the same load, "converge" at once and repeat forever.
    if (!(target > load)) {
      throw SolveError("load increment " + shown(increment) + " at load factor " + shown(load) +
                       " no longer changes the load (load factors have 12 significant digits); " +
                       "raise solver.min_increment" +
                       (last_failure.empty() ? "" : ": " + last_failure));
    }
    if (attempt(target, false)) {
      ++count;
      if (++successes >= 2 && increment < options_.max_increment)
        restart_run(std::min(options_.max_increment, increment * options_.growth));
      continue;
    }
    successes = 0;
    restart_run(increment * 0.5);
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
    constraints.project(viscous);
    if (scaled_residual(options_.newton, viscous) <= options_.newton.tolerance) return;
    scale = std::max(scale / 2, 1e-12);
  }
  throw SolveError("the body did not come to rest in " + std::to_string(options_.max_settle_steps) +
                   " quasi-viscous steps at full load");
}

}  // namespace depthfem
