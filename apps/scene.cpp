#include "apps/scene.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>

#include "apps/json_reader.hpp"
#include "core/error.hpp"
#include "core/mass.hpp"
#include "core/mesh_file.hpp"
#include "core/mesh_generators.hpp"
#include "core/mesh_regions.hpp"
#include "core/node_sets.hpp"
#include "core/overlap_check.hpp"
#include "core/results_file.hpp"
#include "integrators/solvers/residual_scale.hpp"

namespace depthfem {

namespace {

// The values the paper leaves open in its solver preset, chosen by the study on the knee's first
// degrees (bench/results/knee_paper.md).
constexpr int kPaperGmresRestart = 200;
constexpr int kPaperLinearMaxIterations = 1000;
constexpr double kPaperQuasiViscosity = 300;  // [Pa]

using nlohmann::json;

// A number in a message ("1e+300", "inf").
std::string number_text(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}

// A body's mesh as the scene describes it, checked but not yet generated or read.
struct MeshSpec {
  std::variant<std::string, BoxParams, TubeParams, BallParams, CornerParams> source;  // file path
  std::vector<std::string> regions;  // of a file: the element regions to keep (empty: all)
  double scale = 1;
  Vec3 translate = Vec3::Zero();
};

// Reads and checks a "mesh" object; adds the generated counts to `counts` (files count when read).
MeshSpec read_mesh_spec(JsonObject m, const std::string& scene_dir, MeshCounts& counts) {
  MeshSpec spec;
  const auto checked = [&](auto params) {
    try {
      const MeshCounts c = checked_counts(params);
      counts.nodes += c.nodes;
      counts.tets += c.tets;
    } catch (const ParameterError& e) {
      m.fail(e.parameter(), e.reason());
    }
    spec.source = params;
  };
  if (m.has("file")) {
    std::filesystem::path p = m.string("file");
    if (p.is_relative()) p = std::filesystem::path(scene_dir) / p;
    spec.source = p.string();
    if (m.has("regions")) spec.regions = m.strings("regions");
    spec.scale = m.number("scale", 1.0);
    if (!(spec.scale > 0)) m.fail("scale", "must be > 0");
  } else {
    const std::string gen = m.string("generator");
    if (gen == "box") {
      checked(
          BoxParams{m.vec3("lo"), m.vec3("hi"), m.int3("cells"), m.vec3("ratio", Vec3::Ones())});
    } else if (gen == "tube") {
      checked(TubeParams{m.number("inner_radius"), m.number("outer_radius"), m.number("length"),
                         m.integer("cells_through_wall"), m.integer("cells_around"),
                         m.integer("cells_along")});
    } else if (gen == "corner") {
      checked(CornerParams{m.number("size"), m.number("core"), m.integer("core_cells"),
                           m.number("ratio")});
    } else if (gen == "ball") {
      checked(BallParams{m.vec3("center", Vec3::Zero()), m.number("radius"),
                         m.integer("cells_per_axis")});
    } else {
      m.fail("generator", "unknown generator '" + gen + "' (expected box, tube, ball or corner)");
    }
  }
  spec.translate = m.vec3("translate", Vec3::Zero());
  m.finish();
  return spec;
}

// Generates or reads the mesh of a checked spec (of a file: the regions asked for, with the
// file's regions and node sets); every error names the scene key `m` too.
LoadedMesh make_mesh(const MeshSpec& spec, const JsonObject& m) {
  try {
    LoadedMesh loaded = std::visit(
        [&](const auto& source) -> LoadedMesh {
          using S = std::decay_t<decltype(source)>;
          LoadedMesh out;
          if constexpr (std::is_same_v<S, std::string>) {
            out = read_tet_mesh(source);
            if (spec.regions.empty()) {
              // The whole file as one body; without regions the reader has checked it.
              if (!out.region_names.empty()) check_no_overlap(out.mesh, out.source, out.neighbours);
              return out;
            }
            try {
              return select_regions(out, spec.regions);
            } catch (const InputError& e) {
              m.fail("regions", source + ": " + e.what());
            }
          } else if constexpr (std::is_same_v<S, BoxParams>) {
            out.mesh = box_mesh(source);
          } else if constexpr (std::is_same_v<S, TubeParams>) {
            out.mesh = tube_mesh(source);
          } else if constexpr (std::is_same_v<S, BallParams>) {
            out.mesh = ball_mesh(source);
          } else {
            out.mesh = corner_mesh(source);
          }
          return out;
        },
        spec.source);
    TetMesh& mesh = loaded.mesh;
    if (spec.scale != 1 || spec.translate != Vec3::Zero()) {
      // Scaling or moving far can underflow or overflow coordinates: check the mesh again.
      mesh.X *= spec.scale;
      mesh.X.rowwise() += spec.translate.transpose();
      MeshSource moved = loaded.source;
      moved.file = "the scaled and translated mesh" +
                   (std::holds_alternative<std::string>(spec.source) ? " of " + moved.file : "");
      validate_and_orient(mesh, moved);
    }
    return loaded;
  } catch (const InputError& e) {
    m.fail("", e.what());
  }
}

// A material's "viscoelastic" section: a Prony series on its isochoric stress.
PronySeries read_viscoelastic(JsonObject v) {
  PronySeries p;
  p.times = v.numbers("relaxation_times");
  p.weights = v.numbers("weights");
  p.static_relaxed = v.choice("static_modulus", "static modulus",
                              {std::pair{"equilibrium", true}, std::pair{"instantaneous", false}});
  if (const std::optional<PronySeries::Problem> problem = p.problem())
    v.fail(problem->key, problem->why);
  v.finish();
  return p;
}

// A body's materials: one for the whole body (region empty) or one per element region.
struct BodyMaterial {
  std::string region;
  MaterialModel model;
  Vec3 fiber = Vec3::UnitX();
  VolumeFormulation formulation = VolumeFormulation::kStandard;
  int patch_size = 6;        // tets per patch of the patch-volume formulation
  PronySeries viscoelastic;  // empty: elastic
  std::string path;          // the scene key, for messages
};

// Material parameters by model name (the keys are those of the model's struct), with the
// formulation and the relaxation, into `into` (its region and path are the caller's).
void read_material(JsonObject m, BodyMaterial& into) {
  const std::string model = m.string("model");
  // Every model has an isochoric part (materials/isochoric.hpp) and a small-strain bulk
  // modulus, so every model takes every formulation.
  VolumeFormulation& formulation = into.formulation;
  formulation = m.choice<VolumeFormulation>("formulation", "formulation",
                                            {{"standard", VolumeFormulation::kStandard},
                                             {"nodal_pressure", VolumeFormulation::kNodalPressure},
                                             {"patch_volume", VolumeFormulation::kPatchVolume}});
  if (formulation == VolumeFormulation::kPatchVolume) {
    into.patch_size = m.integer("patch_size", into.patch_size);
    if (into.patch_size < 1) m.fail("patch_size", "must be >= 1 (tets per patch)");
  } else if (m.has("patch_size")) {
    m.fail("patch_size", "needs \"formulation\": \"patch_volume\"");
  }
  MaterialModel out;
  // Young's modulus and Poisson's ratio are converted by the model; range errors are reported
  // at the key they concern.
  const auto elastic_constants = [&](auto convert) {
    const double E = m.number("youngs"), nu = m.number("poisson");
    if (!(nu > -1 && nu < 0.5)) m.fail("poisson", "Poisson's ratio must be in (-1, 0.5)");
    try {
      return convert(E, nu);
    } catch (const std::invalid_argument& e) {
      m.fail("youngs", e.what());
    }
  };
  const auto mooney = [&] {
    if (!m.has("youngs")) return MooneyRivlin{m.number("C1"), m.number("C2"), m.number("a")};
    const double C2 = m.number("C2", 0.0);
    return elastic_constants(
        [&](double E, double nu) { return MooneyRivlin::from_youngs(E, nu, C2); });
  };
  const auto veronda = [&] { return Veronda{m.number("alpha"), m.number("beta"), m.number("a")}; };
  if (model == "neo_hookean") {
    out = m.has("youngs") ? elastic_constants(NeoHookean::from_youngs)
                          : NeoHookean{m.number("mu"), m.number("lambda")};
  } else if (model == "mooney_rivlin") {
    out = mooney();
  } else if (model == "veronda") {
    out = veronda();
  } else if (model == "nearly_incompressible_mooney_rivlin") {
    out = NearlyIncompressibleMooneyRivlin{m.number("C1"), m.number("C2"), m.number("kappa")};
  } else if (model == "fiber_mooney_rivlin") {
    out = FiberReinforced<MooneyRivlin>{mooney(), m.number("fiber_alpha"), m.number("fiber_beta")};
  } else if (model == "fiber_veronda") {
    out = FiberReinforced<Veronda>{veronda(), m.number("fiber_alpha"), m.number("fiber_beta")};
  } else {
    m.fail(
        "model",
        "unknown material model '" + model +
            "' (expected neo_hookean, mooney_rivlin, veronda, nearly_incompressible_mooney_rivlin, "
            "fiber_mooney_rivlin or fiber_veronda)");
  }
  if (material_uses_fiber(out)) into.fiber = m.vec3("fiber_direction");
  if (m.has("viscoelastic")) {
    // Relaxation on nodal-pressure or patch-volume tets (isochoric part per tet, volume per patch)
    // is not verified by any test, so the combination is refused rather than run unchecked.
    if (formulation != VolumeFormulation::kStandard)
      m.fail("viscoelastic", "needs \"formulation\": \"standard\"");
    into.viscoelastic = read_viscoelastic(m.object("viscoelastic"));
  }
  try {
    validate_material(out);
  } catch (const std::invalid_argument& e) {
    m.fail("model", e.what());
  }
  const LinearizedModuli moduli = material_moduli(out);
  if (!std::isfinite(moduli.mu) || !std::isfinite(moduli.bulk())) {
    m.fail("model", "the parameters give non-finite moduli (shear " + number_text(moduli.mu) +
                        " Pa, bulk " + number_text(moduli.bulk()) + " Pa)");
  }
  m.finish();
  into.model = out;
  into.path = m.path();
}

// Reads "material" (one for the whole body) or "materials" ({region: material}); the region
// names are checked against the mesh once it is read (region_materials_checked).
std::vector<BodyMaterial> read_body_materials(JsonObject& b) {
  std::vector<BodyMaterial> out;
  if (!b.has("materials")) {
    const JsonObject m = b.object("material");
    read_material(m, out.emplace_back());
    return out;
  }
  if (b.has("material")) b.fail("materials", "give either material or materials, not both");
  JsonObject ms = b.object("materials");
  for (const std::string& region : ms.keys()) {
    const JsonObject m = ms.object(region);
    BodyMaterial& one = out.emplace_back();
    one.region = region;
    read_material(m, one);
  }
  if (out.empty()) b.fail("materials", "names no region");
  ms.finish();
  return out;
}

// The body's materials in the order of the mesh's regions (one for the whole body as given):
// every region of the mesh needs one, and every material a region of the mesh.
std::vector<BodyMaterial> region_materials_checked(const std::vector<BodyMaterial>& materials,
                                                   const LoadedMesh& loaded, const JsonObject& b) {
  if (materials.size() == 1 && materials[0].region.empty()) return materials;
  if (loaded.region_names.empty())
    b.fail("materials", "the body's mesh has no regions (physical volumes); use material");
  std::string known;
  for (const std::string& r : loaded.region_names) known += (known.empty() ? "'" : ", '") + r + "'";
  for (const BodyMaterial& m : materials)
    if (std::ranges::find(loaded.region_names, m.region) == loaded.region_names.end())
      b.fail("materials." + m.region,
             "the body has no region '" + m.region + "' (its regions: " + known + ")");
  std::vector<BodyMaterial> ordered;
  for (const std::string& r : loaded.region_names) {
    const auto it = std::ranges::find(materials, r, &BodyMaterial::region);
    if (it == materials.end())
      b.fail("materials." + r, "missing material for this region of the body");
    ordered.push_back(*it);
  }
  return ordered;
}

// A node set as the scene describes it; the nodes are selected once the meshes exist.
struct NodeSetSpec {
  struct SetName {
    std::string name;
  };
  JsonObject where;
  // box (lo, hi), plane (normal, offset), list, a node set of the mesh files; none: "body" alone
  std::variant<std::monostate, std::pair<Vec3, Vec3>, std::pair<Vec3, double>, std::vector<Index>,
               SetName>
      selector;
  std::string body;  // the whole body alone, or the body the selection is restricted to
  double tolerance = 1e-9;
};

NodeSetSpec read_node_set(JsonObject s) {
  NodeSetSpec spec{s, {}, {}, s.number("tolerance", 1e-9)};
  if (!(spec.tolerance >= 0)) s.fail("tolerance", "must be >= 0");
  int kinds = 0;
  if (s.has("box")) {
    JsonObject b = s.object("box");
    spec.selector = std::pair{b.vec3("lo"), b.vec3("hi")};
    b.finish();
    ++kinds;
  }
  if (s.has("plane")) {
    JsonObject p = s.object("plane");
    const Vec3 normal = p.vec3("normal");
    if (!(normal.norm() > 0)) p.fail("normal", "must be a non-zero vector");
    spec.selector = std::pair{normal, p.number("offset", 0.0)};
    p.finish();
    ++kinds;
  }
  if (s.has("list")) {
    spec.selector = s.indices("list");
    ++kinds;
  }
  if (s.has("set")) {
    spec.selector = NodeSetSpec::SetName{s.string("set")};
    ++kinds;
  }
  if (s.has("body")) spec.body = s.string("body");
  if (kinds > 1 || (kinds == 0 && spec.body.empty()))
    s.fail("",
           "give exactly one of box, plane, list, set or body (set and the others may be "
           "restricted to a body)");
  s.finish();
  return spec;
}

std::vector<Index> select_nodes(const NodeSetSpec& spec, const Mesh& mesh) {
  const JsonObject& s = spec.where;
  std::vector<Index> nodes;
  if (const auto* box = std::get_if<std::pair<Vec3, Vec3>>(&spec.selector)) {
    nodes = nodes_in_box(mesh.X, box->first, box->second, spec.tolerance);
  } else if (const auto* plane = std::get_if<std::pair<Vec3, double>>(&spec.selector)) {
    nodes = nodes_on_plane(mesh.X, plane->first, plane->second, spec.tolerance);
  } else if (const auto* list = std::get_if<std::vector<Index>>(&spec.selector)) {
    for (const Index i : *list)
      if (i >= mesh.num_nodes())
        s.fail("list", "node " + std::to_string(i) + " is outside 0.." +
                           std::to_string(mesh.num_nodes() - 1));
    nodes = *list;
  } else if (const auto* set = std::get_if<NodeSetSpec::SetName>(&spec.selector)) {
    const auto& sets = mesh.node_sets;
    const std::string& name = set->name;
    const auto it = sets.find(name);
    if (it == sets.end()) {
      std::string known;
      for (const auto& [n, set] : sets) known += (known.empty() ? "'" : ", '") + n + "'";
      s.fail("set", "no node set '" + name + "' (the meshes have " +
                        (known.empty() ? std::string("none") : known) + ")");
    }
    nodes = it->second;
  }
  // "body" alone selects the whole body; with another selector it keeps that selection's nodes
  // in the body.
  if (!spec.body.empty()) {
    Index id = -1;
    for (size_t b = 0; b < mesh.bodies.size(); ++b)
      if (mesh.bodies[b].name == spec.body) id = static_cast<Index>(b);
    if (id < 0) s.fail("body", "no body named '" + spec.body + "'");
    const Body& body = mesh.bodies[id];
    if (std::holds_alternative<std::monostate>(spec.selector)) {
      nodes = nodes_of_body(mesh, id);
    } else {
      std::erase_if(nodes, [&](Index i) {
        return i < body.first_node || i >= body.first_node + body.num_nodes;
      });
    }
  }
  if (nodes.empty()) s.fail("", "selects no nodes");
  return nodes;
}

// A boundary condition whose nodes are selected once the meshes exist.
struct ConstraintSpec {
  Constraint constraint;  // without nodes
  NodeSetSpec nodes;
};

// Reads a non-zero direction (an axis, a normal).
Vec3 direction(JsonObject& c, const std::string& key) {
  const Vec3 v = c.vec3(key);
  if (!(v.norm() > 0)) c.fail(key, "must be a non-zero vector");
  return v;
}

ConstraintSpec read_constraint(JsonObject c, size_t index) {
  Constraint out;
  const std::string type = c.string("type");
  out.name = c.string("name", type + "_" + std::to_string(index));
  NodeSetSpec nodes = read_node_set(c.object("nodes"));
  if (type == "fixed") {
    out.kind = Fixed{};
  } else if (type == "displaced") {
    out.kind = Displaced{c.vec3("displacement")};
  } else if (type == "rotated") {
    out.kind = Rotated{direction(c, "axis"), c.vec3("center"),
                       c.number("angle_deg") * std::numbers::pi / 180,
                       c.vec3("translation", Vec3::Zero())};
  } else if (type == "plane") {
    out.kind = InPlane{direction(c, "normal"), c.number("offset", 0.0)};
  } else if (type == "line") {
    out.kind = OnLine{direction(c, "direction")};
  } else {
    c.fail("type", "unknown boundary condition '" + type +
                       "' (expected fixed, displaced, rotated, plane or line)");
  }
  c.finish();
  return {out, nodes};
}

// "exclude": interface names as the results file's /run/contact_names gives them.
std::vector<std::array<Index, 2>> read_excluded(JsonObject& c,
                                                const std::vector<std::string>& bodies,
                                                bool self_contact) {
  std::vector<std::pair<std::string, std::array<Index, 2>>> known;
  std::string list;
  for (Index a = 0; a < static_cast<Index>(bodies.size()); ++a)
    for (Index b = a; b < static_cast<Index>(bodies.size()); ++b)
      if (a != b || self_contact) {
        known.push_back({interface_name(bodies[a], bodies[b]), {a, b}});
        list += (list.empty() ? "" : ", ") + known.back().first;
      }
  std::vector<std::array<Index, 2>> excluded;
  for (const std::string& name : c.strings("exclude")) {
    const auto it = std::ranges::find(known, name, [](const auto& k) { return k.first; });
    if (it == known.end())
      c.fail("exclude", "unknown interface '" + name + "' (the scene's: " + list + ")");
    excluded.push_back(it->second);
  }
  return excluded;
}

void read_contact(JsonObject c, Scene& scene, const std::vector<std::string>& bodies) {
  scene.contact = c.choice<ContactModel>("model", "contact model",
                                         {{"material_depth", ContactModel::kMaterialDepth},
                                          {"node_to_surface", ContactModel::kNodeToSurface}});
  scene.contact_options.penalty = c.number("penalty");
  scene.contact_options.self_contact = c.boolean("self_contact", true);
  if (!(scene.contact_options.penalty > 0)) c.fail("penalty", "must be > 0");
  if (c.has("exclude")) {
    if (scene.contact != ContactModel::kMaterialDepth)
      c.fail("exclude", "only for the material_depth model");
    scene.contact_options.excluded = read_excluded(c, bodies, scene.contact_options.self_contact);
  }
  if (c.has("list_margin")) {
    if (scene.contact != ContactModel::kMaterialDepth)
      c.fail("list_margin", "only for the material_depth model");
    scene.contact_options.list_margin = c.number("list_margin");
    if (!(scene.contact_options.list_margin >= 0 && scene.contact_options.list_margin <= 10))
      c.fail("list_margin", "must be between 0 and 10 mean edge lengths");
    scene.list_margin_given = true;
  }
  c.finish();
}

Obstacle read_obstacle(JsonObject o, size_t index) {
  Obstacle out;
  const std::string type = o.string("type");
  out.name = o.string("name", type + "_" + std::to_string(index));
  if (type == "plane") {
    out.shape = PlaneObstacle{o.vec3("point"), o.vec3("normal")};
    if (!(std::get<PlaneObstacle>(out.shape).normal.norm() > 0))
      o.fail("normal", "must be a non-zero vector");
  } else if (type == "sphere") {
    out.shape = SphereObstacle{o.vec3("center"), o.number("radius")};
    if (!(std::get<SphereObstacle>(out.shape).radius > 0)) o.fail("radius", "must be > 0");
  } else {
    o.fail("type", "unknown obstacle '" + type + "' (expected plane or sphere)");
  }
  out.motion = o.vec3("motion", Vec3::Zero());
  out.penalty = o.number("penalty");
  if (!(out.penalty > 0)) o.fail("penalty", "must be > 0");
  o.finish();
  return out;
}

// The options of one integrator ("newmark": {...}, "arkode": {...}), keyed by its name or by
// its package's (`users`: the integrators that read it, for the message); an error when the
// scene chose another integrator.
std::optional<JsonObject> integrator_section(JsonObject& d, const char* key, bool chosen,
                                             const char* users = nullptr) {
  if (!d.has(key)) return std::nullopt;
  if (!chosen) {
    d.fail(key, std::string("only for \"integrator\": ") +
                    (users ? users : "\"" + std::string(key) + "\""));
  }
  return d.object(key);
}

// The error control of a SUNDIALS section ("arkode", "cvode"), then the end of the section.
void read_error_control(JsonObject& s, ErrorControl& c) {
  c.relative_tolerance = s.number("relative_tolerance", c.relative_tolerance);
  c.absolute_tolerance = s.number("absolute_tolerance", c.absolute_tolerance);
  c.max_steps = s.integer("max_steps", static_cast<int>(c.max_steps));
  if (!(c.relative_tolerance > 0)) s.fail("relative_tolerance", "must be > 0");
  if (!(c.absolute_tolerance > 0)) s.fail("absolute_tolerance", "must be > 0");
  if (!(c.max_steps > 0)) s.fail("max_steps", "must be > 0");
  s.finish();
}

void read_dynamic(JsonObject d, Scene& scene) {
  DynamicOptions& o = scene.dynamic_options;
  o.integrator = d.choice<Integrator>("integrator", "integrator",
                                      {{"implicit_euler", Integrator::kImplicitEuler},
                                       {"newmark", Integrator::kNewmark},
                                       {"generalized_alpha", Integrator::kGeneralizedAlpha},
                                       {"symplectic_euler", Integrator::kSymplecticEuler},
                                       {"arkode", Integrator::kArkode},
                                       {"arkode_dirk", Integrator::kArkodeDirk},
                                       {"cvode_bdf", Integrator::kCvodeBdf}});
  o.time_step = d.number("time_step");
  o.duration = d.number("duration");
  if (!(o.time_step > 0)) d.fail("time_step", "must be > 0");
  if (!(o.duration >= o.time_step)) d.fail("duration", "must be >= time_step");
  scene.elasticity.duration = o.duration;  // viscoelastic groups: time = load * duration
  const double steps = std::ceil(o.duration / o.time_step - 1e-9);
  if (!(steps <= kMaxSteps)) {
    d.fail("time_step", "duration / time_step asks for " + number_text(steps) +
                            " steps, more than the " + std::to_string(kMaxSteps) +
                            " a results file holds");
  }
  const bool explicit_scheme =
      o.integrator == Integrator::kSymplecticEuler || o.integrator == Integrator::kArkode;
  if (scene.analysis == Analysis::kQuasistatic) {
    // Viscous flow without inertia: only implicit Euler, and the viscosity is what resists motion.
    if (o.integrator != Integrator::kImplicitEuler)
      d.fail("integrator", "a quasistatic analysis uses implicit_euler");
    scene.viscosity = d.number("viscosity");
    if (!(scene.viscosity > 0)) d.fail("viscosity", "must be > 0");
  }
  o.mass = d.choice<MassMatrix>(
      "mass", "mass matrix",
      {{"lumped", MassMatrix::kLumped}, {"consistent", MassMatrix::kConsistent}});
  if (o.mass == MassMatrix::kConsistent && explicit_scheme)
    d.fail("mass", "a consistent mass matrix needs an implicit integrator");
  if (o.mass == MassMatrix::kConsistent &&
      (o.integrator == Integrator::kArkodeDirk || o.integrator == Integrator::kCvodeBdf)) {
    d.fail("mass",
           std::string(o.integrator == Integrator::kCvodeBdf ? "cvode_bdf" : "arkode_dirk") +
               " takes the lumped mass matrix");
  }
  if (std::optional<JsonObject> section =
          integrator_section(d, "newmark", o.integrator == Integrator::kNewmark)) {
    JsonObject& n = *section;
    o.newmark.beta = n.number("beta", o.newmark.beta);
    o.newmark.gamma = n.number("gamma", o.newmark.gamma);
    if (!(o.newmark.beta > 0 && o.newmark.beta <= 0.5)) n.fail("beta", "must be in (0, 0.5]");
    if (!(o.newmark.gamma >= 0.5 && o.newmark.gamma <= 1)) n.fail("gamma", "must be in [0.5, 1]");
    n.finish();
  }
  if (std::optional<JsonObject> section = integrator_section(
          d, "generalized_alpha", o.integrator == Integrator::kGeneralizedAlpha)) {
    JsonObject& g = *section;
    o.generalized_alpha.rho_inf = g.number("rho_inf", o.generalized_alpha.rho_inf);
    if (!(o.generalized_alpha.rho_inf >= 0 && o.generalized_alpha.rho_inf <= 1))
      g.fail("rho_inf", "must be in [0, 1]");
    g.finish();
  }
  if (d.has("damping")) {
    JsonObject c = d.object("damping");
    o.damping.mass = c.number("mass", 0.0);
    o.damping.stiffness = c.number("stiffness", 0.0);
    if (!(o.damping.mass >= 0)) c.fail("mass", "must be >= 0");
    if (!(o.damping.stiffness >= 0)) c.fail("stiffness", "must be >= 0");
    if (o.damping.stiffness > 0 && explicit_scheme)
      c.fail("stiffness", "needs an implicit integrator");
    c.finish();
  }
  if (std::optional<JsonObject> section = integrator_section(
          d, "arkode",
          o.integrator == Integrator::kArkode || o.integrator == Integrator::kArkodeDirk,
          "\"arkode\" or \"arkode_dirk\"")) {
    JsonObject& a = *section;
    o.arkode.order = a.integer("order", o.arkode.order);
    o.arkode.fixed_step = a.boolean("fixed_step", o.arkode.fixed_step);
    if (o.integrator == Integrator::kArkode && !has_erk_table(o.arkode.order))
      a.fail("order", "must be 2, 3, 4, 5, 6 or 8");
    if (o.integrator == Integrator::kArkodeDirk && !has_dirk_table(o.arkode.order))
      a.fail("order", "must be 2, 3, 4 or 5 for arkode_dirk");
    read_error_control(a, o.arkode);
  }
  if (std::optional<JsonObject> section =
          integrator_section(d, "cvode", o.integrator == Integrator::kCvodeBdf, "\"cvode_bdf\"")) {
    JsonObject& c = *section;
    o.cvode.max_order = c.integer("max_order", o.cvode.max_order);
    if (!(o.cvode.max_order >= 1 && o.cvode.max_order <= 5)) c.fail("max_order", "must be 1 to 5");
    read_error_control(c, o.cvode);
  }
  d.finish();
}

// The solver preset "paper": the algorithm of Hirota et al.'s sections 3.2 and 5.5, each setting
// with the sentence it implements (apps/README.md, "Solver presets"). Keys given beside the
// preset override it. Where the paper gives no value (restart, iteration cap, viscosity
// constant) the value is the one measured on the knee (bench/results/knee_paper.md).
void apply_paper_preset(Scene& scene) {
  StaticOptions& o = scene.static_options;
  LinearSolverOptions& lin = o.newton.linear;
  // 3.2.3: "an implementation of the Generalized Minimum Residual method (GMRES) with diagonal
  // preconditioning [33] is both efficient and stable."
  lin.kind = LinearSolverKind::kGmres;
  // 3.2.3: "The iteration is terminated when either the residual reduces to one tenth or a
  // predetermined iteration limit is reached." The limit and the restart: measured.
  lin.tolerance = 0.1;
  lin.max_iterations = kPaperLinearMaxIterations;
  lin.restart = kPaperGmresRestart;
  // 3.2.2: "Our method checks if the full Newton step is legal and if the residual decreases.
  // If both of these are true, the step is taken. If not, the step size is halved until the two
  // conditions are satisfied." No fallback direction is named.
  o.newton.line_search = LineSearchRule::kResidual;
  o.newton.full_step_first = true;
  o.newton.gradient_fallback = false;
  // 3.2.2: "After the second step, the initial guess is computed by extrapolating the previous
  // two solutions (two-point predictor)."
  o.predictor = true;
  // 3.2.2: "constrained components must be gradually incremented, and as soon as an illegal
  // configuration is detected, the step size must be reduced (adaptive incremental loading)."
  o.linearised_start = false;
  // 3.2.3: "Each node is assigned a "viscosity" proportional to the sizes of the surrounding
  // elements." The constant: measured.
  scene.quasi_viscosity = kPaperQuasiViscosity;
  // 5.5: "the tree structure is built only once at the beginning of each run. The interval
  // values are efficiently updated in a bottom-up manner at every solution step." A run being
  // one load increment (the paper's knee: one 3-degree interval), MaterialDepthContact::begin_step
  // builds the trees; without depthfem's candidate list, prepare refits and searches them at
  // every solution step.
  if (!scene.list_margin_given) scene.contact_options.list_margin = 0;
}

void read_solver(JsonObject s, Scene& scene) {
  StaticOptions& o = scene.static_options;
  if (s.has("preset")) {
    s.choice<bool>("preset", "solver preset", {{"paper", true}});
    scene.solver_preset = "paper";
    apply_paper_preset(scene);
  }
  if (s.has("linear_solver"))
    o.newton.linear.kind = s.choice<LinearSolverKind>("linear_solver", "linear solver",
                                                      {{"auto", LinearSolverKind::kAuto},
                                                       {"direct", LinearSolverKind::kDirect},
                                                       {"amg", LinearSolverKind::kAmg},
                                                       {"gmres", LinearSolverKind::kGmres},
                                                       {"cg", LinearSolverKind::kCg}});
  // One tolerance and cap for every iterative method; unset, each keeps its own default.
  LinearSolverOptions& lin = o.newton.linear;
  if (s.has("direct_precision"))
    lin.direct.precision = s.choice<FactorPrecision>(
        "direct_precision", "factor precision",
        {{"double", FactorPrecision::kDouble}, {"single", FactorPrecision::kSingle}});
  lin.restart = s.integer("gmres_restart", lin.restart);
  lin.auto_flops_per_entry = s.number("auto_flops_per_entry", lin.auto_flops_per_entry);
  if (s.has("linear_tolerance"))
    lin.tolerance = lin.amg.tolerance = s.number("linear_tolerance", lin.tolerance);
  if (s.has("linear_max_iterations"))
    lin.max_iterations = lin.amg.max_iterations =
        s.integer("linear_max_iterations", lin.max_iterations);
  o.newton.max_iterations = s.integer("max_newton_iterations", o.newton.max_iterations);
  o.newton.max_line_search = s.integer("max_line_search", o.newton.max_line_search);
  o.newton.forcing_max = s.number("forcing_max", o.newton.forcing_max);
  if (s.has("line_search"))
    o.newton.line_search = s.choice<LineSearchRule>(
        "line_search", "rule",
        {{"energy", LineSearchRule::kEnergy}, {"residual", LineSearchRule::kResidual}});
  if (s.has("line_search_start"))
    o.newton.full_step_first = s.choice<bool>("line_search_start", "line search start",
                                              {{"legal", false}, {"full", true}});
  o.newton.gradient_fallback = s.boolean("gradient_fallback", o.newton.gradient_fallback);
  o.linearised_start = s.boolean("linearised_start", o.linearised_start);
  o.initial_increment = s.number("initial_increment", o.initial_increment);
  o.min_increment = s.number("min_increment", o.min_increment);
  o.max_increment = s.number("max_increment", o.max_increment);
  o.predictor = s.boolean("predictor", o.predictor);
  o.max_settle_steps = s.integer("max_settle_steps", o.max_settle_steps);
  scene.quasi_viscosity = s.number("quasi_viscosity", scene.quasi_viscosity);
  scene.elasticity.project_hessian =
      s.boolean("hessian_projection", scene.elasticity.project_hessian);
  scene.tolerance = s.number("tolerance", scene.tolerance);
  scene.ramp_body_loads = s.boolean("ramp_body_loads", scene.ramp_body_loads);
  if (!(o.min_increment > 0 && o.min_increment <= o.initial_increment && o.initial_increment <= 1 &&
        o.max_increment >= o.initial_increment)) {
    s.fail(
        "",
        "need 0 < min_increment <= initial_increment <= max_increment and initial_increment <= 1");
  }
  if (!(lin.tolerance > 0 && lin.tolerance < 1)) s.fail("linear_tolerance", "must be in (0, 1)");
  if (lin.max_iterations < 1) s.fail("linear_max_iterations", "must be >= 1");
  if (!(lin.auto_flops_per_entry > 0)) s.fail("auto_flops_per_entry", "must be > 0");
  if (lin.restart < 1) s.fail("gmres_restart", "must be >= 1");
  if (o.newton.max_iterations < 1) s.fail("max_newton_iterations", "must be >= 1");
  if (o.newton.max_line_search < 0) s.fail("max_line_search", "must be >= 0");
  if (!(o.newton.forcing_max >= 0 && o.newton.forcing_max < 1))
    s.fail("forcing_max", "must be in [0, 1)");
  if (o.newton.linear.max_iterations < 1) s.fail("linear_max_iterations", "must be >= 1");
  if (o.max_settle_steps < 0) s.fail("max_settle_steps", "must be >= 0");
  if (scene.quasi_viscosity < 0) s.fail("quasi_viscosity", "must be >= 0");
  if (!(scene.tolerance > 0)) s.fail("tolerance", "must be > 0");
  s.finish();
}

// Sets the value at a dotted path, creating objects on the way.
void apply_override(json& root, const Override& o, const std::string& file) {
  const std::string where = file + ": --set " + o.path;
  json* node = &root;
  std::stringstream ss(o.path);
  std::string seg;
  while (std::getline(ss, seg, '.')) {
    const bool numeric = !seg.empty() && seg.find_first_not_of("0123456789") == std::string::npos;
    if (numeric && node->is_array()) {
      size_t k = 0;
      const auto [end, ec] = std::from_chars(seg.data(), seg.data() + seg.size(), k);
      if (ec != std::errc() || end != seg.data() + seg.size() || k >= node->size())
        throw InputError(where + ": index " + seg + " out of range");
      node = &(*node)[k];
    } else {
      if (!node->is_object() && !node->is_null())
        throw InputError(where + ": '" + seg + "' is not inside an object");
      node = &(*node)[seg];
    }
  }
  // Arrays, objects and quoted strings (after any JSON whitespace) must be valid JSON, within the
  // size and depth limits of a scene; a bare word that is no JSON number or literal is a string.
  const size_t first = o.value.find_first_not_of(" \t\n\r");
  if (first != std::string::npos &&
      std::string_view("[{\"").find(o.value[first]) != std::string_view::npos) {
    *node = parse_json(o.value, where);
  } else {
    json value = json::parse(o.value, nullptr, false);
    *node = value.is_discarded() ? json(o.value) : value;
  }
}

// The whole text of a scene file, refused unread when it exceeds the JSON size limit.
std::string read_scene_text(const std::string& path) {
  std::error_code error;
  std::ifstream in(path, std::ios::binary);
  if (!in || std::filesystem::is_directory(path, error))
    throw InputError(path + ": cannot open scene file");
  std::string text;
  char buffer[65536];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    text.append(buffer, static_cast<size_t>(in.gcount()));
    if (text.size() > kMaxJsonBytes) {
      throw InputError(path + ": more than the " + std::to_string(kMaxJsonBytes) +
                       " bytes a scene may have");
    }
  }
  if (in.bad()) throw InputError(path + ": cannot read scene file");
  return text;
}

// Physical memory [bytes], or 0 when unknown.
double physical_memory() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? double(pages) * double(page) : 0;
}

