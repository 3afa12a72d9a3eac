#include "core/phase_timer.hpp"

#include <ctime>

namespace depthfem {

double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

void PhaseTimers::add(const std::string& phase, double seconds, double cpu_seconds) {
  for (size_t k = 0; k < phases_.size(); ++k) {
    if (phases_[k].first == phase) {
      phases_[k].second += seconds;
      cpu_[k] += cpu_seconds;
      return;
    }
  }
  phases_.emplace_back(phase, seconds);
  cpu_.push_back(cpu_seconds);
}

double PhaseTimers::seconds(const std::string& phase) const {
  for (const auto& [name, total] : phases_)
    if (name == phase) return total;
  return 0.0;
}

double PhaseTimers::cpu_seconds(const std::string& phase) const {
  for (size_t k = 0; k < phases_.size(); ++k)
    if (phases_[k].first == phase) return cpu_[k];
  return 0.0;
}

}  // namespace depthfem
