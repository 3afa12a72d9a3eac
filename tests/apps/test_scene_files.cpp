// Scene-file errors name the file and the key path; overrides reach nested keys.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "apps/json_reader.hpp"
#include "apps/scene.hpp"
#include "core/error.hpp"
#include "core/two_region_msh.hpp"

namespace depthfem {
namespace {

class SceneFileTest : public ::testing::Test {
 protected:
  // One folder per test process: ctest runs the tests of this suite in parallel processes.
  std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("depthfem_scene_test_" + std::to_string(getpid()));
  void SetUp() override { std::filesystem::create_directories(dir); }
  void TearDown() override { std::filesystem::remove_all(dir); }

  std::string write(const std::string& text) {
    const std::string p = (dir / "scene.json").string();
    std::ofstream(p) << text;
    return p;
  }
  // Loads `text` and returns the InputError message ("" if it loads).
  std::string error(const std::string& text, const std::vector<Override>& o = {}) {
    try {
      load_scene(write(text), o);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
};

const char* kValid = R"({
  "name": "t",
  "bodies": [{"name": "b", "mesh": {"generator": "box", "lo": [0,0,0], "hi": [1,1,1], "cells": [1,1,1]},
              "material": {"model": "mooney_rivlin", "C1": 1, "C2": 1, "a": 1}}],
  "boundary": [{"type": "fixed", "nodes": {"plane": {"normal": [1,0,0], "offset": 0}}}]
})";

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const size_t p = s.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  return s.replace(p, from.size(), to);
}

TEST_F(SceneFileTest, ValidSceneLoads) {
  EXPECT_EQ(error(kValid), "");
  const Scene s = load_scene(write(kValid));
  EXPECT_EQ(s.mesh.num_tets(), 6);
  EXPECT_EQ(s.constraints.size(), 1u);
  EXPECT_EQ(s.constraints[0].nodes.size(), 4u);
  EXPECT_EQ(s.constraints[0].name, "fixed_0");
}

TEST_F(SceneFileTest, UnknownKeyIsNamedWithItsPath) {
  const std::string m = error(replaced(kValid, "\"C2\": 1", "\"C3\": 1"));
  EXPECT_NE(m.find("scene.json: bodies[0].material.C2: missing required key"), std::string::npos)
      << m;
  const std::string u =
      error(replaced(kValid, "\"name\": \"t\"", "\"name\": \"t\", \"gravty\": [0,0,1]"));
  EXPECT_NE(u.find("scene.json: gravty: unknown key"), std::string::npos) << u;
}

// The output section: defaults (displacement and contact fields on, stress and strain off), its
// keys read, an unknown one named.
TEST_F(SceneFileTest, OutputSectionChoosesTheFields) {
  const Scene defaults = load_scene(write(kValid));
  EXPECT_TRUE(defaults.output.displacement);
  EXPECT_FALSE(defaults.output.stress);
  EXPECT_FALSE(defaults.output.strain);
  EXPECT_TRUE(defaults.output.contact);
  const Scene chosen = load_scene(write(replaced(
      kValid, "\"name\": \"t\"",
      R"("name": "t", "output": {"displacement": false, "stress": true, "strain": true, "contact": false})")));
  EXPECT_FALSE(chosen.output.displacement);
  EXPECT_TRUE(chosen.output.stress);
  EXPECT_TRUE(chosen.output.strain);
  EXPECT_FALSE(chosen.output.contact);
  EXPECT_NE(error(replaced(kValid, "\"name\": \"t\"", R"("name": "t", "output": {"strss": true})"))
                .find("scene.json: output.strss: unknown key"),
            std::string::npos);
  EXPECT_NE(error(replaced(kValid, "\"name\": \"t\"", R"("name": "t", "output": {"stress": 1})"))
                .find("output.stress: expected true or false"),
            std::string::npos);
}

TEST_F(SceneFileTest, WrongTypesAreNamed) {
  EXPECT_NE(error(replaced(kValid, "\"C1\": 1", "\"C1\": \"soft\""))
                .find("bodies[0].material.C1: expected a number"),
            std::string::npos);
  EXPECT_NE(error(replaced(kValid, "\"cells\": [1,1,1]", "\"cells\": [1,1]"))
                .find("bodies[0].mesh.cells: expected an array of 3"),
            std::string::npos);
  EXPECT_NE(error(replaced(kValid, "\"offset\": 0", "\"offset\": true"))
                .find("boundary[0].nodes.plane.offset: expected a number"),
            std::string::npos);
}

TEST_F(SceneFileTest, BadValuesAreNamed) {
  EXPECT_NE(error(replaced(kValid, "mooney_rivlin", "rubber"))
                .find("bodies[0].material.model: unknown material model 'rubber'"),
            std::string::npos);
  EXPECT_NE(error(replaced(kValid, "\"C1\": 1", "\"C1\": -1"))
                .find("bodies[0].material.model: mooney_rivlin: C1 and C2 must be >= 0"),
            std::string::npos);
  EXPECT_NE(error(replaced(kValid, "\"offset\": 0", "\"offset\": 5"))
                .find("boundary[0].nodes: selects no nodes"),
            std::string::npos);
  EXPECT_NE(error(replaced(kValid, "\"fixed\"", "\"glued\""))
                .find("boundary[0].type: unknown boundary condition 'glued'"),
            std::string::npos);
  EXPECT_NE(error(kValid, {parse_override(R"(bodies.0.mesh={"file": "missing.msh"})")})
                .find("scene.json: bodies[0].mesh: " + (dir / "missing.msh").string() +
                      ": cannot open file"),
            std::string::npos);
  EXPECT_NE(error("{\"bodies\": [").find("scene.json: invalid JSON"), std::string::npos);
}

TEST_F(SceneFileTest, TimeIntegrationSettingsAreChecked) {
  const auto set = [](const std::string& a, const std::string& d) {
    return std::vector<Override>{parse_override("analysis=" + a), parse_override("dynamic=" + d)};
  };
  EXPECT_NE(error(kValid, set("dynamic", R"({"integrator": "rk4", "time_step": 1, "duration": 1})"))
                .find("dynamic.integrator: unknown integrator 'rk4' (expected implicit_euler, "
                      "newmark, generalized_alpha, symplectic_euler, arkode, arkode_dirk or "
                      "cvode_bdf)"),
            std::string::npos);
  EXPECT_NE(error(kValid, set("quasistatic", R"({"time_step": 1, "duration": 1})"))
                .find("dynamic.viscosity: missing"),
            std::string::npos);
  EXPECT_NE(
      error(kValid,
            set("quasistatic",
                R"({"integrator": "newmark", "time_step": 1, "duration": 1, "viscosity": 1})"))
          .find("dynamic.integrator: a quasistatic analysis uses implicit_euler"),
      std::string::npos);
  EXPECT_NE(error(kValid, set("dynamic",
                              R"({"integrator": "symplectic_euler", "time_step": 1, "duration": 1,
                                             "damping": {"stiffness": 0.1}})"))
                .find("dynamic.damping.stiffness: needs an implicit integrator"),
            std::string::npos);
  EXPECT_NE(
      error(kValid, set("dynamic", R"({"time_step": 1, "duration": 1, "arkode": {"order": 4}})"))
          .find("dynamic.arkode: only for \"integrator\": \"arkode\""),
      std::string::npos);
  EXPECT_NE(error(kValid, {parse_override("analysis=dynamic")})
                .find("dynamic: missing required key for a dynamic analysis"),
            std::string::npos);
  EXPECT_NE(error(kValid, set("dynamic", R"({"time_step": 1, "duration": 1,
                                             "newmark": {"beta": 0.25}})"))
                .find("dynamic.newmark: only for \"integrator\": \"newmark\""),
            std::string::npos);
  EXPECT_NE(error(kValid, set("dynamic", R"({"integrator": "newmark", "time_step": 1, "duration": 1,
                                             "newmark": {"beta": 0.7}})"))
                .find("dynamic.newmark.beta: must be in (0, 0.5]"),
            std::string::npos);
  EXPECT_NE(error(kValid, set("dynamic", R"({"integrator": "newmark", "time_step": 1, "duration": 1,
                                             "newmark": {"gamma": 0.4}})"))
                .find("dynamic.newmark.gamma: must be in [0.5, 1]"),
            std::string::npos);
  EXPECT_NE(error(kValid, set("dynamic", R"({"integrator": "arkode", "time_step": 1, "duration": 1,
                                             "mass": "consistent"})"))
                .find("dynamic.mass: a consistent mass matrix needs an implicit integrator"),
            std::string::npos);
  // The new integrators' settings: each "dynamic" section (time_step and duration 1) and the
  // message that locates its error.
  const std::pair<const char*, const char*> integrator_errors[] = {
      {R"("integrator": "generalized_alpha", "generalized_alpha": {"rho_inf": 2})",
       "dynamic.generalized_alpha.rho_inf: must be in [0, 1]"},
      {R"("integrator": "newmark", "generalized_alpha": {})",
       "dynamic.generalized_alpha: only for \"integrator\": \"generalized_alpha\""},
      {R"("integrator": "arkode_dirk", "arkode": {"order": 8})",
       "dynamic.arkode.order: must be 2, 3, 4 or 5 for arkode_dirk"},
      {R"("integrator": "arkode_dirk", "mass": "consistent")",
       "dynamic.mass: arkode_dirk takes the lumped mass matrix"},
      {R"("integrator": "cvode_bdf", "cvode": {"max_order": 6})",
       "dynamic.cvode.max_order: must be 1 to 5"},
      {R"("integrator": "cvode_bdf", "cvode": {"relative_tolerance": 0})",
       "dynamic.cvode.relative_tolerance: must be > 0"},
      {R"("integrator": "arkode", "cvode": {})",
       "dynamic.cvode: only for \"integrator\": \"cvode_bdf\""},
      {R"("integrator": "cvode_bdf", "mass": "consistent")",
       "dynamic.mass: cvode_bdf takes the lumped mass matrix"}};
  for (const auto& [section, message] : integrator_errors) {
    const std::string d = std::string(R"({"time_step": 1, "duration": 1, )") + section + "}";
    EXPECT_NE(error(kValid, set("dynamic", d)).find(message), std::string::npos) << section;
  }
  EXPECT_NE(
      error(kValid, {parse_override(R"(output={"every": 0})")}).find("output.every: must be >= 1"),
      std::string::npos);
}

TEST_F(SceneFileTest, MooneyRivlinTakesYoungsModulusAndPoissonsRatio) {
  const std::string mr = R"({"model": "mooney_rivlin", "youngs": 3e4, "poisson": 0.45, "C2": 1e3})";
  const Scene s = load_scene(write(kValid), {parse_override("bodies.0.material=" + mr)});
  const auto& m = std::get<MooneyRivlin>(s.groups.at(0).material);
  EXPECT_NEAR(2 * (m.C1 + m.C2), 3e4 / 2.9, 1e-9);  // mu = E / (2 (1 + nu))
  EXPECT_EQ(m.C2, 1e3);
  EXPECT_NE(error(kValid, {parse_override(R"(bodies.0.material={"model": "mooney_rivlin",
                                             "youngs": 3e4, "poisson": 0.5})")})
                .find("bodies[0].material.poisson: Poisson's ratio must be in (-1, 0.5)"),
            std::string::npos);
}

TEST_F(SceneFileTest, FormulationChoosesHowTetsTakeTheVolumeChange) {
  const std::string nh =
      R"({"model": "neo_hookean", "youngs": 3e4, "poisson": 0.4999, "formulation": "nodal_pressure"})";
  const Scene s = load_scene(write(kValid), {parse_override("bodies.0.material=" + nh)});
  EXPECT_EQ(s.groups.at(0).formulation, VolumeFormulation::kNodalPressure);
  EXPECT_EQ(load_scene(write(kValid)).groups.at(0).formulation, VolumeFormulation::kStandard);
  EXPECT_NE(error(kValid, {parse_override("bodies.0.material.formulation=mixed")})
                .find("bodies[0].material.formulation: unknown formulation 'mixed' (expected "
                      "standard, nodal_pressure or patch_volume)"),
            std::string::npos);
  // The patch-volume formulation and its patch size (default 6: the hexahedra of a box mesh).
  const Scene patch =
      load_scene(write(kValid), {parse_override("bodies.0.material=" + nh),
                                 parse_override("bodies.0.material.formulation=patch_volume"),
                                 parse_override("bodies.0.material.patch_size=8")});
  EXPECT_EQ(patch.groups.at(0).formulation, VolumeFormulation::kPatchVolume);
  EXPECT_EQ(patch.groups.at(0).patch_size, 8);
  EXPECT_EQ(
      load_scene(write(kValid), {parse_override("bodies.0.material=" + nh),
                                 parse_override("bodies.0.material.formulation=patch_volume")})
          .groups.at(0)
          .patch_size,
      6);
  EXPECT_NE(error(kValid, {parse_override("bodies.0.material=" + nh),
                           parse_override("bodies.0.material.formulation=patch_volume"),
                           parse_override("bodies.0.material.patch_size=0")})
                .find("bodies[0].material.patch_size: must be >= 1 (tets per patch)"),
            std::string::npos);
  EXPECT_NE(error(kValid, {parse_override("bodies.0.material=" + nh),
                           parse_override("bodies.0.material.patch_size=6")})
                .find("bodies[0].material.patch_size: needs \"formulation\": \"patch_volume\""),
            std::string::npos);
  EXPECT_NE(error(kValid, {parse_override(R"(bodies.0.material={"model": "neo_hookean",
                                             "youngs": 3e4, "poisson": 0.5,
                                             "formulation": "nodal_pressure"})")})
                .find("bodies[0].material.poisson: Poisson's ratio must be in (-1, 0.5)"),
            std::string::npos);
  EXPECT_NE(error(kValid, {parse_override("bodies.0.material=" + nh),
                           parse_override(R"(bodies.0.material.viscoelastic={"relaxation_times":
                                             [1], "weights": [0.5]})")})
                .find("bodies[0].material.viscoelastic: needs \"formulation\": \"standard\""),
            std::string::npos);
}

TEST_F(SceneFileTest, ViscoelasticMaterialsTakeAPronySeries) {
  const auto ve = [](const std::string& section) {
    return std::vector<Override>{parse_override("bodies.0.material.viscoelastic=" + section)};
  };
  const Scene s = load_scene(
      write(kValid),
      ve(R"({"relaxation_times": [0.1, 2], "weights": [0.3, 0.2], "static_modulus": "instantaneous"})"));
  const PronySeries& p = s.groups.at(0).viscoelastic;
  EXPECT_EQ(p.times, (std::vector<double>{0.1, 2}));
  EXPECT_EQ(p.weights, (std::vector<double>{0.3, 0.2}));
  EXPECT_FALSE(p.static_relaxed);
  EXPECT_EQ(s.elasticity.duration, 0.0);  // static: no time
  EXPECT_TRUE(load_scene(write(kValid), ve(R"({"relaxation_times": [1], "weights": [0.5]})"))
                  .groups.at(0)
                  .viscoelastic.static_relaxed);
  // Each bad section with the start of its one-line error.
  const std::pair<const char*, const char*> bad[] = {
      {R"({"relaxation_times": [0.1, -1], "weights": [0.2, 0.3]})",
       "relaxation_times[1]: is -1 s; each relaxation time must be > 0"},
      {R"({"relaxation_times": [0.1], "weights": [0]})",
       "weights[0]: is 0; each weight must be > 0"},
      {R"({"relaxation_times": [0.1, 1], "weights": [0.7, 0.4]})",
       "weights: they sum to 1.1; they must sum to less than 1"},
      {R"({"relaxation_times": [0.1], "weights": [0.2, 0.1]})",
       "weights: 2 weights for 1 relaxation times"},
      {R"({"relaxation_times": [], "weights": []})",
       "relaxation_times: expected a non-empty array of numbers"},
      {R"({"relaxation_times": [1], "weights": [0.5], "tau": 1})", "tau"}};
  for (const auto& [section, message] : bad)
    EXPECT_NE(
        error(kValid, ve(section)).find("bodies[0].material.viscoelastic." + std::string(message)),
        std::string::npos)
        << section;
}

TEST_F(SceneFileTest, OverridesReachNestedKeys) {
  const Scene s = load_scene(write(kValid), {parse_override("bodies.0.mesh.cells=[2,1,1]"),
                                             parse_override("solver.linear_solver=gmres")});
  EXPECT_EQ(s.mesh.num_tets(), 12);
  EXPECT_EQ(s.static_options.newton.linear.kind, LinearSolverKind::kGmres);
  EXPECT_NE(error(kValid, {parse_override("bodies.3.name=x")}).find("index 3 out of range"),
            std::string::npos);
  EXPECT_THROW(parse_override("no_equals_sign"), InputError);
  try {
    load_scene("/nonexistent/scene.json");
    FAIL() << "a missing scene file must throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.json: cannot open scene file"),
              std::string::npos);
  }
}

// The Hessian projection is off unless the solver section asks for it, and takes only a boolean.
TEST_F(SceneFileTest, HessianProjectionIsASolverSwitch) {
  EXPECT_FALSE(load_scene(write(kValid)).elasticity.project_hessian);
  EXPECT_TRUE(load_scene(write(kValid), {parse_override("solver.hessian_projection=true")})
                  .elasticity.project_hessian);
  EXPECT_NE(error(kValid, {parse_override("solver.hessian_projection=1")})
                .find("solver.hessian_projection: expected true or false"),
            std::string::npos);
}

// contact.exclude names interfaces as the results file does and resolves them to body pairs;
// an unknown name lists the scene's interfaces, and the other contact model refuses the key.
TEST_F(SceneFileTest, ContactExcludeNamesInterfaces) {
  const std::string two =
      replaced(kValid, "\"boundary\"",
               R"("contact": {"model": "material_depth", "penalty": 1e6}, "boundary")");
  const std::string scene = replaced(
      two, "}}],",
      R"(}}, {"name": "c", "rigid": true, "mesh": {"generator": "box", "lo": [0,0,1], "hi": [1,1,2], "cells": [1,1,1]}}],)");
  const auto with = [](const std::string& value) {
    return std::vector<Override>{parse_override("contact.exclude=" + value)};
  };
  EXPECT_TRUE(load_scene(write(scene)).contact_options.excluded.empty());
  const Scene s = load_scene(write(scene), with(R"x(["b/c", "b (self)"])x"));
  EXPECT_EQ(s.contact_options.excluded, (std::vector<std::array<Index, 2>>{{0, 1}, {0, 0}}));
  EXPECT_NE(error(scene, with(R"(["c/b"])"))
                .find("contact.exclude: unknown interface 'c/b' (the scene's: b (self), b/c, "
                      "c (self))"),
            std::string::npos);
  EXPECT_NE(error(scene, with(R"("b/c")")).find("contact.exclude: expected a non-empty array"),
            std::string::npos);
  EXPECT_NE(error(scene, {parse_override(R"(contact.model="node_to_surface")"),
                          parse_override(R"(contact.exclude=["b/c"])")})
                .find("contact.exclude: only for the material_depth model"),
            std::string::npos);
}

// Every integer is read in 64 bits and refused, with its key, when it does not fit.
TEST_F(SceneFileTest, IntegersAboveTwoToThe31AreRefusedNotTruncated) {
  EXPECT_NE(error(replaced(kValid, "\"cells\": [1,1,1]", "\"cells\": [4294967336,1,1]"))
                .find("scene.json: bodies[0].mesh.cells: integer 4294967336 is out of range"),
            std::string::npos);
  EXPECT_NE(error(kValid, {parse_override("solver.max_newton_iterations=4294967297")})
                .find("solver.max_newton_iterations: integer 4294967297 is out of range"),
            std::string::npos);
  EXPECT_NE(error(kValid, {parse_override("boundary.0.nodes={\"list\": [18446744073709551615]}")})
                .find("boundary[0].nodes.list: expected node indices in [0, 2147483647]"),
            std::string::npos);
}

TEST_F(SceneFileTest, MeshesTooLargeAreRefusedBeforeAllocating) {
  // 6e15 tets: the cell product overflows 32 and 64-bit ints.
  EXPECT_NE(error(replaced(kValid, "\"cells\": [1,1,1]", "\"cells\": [100000,100000,100000]"))
                .find("bodies[0].mesh.cells: gives 1e+15 nodes and 6e+15 tets, more than the "
                      "2147483647"),
            std::string::npos);
  // 3.2e8 nodes fit an index, but not the memory of any machine this runs on (320 GB at 1 kB
  // per node).
  EXPECT_NE(error(replaced(kValid, "\"cells\": [1,1,1]", "\"cells\": [800,800,500]"))
                .find("scene.json: bodies: the "
                      "generated meshes"),
            std::string::npos);
  // Two bodies that fit one by one (1.8e9 tets each) but not together.
  const auto big = [](const std::string& name) {
    return R"({"name": ")" + name + R"(", "mesh": {"generator": "box", "lo": [0,0,0],
               "hi": [1,1,1], "cells": [1000,1000,300]}, "rigid": true})";
  };
  EXPECT_NE(error(kValid, {parse_override("bodies=[" + big("c") + "," + big("d") + "]")})
                .find("scene.json: bodies: the generated meshes have"),
            std::string::npos);
}