// Refuses generated meshes that no 32-bit index or this machine's memory can hold, before any
// is generated. kBytesPerNode and kBytesPerTet are lower bounds of what a run allocates (mesh,
// element blocks, block-sparse Hessian: about 14 3x3 blocks of a row per node), so a refused
// scene could never have run here.
void check_sizes(JsonObject& r, const MeshCounts& counts) {
  constexpr double kBytesPerNode = 1000, kBytesPerTet = 200;
  constexpr double kMaxIndex = std::numeric_limits<Index>::max();
  if (counts.nodes > kMaxIndex || counts.tets > kMaxIndex) {
    r.fail("bodies", "the generated meshes have " + std::to_string(counts.nodes) + " nodes and " +
                         std::to_string(counts.tets) +
                         " tets together, more than the 2147483647 a 32-bit index can number");
  }
  const double need = kBytesPerNode * counts.nodes + kBytesPerTet * counts.tets;
  const double have = physical_memory();
  if (have > 0 && need > have) {
    r.fail("bodies", "the generated meshes (" + std::to_string(counts.nodes) + " nodes, " +
                         std::to_string(counts.tets) + " tets) need at least " +
                         number_text(need / (1 << 30)) + " GiB, more than the " +
                         number_text(have / (1 << 30)) + " GiB of memory here");
  }
}

