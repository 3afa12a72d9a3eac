#pragma once
/// Options and step records shared by the time integrators (paper section 4 and the explicit
/// comparators): implicit Euler and Newmark (implicit_stepper.hpp), symplectic Euler
/// (symplectic_euler.hpp) and SUNDIALS ARKODE ERKStep (arkode_stepper.hpp).

#include <chrono>
#include <functional>
#include <span>

#include "integrators/newton.hpp"
#include "integrators/nodal_spring.hpp"

namespace depthfem {

/// Time integration scheme.
enum class Integrator {
  kImplicitEuler,  ///< first order, implicit, dissipative
  kNewmark,  ///< Newmark average acceleration (trapezoidal): second order, implicit, no dissipation
  kSymplecticEuler,  ///< first order, explicit, conditionally stable
  kArkode,           ///< SUNDIALS ERKStep: adaptive explicit Runge-Kutta of a chosen order
};

/// Rayleigh damping C = alpha M + beta K(x^n).
struct RayleighDamping {
  double mass = 0;       ///< alpha [1/s]
  double stiffness = 0;  ///< beta [s]; implicit integrators only
};

/// Whether ERKStep has a default explicit Runge-Kutta table of this order (2, 3, 4, 5, 6 or 8).
constexpr bool has_erk_table(int order) {
  return order >= 2 && order <= 8 && order != 7;
}

/// ERKStep settings (integrator kArkode).
struct ArkodeOptions {
  int order = 4;  ///< one with has_erk_table(order)
  double relative_tolerance = 1e-6;
  double absolute_tolerance = 1e-9;  ///< [m] on positions, [m/s] on velocities
  long max_steps = 100000;           ///< internal steps per output interval
};

struct DynamicOptions {
  Integrator integrator = Integrator::kImplicitEuler;
  double time_step = 1e-2;  ///< h [s]; the output interval for ARKODE
  double duration = 1.0;    ///< simulated time [s]; prescribed motions ramp with t / duration
  RayleighDamping damping;
  ArkodeOptions arkode;
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
  VectorX gradient;             ///< gradient of everything the step balances at x, for reactions
  double potential_energy = 0;  ///< elastic + external + contact energy at x [J] (no tethers)
};

using StepCallback = std::function<void(const DynamicStep&)>;

/// Number of steps of size time_step that cover the duration.
Index time_step_count(const DynamicOptions& options);

/// Completes a step record for (x, v) at time t (gradient of the system at x, the potential
/// energy without the integrator's `tethers`, wall time since `start`) and passes it to on_step.
void report_time_step(System& system, std::span<Tether* const> tethers, Index index, double t,
                      NewtonResult newton, const Points& x, const Points& v,
                      std::chrono::steady_clock::time_point start, const StepCallback& on_step);

}  // namespace depthfem
