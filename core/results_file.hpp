#pragma once
/// HDF5 results file of a run (mesh, run metadata, the reference state, the steps, timing) with
/// XDMF sidecars for ParaView, and the reading back of what `depthfem info`, the tests and the
/// tools need. apps/README.md documents every dataset (name, shape, units).
///
/// The file is written in HDF5's single-writer/multiple-reader (SWMR) mode: every object exists
/// from the start, and a step adds one row to each dataset of /steps. After each step the file is
/// flushed in an order that keeps it consistent at every moment, so a reader (opened as a SWMR
/// reader: h5py.File(path, "r", swmr=True), or any reader once the writer has closed it) sees
/// every completed step, during the run and after a killed one.
///
/// Layout (datasets row-major; variable-length strings UTF-8):
///   /mesh: X, tets, tris, tet_body, tri_body, tri_tet, body_names, body_materials, tet_region,
///   region_names, region_materials (the element regions of all bodies, body after body), depth
///   (with material-depth contact only), node_sets/NAME (named node sets of the meshes, '/' in
///   NAME written '_'); with several sidecar blocks also blocks/<k>/tets (block-local node
///   indices; attribute name);
///   /run attributes scene, version, threads, ranks, analysis; datasets status ("running",
///   "completed", "failed") and message (fixed-length strings, rewritten in place),
///   constraint_names, contact_names;
///   /reference: the state before the first step (x, and the fields the run writes: zeros where
///   they vanish, the initial velocity, volume ratio 1);
///   /steps: one row per completed step in each dataset, the step's row k: index (its step
///   index, written last: the number of rows of /steps/index is the number of completed steps;
///   other datasets may hold one more row, of a step not completed), load, settling,
///   newton_iterations, linear_iterations, linear_solves, factorizations, energy, seconds,
///   residual_count, residuals (all steps' residuals one after the other, residual_count of them
///   per step), reactions, x, and those the run writes: displacement, v, kinetic_energy (with
///   velocities), contact_area, contact_forces, contact_force_magnitudes, contact_areas (with
///   contact interfaces), penetration (with material-depth contact), stress, von_mises, strain,
///   volume_ratio, contact_pressure, contact_traction, contact_gap, contact_fraction; /timing:
///   phases (names) and seconds, one row per phase, rewritten after every step;
///   /restart (runs whose RunInfo::restart is not empty): two slots of the restart record of the
///   last two written steps, a row of each dataset per slot: step (the step the slot holds, -1:
///   none; set to -1 and flushed before the slot is overwritten, and to the step after the step's
///   rows are flushed, before its index), acceleration, history, force.
/// The sidecars' blocks: one per body, except that a body with several element regions has one
/// per region (the body's nodes, the region's tets). The sidecar's time of a step is its load
/// (time-dependent runs: its time); ParaView shows one state per distinct time, so the settling
/// steps of a static run, all at load 1, get times 2, 3, ...

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh.hpp"
#include "core/step_record.hpp"

namespace depthfem {

/// The most steps a results file holds: a bound that keeps a mistaken time step from writing
/// without end (the scene reader refuses a run that asks for more).
inline constexpr Index kMaxSteps = 1000000;

/// Which per-step fields a results file holds, fixed when it is created.
struct ResultFields {
  bool velocity = false;     ///< v (time-dependent analyses)
  bool displacement = true;  ///< x - X
  bool stress = false;       ///< Cauchy stress and von Mises stress per tet
  bool strain = false;       ///< logarithmic strain and volume ratio per tet
  bool contact = false;      ///< pressure, traction, gap and contact fraction per boundary triangle
  /// Dissipated energy per step and viscous stress per tet (viscoelastic materials in a
  /// time-dependent analysis).
  bool viscous = false;
};

/// What a time-dependent run carries from step to step besides positions, velocities and its
/// time, so that a run restarted from a written step goes on exactly: written with every step
/// into /restart (see ResultsFile), read back by read_restart_record.
struct RestartRecord {
  Points acceleration;      ///< #nodes x 3 [m/s^2] (Newmark, generalized-alpha); empty otherwise
  Eigen::MatrixXd history;  ///< #tets x columns: Elasticity::history_state(); empty without
  /// #nodes x 3 [N]: grad E at the step as completing it evaluated it, the next step's force
  /// (symplectic Euler); empty otherwise
  Points force;
};

/// Which parts of a RestartRecord a run writes, fixed when its file is created.
struct RestartLayout {
  bool acceleration = false;
  Index history_columns = 0;  ///< columns of RestartRecord::history; 0: none
  bool force = false;
  bool empty() const { return !acceleration && history_columns == 0 && !force; }
};

/// Metadata of a run written to /run at creation, and what its steps will hold.
struct RunInfo {
  std::string scene_json;                     ///< the scene file text
  std::string version;                        ///< depthfem version
  std::string analysis;                       ///< "static", "dynamic", ...
  int threads = 1;                            ///< worker threads of the run (per rank)
  std::vector<std::string> constraint_names;  ///< one per boundary condition, the reaction rows
  /// One per contact interface, in the order every step reports them (StepRecord::contact).
  std::vector<std::string> contact_names;
  std::vector<std::string> body_materials;  ///< per body: material model name or "rigid"
  /// Per element region of the mesh (Body::regions, body after body): its material model name
  /// or "rigid".
  std::vector<std::string> region_materials;
  ResultFields fields;         ///< the per-step fields every step will hold
  Points initial_velocity;     ///< #nodes x 3 [m/s], when fields.velocity
  RestartLayout restart = {};  ///< what every step's restart record holds (none: no /restart)
  int ranks = 1;               ///< processes of the run (mpirun -n)
};

/// Writes a results file. Every call leaves the file flushed and complete up to that call, so a
/// run that dies keeps all completed steps (its status stays "running"). The sidecars (the path
/// with extensions ".xmf" and ".xdmf2", see results_sidecars) name the HDF5 file relatively and
/// grow by one entry per step, at a cost that does not depend on the number of steps before.
/// A lock file beside the results refuses a second writer. All failures throw InputError naming
/// the results file and the object at fault.
class ResultsFile {
 public:
  /// Writes /mesh, /run, /reference and the empty datasets of /steps and /timing into a hidden
  /// file beside `path`, which then replaces `path`; `depth` is #nodes [m], or empty when the
  /// run has no material-depth contact (no /mesh/depth then).
  ResultsFile(const std::string& path, const Mesh& mesh, const VectorX& depth, const RunInfo& info);
  /// Closes the file; the status is left as the last `finish` set it ("running" without one).
  ~ResultsFile();
  ResultsFile(const ResultsFile&) = delete;
  ResultsFile& operator=(const ResultsFile&) = delete;

