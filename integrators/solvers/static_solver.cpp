#include "integrators/solvers/static_solver.hpp"

#include <chrono>
#include <cmath>

#include "core/decimal.hpp"
#include "core/error.hpp"

namespace depthfem {

void StaticSolver::run(Points& x, double start_load) {
  Path path{start_load, start_load, x};
  last_failure_.clear();
  load_to_one(x, path);
  if (viscosity_) settle(x, path);
}

bool StaticSolver::legal_start(const Points& x, double target, Points& trial) {
  const Constraints& constraints = lifecycle_.constraints();
  System& system = lifecycle_.system();
  system.prepare(trial);
  if (std::isfinite(system.energy(trial))) return true;
  // An illegal trial (the predictor, or the prescribed motion alone, inverts a tet): carry the
  // prescribed motion into the body by the stiffness at x (linearised_start), else try the
  // motion alone, else give up on the increment (it is halved).
  Points moved = x;
  constraints.impose(target, moved);
  if (options_.linearised_start) {
    trial = newton_.linearised_step(x, moved - x);
    constraints.impose(target, trial);
    system.prepare(trial);
    if (std::isfinite(system.energy(trial))) return true;
  }
  trial = moved;
  system.prepare(trial);
  if (std::isfinite(system.energy(trial))) return true;
  last_failure_ = "prescribed motion inverts an element";
  return false;
}

bool StaticSolver::attempt(Points& x, Path& path, double target, bool settling) {
  const auto start = std::chrono::steady_clock::now();
  const auto failed = [&](const NewtonResult* r) {
    if (on_failure_)
      on_failure_(
          {path.load, target, settling, r, last_failure_,
           std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()});
    return false;
  };
  Points trial = x;
  if (options_.predictor && lifecycle_.completed() >= 1 && !settling &&
      path.load > path.previous_load) {
    trial = x + (target - path.load) / (path.load - path.previous_load) * (x - path.previous);
  }
  lifecycle_.constraints().impose(target, trial);
  if (viscosity_) viscosity_->set_anchor(x);
  lifecycle_.begin(x, target);
  if (!legal_start(x, target, trial)) return failed(nullptr);
  NewtonResult r = newton_.solve(trial);
  if (!r.converged) {
    last_failure_ = r.failure;
    return failed(&r);
  }
  path.previous = x;
  path.previous_load = path.load;
  x = trial;
  path.load = target;
  lifecycle_.complete(path.load, r, x, nullptr, settling);
  return true;
}

void StaticSolver::load_to_one(Points& x, Path& path) {
  // Load factors are base + k increment within a run of equal increments, so that ten steps of
  // 0.1 end exactly at 1 instead of accumulating round-off, rounded to the decimal they stand
  // for (0.44, not 0.44000000000000006).
  double increment = std::min(options_.initial_increment, options_.max_increment);
  double base = path.load;
  int count = 0, successes = 0;
  const auto restart_run = [&](double new_increment) {
    increment = new_increment;
    base = path.load;
    count = 0;
  };
  while (path.load < 1.0) {
    double target = round_to_decimal(base + (count + 1) * increment);
    if (target > 1.0 || 1.0 - target <= 1e-9 * increment) target = 1.0;
    // Every attempt must move the load: an increment below the resolution of the rounded load
    // factors would land on the same load, "converge" at once and repeat forever.
    if (!(target > path.load)) {
      throw SolveError(
          "load increment " + shown(increment) + " at load factor " + shown(path.load) +
          " no longer changes the load (load factors have 12 significant digits); " +
          "raise solver.min_increment" + (last_failure_.empty() ? "" : ": " + last_failure_));
    }
    if (attempt(x, path, target, false)) {
      ++count;
      if (++successes >= 2 && increment < options_.max_increment)
        restart_run(std::min(options_.max_increment, increment * options_.growth));
      continue;
    }
    successes = 0;
    restart_run(increment * 0.5);
    if (increment < options_.min_increment) {
      throw SolveError("load increment fell below min_increment " + shown(options_.min_increment) +
                       " at load factor " + shown(path.load) + ": " + last_failure_);
    }
  }
}

void StaticSolver::settle(Points& x, Path& path) {
  // Pseudo-transient continuation: each step is a viscous (proximal) step from the last one; the
  // viscosity is halved after every success and raised fourfold after a failure, so the body
  // first creeps off unstable equilibria, then the steps approach plain Newton solves. At rest
  // the motion of a step at the base viscosity exerts no force worth the Newton tolerance.
  double scale = 1.0;
  for (int k = 0; k < options_.max_settle_steps; ++k) {
    const Points before = x;
    viscosity_->set_scale(scale);
    if (!attempt(x, path, 1.0, true)) {
      scale *= 4;
      if (scale > 1e6) throw SolveError("settling step failed at full load: " + last_failure_);
      continue;
    }
    VectorX viscous = VectorX::Zero(3 * x.rows());
    viscosity_->set_scale(1.0);
    viscosity_->set_anchor(before);
    viscosity_->evaluate(x, &viscous, nullptr);
    lifecycle_.constraints().project(viscous);
    if (scaled_residual(options_.newton, viscous) <= options_.newton.tolerance) return;
    scale = std::max(scale / 2, 1e-12);
  }
  throw SolveError("the body did not come to rest in " + std::to_string(options_.max_settle_steps) +
                   " quasi-viscous steps at full load");
}

}  // namespace depthfem
