#pragma once
/// Explicit comparator from SUNDIALS: ARKODE's ERKStep (adaptive explicit Runge-Kutta with
/// embedded error estimates) on the first-order system
///   dx/dt = P v,   dv/dt = P M^-1 (-grad E(x) - alpha M v),
/// where P removes the constrained directions and grad E is evaluated with the Dirichlet
/// conditions imposed at time t, so they hold exactly at every stage and output.

#include "integrators/constraints.hpp"
#include "integrators/dynamics.hpp"
#include "integrators/system.hpp"

namespace depthfem {

class ArkodeStepper {
 public:
  /// Throws InputError for an order without a default table or stiffness-proportional damping.
  ArkodeStepper(System& system, const Constraints& constraints, VectorX mass,
                DynamicOptions options);

  /// Advances (x, v) to the end time, reporting every options.time_step of simulated time (the
  /// internal steps are ARKODE's). Throws SolveError with ARKODE's flag and message on failure
  /// (the outputs reported so far stay valid).
  void run(Points& x, Points& v, const StepCallback& on_step);

 private:
  System& system_;
  const Constraints& constraints_;
  VectorX mass_;
  DynamicOptions options_;
};

}  // namespace depthfem
