#pragma once
/// Explicit comparator from SUNDIALS: ARKODE's ERKStep (adaptive explicit Runge-Kutta with
/// embedded error estimates) on the first-order system
///   dx/dt = P v,   dv/dt = P M^-1 (-grad E(x) - alpha M v),
/// where P removes the constrained directions and grad E is evaluated with the Dirichlet
/// conditions imposed at time t, so they hold exactly at every stage and output.

#include "integrators/solvers/dynamics.hpp"
#include "integrators/solvers/step_lifecycle.hpp"

namespace depthfem {

class ArkodeStepper {
 public:
  /// Throws InputError for an order without a default table, stiffness-proportional damping or
  /// a consistent mass.
  ArkodeStepper(StepLifecycle& lifecycle, VectorX mass, DynamicOptions options);

  /// Advances (x, v) to the end time, completing a step through the lifecycle every
  /// options.time_step of simulated time (the internal steps are ARKODE's; every stage moves the
  /// modules to its time). Throws SolveError with ARKODE's flag and message on failure (the steps
  /// completed so far stay valid).
  void run(Points& x, Points& v);

 private:
  StepLifecycle& lifecycle_;
  VectorX mass_;
  DynamicOptions options_;
};

}  // namespace depthfem
