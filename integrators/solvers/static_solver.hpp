#pragma once
/// Static analysis: adaptive incremental loading with a two-point predictor around Newton
/// (LOOP1 of the paper's section 3.2), and quasi-viscous settling.

#include <functional>
#include <string>

#include "integrators/forces/nodal_spring.hpp"
#include "integrators/solvers/newton.hpp"
#include "integrators/solvers/step_lifecycle.hpp"

namespace depthfem {

struct StaticOptions {
  double initial_increment = 1.0;  ///< first load-factor increment
  double min_increment = 1e-3;     ///< below this the run stops with an error
  double max_increment = 1.0;
  double growth = 2.0;    ///< increment factor after two successes in a row
  bool predictor = true;  ///< extrapolate the last two solutions (two-point predictor)
  /// Where the predicted start of an increment is illegal, try the prescribed motion carried
  /// into the body by the stiffness (NewtonSolver::linearised_step) before the motion alone;
  /// false: the motion alone, and the increment is halved if that is illegal too (the paper).
  bool linearised_start = true;
  /// With quasi-viscosity: steps at full load after loading, until the viscous force is
  /// below the Newton tolerance (the body has come to rest), at most this many.
  int max_settle_steps = 200;
  NewtonOptions newton;
};

/// An attempt at an increment that failed: from load factor `from` towards `target`, its Newton
/// solve (null where no legal start was found and Newton did not run), why, and its wall time.
/// A failed attempt completes no step, so this is a long run's only sign of it.
struct FailedAttempt {
  double from = 0, target = 0;
  bool settling = false;
  const NewtonResult* newton = nullptr;
  std::string why;
  double seconds = 0;
};
using AttemptObserver = std::function<void(const FailedAttempt&)>;

/// Drives a System from the reference state to load factor 1 (and to rest, with quasi-viscosity).
class StaticSolver {
 public:
  /// `viscosity` is the quasi-viscosity module inside the lifecycle's System, or null;
  /// `on_failure`, if set, is called after every failed attempt.
  StaticSolver(StepLifecycle& lifecycle, NodalSpring* viscosity, StaticOptions options,
               AttemptObserver on_failure = {})
      : lifecycle_(lifecycle),
        viscosity_(viscosity),
        options_(options),
        newton_(lifecycle.system(), lifecycle.constraints(), options.newton),
        on_failure_(std::move(on_failure)) {}

  /// Runs from x, an equilibrium at load factor `start_load` in [0, 1] (0: the reference state;
  /// more: a restart from a completed step), completing every converged increment through the
  /// lifecycle. Load factors are the start of the current run of equal increments plus a whole
  /// number of them, rounded to the decimal they stand for (round_to_decimal), and the last one
  /// is exactly 1. Throws SolveError when the increment falls below the minimum or settling does
  /// not finish; the steps completed so far stay valid (x holds the last one).
  void run(Points& x, double start_load = 0);

 private:
  /// The last converged load factor, and the one before with its solution: the predictor's
  /// second point.
  struct Path {
    double load, previous_load;
    Points previous;
  };
  /// Adaptive incremental loading from path.load to 1 (LOOP1).
  void load_to_one(Points& x, Path& path);
  /// Quasi-viscous steps at full load until the body is at rest.
  void settle(Points& x, Path& path);
  /// One attempt at load factor `target` from the converged x: predictor, legal start, Newton;
  /// on success x and `path` move to it and the step is completed. False (last_failure_ says
  /// why) when it does not converge.
  bool attempt(Points& x, Path& path, double target, bool settling);
  /// Makes `trial` (prepared) a legal configuration to start Newton from at `target`: as it is,
  /// else the prescribed motion carried into the body by the stiffness at x (with
  /// linearised_start), else the prescribed motion alone. False when all of them invert a tet.
  bool legal_start(const Points& x, double target, Points& trial);

  StepLifecycle& lifecycle_;
  NodalSpring* viscosity_;
  StaticOptions options_;
  NewtonSolver newton_;
  AttemptObserver on_failure_;
  std::string last_failure_;  ///< why the last attempt failed
};

}  // namespace depthfem
