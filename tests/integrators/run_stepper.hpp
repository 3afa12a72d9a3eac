#pragma once
// Runs a dynamic scheme's stepper on a lifecycle built in code, the stepper chosen per
// integrator as apps/run_scene.cpp chooses it.

#include <vector>

#include "integrators/solvers/implicit_stepper.hpp"
#include "integrators/solvers/sundials_stepper.hpp"
#include "integrators/solvers/symplectic_euler.hpp"

namespace depthfem::testing {

// Runs o.integrator from (x, v): ImplicitStepper with the tethers `implicit`; SundialsStepper with
// `mass` (ERK) or `mass` and `implicit` (DIRK, BDF); SymplecticEuler with `mass`, refusing steps
// above `stable_step`. Returns SUNDIALS' internal steps (none for the other steppers).
inline std::vector<SundialsInternalStep> run_stepper(StepLifecycle& lifecycle, const VectorX& mass,
                                                     const DynamicOptions& o,
                                                     const ImplicitTerms& implicit,
                                                     double stable_step, Points& x, Points& v) {
  switch (o.integrator) {
    case Integrator::kImplicitEuler:
    case Integrator::kNewmark:
    case Integrator::kGeneralizedAlpha:
      ImplicitStepper(lifecycle, implicit, o).run(x, v);
      return {};
    case Integrator::kSymplecticEuler:
      SymplecticEuler(lifecycle, mass, o, stable_step).run(x, v);
      return {};
    case Integrator::kArkode:
    case Integrator::kArkodeDirk:
    case Integrator::kCvodeBdf: {
      SundialsStepper stepper(lifecycle, mass, o,
                              o.integrator == Integrator::kArkode ? ImplicitTerms{} : implicit);
      stepper.run(x, v);
      return stepper.history();
    }
  }
  return {};
}

}  // namespace depthfem::testing