// The Newton test of the scene (see apps/README.md), for the static and the time-dependent
// solvers alike: the residual divided per dof by the force of unit strain on a cell of the
// stiffest material at that node (`force_scale`), its root mean square at most the scene's
// relative tolerance (`tolerance` = that times sqrt(#dofs)).
// A test that is infinite would call any residual converged, one that underflows to zero none:
// both come from extreme moduli, mesh sizes or tolerances. Residual norms square forces of order
// E h^2, so E^2 and (E h^2)^2 must be finite and normal too.
void set_newton_test(JsonObject& r, Scene& scene, const std::vector<std::string>& material_paths) {
  NewtonOptions& newton = scene.static_options.newton;
  newton.force_scale = residual_force_scale(scene.mesh.X, scene.mesh.tets, scene.groups);
  newton.tolerance = scene.tolerance * std::sqrt(3.0 * scene.mesh.num_nodes());
  scene.dynamic_options.newton.force_scale = newton.force_scale;
  scene.dynamic_options.newton.tolerance = newton.tolerance;
  size_t stiffest = 0;
  double E = 0;
  for (size_t g = 0; g < scene.groups.size(); ++g) {
    const double Eg = material_moduli(scene.groups[g].material).youngs();
    if (!(Eg <= E)) E = Eg, stiffest = g;
  }
  // A scale whose square is subnormal (E = 1e-320 Pa) keeps a few digits, or none.
  const auto normal_square = [](double v) { return v > 0 && std::isnormal(v * v); };
  const bool scale_ok =
      std::all_of(newton.force_scale.begin(), newton.force_scale.end(), normal_square) &&
      normal_square(E);
  const double tolerance = newton.tolerance;
  if (std::isfinite(tolerance) && tolerance > 0 && scale_ok) return;
  const std::string why =
      "the Newton test (residual / E h^2 against tolerance x sqrt(#dofs) = " +
      number_text(tolerance) + ") is not a finite, normal positive number (E = " + number_text(E) +
      " Pa, mean edge h = " + number_text(mean_edge_length(scene.mesh.X, scene.mesh.tets)) + " m)";
  if (!scale_ok || scene.groups.empty())
    r.fail(scene.groups.empty() ? "bodies" : material_paths[stiffest], why);
  r.fail("solver.tolerance", why);
}

