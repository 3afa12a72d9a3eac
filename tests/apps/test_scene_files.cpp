// Scene-file errors name the file and the key path; overrides reach nested keys.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "apps/scene.hpp"
#include "core/error.hpp"

namespace depthfem {
namespace {

class SceneFileTest : public ::testing::Test {
 protected:
  std::filesystem::path dir = std::filesystem::temp_directory_path() / "depthfem_scene_test";
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
  EXPECT_NE(error(replaced(kValid, "\"generator\": \"box\"", "\"file\": \"missing.msh\""))
                .find("missing.msh"),
            std::string::npos);
  EXPECT_NE(error("{\"bodies\": [").find("scene.json: invalid JSON"), std::string::npos);
}

TEST_F(SceneFileTest, TimeIntegrationSettingsAreChecked) {
  const auto set = [](const std::string& a, const std::string& d) {
    return std::vector<Override>{parse_override("analysis=" + a), parse_override("dynamic=" + d)};
  };
  EXPECT_NE(error(kValid, set("dynamic", R"({"integrator": "rk4", "time_step": 1, "duration": 1})"))
                .find("dynamic.integrator: unknown integrator 'rk4' (expected implicit_euler, "
                      "newmark, symplectic_euler or arkode)"),
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

// Two tets sharing the face (7, 300, 12): tet 3 in the physical volume "soft", tet 4 in "bone",
// the triangle (50, 7, 300) in the surface "base plate".
constexpr const char* kTwoRegions = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
3
2 5 "base plate"
3 1 "soft"
3 2 "bone"
$EndPhysicalNames
$Nodes
5
50 0 0 0
7 1 0 0
300 0 1 0
12 0 0 1
9 1 1 1
$EndNodes
$Elements
3
2 2 2 5 1 50 7 300
3 4 2 1 1 50 7 300 12
4 4 2 2 2 7 300 12 9
$EndElements
)";

// One body per region of kTwoRegions, and a body with both regions and a material per region.
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
    std::ofstream(dir / "two.msh") << kTwoRegions;
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
                .find("boundary[0].nodes.set: no node set 'top' (the meshes have 'base plate', "
                      "'bone', 'soft')"),
            std::string::npos);
  // The plane x = 5 holds nodes of "both" only.
  EXPECT_NE(error(replaced(kRegions, "\"set\": \"base plate\"",
                           "\"plane\": {\"normal\": [1, 0, 0], \"offset\": 5}, \"body\": \"soft\""))
                .find("boundary[0].nodes: selects no nodes"),
            std::string::npos);
}

}  // namespace
}  // namespace depthfem
