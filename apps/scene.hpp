#pragma once
/// Scene files: JSON describing bodies, materials, boundary conditions and solver options,
/// mapped onto the option structs of the modules. Only apps/ knows the file format.

#include <string>
#include <vector>

#include "contact/material_depth_contact.hpp"
#include "contact/obstacle_contact.hpp"
#include "core/mesh.hpp"
#include "core/results_file.hpp"
#include "integrators/forces/constraints.hpp"
#include "integrators/forces/elasticity.hpp"
#include "integrators/solvers/dynamics.hpp"
#include "integrators/solvers/static_solver.hpp"

namespace depthfem {

/// What a scene solves for.
enum class Analysis {
  kStatic,       ///< equilibrium under a load ramped from 0 to 1
  kDynamic,      ///< motion with inertia, by any integrator
  kQuasistatic,  ///< viscous flow without inertia, by implicit Euler
};

/// The scene file's name of an analysis: "static", "dynamic" or "quasistatic".
const char* to_string(Analysis analysis);

/// Which contact model a scene uses between (and within) its bodies.
enum class ContactModel { kNone, kMaterialDepth, kNodeToSurface };

/// Everything a run needs, read and validated from a scene file.

struct Scene {
  std::string name;
  std::string file;                 ///< path it was read from
  std::vector<std::string> inputs;  ///< every file the scene reads (itself, mesh files)
  std::string json_text;  ///< the (possibly overridden) scene as JSON, stored in the results
  Analysis analysis = Analysis::kStatic;
  Mesh mesh;
  std::vector<ElasticGroup> groups;  ///< one per deformable body
  ElasticityOptions elasticity;      ///< solver key hessian_projection
  VectorX tet_density;               ///< [kg/m^3] per tet
  Vec3 gravity = Vec3::Zero();       ///< [m/s^2]
  std::vector<Constraint> constraints;
  ContactModel contact = ContactModel::kNone;
  ContactOptions contact_options;
  bool list_margin_given = false;  ///< the contact key list_margin (the solver preset keeps it)
  std::vector<Obstacle> obstacles;
  std::string solver_preset;       ///< the solver key "preset" ("paper"), or empty
  double quasi_viscosity = 0;      ///< [Pa]; 0: off
  double tolerance = 1e-9;         ///< relative Newton tolerance (see scene docs)
  bool ramp_body_loads = true;     ///< static analysis: gravity scales with the load factor
  StaticOptions static_options;    ///< with the scene's Newton test (set by load_scene)
  DynamicOptions dynamic_options;  ///< analyses "dynamic" and "quasistatic"; the same Newton test
  double viscosity = 0;            ///< [Pa s] of a quasistatic analysis
  Points initial_velocity;         ///< #nodes x 3 [m/s]
  /// The "output" section: which fields the results file writes per step. `contact` asks for the
  /// contact fields where the scene has material-depth or obstacle contact; `velocity` is not a
  /// key (time-dependent analyses write velocities).
  ResultFields output{.contact = true};
  /// The "output" key `every`: the results file takes every N-th completed step and the last.
  int output_every = 1;
};

/// A `--set path=value` override: path segments separated by '.', array indices as numbers,
/// value parsed as JSON (a bare word is taken as a string).
struct Override {
  std::string path, value;
};

/// Reads, overrides and validates a scene. Throws InputError naming the file and key path.
Scene load_scene(const std::string& path, const std::vector<Override>& overrides = {});

/// Parses "path=value". Throws InputError for text without '='.
Override parse_override(const std::string& text);

}  // namespace depthfem