// A body as the scene file gives it, read and checked before any mesh is made.
struct BodySpec {
  JsonObject where;
  std::string name;
  MeshSpec mesh;
  JsonObject mesh_where;
  bool rigid;
  std::vector<BodyMaterial> materials;  // deformable bodies
  double density;
  Vec3 velocity;
};

// Every entry of "bodies"; the mesh files they read join scene.inputs.
std::vector<BodySpec> read_bodies(JsonObject& r, const std::string& dir, Scene& scene) {
  std::vector<BodySpec> bodies;
  MeshCounts counts;
  for (JsonObject b : r.objects("bodies")) {
    const std::string name = b.string("name");
    for (const BodySpec& existing : bodies)
      if (existing.name == name) b.fail("name", "duplicate body name '" + name + "'");
    const JsonObject mesh_where = b.object("mesh");
    BodySpec body{.where = b,
                  .name = name,
                  .mesh = read_mesh_spec(mesh_where, dir, counts),
                  .mesh_where = mesh_where,
                  .rigid = b.boolean("rigid", false),
                  .materials = {},
                  .density = 0,
                  .velocity = Vec3::Zero()};
    if (body.rigid) {
      for (const char* key : {"material", "materials"})
        if (b.has(key)) b.fail(key, "a rigid body takes no material");
    } else {
      if (b.has("materials") && !std::holds_alternative<std::string>(body.mesh.source))
        b.fail("materials", "the body's mesh has no regions (physical volumes); use material");
      body.materials = read_body_materials(b);
    }
    body.density = b.number("density", 1000.0);
    if (!(body.density > 0)) b.fail("density", "must be > 0");
    body.velocity = b.vec3("velocity", Vec3::Zero());
    b.finish();
    if (const auto* file = std::get_if<std::string>(&body.mesh.source)) {
      std::filesystem::path p(*file);
      scene.inputs.push_back(*file);
      if (p.extension() == ".node" || p.extension() == ".ele") {  // a TetGen mesh is two files
        scene.inputs.push_back(p.replace_extension(".node").string());
        scene.inputs.push_back(p.replace_extension(".ele").string());
      }
    }
    bodies.push_back(std::move(body));
  }
  if (bodies.empty()) r.fail("bodies", "a scene needs at least one body");
  check_sizes(r, counts);
  return bodies;
}

