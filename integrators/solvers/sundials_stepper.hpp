#pragma once
/// SUNDIALS ARKODE and CVODE on the first-order system y = (x, v),
///   dx/dt = P v,   dv/dt = P M^-1 (-grad E(x) - C v),
/// where P removes the constrained directions and grad E is evaluated with the Dirichlet
/// conditions imposed at time t, so they hold exactly at every stage and output. Three methods:
///
/// * ERKStep (integrator kArkode): adaptive explicit Runge-Kutta, C = alpha M.
/// * ARKStep with a diagonally implicit table (kArkodeDirk) and CVODE's variable-order BDF
///   (kCvodeBdf, orders 1 to max_order): each implicit stage (BDF step) solves
///   z = b + gamma f(t, z) (gamma = h a_ii, or h / l_1 for BDF; b: the step's known part) by
///   depthfem's Newton through a custom SUNNonlinearSolver. Eliminating
///   z_v = (z_x - b_x) / gamma on the free directions leaves
///   M (z_x - b_x - gamma b_v) / gamma^2 + C (z_x - b_x) / gamma + grad E(z_x) = 0: the
///   stationarity of an incremental potential whose inertia tether has scale 1 / gamma^2 and
///   anchor b_x + gamma b_v and whose damping tethers have scale 1 / gamma and anchor b_x, so the
///   Newton matrix is the exact assembled K + C / gamma + M / gamma^2 (times gamma^2: the
///   velocity block M + gamma C + gamma^2 K of the first-order Newton matrix), with the line
///   search, contact and linear solvers of every other implicit scheme. A solve that fails is a
///   recoverable failure: the stepper retries with a smaller step.
///
/// All control the step size by their error estimates (relative and absolute tolerances). A step
/// of the lifecycle is one output interval (options.time_step): begun at its start, completed at
/// its end; the internal steps inside it see the modules' per-step state (contact trees, the
/// elastic Hessian of stiffness damping) of the interval's start, and each accepted internal
/// step up to the output time moves the modules' internal variables (complete_step).

#include <vector>

#include "integrators/solvers/dynamics.hpp"
#include "integrators/solvers/implicit_stepper.hpp"
#include "integrators/solvers/step_lifecycle.hpp"

namespace depthfem {

/// One internal step the stepper accepted.
struct SundialsInternalStep {
  double time = 0;  ///< at its end [s]
  double size = 0;  ///< h [s]
};

class SundialsStepper {
 public:
  /// options.integrator kArkode (explicit; `implicit` left empty), kArkodeDirk or kCvodeBdf
  /// (`implicit`: the inertia and damping tethers of the lifecycle's System). `mass`: lumped, per
  /// node [kg]. Throws InputError for an order without a default table (a BDF order outside 1-5),
  /// and for the explicit method with stiffness-proportional damping or a consistent mass.
  SundialsStepper(StepLifecycle& lifecycle, VectorX mass, DynamicOptions options,
                  ImplicitTerms implicit = {});

  /// Advances (x, v) to the end time, completing a step through the lifecycle every
  /// options.time_step of simulated time (the internal steps are the stepper's; every stage moves
  /// the modules to its time). Throws SolveError with the stepper's flag and message on failure
  /// (the steps completed so far stay valid).
  void run(Points& x, Points& v);

  /// The internal steps of the last run(), in order.
  const std::vector<SundialsInternalStep>& history() const { return history_; }

 private:
  StepLifecycle& lifecycle_;
  VectorX mass_;
  DynamicOptions options_;
  ImplicitTerms implicit_;
  std::vector<SundialsInternalStep> history_;
};

}  // namespace depthfem
