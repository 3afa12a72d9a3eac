#pragma once
/// Running a scene: builds its force modules, drives the solver, writes the results file.

#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "apps/scene.hpp"
#include "core/phase_timer.hpp"

namespace depthfem {

struct StepSummary;

struct RunOptions {
  std::string out;  ///< results file (.h5); empty: no file
  int threads = 0;  ///< 0: all cores
  /// Called after every completed step with its summary and positions (e.g. to sample a
  /// trajectory without writing a file).
  std::function<void(const StepSummary&, const Points& x)> observer;
};

/// Per-step summary kept in memory (the results file has everything).
struct StepSummary {
  double load = 0;
  int newton_iterations = 0, linear_iterations = 0;
  double energy = 0, residual = 0;
  Eigen::Matrix<double, Eigen::Dynamic, 3> reactions;  ///< per boundary condition [N]
  std::optional<double> contact_area;                  ///< [m^2], with contact or obstacles
  std::optional<double> contact_force;  ///< [N]: obstacle force + sum over pairs of |pair force|
  std::optional<double> penetration;    ///< [m] deepest geometric penetration (contact pairs)
  double kinetic_energy = 0;            ///< dynamic runs: sum m |v|^2 / 2 [J]
  double potential_energy = 0;          ///< dynamic runs: E(x) without inertia and damping [J]
};

/// Outcome of a run. On failure `message` says why; completed steps are kept.
struct RunResult {
  bool success = false;
  std::string message;
  std::vector<StepSummary> steps;
  Points x;  ///< final positions (last completed step)
  PhaseTimers timers;
  double seconds = 0;
};

/// Runs `scene`, printing one progress line per step to `log`. Input errors found while
/// building the modules are thrown (InputError); solver failures are returned in the result
/// (and recorded in the results file).
RunResult run_scene(const Scene& scene, const RunOptions& options, std::ostream& log);

/// Prints the phase timing table of a run (seconds and share of the total).
void print_timing(const PhaseTimers& timers, double total_seconds, std::ostream& out);

}  // namespace depthfem
