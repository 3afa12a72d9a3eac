#include "integrators/dynamics.hpp"

#include <cmath>

namespace depthfem {

Index time_step_count(const DynamicOptions& options) {
  return static_cast<Index>(std::ceil(options.duration / options.time_step - 1e-9));
}

void report_time_step(System& system, std::span<Tether* const> tethers, Index index, double t,
                      NewtonResult newton, const Points& x, const Points& v,
                      std::chrono::steady_clock::time_point start, const StepCallback& on_step) {
  DynamicStep step;
  step.index = index;
  step.time = t;
  step.newton = std::move(newton);
  step.x = &x;
  step.v = &v;
  step.potential_energy = system.gradient(x, step.gradient);
  for (const Tether* tether : tethers)
    step.potential_energy -= tether->evaluate(x, nullptr, nullptr);
  step.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  on_step(step);
}

}  // namespace depthfem
