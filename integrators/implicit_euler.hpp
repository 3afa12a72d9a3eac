#pragma once
/// Dynamic analysis by implicit Euler (paper section 4): each time step minimises the incremental
/// potential  sum_i m_i / (2 h^2) |x_i - (x_i^n + h v_i^n)|^2 + E(x)  with the same Newton core as
/// static analysis; then v^{n+1} = (x^{n+1} - x^n) / h.

#include <chrono>
#include <functional>

#include "integrators/newton.hpp"
#include "integrators/nodal_spring.hpp"

namespace depthfem {

/// Time integration scheme of a dynamic analysis.
enum class Integrator { kImplicitEuler, kSymplecticEuler };

struct DynamicOptions {
  Integrator integrator = Integrator::kImplicitEuler;
  double time_step = 1e-2;  ///< h [s]
  double duration = 1.0;    ///< simulated time [s]; prescribed motions ramp with t / duration
  NewtonOptions newton;
};

/// One completed time step.
struct DynamicStep {
  Index index = 0;
  double time = 0;  ///< [s]
  NewtonResult newton;
  double seconds = 0;
  const Points* x = nullptr;
  const Points* v = nullptr;
  VectorX gradient;  ///< gradient of the incremental potential at x, for reactions
};

/// Number of steps of size time_step that cover the duration.
Index time_step_count(const DynamicOptions& options);

/// Completes a step record for (x, v) at time t (gradient of the system at x, wall time since
/// `start`) and passes it to on_step. Shared by the time integrators.
void report_time_step(System& system, Index index, double t, NewtonResult newton, const Points& x, const Points& v,
                      std::chrono::steady_clock::time_point start,
                      const std::function<void(const DynamicStep&)>& on_step);

/// Implicit Euler over a System. `inertia` is a NodalSpring inside the system with stiffness m_i;
/// the stepper scales it by 1/h^2 and anchors it at the predicted positions x^n + h v^n.
class ImplicitEuler {
 public:
  ImplicitEuler(System& system, const Constraints& constraints, NodalSpring& inertia, DynamicOptions options)
      : system_(system), constraints_(constraints), inertia_(inertia), options_(options),
        newton_(system, constraints, options.newton) {}

  /// Advances (x, v) to the end time; calls on_step after every step. Throws SolveError when a
  /// step fails (the steps reported so far stay valid).
  void run(Points& x, Points& v, const std::function<void(const DynamicStep&)>& on_step);

 private:
  System& system_;
  const Constraints& constraints_;
  NodalSpring& inertia_;
  DynamicOptions options_;
  NewtonSolver newton_;
};

}  // namespace depthfem