TEST_F(SceneFileTest, StepCountsAreBounded) {
  EXPECT_NE(error(kValid, {parse_override("analysis=dynamic"),
                           parse_override(R"(dynamic={"time_step": 1e-9, "duration": 1000})")})
                .find("dynamic.time_step: duration / time_step asks for 1e+12 steps, more than "
                      "the 1000000 a results file holds"),
            std::string::npos);
}

TEST_F(SceneFileTest, NonFiniteScalesAreErrorsNamingTheKey) {
  // A finite tolerance whose product with sqrt(#dofs) overflows.
  EXPECT_NE(error(kValid, {parse_override("solver.tolerance=1e308")})
                .find("scene.json: solver.tolerance: the Newton test (residual / E h^2 against "
                      "tolerance x sqrt(#dofs) = inf)"),
            std::string::npos);
  // Young's modulus 1e308: its square, which residual norms form, overflows.
  EXPECT_NE(error(kValid, {parse_override(R"(bodies.0.material={"model": "mooney_rivlin",
                                             "youngs": 1e308, "poisson": 0.3})")})
                .find("scene.json: bodies[0].material: the Newton test"),
            std::string::npos);
  // Young's modulus 1e-320 (subnormal): its square underflows to zero, and the force scale
  // E h^2 keeps a few digits at most.
  EXPECT_NE(error(kValid, {parse_override(R"(bodies.0.material={"model": "neo_hookean",
                                             "youngs": 1e-320, "poisson": 0.3})")})
                .find("scene.json: bodies[0].material: the Newton test"),
            std::string::npos);
  EXPECT_NE(error(kValid, {parse_override("bodies.0.mesh.lo=[-1e308,0,0]"),
                           parse_override("bodies.0.mesh.hi=[1e308,1,1]")})
                .find("bodies[0].mesh.hi: must be finite, and so must hi - lo"),
            std::string::npos);
}

TEST_F(SceneFileTest, JsonIsBoundedAndStrict) {
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  EXPECT_NE(error("{\"name\": " + deep + "}").find("scene.json:1: nested more than 64 levels"),
            std::string::npos);
  EXPECT_NE(error(kValid, {parse_override("gravity=" + deep)})
                .find("scene.json: --set gravity:1: nested more than 64 levels"),
            std::string::npos);
  EXPECT_NE(
      error(std::string(kMaxJsonBytes + 1, ' ')).find("scene.json: more than the 16777216 bytes"),
      std::string::npos);
  EXPECT_NE(error(replaced(kValid, "\"C2\": 1", "\"C2\": 1, \"C1\": 2"))
                .find("scene.json: bodies[0].material.C1: duplicate key"),
            std::string::npos);
  EXPECT_NE(error("{\"bodies\": [1,").find("scene.json: invalid JSON: parse error at line 1"),
            std::string::npos);
}

// Found by fuzzing the scene reader: a number beyond a double left the parser as the JSON
// library's own exception, which named neither file nor key and quoted the whole number.
TEST_F(SceneFileTest, NumberBeyondADoubleIsNamedWithItsKey) {
  const std::string m = error(replaced(kValid, "\"C1\": 1", "\"C1\": 1e999"));
  EXPECT_NE(m.find("scene.json: bodies[0].material.C1: a number beyond the range of a double"),
            std::string::npos)
      << m;
  EXPECT_NE(error("[1, -2e400]").find("scene.json: [1]: a number beyond"), std::string::npos);
  EXPECT_NE(error(kValid, {parse_override("gravity=[0, 0, " + std::string(400, '9') + "]")})
                .find("scene.json: --set gravity: [2]: a number beyond"),
            std::string::npos);
}

// A --set value is read as JSON after leading whitespace too, within the same limits: " [[[..."
// escaped the depth limit and overflowed the stack when the scene was copied (found by reading
// apply_override, confirmed with AddressSanitizer).
TEST_F(SceneFileTest, SetValueAfterWhitespaceIsBoundedLikeAnyJson) {
  const std::string deep = " " + std::string(100000, '[') + std::string(100000, ']');
  EXPECT_NE(error(kValid, {parse_override("gravity=" + deep)})
                .find("scene.json: --set gravity:1: nested more than 64 levels"),
            std::string::npos);
  EXPECT_EQ(load_scene(write(kValid), {parse_override("gravity=\t [0, 0, -9.5]")}).gravity.z(),
            -9.5);
}

TEST_F(SceneFileTest, EveryErrorNamesTheSceneFileAndKey) {
  // Generator parameters, at the key of the scene.
  EXPECT_NE(error(replaced(kValid, "\"cells\": [1,1,1]", "\"cells\": [0,1,1]"))
                .find("scene.json: bodies[0].mesh.cells: must be >= 1 along every axis"),
            std::string::npos);
  EXPECT_NE(error(kValid, {parse_override("bodies.0.mesh.cells=[40,1,1]"),
                           parse_override("bodies.0.mesh.ratio=[1e10,1,1]")})
                .find("scene.json: bodies[0].mesh.ratio: ratio^cells overflows along axis 0"),
            std::string::npos);
  // A generated mesh moved so far that round-off flattens its elements.
  EXPECT_NE(error(kValid, {parse_override("bodies.0.mesh.translate=[1e20,0,0]")})
                .find("scene.json: bodies[0].mesh: the scaled and translated mesh: element 0 is "
                      "degenerate"),
            std::string::npos);
  EXPECT_NE(error(kValid, {parse_override("bodies.99999999999999999999999.name=x")})
                .find("scene.json: --set bodies.99999999999999999999999.name: index "
                      "99999999999999999999999 out of range"),
            std::string::npos);
  EXPECT_NE(error(kValid, {parse_override("boundary.0.nodes={\"list\": [99]}")})
                .find("scene.json: boundary[0].nodes.list: node 99 is outside 0..7"),
            std::string::npos);
  EXPECT_NE(error(kValid, {parse_override(R"(boundary.0={"type": "rotated", "axis": [0,0,0],
                                             "center": [0,0,0], "angle_deg": 90,
                                             "nodes": {"body": "b"}})")})
                .find("scene.json: boundary[0].axis: must be a non-zero vector"),
            std::string::npos);
  // x = 0 and x = 0.5 on the same nodes.
  const std::string fixed = R"({"type": "plane", "normal": [1,0,0],
                                "nodes": {"plane": {"normal": [1,0,0]}}})";
  const std::string moved = R"({"type": "plane", "normal": [1,0,0], "offset": 0.5,
                                "nodes": {"plane": {"normal": [1,0,0]}}})";
  EXPECT_NE(error(kValid, {parse_override("boundary=[" + fixed + "," + moved + "]")})
                .find("scene.json: boundary: boundary conditions on node 0 contradict each other"),
            std::string::npos);
}

