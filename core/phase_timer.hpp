#pragma once
/// Wall-clock and CPU-time accumulators per named phase (force/stiffness, collision detection,
/// linear solve...).

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace depthfem {

/// CPU seconds this process has used so far, all its threads together.
double process_cpu_seconds();

/// Seconds spent per phase, in the order phases were first used: wall-clock, and the CPU time of
/// all the process's threads meanwhile (CPU / wall is the number of threads busy on average in
/// that phase; phases are timed one after another, never nested).
class PhaseTimers {
 public:
  /// Adds `seconds` of wall-clock and `cpu_seconds` of CPU time to `phase` (created on first use).
  void add(const std::string& phase, double seconds, double cpu_seconds = 0);
  /// Total wall-clock seconds of `phase` (0 if never used).
  double seconds(const std::string& phase) const;
  /// Total CPU seconds of `phase` (0 if never used).
  double cpu_seconds(const std::string& phase) const;
  /// Wall-clock seconds per phase.
  const std::vector<std::pair<std::string, double>>& phases() const { return phases_; }

  /// Times the enclosing scope into one phase.
  class Scope {
   public:
    Scope(PhaseTimers& timers, std::string phase)
        : timers_(timers),
          phase_(std::move(phase)),
          start_(std::chrono::steady_clock::now()),
          cpu_start_(process_cpu_seconds()) {}
    ~Scope() {
      timers_.add(phase_,
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(),
                  process_cpu_seconds() - cpu_start_);
    }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    PhaseTimers& timers_;
    std::string phase_;
    std::chrono::steady_clock::time_point start_;
    double cpu_start_;
  };

 private:
  std::vector<std::pair<std::string, double>> phases_;
  std::vector<double> cpu_;  // per phase, in the order of phases_
};

}  // namespace depthfem