// The sections after the bodies: boundary (returned, its node selections resolved once the
// meshes exist), contact, obstacles, solver, output, dynamic.
std::vector<ConstraintSpec> read_sections(JsonObject& r, Scene& scene,
                                          const std::vector<BodySpec>& bodies) {
  std::vector<ConstraintSpec> boundary;
  if (r.has("boundary")) {
    std::vector<JsonObject> list = r.objects("boundary");
    for (size_t k = 0; k < list.size(); ++k) boundary.push_back(read_constraint(list[k], k));
  }
  if (r.has("contact")) {
    std::vector<std::string> names;
    for (const BodySpec& b : bodies) names.push_back(b.name);
    read_contact(r.object("contact"), scene, names);
  }
  if (r.has("obstacles")) {
    std::vector<JsonObject> list = r.objects("obstacles");
    for (size_t k = 0; k < list.size(); ++k) scene.obstacles.push_back(read_obstacle(list[k], k));
  }
  if (r.has("solver")) read_solver(r.object("solver"), scene);
  if (r.has("output")) {
    JsonObject o = r.object("output");
    scene.output.displacement = o.boolean("displacement", true);
    scene.output.stress = o.boolean("stress", false);
    scene.output.strain = o.boolean("strain", false);
    scene.output.contact = o.boolean("contact", true);
    scene.output_every = o.integer("every", 1);
    if (scene.output_every < 1) o.fail("every", "must be >= 1");
    o.finish();
  }
  if (r.has("dynamic")) {
    if (scene.analysis == Analysis::kStatic)
      r.fail("dynamic", "only for a dynamic or quasistatic analysis");
    read_dynamic(r.object("dynamic"), scene);
  } else if (scene.analysis != Analysis::kStatic) {
    r.fail("dynamic",
           "missing required key for a " + std::string(to_string(scene.analysis)) + " analysis");
  }
  scene.dynamic_options.newton = scene.static_options.newton;
  return boundary;
}

