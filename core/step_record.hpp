#pragma once
/// What a completed step (static load increment or time step) reports: the one record every
/// driver fills through the step lifecycle, the results file writes and the tools read.

#include <optional>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

/// The force one contact interface (a pair of bodies, a body against itself, a body set against
/// an obstacle) carries at a step.
struct InterfaceForce {
  std::string name;           ///< "femur/patella", "skin (self)", "obstacle floor"
  Vec3 force = Vec3::Zero();  ///< [N] on the first-named body (see the module's docs)
  /// [N] the forces on the penetrating boundary triangles (netted per triangle) summed as
  /// magnitudes, each contact surface counted once: |force| where the pressure points one way,
  /// and for self-contact (whose net force is internal and cancels) the force pressed across
  /// the fold. It is the integral of the contact pressure over the interface's triangles.
  double magnitude = 0;
  double area = 0;  ///< [m^2] of surface in contact, each contact surface counted once
};

/// Contact on each boundary triangle at a step, summed over the contact pairs whose penetrating
/// surface is that triangle: the triangle inside a tet of another body (or of its own body, with
/// self-contact), or inside an obstacle. The contact modules fill it in report(); it stays empty
/// without contact.
struct SurfaceContact {
  /// #tris x 3 [N]: force on the triangle's body through the triangle's pairs. Body-to-body
  /// contact is found from both sides, so each of two touching surfaces carries a share.
  Eigen::Matrix<double, Eigen::Dynamic, 3> force;
  /// #tris [N]: the magnitudes of the triangle's net force per body or obstacle it enters,
  /// summed (|force| where it enters one)
  VectorX magnitude;
  VectorX area;            ///< #tris [m^2]: area of the triangle inside what it penetrates
  VectorX depth_integral;  ///< #tris [m^3]: penetration depth integrated over that area

  bool empty() const { return area.size() == 0; }
  /// Sizes every array for `num_tris` triangles, all zero, unless they are sized already.
  void resize(Index num_tris) {
    if (area.size() == num_tris) return;
    force = Eigen::Matrix<double, Eigen::Dynamic, 3>::Zero(num_tris, 3);
    magnitude = area = depth_integral = VectorX::Zero(num_tris);
  }
};

/// Per-tet stress and strain of a configuration (arrays left empty when not computed). Symmetric
/// tensors are 6 components in the order xx, yy, zz, xy, yz, xz (VTK's and ParaView's).
struct ElementFields {
  Eigen::Matrix<double, Eigen::Dynamic, 6> stress;  ///< #tets x 6 Cauchy stress [Pa]
  VectorX von_mises;                                ///< #tets von Mises stress [Pa]
  Eigen::Matrix<double, Eigen::Dynamic, 6> strain;  ///< #tets x 6 logarithmic strain ln V [-]
  VectorX volume_ratio;                             ///< #tets J = det F [-]
  /// #tets x 6 Cauchy viscous stress of viscoelastic materials [Pa] (zero in elastic tets)
  Eigen::Matrix<double, Eigen::Dynamic, 6> viscous_stress;
};

/// One completed step.
struct StepRecord {
  Index index = 0;            ///< 0, 1, ... in the order completed
  double load = 0;            ///< load factor in (0, 1] (static) or time [s]
  bool settling = false;      ///< a quasi-viscous step at full load (static)
  int newton_iterations = 0;  ///< implicit: Newton steps; ARKODE: internal Runge-Kutta steps
  int linear_iterations = 0;  ///< summed over the Newton steps
  int linear_solves = 0;      ///< linear systems solved (one per Newton step)
  int factorizations = 0;     ///< of those, solved by a new LL^T factorisation
  /// Time steps taken over the record's interval: 1 for the fixed-step integrators and static
  /// steps, the accepted internal steps for ARKODE and CVODE.
  int time_steps = 1;
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
  /// Contact per boundary triangle (empty without material-depth or obstacle contact).
  SurfaceContact surface;
  /// Deepest geometric penetration [m] of the material-depth contact pairs (deepest_penetration;
  /// set by the scene runner), absent without material-depth contact.
  std::optional<double> penetration;
  /// Energy [J] the viscoelastic materials dissipated over the step, absent without them (or in
  /// a static analysis).
  std::optional<double> dissipated_energy;

  /// Total contact area [m^2] over all interfaces.
  double contact_area() const {
    double a = 0;
    for (const InterfaceForce& f : contact) a += f.area;
    return a;
  }
};

}  // namespace depthfem
