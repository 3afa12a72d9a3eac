#pragma once
/// SUNDIALS ARKODE on the first-order system y = (x, v),
///   dx/dt = P v,   dv/dt = P M^-1 (-grad E(x) - C v),
/// where P removes the constrained directions and grad E is evaluated with the Dirichlet
/// conditions imposed at time t, so they hold exactly at every stage and output. Two methods:
///
/// * ERKStep (integrator kArkode): adaptive explicit Runge-Kutta, C = alpha M.
/// * ARKStep with a diagonally implicit table (kArkodeDirk): each implicit stage solves
///   z = b + gamma f(t, z) (gamma = h a_ii, b: the step's known part) by depthfem's Newton through
///   a custom SUNNonlinearSolver. Eliminating z_v = (z_x - b_x) / gamma on the free directions
///   leaves M (z_x - b_x - gamma b_v) / gamma^2 + C (z_x - b_x) / gamma + grad E(z_x) = 0: the
///   stationarity of an incremental potential whose inertia tether has scale 1 / gamma^2 and
///   anchor b_x + gamma b_v and whose damping tethers have scale 1 / gamma and anchor b_x, so the
///   Newton matrix is the exact assembled K + C / gamma + M / gamma^2 (times gamma^2: the
///   velocity block M + gamma C + gamma^2 K of the first-order Newton matrix), with the line
///   search, contact and linear solvers of every other implicit scheme. A stage whose Newton
///   solve fails is a recoverable failure: ARKODE retries with a smaller step.
///
/// Both control the step size by their embedded error estimates (relative and absolute
/// tolerances). A step of the lifecycle is one output interval (options.time_step): begun at its
/// start, completed at its end; the internal steps inside it see the modules' per-step state
/// (contact trees, the elastic Hessian of stiffness damping) of the interval's start.

#include <vector>

#include "integrators/solvers/dynamics.hpp"
#include "integrators/solvers/implicit_stepper.hpp"
#include "integrators/solvers/step_lifecycle.hpp"

namespace depthfem {

/// One internal step ARKODE accepted.
struct ArkodeInternalStep {
  double time = 0;  ///< at its end [s]
  double size = 0;  ///< h [s]
};

class ArkodeStepper {
 public:
  /// options.integrator kArkode (explicit; `implicit` left empty) or kArkodeDirk (`implicit`:
  /// the inertia and damping tethers of the lifecycle's System). `mass`: lumped, per node [kg].
  /// Throws InputError for an order without a default table, and for the explicit method with
  /// stiffness-proportional damping or a consistent mass.
  ArkodeStepper(StepLifecycle& lifecycle, VectorX mass, DynamicOptions options,
                ImplicitTerms implicit = {});

  /// Advances (x, v) to the end time, completing a step through the lifecycle every
  /// options.time_step of simulated time (the internal steps are ARKODE's; every stage moves the
  /// modules to its time). Throws SolveError with ARKODE's flag and message on failure (the steps
  /// completed so far stay valid).
  void run(Points& x, Points& v);

  /// The internal steps of the last run(), in order.
  const std::vector<ArkodeInternalStep>& history() const { return history_; }

 private:
  StepLifecycle& lifecycle_;
  VectorX mass_;
  DynamicOptions options_;
  ImplicitTerms implicit_;
  std::vector<ArkodeInternalStep> history_;
};

}  // namespace depthfem