// The results file stores a node set under stored_set_name: two names of different bodies'
// meshes must not become one there (a name they share is one set, holding the nodes of each).
void check_stored_set_names(const BodySpec& b, const LoadedMesh& loaded, const Mesh& mesh) {
  for (const auto& [set, nodes] : loaded.node_sets) {
    for (const auto& [earlier, earlier_nodes] : mesh.node_sets) {
      if (earlier != set && stored_set_name(earlier) == stored_set_name(set)) {
        b.mesh_where.fail("", loaded.source.file + ": node set '" + set + "' and node set '" +
                                  earlier + "' of an earlier body would be stored as the same '" +
                                  stored_set_name(set) +
                                  "' in the results file ('/' becomes '_'); rename one");
      }
    }
  }
}

// Makes the body's mesh and adds it to the scene: a rigid body as a fixed constraint, a
// deformable one as a material group per region (their material paths join `material_paths`);
// its density per tet and velocity per node join the lists.
void add_body(const BodySpec& b, Scene& scene, std::vector<std::string>& material_paths,
              std::vector<double>& density, std::vector<Vec3>& velocity) {
  const LoadedMesh loaded = make_mesh(b.mesh, b.mesh_where);
  check_stored_set_names(b, loaded, scene.mesh);
  const Index id = scene.mesh.add_body(b.name, loaded.mesh, loaded.node_sets, loaded.region_names,
                                       loaded.tet_region);
  Body& body = scene.mesh.bodies[id];
  body.rigid = b.rigid;
  if (b.rigid) {
    // No unknowns: held in place unless a boundary condition on the body moves it.
    std::vector<Index> nodes(static_cast<size_t>(body.num_nodes));
    for (Index k = 0; k < body.num_nodes; ++k) nodes[k] = body.first_node + k;
    scene.constraints.push_back({b.name + "_rigid", nodes, Fixed{}});
  } else {
    for (const BodyMaterial& m : region_materials_checked(b.materials, loaded, b.where)) {
      // The whole body, or the region's range of its tets (add_body grouped them by region;
      // a region without tets has none).
      Region tets{"", body.first_tet, body.num_tets};
      if (!m.region.empty()) {
        const auto it = std::ranges::find(body.regions, m.region, &Region::name);
        tets = it != body.regions.end() ? *it : Region{};
      }
      ElasticGroup g{.material = m.model,
                     .tets = {},
                     .fibers = Points(),
                     .formulation = m.formulation,
                     .patch_size = m.patch_size,
                     .viscoelastic = m.viscoelastic};
      for (Index t = 0; t < tets.num_tets; ++t) g.tets.push_back(tets.first_tet + t);
      if (material_uses_fiber(g.material))
        g.fibers = m.fiber.transpose().replicate(static_cast<Index>(g.tets.size()), 1);
      scene.groups.push_back(std::move(g));
      material_paths.push_back(m.path);
    }
  }
  velocity.insert(velocity.end(), static_cast<size_t>(body.num_nodes), b.velocity);
  density.insert(density.end(), static_cast<size_t>(body.num_tets), b.density);
}

