#include "apps/scene.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "apps/json_reader.hpp"
#include "core/error.hpp"
#include "core/mesh_file.hpp"
#include "core/mesh_generators.hpp"
#include "core/mesh_regions.hpp"
#include "core/node_sets.hpp"

namespace depthfem {

namespace {

using nlohmann::json;

// A body's mesh: generated, or read from a file (all of it, or the tets of some regions), with
// the file's regions and node sets.
LoadedMesh read_body_mesh(JsonObject m, const std::string& scene_dir) {
  LoadedMesh loaded;
  TetMesh& mesh = loaded.mesh;
  if (m.has("file")) {
    std::filesystem::path p = m.string("file");
    if (p.is_relative()) p = std::filesystem::path(scene_dir) / p;
    loaded = read_tet_mesh(p.string());
    if (m.has("regions")) {
      try {
        loaded = select_regions(loaded, m.strings("regions"));
      } catch (const InputError& e) {
        m.fail("regions", p.string() + ": " + e.what());
      }
    }
    mesh.X *= m.number("scale", 1.0);
  } else {
    const std::string gen = m.string("generator");
    if (gen == "box") {
      mesh = box_mesh({m.vec3("lo"), m.vec3("hi"), m.int3("cells"), m.vec3("ratio", Vec3::Ones())});
    } else if (gen == "tube") {
      mesh = tube_mesh({m.number("inner_radius"), m.number("outer_radius"), m.number("length"),
                        m.integer("cells_through_wall"), m.integer("cells_around"),
                        m.integer("cells_along")});
    } else if (gen == "corner") {
      mesh = corner_mesh(
          {m.number("size"), m.number("core"), m.integer("core_cells"), m.number("ratio")});
    } else if (gen == "ball") {
      mesh = ball_mesh(
          {m.vec3("center", Vec3::Zero()), m.number("radius"), m.integer("cells_per_axis")});
    } else {
      m.fail("generator", "unknown generator '" + gen + "' (expected box, tube, ball or corner)");
    }
  }
  mesh.X.rowwise() += m.vec3("translate", Vec3::Zero()).transpose();
  m.finish();
  return loaded;
}

// Material parameters by model name; the keys are those of the model's struct.
MaterialModel read_material(JsonObject m, Vec3& fiber_direction) {
  const std::string model = m.string("model");
  MaterialModel out;
  const auto mooney = [&] { return MooneyRivlin{m.number("C1"), m.number("C2"), m.number("a")}; };
  const auto veronda = [&] { return Veronda{m.number("alpha"), m.number("beta"), m.number("a")}; };
  if (model == "neo_hookean") {
    out = m.has("youngs") ? NeoHookean::from_youngs(m.number("youngs"), m.number("poisson"))
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
  if (material_uses_fiber(out)) fiber_direction = m.vec3("fiber_direction");
  try {
    validate_material(out);
  } catch (const std::invalid_argument& e) {
    m.fail("model", e.what());
  }
  m.finish();
  return out;
}

// Elastic groups of a deformable body: one material for the whole body ("material"), or one per
// region of its mesh ("materials": {region: material}).
void add_material_groups(JsonObject& b, const LoadedMesh& loaded, const Body& body,
                         std::vector<ElasticGroup>& groups) {
  const auto group = [&](JsonObject m, Index region) {
    Vec3 fiber = Vec3::UnitX();
    ElasticGroup g{read_material(std::move(m), fiber), {}, Points()};
    for (Index t = 0; t < body.num_tets; ++t)
      if (region < 0 || loaded.tet_region[t] == region) g.tets.push_back(body.first_tet + t);
    if (material_uses_fiber(g.material))
      g.fibers = fiber.transpose().replicate(static_cast<Index>(g.tets.size()), 1);
    groups.push_back(std::move(g));
  };
  if (!b.has("materials")) {
    group(b.object("material"), -1);
    return;
  }
  if (b.has("material")) b.fail("materials", "give either material or materials, not both");
  JsonObject ms = b.object("materials");
  if (loaded.region_names.empty())
    b.fail("materials", "the body's mesh has no regions (physical volumes); use material");
  for (const std::string& key : ms.keys()) {
    if (std::ranges::find(loaded.region_names, key) == loaded.region_names.end()) {
      std::string known;
      for (const std::string& r : loaded.region_names)
        known += (known.empty() ? "'" : ", '") + r + "'";
      ms.fail(key, "the body has no region '" + key + "' (its regions: " + known + ")");
    }
  }
  for (size_t r = 0; r < loaded.region_names.size(); ++r) {
    if (!ms.has(loaded.region_names[r]))
      ms.fail(loaded.region_names[r], "missing material for this region of the body");
    group(ms.object(loaded.region_names[r]), static_cast<Index>(r));
  }
  ms.finish();
}

std::vector<Index> read_node_set(JsonObject s, const Mesh& mesh) {
  const double tol = s.number("tolerance", 1e-9);
  std::vector<Index> nodes;
  int kinds = 0;
  if (s.has("box")) {
    JsonObject b = s.object("box");
    nodes = nodes_in_box(mesh.X, b.vec3("lo"), b.vec3("hi"), tol);
    b.finish();
    ++kinds;
  }
  if (s.has("plane")) {
    JsonObject p = s.object("plane");
    nodes = nodes_on_plane(mesh.X, p.vec3("normal"), p.number("offset", 0.0), tol);
    p.finish();
    ++kinds;
  }
  if (s.has("list")) {
    nodes = s.indices("list");
    ++kinds;
  }
  if (s.has("set")) {
    const std::string name = s.string("set");
    const auto it = mesh.node_sets.find(name);
    if (it == mesh.node_sets.end()) {
      std::string known;
      for (const auto& [n, set] : mesh.node_sets) known += (known.empty() ? "'" : ", '") + n + "'";
      s.fail("set", "no node set '" + name + "' (the meshes have " +
                        (known.empty() ? std::string("none") : known) + ")");
    }
    nodes = it->second;
    ++kinds;
  }
  // "body" alone selects the whole body; with another selector it keeps that selection's nodes
  // in the body.
  if (s.has("body")) {
    const std::string name = s.string("body");
    Index id = -1;
    for (size_t b = 0; b < mesh.bodies.size(); ++b)
      if (mesh.bodies[b].name == name) id = static_cast<Index>(b);
    if (id < 0) s.fail("body", "no body named '" + name + "'");
    if (kinds == 0) {
      nodes = nodes_of_body(mesh, id);
      ++kinds;
    } else {
      const Body& body = mesh.bodies[id];
      std::erase_if(nodes, [&](Index i) {
        return i < body.first_node || i >= body.first_node + body.num_nodes;
      });
    }
  }
  if (kinds != 1)
    s.fail("",
           "give exactly one of box, plane, list, set or body (set and the others may be "
           "restricted to a body)");
  if (nodes.empty()) s.fail("", "selects no nodes");
  s.finish();
  return nodes;
}

Constraint read_constraint(JsonObject c, const Mesh& mesh, size_t index) {
  Constraint out;
  const std::string type = c.string("type");
  out.name = c.string("name", type + "_" + std::to_string(index));
  out.nodes = read_node_set(c.object("nodes"), mesh);
  if (type == "fixed") {
    out.kind = Fixed{};
  } else if (type == "displaced") {
    out.kind = Displaced{c.vec3("displacement")};
  } else if (type == "rotated") {
    out.kind =
        Rotated{c.vec3("axis"), c.vec3("center"), c.number("angle_deg") * std::numbers::pi / 180,
                c.vec3("translation", Vec3::Zero())};
  } else if (type == "plane") {
    out.kind = InPlane{c.vec3("normal"), c.number("offset", 0.0)};
  } else if (type == "line") {
    out.kind = OnLine{c.vec3("direction")};
  } else {
    c.fail("type", "unknown boundary condition '" + type +
                       "' (expected fixed, displaced, rotated, plane or line)");
  }
  c.finish();
  return out;
}

void read_contact(JsonObject c, Scene& scene) {
  scene.contact = c.choice<ContactModel>("model", "contact model",
                                         {{"material_depth", ContactModel::kMaterialDepth},
                                          {"node_to_surface", ContactModel::kNodeToSurface}});
  scene.contact_options.penalty = c.number("penalty");
  scene.contact_options.self_contact = c.boolean("self_contact", true);
  if (!(scene.contact_options.penalty > 0)) c.fail("penalty", "must be > 0");
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

void read_dynamic(JsonObject d, Scene& scene) {
  DynamicOptions& o = scene.dynamic_options;
  o.integrator = d.choice<Integrator>("integrator", "integrator",
                                      {{"implicit_euler", Integrator::kImplicitEuler},
                                       {"newmark", Integrator::kNewmark},
                                       {"symplectic_euler", Integrator::kSymplecticEuler},
                                       {"arkode", Integrator::kArkode}});
  o.time_step = d.number("time_step");
  o.duration = d.number("duration");
  if (!(o.time_step > 0)) d.fail("time_step", "must be > 0");
  if (!(o.duration >= o.time_step)) d.fail("duration", "must be >= time_step");
  const bool explicit_scheme =
      o.integrator == Integrator::kSymplecticEuler || o.integrator == Integrator::kArkode;
  if (scene.analysis == "quasistatic") {
    // Viscous flow without inertia: only implicit Euler, and the viscosity is what resists motion.
    if (o.integrator != Integrator::kImplicitEuler)
      d.fail("integrator", "a quasistatic analysis uses implicit_euler");
    scene.viscosity = d.number("viscosity");
    if (!(scene.viscosity > 0)) d.fail("viscosity", "must be > 0");
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
  if (d.has("arkode")) {
    if (o.integrator != Integrator::kArkode)
      d.fail("arkode", "only for \"integrator\": \"arkode\"");
    JsonObject a = d.object("arkode");
    o.arkode.order = a.integer("order", o.arkode.order);
    o.arkode.relative_tolerance = a.number("relative_tolerance", o.arkode.relative_tolerance);
    o.arkode.absolute_tolerance = a.number("absolute_tolerance", o.arkode.absolute_tolerance);
    o.arkode.max_steps = a.integer("max_steps", static_cast<int>(o.arkode.max_steps));
    if (!has_erk_table(o.arkode.order)) a.fail("order", "must be 2, 3, 4, 5, 6 or 8");
    if (!(o.arkode.relative_tolerance > 0)) a.fail("relative_tolerance", "must be > 0");
    if (!(o.arkode.absolute_tolerance > 0)) a.fail("absolute_tolerance", "must be > 0");
    if (!(o.arkode.max_steps > 0)) a.fail("max_steps", "must be > 0");
    a.finish();
  }
  d.finish();
}

void read_solver(JsonObject s, Scene& scene) {
  StaticOptions& o = scene.static_options;
  o.newton.linear.kind = s.choice<LinearSolverKind>("linear_solver", "linear solver",
                                                    {{"direct", LinearSolverKind::kDirect},
                                                     {"gmres", LinearSolverKind::kGmres},
                                                     {"cg", LinearSolverKind::kCg}});
  o.newton.linear.tolerance = s.number("linear_tolerance", o.newton.linear.tolerance);
  o.newton.linear.max_iterations =
      s.integer("linear_max_iterations", o.newton.linear.max_iterations);
  o.newton.max_iterations = s.integer("max_newton_iterations", o.newton.max_iterations);
  o.newton.max_line_search = s.integer("max_line_search", o.newton.max_line_search);
  o.newton.line_search = s.choice<LineSearchRule>(
      "line_search", "rule",
      {{"energy", LineSearchRule::kEnergy}, {"residual", LineSearchRule::kResidual}});
  o.initial_increment = s.number("initial_increment", o.initial_increment);
  o.min_increment = s.number("min_increment", o.min_increment);
  o.max_increment = s.number("max_increment", o.max_increment);
  o.predictor = s.boolean("predictor", o.predictor);
  o.max_settle_steps = s.integer("max_settle_steps", o.max_settle_steps);
  scene.quasi_viscosity = s.number("quasi_viscosity", 0.0);
  scene.tolerance = s.number("tolerance", scene.tolerance);
  if (!(o.min_increment > 0 && o.min_increment <= o.initial_increment && o.initial_increment <= 1 &&
        o.max_increment >= o.initial_increment)) {
    s.fail(
        "",
        "need 0 < min_increment <= initial_increment <= max_increment and initial_increment <= 1");
  }
  if (!(o.newton.linear.tolerance > 0 && o.newton.linear.tolerance < 1))
    s.fail("linear_tolerance", "must be in (0, 1)");
  if (o.newton.max_iterations < 1) s.fail("max_newton_iterations", "must be >= 1");
  if (scene.quasi_viscosity < 0) s.fail("quasi_viscosity", "must be >= 0");
  if (!(scene.tolerance > 0)) s.fail("tolerance", "must be > 0");
  s.finish();
}

// Sets the value at a dotted path, creating objects on the way.
void apply_override(json& root, const Override& o, const std::string& file) {
  json* node = &root;
  std::stringstream ss(o.path);
  std::string seg;
  while (std::getline(ss, seg, '.')) {
    const bool numeric = !seg.empty() && seg.find_first_not_of("0123456789") == std::string::npos;
    if (numeric && node->is_array()) {
      const size_t k = std::stoul(seg);
      if (k >= node->size())
        throw InputError(file + ": --set " + o.path + ": index " + seg + " out of range");
      node = &(*node)[k];
    } else {
      if (!node->is_object() && !node->is_null())
        throw InputError(file + ": --set " + o.path + ": '" + seg + "' is not inside an object");
      node = &(*node)[seg];
    }
  }
  json value = json::parse(o.value, nullptr, false);
  *node = value.is_discarded() ? json(o.value) : value;
}

}  // namespace

Override parse_override(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("--set expects PATH=VALUE, got '" + text + "'");
  return {text.substr(0, eq), text.substr(eq + 1)};
}

Scene load_scene(const std::string& path, const std::vector<Override>& overrides) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open scene file");
  json root;
  try {
    root = json::parse(in);
  } catch (const json::parse_error& e) {
    throw InputError(path + ": invalid JSON: " + e.what());
  }
  for (const Override& o : overrides) apply_override(root, o, path);

  Scene scene;
  scene.file = path;
  scene.json_text = root.dump(2);
  JsonObject r(root, "", path);
  scene.name = r.string("name", std::filesystem::path(path).stem().string());
  r.ignore("description");
  scene.analysis = r.string("analysis", "static");
  if (scene.analysis != "static" && scene.analysis != "dynamic" &&
      scene.analysis != "quasistatic") {
    r.fail("analysis",
           "unknown analysis '" + scene.analysis + "' (expected static, dynamic or quasistatic)");
  }
  scene.gravity = r.vec3("gravity", Vec3::Zero());

  const std::string dir = std::filesystem::path(path).parent_path().string();
  std::vector<double> density;
  std::vector<Vec3> velocity;
  for (JsonObject b : r.objects("bodies")) {
    const std::string name = b.string("name");
    for (const Body& existing : scene.mesh.bodies)
      if (existing.name == name) b.fail("name", "duplicate body name '" + name + "'");
    const LoadedMesh loaded = read_body_mesh(b.object("mesh"), dir);
    const bool rigid = b.boolean("rigid", false);
    const Index id = scene.mesh.add_body(name, loaded.mesh, loaded.node_sets);
    const Body& body = scene.mesh.bodies[id];
    scene.rigid.push_back(rigid);
    if (rigid) {
      // No unknowns: held in place unless a boundary condition on the body moves it.
      std::vector<Index> nodes(static_cast<size_t>(body.num_nodes));
      for (Index k = 0; k < body.num_nodes; ++k) nodes[k] = body.first_node + k;
      scene.constraints.push_back({name + "_rigid", nodes, Fixed{}});
      for (const char* key : {"material", "materials"})
        if (b.has(key)) b.fail(key, "a rigid body takes no material");
    } else {
      add_material_groups(b, loaded, body, scene.groups);
    }
    const double rho = b.number("density", 1000.0);
    if (!(rho > 0)) b.fail("density", "must be > 0");
    velocity.insert(velocity.end(), static_cast<size_t>(body.num_nodes),
                    b.vec3("velocity", Vec3::Zero()));
    b.finish();
    density.insert(density.end(), static_cast<size_t>(body.num_tets), rho);
  }
  if (scene.mesh.bodies.empty()) r.fail("bodies", "a scene needs at least one body");
  scene.initial_velocity.resize(scene.mesh.num_nodes(), 3);
  for (Index i = 0; i < scene.mesh.num_nodes(); ++i)
    scene.initial_velocity.row(i) = velocity[i].transpose();
  scene.tet_density =
      Eigen::Map<VectorX>(density.data(), static_cast<Eigen::Index>(density.size()));

  if (r.has("boundary")) {
    std::vector<JsonObject> list = r.objects("boundary");
    for (size_t k = 0; k < list.size(); ++k)
      scene.constraints.push_back(read_constraint(list[k], scene.mesh, k));
  }
  if (r.has("contact")) read_contact(r.object("contact"), scene);
  if (r.has("obstacles")) {
    std::vector<JsonObject> list = r.objects("obstacles");
    for (size_t k = 0; k < list.size(); ++k) scene.obstacles.push_back(read_obstacle(list[k], k));
  }
  if (r.has("solver")) read_solver(r.object("solver"), scene);
  if (r.has("dynamic")) {
    if (scene.analysis == "static") r.fail("dynamic", "only for a dynamic or quasistatic analysis");
    read_dynamic(r.object("dynamic"), scene);
  } else if (scene.analysis != "static") {
    r.fail("dynamic", "missing required key for a " + scene.analysis + " analysis");
  }
  scene.dynamic_options.newton = scene.static_options.newton;
  r.finish();
  return scene;
}

}  // namespace depthfem
