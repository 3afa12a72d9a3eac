#pragma once
/// Running a scene: builds its model, drives the solver, writes the results file.

#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "apps/scene.hpp"
#include "core/phase_timer.hpp"
#include "core/results_file.hpp"
#include "core/step_record.hpp"

namespace depthfem {

struct RunOptions {
  std::string out;  ///< results file (.h5); empty: no file
  int threads = 0;  ///< 0: all cores
  /// A results file of the same scene whose step `restart_step` (the last one when < 0) is the
  /// starting state: positions and load factor (static); positions, time, velocities and the
  /// step's restart record (time-dependent, every integrator but ARKODE's); empty: start at rest.
  std::string restart;
  Index restart_step = -1;
  /// Called after every completed step with its record and positions (e.g. to sample a
  /// trajectory without writing a file).
  std::function<void(const StepRecord&, const Points& x)> observer;
};

/// Outcome of a run. On failure `message` says why; completed steps are kept.
struct RunResult {
  bool success = false;
  std::string message;
  std::vector<StepRecord> steps;
  Points x;  ///< final positions (last completed step)
  PhaseTimers timers;
  double seconds = 0;
};

/// Runs `scene`, printing one progress line per step to `log`. Input errors found while
/// building the modules are thrown (InputError); solver failures are returned in the result
/// (and recorded in the results file).
RunResult run_scene(const Scene& scene, const RunOptions& options, std::ostream& log);

/// The starting state of a restart (RunOptions::restart): step `step` (the last one when < 0)
/// of the results file `path`, which a run of `analysis` of a scene with `mesh` must have written
/// (the same nodes and tets, not only as many), with finite positions and a load factor in
/// [0, 1] (static) or a time >= 0 and finite velocities (time-dependent); throws InputError
/// naming the file (and the dataset at fault) otherwise.
StepState restart_state(const std::string& path, Index step, const Mesh& mesh, Analysis analysis);

/// Prints the phase timing table of a run (seconds and share of the total), then each phase's CPU
/// seconds (all threads) and CPU / wall, the threads busy in it on average.
void print_timing(const PhaseTimers& timers, double total_seconds, std::ostream& out);

}  // namespace depthfem
