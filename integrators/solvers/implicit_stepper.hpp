#pragma once
/// Implicit time stepping by minimising an incremental potential with the static Newton core
/// (paper section 4): each step solves  min_x  s_m / 2 |x - x_pred|_M^2 + s_c / 2 |x - x_c|_C^2 +
/// E(x), where M (mass) and C (damping) are tethers whose scales and anchors define the scheme.
/// With the step h = t^{n+1} - t^n:
///
///   implicit Euler:  s_m = 1/h^2, x_pred = x^n + h v^n;                  s_c = 1/h, x_c = x^n;
///                    v^{n+1} = (x^{n+1} - x^n) / h.
///   Newmark (beta, gamma):
///                    s_m = 1/(beta h^2), x_pred = x^n + h v^n + h^2 (1/2 - beta) a^n;
///                    s_c = gamma/(beta h), x_c = x_pred - beta h / gamma (v^n + h (1 - gamma)
///                    a^n); a^{n+1} = (x^{n+1} - x_pred) / (beta h^2), v^{n+1} = v^n + h ((1 -
///                    gamma) a^n + gamma a^{n+1}).
///
/// (The stationarity condition of the Newmark potential is M a^{n+1} + C v^{n+1} + grad E = 0;
/// for beta = 1/4, gamma = 1/2: s_m = 4/h^2, x_c = x^n + h/2 v^n.) Without inertia, implicit
/// Euler is the quasistatic viscous flow C dx/dt = -grad E.

#include <vector>

#include "integrators/solvers/dynamics.hpp"
#include "integrators/solvers/step_lifecycle.hpp"

namespace depthfem {

/// The tethers a scheme drives: inertia (absent for quasistatic flow) and damping terms.
struct ImplicitTerms {
  Tether* inertia = nullptr;     ///< K = the mass matrix (lumped or consistent)
  std::vector<Tether*> damping;  ///< alpha M, beta K(x^n) or a viscosity
};

/// Implicit Euler or Newmark over the System of a lifecycle that contains the given tethers.
class ImplicitStepper {
 public:
  /// options.integrator must be kImplicitEuler or kNewmark (Newmark needs inertia).
  ImplicitStepper(StepLifecycle& lifecycle, ImplicitTerms terms, DynamicOptions options);

  /// Advances (x, v) from `start` to the end time, completing every step through the lifecycle;
  /// Newmark and generalized-alpha hand it their acceleration after every step
  /// (StepLifecycle::acceleration), and start from start.acceleration where it is given. Throws
  /// SolveError when a step fails (the steps completed so far stay valid).
  void run(Points& x, Points& v, const DynamicStart& start = {});

 private:
  /// Newmark's a^0 from M a = -(grad E(x) + C v) on the free directions.
  Points initial_acceleration(const Points& x, const Points& v);

  StepLifecycle& lifecycle_;
  ImplicitTerms terms_;
  DynamicOptions options_;
  NewtonSolver newton_;
};

}  // namespace depthfem
