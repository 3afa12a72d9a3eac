#pragma once
/// HDF5 results file of a run (mesh, run metadata, one group per step, timing) with an XDMF sidecar
/// for ParaView, and the reading back of what `depthfem info` and the tools need.
///
/// Layout (datasets row-major; strings variable-length UTF-8):
///   /mesh/X (#nodes x 3 f64 [m]), /mesh/tets (#tets x 4 i32), /mesh/tris (#tris x 3 i32),
///   /mesh/tet_body (#tets i32), /mesh/tri_body (#tris i32), /mesh/depth (#nodes f64 [m]),
///   /mesh/body_names (#bodies strings), /mesh/node_sets/NAME (named node sets, i32 node indices;
///   a '/' in NAME is written '_');
///   /run attributes scene, version, threads, analysis, status ("running", "completed", "failed"),
///   message, and dataset /run/constraint_names (#constraints strings);
///   /steps/NNNNNN (6-digit step index) attributes index, load, newton_iterations,
///   linear_iterations, energy [J], seconds, optional contact_area [m^2], contact_force [N] and
///   penetration [m],
///   datasets x (#nodes x 3 f64 [m]), optional v (#nodes x 3 f64 [m/s]), residuals (one norm per
///   Newton iteration), reactions (#constraints x 3 f64 [N]);
///   /timing attributes, one f64 [s] per phase, in the order given.

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh.hpp"

namespace depthfem {

/// One completed step, as written to /steps/<index>.
struct StepRecord {
  Index index = 0;
  double load = 0;            ///< load factor (static) or time [s] (dynamic)
  const Points* x = nullptr;  ///< #nodes x 3 current positions [m], required
  const Points* v = nullptr;  ///< #nodes x 3 velocities [m/s], or null
  int newton_iterations = 0, linear_iterations = 0;
  double energy = 0;                                   ///< total energy [J]
  double seconds = 0;                                  ///< wall time of the step [s]
  std::vector<double> residuals;                       ///< residual norm of each Newton iteration
  Eigen::Matrix<double, Eigen::Dynamic, 3> reactions;  ///< #constraints x 3 constraint forces [N]
  std::optional<double> contact_area;                  ///< [m^2], written only when set
  std::optional<double> contact_force;                 ///< [N], written only when set
  std::optional<double> penetration;  ///< deepest penetration [m], written only when set
};

/// Metadata of a run written to /run at creation.
struct RunInfo {
  std::string scene_json;                     ///< the scene file text
  std::string version;                        ///< depthfem version
  std::string analysis;                       ///< "static", "dynamic", ...
  int threads = 1;                            ///< worker threads of the run
  std::vector<std::string> constraint_names;  ///< one per boundary condition, the reaction rows
};

/// Writes a results file. Every call leaves the file flushed and complete up to that call, so a
/// run that dies keeps all completed steps (its status stays "running"). The constructor and every
/// step rewrite the XDMF sidecar (the path with extension ".xmf"), which names the HDF5 file
/// relatively. The file is opened without HDF5 file locks, so that other processes can read it
/// during the run. All failures throw InputError naming the results file and the object at fault.
class ResultsFile {
 public:
  /// Creates (truncates) `path` and writes /mesh and /run; `depth` is #nodes [m] or empty (zeros).
  ResultsFile(const std::string& path, const Mesh& mesh, const VectorX& depth, const RunInfo& info);
  /// Closes the file; the status is left as the last `finish` set it ("running" without one).
  ~ResultsFile();
  ResultsFile(const ResultsFile&) = delete;
  ResultsFile& operator=(const ResultsFile&) = delete;

  /// Writes /steps/<index>; throws if that step exists or the array sizes do not match the mesh.
  void append_step(const StepRecord& step);
  /// (Re)writes /timing with one attribute per (phase name, seconds), in this order.
  void write_timing(const std::vector<std::pair<std::string, double>>& phases);
  /// Sets /run status to "completed" (success) or "failed", and /run message.
  void finish(bool success, const std::string& message);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// What `depthfem info` prints, read back from a results file.
struct ResultsSummary {
  Index num_nodes = 0, num_tets = 0, num_tris = 0;
  std::vector<std::string> body_names;
  std::string analysis, status, message, version;
  int threads = 0;
  Index num_steps = 0;
  double last_load = 0;  ///< load (static) or time [s] (dynamic) of the last step; 0 without steps
  long total_newton_iterations = 0, total_linear_iterations = 0;
  std::vector<std::pair<std::string, double>> timing;  ///< (phase, seconds) in written order
};

/// Reads the summary of a results file; throws InputError naming the file when it is missing, not
/// HDF5, or not a depthfem results file.
ResultsSummary read_results_summary(const std::string& path);

/// Positions /steps/<step>/x (#nodes x 3 [m]); throws InputError naming file and step if absent.
Points read_step_positions(const std::string& path, Index step);

}  // namespace depthfem
