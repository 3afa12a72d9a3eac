#pragma once
/// Options and step records shared by the time integrators (paper section 4 and the explicit
/// comparators): implicit Euler and Newmark (implicit_stepper.hpp), symplectic Euler
/// (symplectic_euler.hpp) and SUNDIALS ARKODE ERKStep (arkode_stepper.hpp).

#include "integrators/solvers/newton.hpp"

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

/// Newmark's parameters: x^{n+1} = x^n + h v^n + h^2 ((1/2 - beta) a^n + beta a^{n+1}),
/// v^{n+1} = v^n + h ((1 - gamma) a^n + gamma a^{n+1}). The defaults (average acceleration) are
/// second order and free of numerical dissipation; 2 beta >= gamma >= 1/2 is unconditionally
/// stable for linear problems, and gamma > 1/2 damps high frequencies at first order.
struct NewmarkOptions {
  double beta = 0.25;
  double gamma = 0.5;
};

/// Which mass matrix the inertia of an implicit scheme uses.
enum class MassMatrix {
  kLumped,      ///< diagonal, a quarter of each tet's mass per corner
  kConsistent,  ///< rho V / 20 (1 + delta_ab) per tet corner pair (linear tets)
};

struct DynamicOptions {
  Integrator integrator = Integrator::kImplicitEuler;
  MassMatrix mass = MassMatrix::kLumped;  ///< explicit integrators need kLumped
  NewmarkOptions newmark;
  double time_step = 1e-2;  ///< h [s]; the output interval for ARKODE
  double duration = 1.0;    ///< simulated time [s]; prescribed motions ramp with t / duration
  RayleighDamping damping;
  ArkodeOptions arkode;
  NewtonOptions newton;
};

/// Number of steps of size time_step that cover the duration (the last one may be shorter).
Index time_step_count(const DynamicOptions& options);

/// End time of step n (0-based) [s]: (n + 1) time_step as a decimal (round_to_decimal), and
/// exactly the duration for the last.
double step_end_time(const DynamicOptions& options, Index n);

}  // namespace depthfem
