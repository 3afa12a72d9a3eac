#pragma once
/// The force modules, constraints and solver settings of a scene: everything a driver needs,
/// assembled once from the Scene, with typed handles to the modules a driver sets per step.

#include <memory>

#include "apps/scene.hpp"
#include "contact/material_depth_contact.hpp"
#include "integrators/forces/patch_volume.hpp"
#include "integrators/solvers/implicit_stepper.hpp"
#include "integrators/solvers/ranks.hpp"
#include "integrators/solvers/step_lifecycle.hpp"

namespace depthfem {

/// A scene turned into a System of force modules. Build it with build_model(); it is not
/// copyable (the System owns the modules, the handles point into it).
struct SceneModel {
  SceneModel(Index num_nodes, PhaseTimers& timers) : system(num_nodes, timers) {}

  System system;
  Constraints constraints;
  VectorX lumped_mass;  ///< per node [kg]
  VectorX depth;        ///< material depth per node [m]; empty without material-depth contact
  Elasticity* elasticity = nullptr;               ///< a restart restores its viscoelastic history
  const PatchVolume* patch_volume = nullptr;      ///< with nodal-pressure or patch-volume groups
  const MaterialDepthContact* contact = nullptr;  ///< material-depth contact, when on
  NodalSpring* quasi_viscosity = nullptr;         ///< static analysis with quasi_viscosity > 0
  ImplicitTerms implicit;                         ///< inertia and damping of the implicit schemes
  /// K = M for the kinetic energy of time-dependent runs: the inertia module when the scheme
  /// has one, else this lumped mass (not part of the System).
  std::unique_ptr<NodalSpring> mass_outside_system;
  StaticOptions static_options;    ///< with the Newton tolerance of the scene
  DynamicOptions dynamic_options;  ///< with the Newton tolerance of the scene

  /// Which modules the lifecycle leaves out of the reported energy, and the mass matrix.
  LifecycleTerms lifecycle_terms() const;
};

/// Builds the modules `scene` asks for (and nothing else). Material depth is computed here
/// (timed as collision detection). Throws InputError for inconsistent input. With `ranks`
/// (partitioned), a distributed model: elasticity and material-depth contact evaluate this
/// rank's tets and their pairs, every other module is evaluated whole by rank 0 (System, Share).
std::unique_ptr<SceneModel> build_model(const Scene& scene, PhaseTimers& timers,
                                        Ranks* ranks = nullptr);

}  // namespace depthfem
