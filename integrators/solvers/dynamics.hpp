#pragma once
/// Options and step records shared by the time integrators (paper section 4 and the explicit
/// comparators): implicit Euler, Newmark and generalized-alpha (implicit_stepper.hpp), symplectic
/// Euler (symplectic_euler.hpp) and SUNDIALS ARKODE, ERKStep and ARKStep's diagonally implicit
/// methods, CVODE's BDF (sundials_stepper.hpp).

#include "integrators/solvers/newton.hpp"

namespace depthfem {

/// Time integration scheme.
enum class Integrator {
  kImplicitEuler,  ///< first order, implicit, dissipative
  kNewmark,  ///< Newmark average acceleration (trapezoidal): second order, implicit, no dissipation
  kSymplecticEuler,   ///< first order, explicit, conditionally stable
  kArkode,            ///< SUNDIALS ERKStep: adaptive explicit Runge-Kutta of a chosen order
  kGeneralizedAlpha,  ///< Chung-Hulbert: second order, implicit, tunable high-frequency damping
  kArkodeDirk,        ///< SUNDIALS ARKStep: adaptive diagonally implicit Runge-Kutta (order 2-5)
  kCvodeBdf,          ///< SUNDIALS CVODE: variable-order (1 to max_order), variable-step BDF
};

/// Whether the scheme solves a nonlinear system per step (or stage) with Newton over a System
/// that carries inertia and damping as tethers.
constexpr bool is_implicit(Integrator integrator) {
  return integrator != Integrator::kSymplecticEuler && integrator != Integrator::kArkode;
}

/// Rayleigh damping C = alpha M + beta K(x^n).
struct RayleighDamping {
  double mass = 0;       ///< alpha [1/s]
  double stiffness = 0;  ///< beta [s]; implicit integrators only
};

/// Whether ERKStep has a default explicit Runge-Kutta table of this order (2, 3, 4, 5, 6 or 8).
constexpr bool has_erk_table(int order) {
  return order >= 2 && order <= 8 && order != 7;
}

/// The error control of SUNDIALS' adaptive steppers (ARKODE and CVODE).
struct ErrorControl {
  double relative_tolerance = 1e-6;
  double absolute_tolerance = 1e-9;  ///< [m] on positions, [m/s] on velocities
  long max_steps = 100000;           ///< internal steps per output interval
};

/// ARKODE settings (integrators kArkode and kArkodeDirk).
struct ArkodeOptions : ErrorControl {
  int order = 4;  ///< kArkode: has_erk_table(order); kArkodeDirk: has_dirk_table(order)
  /// Internal steps of exactly time_step, without error control (for measured orders).
  bool fixed_step = false;
};

/// CVODE settings (integrator kCvodeBdf).
struct CvodeOptions : ErrorControl {
  int max_order = 5;  ///< the highest BDF order CVODE may choose, 1 to 5
};

/// Newmark's parameters: x^{n+1} = x^n + h v^n + h^2 ((1/2 - beta) a^n + beta a^{n+1}),
/// v^{n+1} = v^n + h ((1 - gamma) a^n + gamma a^{n+1}). The defaults (average acceleration) are
/// second order and free of numerical dissipation; 2 beta >= gamma >= 1/2 is unconditionally
/// stable for linear problems, and gamma > 1/2 damps high frequencies at first order.
struct NewmarkOptions {
  double beta = 0.25;
  double gamma = 0.5;
};

/// Chung and Hulbert's generalized-alpha method (J. Appl. Mech. 60, 1993): the balance
/// M a^{n+1-alpha_m} + C v^{n+1-alpha_f} + grad E(x^{n+1-alpha_f}) = 0 with
/// y^{n+1-alpha} = (1 - alpha) y^{n+1} + alpha y^n and Newmark's updates, where
/// alpha_m = (2 rho - 1) / (rho + 1), alpha_f = rho / (rho + 1), gamma = 1/2 - alpha_m + alpha_f,
/// beta = (1 - alpha_m + alpha_f)^2 / 4 for the spectral radius rho = rho_inf at infinite
/// frequency: second order, unconditionally stable for linear problems; rho_inf = 1 is the
/// non-dissipative midpoint-like rule, rho_inf = 0 annihilates the highest frequencies in one step.
struct GeneralizedAlphaOptions {
  double rho_inf = 0.8;  ///< in [0, 1]
};

/// The four parameters of a generalized-alpha step: Newmark is alpha_m = alpha_f = 0.
struct AlphaParameters {
  double alpha_m = 0, alpha_f = 0, beta = 0.25, gamma = 0.5;
};
/// Chung and Hulbert's optimal parameters for rho_inf (GeneralizedAlphaOptions).
AlphaParameters chung_hulbert(double rho_inf);

/// Whether ARKStep has a default diagonally implicit table of this order (2, 3, 4 or 5).
constexpr bool has_dirk_table(int order) {
  return order >= 2 && order <= 5;
}

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
  ArkodeOptions arkode;  ///< also for kArkodeDirk (order: has_dirk_table)
  CvodeOptions cvode;
  GeneralizedAlphaOptions generalized_alpha;
  NewtonOptions newton;
};

/// Number of steps of size time_step that cover the duration (the last one may be shorter).
Index time_step_count(const DynamicOptions& options);

/// End time of step n (0-based) [s]: (n + 1) time_step as a decimal (round_to_decimal), and
/// exactly the duration for the last.
double step_end_time(const DynamicOptions& options, Index n);

/// The first step of the time grid that ends after `time` [s] by more than 1e-9 time_step: the
/// step after the one that ended at `time`, when a run goes on from a completed step.
Index first_step_after(const DynamicOptions& options, double time);

/// Where a time integrator starts: at rest at time 0 (the default), or from a completed step of
/// an earlier run (a restart), whose time it continues with, and the acceleration (Newmark,
/// generalized-alpha) or force (symplectic Euler) the scheme carries.
struct DynamicStart {
  double time = 0;      ///< [s]
  Points acceleration;  ///< #nodes x 3 [m/s^2]; empty: computed from the balance at the start
  /// Symplectic Euler: the force of the first step, grad E at the start as the step that ended
  /// there evaluated it (#nodes x 3 [N]); empty: evaluated at the start.
  Points force;
};

}  // namespace depthfem