  /// Adds a step with positions x, velocities v (exactly when info.fields.velocity; null
  /// otherwise), the element fields the run writes (`elements`: null when it writes none) and its
  /// restart record (exactly when info.restart is not empty; null otherwise). Throws if its index
  /// is not above the last one's, an array does not match the mesh or info.restart, a field the
  /// run writes is missing (step.surface for contact fields), or the contact interfaces are not
  /// info.contact_names.
  void append_step(const StepRecord& step, const Points& x, const Points* v,
                   const ElementFields* elements = nullptr, const RestartRecord* restart = nullptr);
  /// (Re)writes /timing with one row per (phase name, seconds), in this order.
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

/// Reads the summary of a results file; throws InputError naming the file (and the dataset at
/// fault) when it is missing, not HDF5, not a depthfem results file, or holds what a writer could
/// not have written: a dataset of another shape or type, a count that is not a whole number in
/// range, a load or time that is not finite. Every reader below checks what it reads the same way,
/// and none waits long on a damaged file (H5File::open).
ResultsSummary read_results_summary(const std::string& path);

/// The sidecars of results file `path`, the paths the writer writes beside it.
std::vector<std::string> results_sidecars(const std::string& path);

/// The writer's lock file of results file `path`: ".NAME.lock" beside it.
std::string results_lock_path(const std::string& path);

/// Row of step `step` (its index) of dataset /steps/NAME ("x", "stress", "load", "residuals",
/// ...) as #rows x #columns (one column for a series of vectors, 1 x 1 for scalars), its values
/// as written (NaN included); throws InputError naming file, step and dataset if absent.
Eigen::MatrixXd read_step_dataset(const std::string& path, Index step, const std::string& name);

/// Positions x of step `step` (#nodes x 3 [m]); throws InputError naming file and step if absent.
Points read_step_positions(const std::string& path, Index step);

/// A completed step read back to restart a run from it.
struct StepState {
  Index index = 0;  ///< step index in the file
  double load = 0;  ///< load factor (static) or time [s]
  Points x;         ///< #nodes x 3 [m]
  Points v;         ///< #nodes x 3 [m/s] where the file holds velocities; empty otherwise
};

/// Step `step` of a results file, the last one when `step` < 0, with a finite load and finite
/// positions (and velocities, where it holds /steps/v) of the nodes of /mesh/X; throws InputError
/// naming the file (and the dataset at fault) when it has no such step (or no steps at all) or they
/// are not.
StepState read_step_state(const std::string& path, Index step = -1);

/// The restart record of step `step` (its index) of a results file, as `layout` says it must
/// hold: the /restart slot written with that step, with finite values of the shapes the layout
/// and /mesh give. Throws InputError naming the file (and the dataset at fault) when the file
/// holds no such record (another layout, a step whose slot was overwritten since) or a damaged
/// one.
RestartRecord read_restart_record(const std::string& path, Index step, const RestartLayout& layout);

/// Throws InputError naming the file and the dataset unless the results file at `path` was
/// written for `mesh`: /mesh/tets equal to its tets, /mesh/X its node positions (to 1e-9 of the
/// mesh's size). Counts alone do not tell two meshes apart.
void check_results_mesh(const std::string& path, const Mesh& mesh);

}  // namespace depthfem