TEST_F(SceneFileTest, WholeSceneIsCheckedBeforeAnyMeshIsRead) {
  // The mesh file does not exist, but the misspelt solver key is reported first: no mesh is
  // read or generated before every key has been checked.
  const std::string m = error(kValid, {parse_override(R"(bodies.0.mesh={"file": "missing.msh"})"),
                                       parse_override("solver.tolerence=1")});
  EXPECT_NE(m.find("scene.json: solver.tolerence: unknown key"), std::string::npos) << m;
}

// One body per region of testing::kTwoRegionMsh, and a body with both regions and a material per
// region.
const char* kRegions = R"({
  "bodies": [
    {"name": "soft", "mesh": {"file": "two.msh", "regions": ["soft"]},
     "material": {"model": "neo_hookean", "mu": 1, "lambda": 1}},
    {"name": "bone", "mesh": {"file": "two.msh", "regions": ["bone"]}, "rigid": true},
    {"name": "both", "mesh": {"file": "two.msh", "translate": [5, 0, 0]},
     "materials": {"soft": {"model": "neo_hookean", "mu": 1, "lambda": 1},
                   "bone": {"model": "neo_hookean", "mu": 100, "lambda": 100}}}],
  "boundary": [{"type": "fixed", "nodes": {"set": "base plate"}}]
})";

