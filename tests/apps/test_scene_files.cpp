// Scene-file errors name the file and the key path; overrides reach nested keys.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "apps/scene.hpp"
#include "core/error.hpp"

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
}

TEST_F(SceneFileTest, MooneyRivlinTakesYoungsModulusAndPoissonsRatio) {
  const std::string mr = R"({"model": "mooney_rivlin", "youngs": 3e4, "poisson": 0.45, "C2": 1e3})";
  const Scene s = load_scene(write(kValid), {parse_override("bodies.0.material=" + mr)});
  const auto& m = std::get<MooneyRivlin>(s.groups.at(0).material);
  EXPECT_NEAR(2 * (m.C1 + m.C2), 3e4 / 2.9, 1e-9);  // mu = E / (2 (1 + nu))
  EXPECT_EQ(m.C2, 1e3);
  EXPECT_NE(
      error(kValid, {parse_override(R"(bodies.0.material={"model": "mooney_rivlin",
                                             "youngs": 3e4, "poisson": 0.5})")})
          .find("bodies[0].material.youngs: mooney_rivlin: Poisson's ratio must be in (-1, 0.5)"),
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

}  // namespace
}  // namespace depthfem