// The boundary conditions on the scene's nodes, checked for conditions that contradict each
// other on a node.
void add_boundary(JsonObject& r, std::vector<ConstraintSpec>& boundary, Scene& scene) {
  for (ConstraintSpec& c : boundary) {
    c.constraint.nodes = select_nodes(c.nodes, scene.mesh);
    scene.constraints.push_back(std::move(c.constraint));
  }
  try {
    [[maybe_unused]] const Constraints constraints(scene.mesh.X, scene.constraints);
  } catch (const InputError& e) {
    r.fail("boundary", e.what());
  }
}

}  // namespace

const char* to_string(Analysis analysis) {
  switch (analysis) {
    case Analysis::kStatic:
      return "static";
    case Analysis::kDynamic:
      return "dynamic";
    case Analysis::kQuasistatic:
      return "quasistatic";
  }
  return "unknown";
}

Override parse_override(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("--set expects PATH=VALUE, got '" + text + "'");
  return {text.substr(0, eq), text.substr(eq + 1)};
}

Scene load_scene(const std::string& path, const std::vector<Override>& overrides) {
  json root = parse_json(read_scene_text(path), path);
  for (const Override& o : overrides) apply_override(root, o, path);

  // First every key is read and checked; only then are meshes generated or read.
  Scene scene;
  scene.file = path;
  scene.inputs.push_back(path);
  scene.json_text = root.dump(2, ' ', false, json::error_handler_t::replace);
  JsonObject r(root, "", path);
  scene.name = r.string("name", std::filesystem::path(path).stem().string());
  r.ignore("description");
  scene.analysis =
      r.choice<Analysis>("analysis", "analysis",
                         {{to_string(Analysis::kStatic), Analysis::kStatic},
                          {to_string(Analysis::kDynamic), Analysis::kDynamic},
                          {to_string(Analysis::kQuasistatic), Analysis::kQuasistatic}});
  scene.gravity = r.vec3("gravity", Vec3::Zero());
  const std::vector<BodySpec> bodies =
      read_bodies(r, std::filesystem::path(path).parent_path().string(), scene);
  std::vector<ConstraintSpec> boundary = read_sections(r, scene, bodies);
  r.finish();

  // Then the meshes, and what depends on them.
  std::vector<std::string> material_paths;  // of the deformable bodies' groups, in order
  std::vector<double> density;
  std::vector<Vec3> velocity;
  for (const BodySpec& b : bodies) add_body(b, scene, material_paths, density, velocity);
  scene.initial_velocity.resize(scene.mesh.num_nodes(), 3);
  for (Index i = 0; i < scene.mesh.num_nodes(); ++i)
    scene.initial_velocity.row(i) = velocity[i].transpose();
  scene.tet_density =
      Eigen::Map<VectorX>(density.data(), static_cast<Eigen::Index>(density.size()));
  add_boundary(r, boundary, scene);
  set_newton_test(r, scene, material_paths);
  return scene;
}

}  // namespace depthfem