class RegionSceneTest : public SceneFileTest {
 protected:
  void SetUp() override {
    SceneFileTest::SetUp();
    std::ofstream(dir / "two.msh") << testing::kTwoRegionMsh;
  }
};

TEST_F(RegionSceneTest, BodiesTakeRegionsOfAFileAndAMaterialPerRegion) {
  const Scene s = load_scene(write(kRegions));
  ASSERT_EQ(s.mesh.bodies.size(), 3u);
  EXPECT_EQ(s.mesh.bodies[0].num_nodes, 4);  // nodes 50, 7, 300, 12
  EXPECT_EQ(s.mesh.bodies[1].num_nodes, 4);  // nodes 7, 300, 12, 9
  EXPECT_EQ(s.mesh.bodies[2].num_nodes, 5);
  // Groups: the soft body, then the two regions of "both" (tets 3 and 4 of the scene).
  ASSERT_EQ(s.groups.size(), 3u);
  EXPECT_EQ(s.groups[1].tets, (std::vector<Index>{2}));
  EXPECT_EQ(s.groups[2].tets, (std::vector<Index>{3}));
  EXPECT_EQ(material_moduli(s.groups[2].material).mu, 100);
  // The regions of "both" as the mesh stores them; a body of one region has that region.
  ASSERT_EQ(s.mesh.bodies[2].regions.size(), 2u);
  EXPECT_EQ(s.mesh.bodies[2].regions[0].name, "soft");
  EXPECT_EQ(s.mesh.bodies[2].regions[0].first_tet, 2);
  EXPECT_EQ(s.mesh.bodies[2].regions[1].name, "bone");
  EXPECT_EQ(s.mesh.bodies[2].regions[1].first_tet, 3);
  ASSERT_EQ(s.mesh.bodies[1].regions.size(), 1u);
  EXPECT_EQ(s.mesh.bodies[1].regions[0].num_tets, 1);
  // Each body keeps the nodes of "base plate" it has: all three in "soft" (scene nodes 0, 1, 2)
  // and "both" (8, 9, 10), nodes 7 and 300 in "bone" (4, 5).
  const std::vector<Index> base = {0, 1, 2, 4, 5, 8, 9, 10};
  EXPECT_EQ(s.mesh.node_sets.at("base plate"), base);
  EXPECT_EQ(s.constraints.back().nodes, base);
  // Every physical volume is also a node set; "body" restricts a set to one body.
  const Scene r = load_scene(
      write(kRegions), {parse_override(R"(boundary.0.nodes={"set": "bone", "body": "both"})")});
  EXPECT_EQ(r.constraints.back().nodes, (std::vector<Index>{9, 10, 11, 12}));
}

