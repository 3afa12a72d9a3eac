#pragma once
/// Explicit comparator: symplectic (semi-implicit) Euler on lumped masses with optional
/// mass-proportional damping alpha,
///   v^{n+1} = v^n - h (M^-1 grad E(x^n) + alpha v^n),  x^{n+1} = x^n + h v^{n+1},
/// stable only below the critical time step of the mesh, which is estimated and enforced.

#include "integrators/forces/elasticity.hpp"
#include "integrators/solvers/dynamics.hpp"
#include "integrators/solvers/step_lifecycle.hpp"

namespace depthfem {

/// Critical time step estimate [s]: min over tets of l_e / c_e, with l_e = 3 V / (largest face
/// area) the smallest altitude and c_e = sqrt((lambda + 2 mu) / rho) the dilatational wave speed
/// of the tet's material at small strain (the usual explicit-dynamics bound).
double critical_time_step(const Points& X, const TetIndices& tets, const VectorX& tet_density,
                          const std::vector<ElasticGroup>& groups);

/// Symplectic Euler over the System of a lifecycle (its modules must not include inertia).
class SymplecticEuler {
 public:
  /// Throws InputError when options.time_step exceeds `critical_step`, or stiffness-proportional
  /// damping or a consistent mass is requested.
  SymplecticEuler(StepLifecycle& lifecycle, VectorX mass, DynamicOptions options,
                  double critical_step);

  /// Advances (x, v) to the end time, completing every step through the lifecycle (no Newton
  /// iterations). Forces of step n are those at (x^n, t^n); the gradient computed to report a
  /// step is the next step's force, so each step evaluates the forces once. Starts at
  /// start.time, with start.force where it is given (its acceleration is not used).
  void run(Points& x, Points& v, const DynamicStart& start = {});

 private:
  StepLifecycle& lifecycle_;
  VectorX mass_;
  DynamicOptions options_;
};

}  // namespace depthfem
