#include "apps/scene_model.hpp"

#include <cmath>

#include "contact/material_depth.hpp"
#include "contact/node_to_surface_contact.hpp"
#include "core/mass.hpp"
#include "integrators/forces/consistent_mass.hpp"
#include "integrators/forces/gravity.hpp"
#include "integrators/forces/stiffness_tether.hpp"

namespace depthfem {

LifecycleTerms SceneModel::lifecycle_terms() const {
  LifecycleTerms terms;
  if (quasi_viscosity) terms.excluded.push_back(quasi_viscosity);
  if (implicit.inertia) terms.excluded.push_back(implicit.inertia);
  for (const Tether* d : implicit.damping) terms.excluded.push_back(d);
  terms.mass = implicit.inertia ? implicit.inertia : mass_outside_system.get();
  return terms;
}

namespace {

// The tets of each group that this rank owns, with their fiber directions (a group may be left
// empty; it still validates its material).
std::vector<ElasticGroup> own_part(std::vector<ElasticGroup> groups, const Ranks& ranks) {
  for (ElasticGroup& g : groups) {
    std::vector<Index> rows;
    for (size_t k = 0; k < g.tets.size(); ++k)
      if (ranks.owns_tet(g.tets[k])) rows.push_back(static_cast<Index>(k));
    std::vector<Index> tets;
    for (const Index k : rows) tets.push_back(g.tets[static_cast<size_t>(k)]);
    if (g.fibers.rows() > 0) g.fibers = Points(g.fibers(rows, Eigen::all));
    g.tets = std::move(tets);
  }
  return groups;
}

}  // namespace

std::unique_ptr<SceneModel> build_model(const Scene& scene, PhaseTimers& timers, Ranks* ranks) {
  const Mesh& mesh = scene.mesh;
  auto model = std::make_unique<SceneModel>(mesh.num_nodes(), timers);
  System& system = model->system;
  system.distribute(ranks);
  model->elasticity =
      &system.add(std::make_unique<Elasticity>(
                      mesh.X, mesh.tets, ranks ? own_part(scene.groups, *ranks) : scene.groups,
                      scene.elasticity),
                  Share::kOwnPart);
  // Groups with the nodal-pressure or patch-volume formulation: their volume change taken on
  // patches of tets.
  if (auto volume = make_patch_volume(mesh.X, mesh.tets, scene.groups))
    model->patch_volume = &system.add(std::move(volume));
  model->lumped_mass = lumped_mass(mesh.X, mesh.tets, scene.tet_density);
  const VectorX& mass = model->lumped_mass;
  const bool time_dependent = scene.analysis != Analysis::kStatic;
  if (scene.gravity.norm() > 0) {
    const bool ramp = !time_dependent && scene.ramp_body_loads;
    system.add(std::make_unique<Gravity>(mass, scene.gravity, ramp));
  }
  // Time-dependent analyses: the implicit schemes carry inertia and damping as tethers.
  const DynamicOptions& dyn = scene.dynamic_options;
  if (time_dependent && is_implicit(dyn.integrator)) {
    ImplicitTerms& terms = model->implicit;
    // Inertia and mass damping with the lumped or the consistent mass matrix.
    const auto mass_tether = [&](const char* name, double factor) -> Tether* {
      if (dyn.mass == MassMatrix::kConsistent)
        return &system.add(
            std::make_unique<ConsistentMass>(name, mesh.X, mesh.tets, scene.tet_density, factor));
      return &system.add(std::make_unique<NodalSpring>(name, factor * mass));
    };
    if (scene.analysis == Analysis::kDynamic) terms.inertia = mass_tether("inertia", 1.0);
    if (scene.analysis == Analysis::kQuasistatic) {
      terms.damping.push_back(&system.add(std::make_unique<NodalSpring>(
          "viscosity", quasi_viscosity_stiffness(mesh.X, mesh.tets, scene.viscosity))));
    }
    if (dyn.damping.mass > 0)
      terms.damping.push_back(mass_tether("mass damping", dyn.damping.mass));
    if (dyn.damping.stiffness > 0) {
      // K(x^n) of this rank's tets, as the elasticity it is taken from.
      terms.damping.push_back(
          &system.add(std::make_unique<StiffnessTether>("stiffness damping", *model->elasticity,
                                                        dyn.damping.stiffness),
                      Share::kOwnPart));
    }
  }
  if (time_dependent && !model->implicit.inertia)
    model->mass_outside_system = std::make_unique<NodalSpring>("mass", mass);
  if (scene.quasi_viscosity > 0) {
    model->quasi_viscosity = &system.add(std::make_unique<NodalSpring>(
        "quasi-viscosity", quasi_viscosity_stiffness(mesh.X, mesh.tets, scene.quasi_viscosity)));
  }
  // Contact is built only when the scene asks for it.
  if (scene.contact == ContactModel::kMaterialDepth) {
    {
      PhaseTimers::Scope t(timers, "collision detection: material depth");
      model->depth = material_depth(mesh);
    }
    ContactPart part;
    if (ranks) {
      part.owned.resize(static_cast<size_t>(mesh.num_tets()));
      for (Index t = 0; t < mesh.num_tets(); ++t)
        part.owned[static_cast<size_t>(t)] = ranks->owns_tet(t);
      part.concatenate = [ranks](const std::vector<double>& mine) {
        return ranks->concatenate(mine);
      };
    }
    auto contact = std::make_unique<MaterialDepthContact>(mesh, model->depth, scene.contact_options,
                                                          std::move(part));
    model->contact = &system.add(std::move(contact), Share::kOwnPart);
  } else if (scene.contact == ContactModel::kNodeToSurface) {
    system.add(std::make_unique<NodeToSurfaceContact>(mesh, scene.contact_options.penalty));
  }
  if (!scene.obstacles.empty()) {
    std::vector<Index> deformable;
    for (size_t b = 0; b < mesh.bodies.size(); ++b)
      if (!mesh.bodies[b].rigid) deformable.push_back(static_cast<Index>(b));
    system.add(std::make_unique<ObstacleContact>(mesh, deformable, scene.obstacles));
  }
  model->constraints = Constraints(mesh.X, scene.constraints);
  model->static_options = scene.static_options;
  model->dynamic_options = scene.dynamic_options;
  return model;
}

}  // namespace depthfem
