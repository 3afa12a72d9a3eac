#include "integrators/implicit_euler.hpp"

#include <chrono>
#include <cmath>

#include "core/error.hpp"

namespace depthfem {

Index time_step_count(const DynamicOptions& options) {
  return static_cast<Index>(std::ceil(options.duration / options.time_step - 1e-9));
}

void report_time_step(System& system, Index index, double t, NewtonResult newton, const Points& x, const Points& v,
                      std::chrono::steady_clock::time_point start,
                      const std::function<void(const DynamicStep&)>& on_step) {
  DynamicStep step;
  step.index = index;
  step.time = t;
  step.newton = std::move(newton);
  step.x = &x;
  step.v = &v;
  system.gradient(x, step.gradient);
  step.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  on_step(step);
}

void ImplicitEuler::run(Points& x, Points& v, const std::function<void(const DynamicStep&)>& on_step) {
  const double h = options_.time_step;
  const Index steps = time_step_count(options_);
  inertia_.set_scale(1.0 / (h * h));
  for (Index n = 0; n < steps; ++n) {
    const auto start = std::chrono::steady_clock::now();
    const double t = (n + 1) * h;
    const Points predicted = x + h * v;
    Points next = predicted;
    constraints_.impose(t / options_.duration, next);
    inertia_.set_anchor(predicted);
    system_.begin_step(x, t / options_.duration);
    NewtonResult r = newton_.solve(next);
    if (!r.converged) {
      throw SolveError("time step " + std::to_string(n) + " (t = " + std::to_string(t) + " s) failed: " + r.failure);
    }
    v = (next - x) / h;
    x = next;
    report_time_step(system_, n, t, std::move(r), x, v, start, on_step);
  }
}

}  // namespace depthfem
