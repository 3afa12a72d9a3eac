// libFuzzer target for the command line: the input is the argument list, split at NUL bytes,
// given to the entry point `main` uses (apps/command_line.hpp) in its checking stage, which reads
// and checks the arguments and the scene with every `--set` override but runs nothing and reads
// or writes no results file. The arguments may name the scenes (and their mesh) that the target
// writes into a temporary folder, the working directory during the call; arguments that could reach
// outside it (an absolute path, "..") are skipped. Exit status 0 needs no error output, 1 exactly
// one line "depthfem: error: ARG: ..." naming one of the arguments (the scene, or the option at
// fault), 2 one such line followed by the usage text; anything else (another status, several lines,
// a crash, a sanitizer report) is a finding.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "apps/command_line.hpp"

namespace {

// A static box pulled at one end.
constexpr const char* kStaticScene = R"({
  "name": "box", "analysis": "static", "gravity": [0, 0, -9.81],
  "bodies": [{"name": "b", "mesh": {"generator": "box", "lo": [0,0,0], "hi": [1,0.2,0.2], "cells": [3,1,1]},
              "material": {"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3}, "density": 1000}],
  "boundary": [{"name": "clamp", "type": "fixed", "nodes": {"plane": {"normal": [1,0,0], "offset": 0}}},
               {"type": "displaced", "displacement": [0.1,0,0], "nodes": {"plane": {"normal": [1,0,0], "offset": 1}}}],
  "solver": {"linear_solver": "direct", "tolerance": 1e-9, "max_newton_iterations": 30,
             "initial_increment": 0.5, "min_increment": 1e-3, "max_increment": 1},
  "output": {"stress": true, "strain": false}
})";

// Two bodies in contact over a floor, integrated in time.
constexpr const char* kDynamicScene = R"({
  "name": "drop", "analysis": "dynamic", "gravity": [0, 0, -9.81],
  "bodies": [{"name": "base", "mesh": {"generator": "box", "lo": [0,0,0], "hi": [1,1,0.2], "cells": [2,2,1]},
              "material": {"model": "mooney_rivlin", "C1": 1e4, "C2": 1e3, "a": 1e5}},
             {"name": "top", "mesh": {"generator": "ball", "center": [0.5,0.5,0.5], "radius": 0.2, "cells_per_axis": 2},
              "material": {"model": "veronda", "alpha": 1e3, "beta": 2, "a": 1e5}, "velocity": [0,0,-1]}],
  "contact": {"model": "material_depth", "penalty": 1e7, "self_contact": false},
  "obstacles": [{"name": "floor", "type": "plane", "point": [0,0,0], "normal": [0,0,1], "penalty": 1e7}],
  "boundary": [{"type": "fixed", "nodes": {"list": [0, 1, 2]}}],
  "dynamic": {"integrator": "newmark", "time_step": 0.01, "duration": 0.1, "mass": "lumped"}
})";

// A Gmsh mesh of two tets with a named volume and a named face, and a scene using it.
constexpr const char* kMesh = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
2
2 2 "face"
3 1 "body"
$EndPhysicalNames
$Nodes
5
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 1
5 1 1 1
$EndNodes
$Elements
3
1 2 2 2 1 1 2 3
2 4 2 1 1 1 2 3 4
3 4 2 1 1 2 3 4 5
$EndElements
)";
constexpr const char* kMeshScene = R"({
  "name": "file", "analysis": "static",
  "bodies": [{"name": "m", "mesh": {"file": "mesh.msh", "scale": 0.001, "regions": ["body"], "translate": [0,0,1]},
              "materials": {"body": {"model": "mooney_rivlin", "youngs": 1e5, "poisson": 0.3}}}],
  "boundary": [{"type": "fixed", "nodes": {"set": "face", "body": "m"}}],
  "solver": {"quasi_viscosity": 1e3}
})";

std::filesystem::path work_folder() {
  return std::filesystem::temp_directory_path() /
         ("depthfem_fuzz_command_line_" + std::to_string(getpid()));
}

// Aborts with `why` and what the command line printed: a finding.
[[noreturn]] void finding(const char* why, int status, const std::string& err) {
  std::fprintf(stderr, "%s (exit status %d): %s\n", why, status, err.c_str());
  std::abort();
}

// Whether `line` (after "depthfem: error: ") starts with one of `args`, as the error line writes
// it, and a colon.
bool names_an_argument(std::string_view line, const std::vector<std::string>& args) {
  for (const std::string& a : args) {
    const std::string written = depthfem::one_line(a);
    if (!a.empty() && line.substr(0, written.size()) == written &&
        line.substr(written.size(), 1) == ":")
      return true;
  }
  return false;
}

}  // namespace

// Writes the files the arguments may name into a fresh folder, removed at exit.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  std::filesystem::create_directories(work_folder());
  std::atexit([] { std::filesystem::remove_all(work_folder()); });
  for (const auto& [name, text] :
       {std::pair{"static.json", kStaticScene}, std::pair{"dynamic.json", kDynamicScene},
        std::pair{"mesh.msh", kMesh}, std::pair{"mesh.json", kMeshScene}})
    std::ofstream(work_folder() / name, std::ios::binary) << text;
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<std::string> args;
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  for (size_t begin = 0; begin <= input.size();) {
    const size_t end = std::min(input.find('\0', begin), input.size());
    args.emplace_back(input.substr(begin, end - begin));
    begin = end + 1;
  }
  for (const std::string& a : args)
    if (a.rfind('/', 0) == 0 || a.find("..") != std::string::npos) return 0;

  // The work folder is the working directory only during the call: libFuzzer reads its corpus
  // and writes its findings relative to the one it was started in.
  std::ostringstream out, err;
  const std::filesystem::path started_in = std::filesystem::current_path();
  std::filesystem::current_path(work_folder());
  const int status = depthfem::command_line(args, out, err, depthfem::CommandStage::kCheck);
  std::filesystem::current_path(started_in);
  const std::string text = err.str();
  const std::string_view prefix = "depthfem: error: ";
  if (status == 0) {
    if (!text.empty()) finding("error output with exit status 0", status, text);
    return 0;
  }
  if (status != 1 && status != 2) finding("exit status neither 0, 1 nor 2", status, text);
  const size_t line_end = text.find('\n');
  if (text.rfind(prefix, 0) != 0 || line_end == std::string::npos)
    finding("no 'depthfem: error:' line", status, text);
  const std::string_view rest = std::string_view(text).substr(line_end + 1);
  if (rest != (status == 2 ? depthfem::kCommandLineUsage : ""))
    finding("more than one error line", status, text);
  const std::string_view line =
      std::string_view(text).substr(prefix.size(), line_end - prefix.size());
  if (status == 1 && !names_an_argument(line, args))
    finding("an input error that names no argument", status, text);
  return 0;
}
