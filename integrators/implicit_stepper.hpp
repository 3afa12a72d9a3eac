#pragma once
/// Implicit time stepping by minimising an incremental potential with the static Newton core
/// (paper section 4): each step solves  min_x  s_m / 2 |x - x_pred|_M^2 + s_c / 2 |x - x_c|_C^2 +
/// E(x), where M (lumped mass) and C (damping) are tethers whose scales and anchors define the
/// scheme:
///
///   implicit Euler:  s_m = 1/h^2, x_pred = x^n + h v^n;                  s_c = 1/h, x_c = x^n;
///                    v^{n+1} = (x^{n+1} - x^n) / h.
///   Newmark (beta = 1/4, gamma = 1/2, average acceleration):
///                    s_m = 4/h^2, x_pred = x^n + h v^n + h^2/4 a^n;      s_c = 2/h, x_c = x^n +
///                    h/2 v^n; a^{n+1} = 4/h^2 (x^{n+1} - x_pred),  v^{n+1} = v^n + h/2 (a^n +
///                    a^{n+1}).
///
/// (The stationarity condition of the Newmark potential is M a^{n+1} + C v^{n+1} + grad E = 0.)
/// Without inertia, implicit Euler is the quasistatic viscous flow C dx/dt = -grad E.

#include <vector>

#include "integrators/dynamics.hpp"

namespace depthfem {

/// The tethers a scheme drives: inertia (absent for quasistatic flow) and damping terms.
struct ImplicitTerms {
  NodalSpring* inertia = nullptr;  ///< stiffness = lumped mass
  std::vector<Tether*> damping;    ///< alpha M, beta K(x^n) or a viscosity
};

/// Implicit Euler or Newmark over a System that contains the given tethers.
class ImplicitStepper {
 public:
  /// options.integrator must be kImplicitEuler or kNewmark (Newmark needs inertia).
  ImplicitStepper(System& system, const Constraints& constraints, ImplicitTerms terms,
                  DynamicOptions options);

  /// Advances (x, v) to the end time; calls on_step after every step. Throws SolveError when a
  /// step fails (the steps reported so far stay valid).
  void run(Points& x, Points& v, const StepCallback& on_step);

 private:
  /// Newmark's a^0 from M a = -(grad E(x) + C v) on the free directions.
  Points initial_acceleration(const Points& x, const Points& v);

  System& system_;
  const Constraints& constraints_;
  ImplicitTerms terms_;
  std::vector<Tether*> tethers_;  // inertia and damping, excluded from the potential energy
  DynamicOptions options_;
  NewtonSolver newton_;
};

}  // namespace depthfem