TEST_F(RegionSceneTest, RegionAndSetErrorsNameFileKeyAndChoices) {
  EXPECT_NE(error(replaced(kRegions, "\"regions\": [\"soft\"]", "\"regions\": [\"fat\"]"))
                .find("scene.json: bodies[0].mesh.regions: "),
            std::string::npos);
  EXPECT_NE(error(replaced(kRegions, "\"regions\": [\"soft\"]", "\"regions\": [\"fat\"]"))
                .find("two.msh: no region 'fat' (the mesh has 'soft', 'bone')"),
            std::string::npos);
  EXPECT_NE(error(replaced(kRegions, "\"bone\": {\"model\"", "\"bones\": {\"model\""))
                .find("bodies[2].materials.bones: the body has no region 'bones' (its regions: "
                      "'soft', 'bone')"),
            std::string::npos);
  EXPECT_NE(error(replaced(kRegions,
                           ",\n                   \"bone\": {\"model\": \"neo_hookean\", "
                           "\"mu\": 100, \"lambda\": 100}",
                           ""))
                .find("bodies[2].materials.bone: missing material for this region"),
            std::string::npos);
  EXPECT_NE(error(replaced(kValid, "\"material\"", "\"materials\""))
                .find("bodies[0].materials: "
                      "the body's mesh has no "
                      "regions"),
            std::string::npos);
  EXPECT_NE(error(replaced(kRegions, "\"set\": \"base plate\"", "\"set\": \"top\""))
                .find("boundary[0].nodes.set: no node set 'top' (the meshes have '7', "
                      "'base plate', 'bone', 'soft')"),
            std::string::npos);
  // The plane x = 5.1 holds nodes of "both" only.
  EXPECT_NE(
      error(replaced(kRegions, "\"set\": \"base plate\"",
                     "\"plane\": {\"normal\": [1, 0, 0], \"offset\": 5.1}, \"body\": \"soft\""))
          .find("boundary[0].nodes: selects no nodes"),
      std::string::npos);
}

