#pragma once
/// Static analysis: adaptive incremental loading with a two-point predictor around Newton
/// (LOOP1 of the paper's section 3.2), and quasi-viscous settling.

#include <functional>

#include "integrators/newton.hpp"
#include "integrators/nodal_spring.hpp"

namespace depthfem {

struct StaticOptions {
  double initial_increment = 1.0;  ///< first load-factor increment
  double min_increment = 1e-3;     ///< below this the run stops with an error
  double max_increment = 1.0;
  double growth = 2.0;    ///< increment factor after two successes in a row
  bool predictor = true;  ///< extrapolate the last two solutions (two-point predictor)
  /// With quasi-viscosity: steps at full load after loading, until the viscous force is
  /// below the Newton tolerance (the body has come to rest), at most this many.
  int max_settle_steps = 200;
  NewtonOptions newton;
};

/// One completed load step as reported to the caller.
struct StaticStep {
  Index index = 0;
  double load = 0;        ///< load factor in (0, 1]
  bool settling = false;  ///< a quasi-viscous step at full load
  NewtonResult newton;
  double seconds = 0;  ///< wall time of the step, failed attempts included
  const Points* x = nullptr;
  VectorX gradient;  ///< unprojected energy gradient at x (for reactions)
};

/// Drives a System from the reference state to load factor 1 (and to rest, with quasi-viscosity).
class StaticSolver {
 public:
  /// `viscosity` is the quasi-viscosity module inside `system`, or null.
  StaticSolver(System& system, const Constraints& constraints, NodalSpring* viscosity,
               StaticOptions options)
      : system_(system),
        constraints_(constraints),
        viscosity_(viscosity),
        options_(options),
        newton_(system, constraints, options.newton) {}

  /// Runs from x; calls `on_step` after every completed step. Throws SolveError when the
  /// increment falls below the minimum or settling does not finish; the steps reported so far
  /// stay valid (x holds the last completed one).
  void run(Points& x, const std::function<void(const StaticStep&)>& on_step);

 private:
  System& system_;
  const Constraints& constraints_;
  NodalSpring* viscosity_;
  StaticOptions options_;
  NewtonSolver newton_;
};

}  // namespace depthfem
