#pragma once
/// The one step lifecycle every driver follows (static increments, implicit and explicit time
/// steps): begin the step, prepare + evaluate while converging, prepare + report once converged.

#include <chrono>
#include <functional>
#include <vector>

#include "core/step_record.hpp"
#include "integrators/forces/constraints.hpp"
#include "integrators/forces/nodal_spring.hpp"
#include "integrators/forces/system.hpp"
#include "integrators/solvers/newton.hpp"

namespace depthfem {

/// Called after every completed step with its record, positions and (time-dependent analyses)
/// velocities; null v for static steps.
using StepObserver = std::function<void(const StepRecord&, const Points& x, const Points* v)>;

/// What the lifecycle needs besides the System: which of its modules are not physics (inertia,
/// damping and viscosity tethers, left out of the reported energy) and the mass matrix that
/// turns velocities into kinetic energy.
struct LifecycleTerms {
  std::vector<const Tether*> excluded;  ///< modules of the System left out of StepRecord::energy
  const Tether* mass = nullptr;         ///< K = M, for 1/2 v^T M v (need not be in the System)
};

/// Drives the System's hooks in the same order for every analysis and builds the step records.
class StepLifecycle {
 public:
  StepLifecycle(System& system, const Constraints& constraints, LifecycleTerms terms,
                StepObserver observer)
      : system_(system),
        constraints_(constraints),
        terms_(std::move(terms)),
        observer_(std::move(observer)) {}

  System& system() { return system_; }
  const Constraints& constraints() const { return constraints_; }

  /// Starts a step (or a new attempt at one) from the converged state x towards `load` (load
  /// factor, or time / duration): modules rebuild what they keep per step and move to `load`.
  /// The step's wall time runs from the first begin() after the last completed step.
  void begin(const Points& x, double load);
  /// Moves the modules to `load` within a step (explicit Runge-Kutta stages).
  void set_load(double load) { system_.set_load(load); }
  /// prepare(x), then the energy and its gradient (overwritten) at x.
  double gradient(const Points& x, VectorX& g);

  /// Completes step `load` (load factor or time [s]) at the converged x (v: velocities or null):
  /// prepare(x) and the gradient at x for reactions and energy, the modules' complete_step
  /// (internal variables move to x) and reports, the observer. `newton` gives the iteration counts
  /// and residuals of the solve; `time_steps` the integrator's steps over the record's interval
  /// (StepRecord::time_steps).
  void complete(double load, const NewtonResult& newton, const Points& x, const Points* v,
                bool settling = false, int time_steps = 1);

  /// Sets the acceleration a scheme carries from step to step (Newmark, generalized-alpha), as
  /// it stands after the step about to be completed: a run that goes on from that step needs it.
  void set_acceleration(const Points& a) { acceleration_ = a; }
  /// The acceleration set last (#nodes x 3 [m/s^2]), empty when the scheme carries none.
  const Points& acceleration() const { return acceleration_; }

  /// Steps completed so far.
  Index completed() const { return completed_; }
  /// Total energy (every module) and its gradient at the state of the last complete(): an
  /// explicit scheme's force for its next step.
  double last_energy() const { return last_energy_; }
  const VectorX& last_gradient() const { return last_gradient_; }

 private:
  System& system_;
  const Constraints& constraints_;
  LifecycleTerms terms_;
  StepObserver observer_;
  Index completed_ = 0;
  double last_energy_ = 0;
  VectorX last_gradient_;
  Points acceleration_;
  bool timing_ = false;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace depthfem
