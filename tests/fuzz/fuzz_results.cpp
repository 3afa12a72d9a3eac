// libFuzzer target for the readers of results files: the input is a results file, read as
// `depthfem info` reads it (the command line's info command, which reads and prints the summary)
// and as `depthfem run SCENE --restart FILE` reads it (restart_state: the summary, the mesh
// checked against the scene's, the last step's load and positions; for the scene's dynamic
// variant also the velocities and the restart record, read_restart_record), and step 0's
// residuals as the tools read a dataset. The scene is a static box of 8 nodes and 6 tets; the
// seeds in corpus/results/ are results files of runs of it and of its dynamic variant, so that a
// mutated seed passes the mesh check and reaches the steps. `info` may print its summary (exit
// status 0) or one line "depthfem: error: FILE: ..." (exit status 1); the readers may return or
// throw an InputError of one line starting with "FILE: ". Anything else (another status, exception
// or message, a crash, a sanitizer report, a hang) is a finding.
//
// DEPTHFEM_FUZZ_WRITE_SEEDS=DIR fuzz_results writes the seeds into DIR and exits: "static_run"
// (the scene run to the end: steps 0 and 1 at loads 0.5 and 1) and "no_steps" (a file of the
// scene before its first step, status "failed") and "dynamic_run" (the dynamic variant: two
// Newmark steps of a viscoelastic cube, with velocities and a restart record).
#include <hdf5.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "apps/command_line.hpp"
#include "apps/run_scene.hpp"
#include "apps/scene.hpp"
#include "core/error.hpp"
#include "core/results_file.hpp"

namespace {

namespace fs = std::filesystem;

// A unit cube of one cell (8 nodes, 6 tets) pulled at one end in two load steps.
constexpr const char* kScene = R"({
  "name": "cube", "analysis": "static",
  "bodies": [{"name": "b", "mesh": {"generator": "box", "lo": [0,0,0], "hi": [1,1,1], "cells": [1,1,1]},
              "material": {"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3}}],
  "boundary": [{"name": "clamp", "type": "fixed", "nodes": {"plane": {"normal": [1,0,0], "offset": 0}}},
               {"name": "pull", "type": "displaced", "displacement": [0.1,0,0], "nodes": {"plane": {"normal": [1,0,0], "offset": 1}}}],
  "solver": {"linear_solver": "direct", "initial_increment": 0.5},
  "output": {"displacement": false}
})";

fs::path work_folder() {
  return fs::temp_directory_path() / ("depthfem_fuzz_results_" + std::to_string(getpid()));
}

// The dynamic variant of the scene: viscoelastic (one Prony term), two Newmark steps.
const std::vector<std::string> kDynamicOverrides = {
    "analysis=dynamic",
    R"(bodies.0.material={"model": "neo_hookean", "youngs": 1e5, "poisson": 0.3,
       "viscoelastic": {"relaxation_times": [0.01], "weights": [0.3]}})",
    R"(dynamic={"integrator": "newmark", "time_step": 0.01, "duration": 0.02})"};
// Its restart record: the acceleration, and the history of one Prony term (6 (1 + 2) columns).
const depthfem::RestartLayout kDynamicLayout{.acceleration = true, .history_columns = 18};

// The scene and its dynamic variant, read once.
std::unique_ptr<depthfem::Scene> scene, dynamic_scene;

// Aborts with `why` and the message: a finding.
[[noreturn]] void finding(const char* why, const std::string& message) {
  std::fprintf(stderr, "%s: %s\n", why, message.c_str());
  std::abort();
}

// Aborts unless `message` is one line that starts with "FILE: ".
void check_located(const std::string& message, const std::string& file) {
  if (message.rfind(file + ": ", 0) != 0 || message.find('\n') != std::string::npos)
    finding("unlocated or multi-line message", message);
}

// Writes the seeds into `folder` (see the top of the file).
void write_seeds(const fs::path& folder) {
  fs::create_directories(folder);
  const std::string run = (work_folder() / "static_run.h5").string();
  depthfem::RunOptions options;
  options.out = run;
  options.threads = 1;
  std::ostringstream log;
  if (!depthfem::run_scene(*scene, options, log).success) finding("the seed run failed", log.str());
  fs::copy_file(run, folder / "static_run", fs::copy_options::overwrite_existing);
  const std::string empty = (work_folder() / "no_steps.h5").string();
  {
    depthfem::RunInfo info{scene->json_text, "0.1.0", "static", 1, {"clamp", "pull"}, {},
                           {"neo_hookean"},  {},      {},       {}};
    depthfem::ResultsFile file(empty, scene->mesh, depthfem::VectorX(), info);
    file.finish(false, "stopped before its first step");
  }
  fs::copy_file(empty, folder / "no_steps", fs::copy_options::overwrite_existing);
  const std::string dynamic = (work_folder() / "dynamic_run.h5").string();
  options.out = dynamic;
  if (!depthfem::run_scene(*dynamic_scene, options, log).success)
    finding("the dynamic seed run failed", log.str());
  fs::copy_file(dynamic, folder / "dynamic_run", fs::copy_options::overwrite_existing);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fs::create_directories(work_folder());
  std::atexit([] { fs::remove_all(work_folder()); });
  const fs::path scene_path = work_folder() / "cube.json";
  std::ofstream(scene_path, std::ios::binary) << kScene;
  scene = std::make_unique<depthfem::Scene>(depthfem::load_scene(scene_path.string()));
  std::vector<depthfem::Override> overrides;
  for (const std::string& o : kDynamicOverrides) overrides.push_back(depthfem::parse_override(o));
  dynamic_scene =
      std::make_unique<depthfem::Scene>(depthfem::load_scene(scene_path.string(), overrides));
  if (const char* seeds = std::getenv("DEPTHFEM_FUZZ_WRITE_SEEDS")) {
    write_seeds(seeds);
    std::exit(0);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string file = (work_folder() / "input.h5").string();
  std::ofstream(file, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), std::streamsize(size));

  // `depthfem info FILE`.
  std::ostringstream out, err;
  const int status =
      depthfem::command_line({"info", file}, out, err, depthfem::CommandStage::kExecute);
  const std::string text = err.str();
  if (status == 0 && !text.empty()) finding("error output with exit status 0", text);
  if (status != 0) {
    const std::string prefix = "depthfem: error: ";
    if (status != 1 || text.rfind(prefix, 0) != 0 || text.find('\n') != text.size() - 1)
      finding(("info: not one error line (exit status " + std::to_string(status) + ")").c_str(),
              text);
    check_located(text.substr(prefix.size(), text.size() - prefix.size() - 1), file);
  }

  // `depthfem run SCENE --restart FILE`, and a dataset read by the tools.
  for (int reader = 0; reader < 3; ++reader) {
    try {
      if (reader == 0) depthfem::restart_state(file, -1, scene->mesh, depthfem::Analysis::kStatic);
      if (reader == 1) depthfem::read_step_dataset(file, 0, "residuals");
      if (reader == 2) {
        const depthfem::StepState state =
            depthfem::restart_state(file, -1, scene->mesh, depthfem::Analysis::kDynamic);
        depthfem::read_restart_record(file, state.index, kDynamicLayout);
      }
    } catch (const depthfem::InputError& e) {
      check_located(e.what(), file);
    }
  }
  // Every HDF5 file and object the readers opened is closed again (HDF5's own leaks on damaged
  // files are suppressed in lsan.supp: this check is what finds a leak of ours).
  const ssize_t open = H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL);
  if (open != 0) finding("HDF5 files or objects left open", std::to_string(open));
  return 0;
}
