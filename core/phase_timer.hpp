#pragma once
/// Wall-clock accumulators per named phase (force/stiffness, collision detection, linear solve...).

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace depthfem {

/// Seconds spent per phase, in the order phases were first used.
class PhaseTimers {
 public:
  /// Adds `seconds` to `phase` (created on first use).
  void add(const std::string& phase, double seconds);
  /// Total seconds of `phase` (0 if never used).
  double seconds(const std::string& phase) const;
  const std::vector<std::pair<std::string, double>>& phases() const { return phases_; }

  /// Times the enclosing scope into one phase.
  class Scope {
   public:
    Scope(PhaseTimers& timers, std::string phase)
        : timers_(timers), phase_(std::move(phase)), start_(std::chrono::steady_clock::now()) {}
    ~Scope() {
      timers_.add(phase_,
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
    }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    PhaseTimers& timers_;
    std::string phase_;
    std::chrono::steady_clock::time_point start_;
  };

 private:
  std::vector<std::pair<std::string, double>> phases_;
};

}  // namespace depthfem