// testing::kTwoRegionMsh with a second tet in "bone" on nodes of its own (61..64, lines 17..20),
// inside the "soft" tet: each region alone is a valid body, both together overlap.
std::string overlapping_regions() {
  std::string text = testing::kTwoRegionMsh;
  text = replaced(text, "$Nodes\n5\n", "$Nodes\n9\n");
  text = replaced(text, "$EndNodes\n",
                  "61 0.4 0.1 0.6\n62 0.6 0.1 0.6\n63 0.4 0.3 0.6\n64 0.4 0.1 0.8\n$EndNodes\n");
  text = replaced(text, "$Elements\n4\n", "$Elements\n5\n");
  return replaced(text, "$EndElements\n", "49 4 2 2 2 61 62 63 64\n$EndElements\n");
}

TEST_F(RegionSceneTest, OverlappingRegionsOfOneBodyAreAnError) {
  std::ofstream(dir / "over.msh") << overlapping_regions();
  const std::string bone = R"({"bodies": [
    {"name": "bone", "mesh": {"file": "over.msh", "regions": ["bone"]}, "rigid": true},
    {"name": "soft", "mesh": {"file": "over.msh", "regions": ["soft"], "translate": [5, 0, 0]},
     "material": {"model": "neo_hookean", "mu": 1, "lambda": 1}}],
    "boundary": [{"type": "fixed", "nodes": {"set": "base plate"}}]})";
  EXPECT_EQ(error(bone), "");
  // Both regions in one body, named or by taking the whole file.
  const std::string both = R"({"bodies": [
    {"name": "both", "mesh": {"file": "over.msh", "regions": ["soft", "bone"]},
     "materials": {"soft": {"model": "neo_hookean", "mu": 1, "lambda": 1},
                   "bone": {"model": "neo_hookean", "mu": 100, "lambda": 100}}}],
    "boundary": [{"type": "fixed", "nodes": {"set": "base plate"}}]})";
  for (const std::string& scene : {both, replaced(both, R"(, "regions": ["soft", "bone"])", "")}) {
    const std::string m = error(scene);
    EXPECT_NE(m.find("scene.json: bodies[0].mesh: "), std::string::npos) << m;
    EXPECT_NE(m.find("over.msh:28: element 49 (line 28) overlaps element 3 (line 26): the space "
                     "just inside its boundary face"),
              std::string::npos)
        << m;
  }
}

TEST_F(RegionSceneTest, NodeSetNamesThatTheResultsFileStoresAsOneAreAnError) {
  // Each file alone is fine; a body of each makes "base/plate" and "base_plate", which the
  // results file would store under one name.
  std::ofstream(dir / "slash.msh")
      << replaced(testing::kTwoRegionMsh, "\"base plate\"", "\"base/plate\"");
  std::ofstream(dir / "under.msh")
      << replaced(testing::kTwoRegionMsh, "\"base plate\"", "\"base_plate\"");
  const std::string m = error(R"({"bodies": [
    {"name": "a", "mesh": {"file": "slash.msh", "regions": ["soft"]}, "rigid": true},
    {"name": "b", "mesh": {"file": "under.msh", "regions": ["soft"], "translate": [5, 0, 0]},
     "rigid": true}],
    "boundary": [{"type": "fixed", "nodes": {"body": "a"}}]})");
  EXPECT_NE(m.find("scene.json: bodies[1].mesh: "), std::string::npos) << m;
  EXPECT_NE(m.find("under.msh: node set 'base_plate' and node set 'base/plate' of an earlier body "
                   "would be stored as the same 'base_plate' in the results file"),
            std::string::npos)
      << m;
}

}  // namespace
}  // namespace depthfem
