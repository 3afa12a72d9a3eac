#pragma once
// Helpers for tests that run the scenes of apps/scenes.

#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

#include "apps/run_scene.hpp"
#include "core/results_file.hpp"

namespace depthfem::testing {

/// A path in the temporary folder unique to this process (tests of one suite run in parallel
/// processes, and several checkouts may test at once).
inline std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("depthfem_" + std::to_string(getpid()) + "_" + name))
      .string();
}

/// Removes results file `path` and the sidecars written beside it.
inline void remove_results(const std::string& path) {
  std::filesystem::remove(path);
  for (const std::string& sidecar : results_sidecars(path)) std::filesystem::remove(sidecar);
}

/// A results file at temp_path(name + ".h5"), removed with its sidecars when the test ends.
struct TemporaryResults {
  std::string path;
  explicit TemporaryResults(const std::string& name) : path(temp_path(name + ".h5")) {}
  ~TemporaryResults() { remove_results(path); }
  TemporaryResults(const TemporaryResults&) = delete;
  TemporaryResults& operator=(const TemporaryResults&) = delete;
};

inline std::string scene_path(const std::string& name) {
  return std::string(DEPTHFEM_SOURCE_DIR) + "/apps/scenes/" + name + ".json";
}

inline Scene load(const std::string& name, const std::vector<std::string>& overrides = {}) {
  std::vector<Override> o;
  for (const std::string& s : overrides) o.push_back(parse_override(s));
  return load_scene(scene_path(name), o);
}

/// The contact row named `name` of a step (a failed test when there is none).
inline const InterfaceForce& interface(const StepRecord& step, const std::string& name) {
  for (const InterfaceForce& f : step.contact)
    if (f.name == name) return f;
  throw std::runtime_error("step " + std::to_string(step.index) + " has no contact row " + name);
}

inline RunResult run(const Scene& scene, const std::string& out = "") {
  std::ostringstream log;
  RunOptions options;
  options.out = out;
  return run_scene(scene, options, log);
}

}  // namespace depthfem::testing
