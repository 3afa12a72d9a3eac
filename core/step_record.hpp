#pragma once
/// What a completed step (static load increment or time step) reports: the one record every
/// driver fills through the step lifecycle, the results file writes and the tools read.

#include <string>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

/// The force one contact interface (a pair of bodies, a body against itself, a body set against
/// an obstacle) carries at a step.
struct InterfaceForce {
  std::string name;           ///< "femur/patella", "skin (self)", "obstacle floor"
  Vec3 force = Vec3::Zero();  ///< [N] on the first-named body (see the module's docs)
  /// [N] the pair forces summed as magnitudes, each contact surface counted once: |force| where
  /// the pressure points one way, and for self-contact (whose net force is internal and
  /// cancels) the force pressed across the fold.
  double magnitude = 0;
  double area = 0;  ///< [m^2] of surface in contact, each contact surface counted once
};

/// One completed step.
struct StepRecord {
  Index index = 0;                ///< 0, 1, ... in the order completed
  double load = 0;                ///< load factor in (0, 1] (static) or time [s]
  bool settling = false;          ///< a quasi-viscous step at full load (static)
  int newton_iterations = 0;      ///< implicit: Newton steps; ARKODE: internal Runge-Kutta steps
  int linear_iterations = 0;      ///< summed over the Newton steps
  std::vector<double> residuals;  ///< |P grad E| [N] at every Newton iterate, the first included
  double energy = 0;              ///< potential energy [J]: every force module but inertia/damping
  double kinetic_energy = 0;      ///< 1/2 v^T M v [J] (time-dependent analyses; 0 otherwise)
  double seconds = 0;             ///< wall time of the step, failed attempts included [s]
  /// #conditions x 3 [N]: force each boundary condition exerts on the bodies. Every constrained
  /// degree of freedom belongs to exactly one condition, so at equilibrium the rows sum to minus
  /// the applied loads.
  Eigen::Matrix<double, Eigen::Dynamic, 3> reactions;
  /// One row per contact interface of the scene, in a fixed order (empty without contact).
  std::vector<InterfaceForce> contact;

  /// Total contact area [m^2] over all interfaces.
  double contact_area() const {
    double a = 0;
    for (const InterfaceForce& f : contact) a += f.area;
    return a;
  }
};

}  // namespace depthfem
