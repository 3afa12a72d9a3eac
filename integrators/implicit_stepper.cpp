#include "integrators/implicit_stepper.hpp"

#include <stdexcept>

#include "core/error.hpp"

namespace depthfem {

ImplicitStepper::ImplicitStepper(System& system, const Constraints& constraints,
                                 ImplicitTerms terms, DynamicOptions options)
    : system_(system),
      constraints_(constraints),
      terms_(std::move(terms)),
      options_(options),
      newton_(system, constraints, options.newton) {
  if (options_.integrator != Integrator::kImplicitEuler &&
      options_.integrator != Integrator::kNewmark)
    throw std::logic_error("ImplicitStepper: not an implicit integrator");
  if (options_.integrator == Integrator::kNewmark && !terms_.inertia)
    throw std::logic_error("ImplicitStepper: Newmark needs inertia");
  if (terms_.inertia) tethers_.push_back(terms_.inertia);
  tethers_.insert(tethers_.end(), terms_.damping.begin(), terms_.damping.end());
}

Points ImplicitStepper::initial_acceleration(const Points& x, const Points& v) {
  terms_.inertia->set_scale(0.0);
  terms_.inertia->set_anchor(x);
  for (Tether* d : terms_.damping) {  // gradient s C (x - x_c) = C v with s = 1, x_c = x - v
    d->set_scale(1.0);
    d->set_anchor(x - v);
  }
  system_.begin_step(x, 0.0);
  system_.prepare(x);
  VectorX g;  // hessian(), not gradient(): it binds the pattern a stiffness tether assembles into
  if (!std::isfinite(system_.hessian(x, g)))
    throw SolveError("the initial configuration is illegal");
  constraints_.project(g);
  Points a = -as_points(g);
  a.array().colwise() /= terms_.inertia->stiffness().array();
  return a;
}

void ImplicitStepper::run(Points& x, Points& v, const StepCallback& on_step) {
  const double h = options_.time_step;
  const bool newmark = options_.integrator == Integrator::kNewmark;
  Points a;
  if (newmark) a = initial_acceleration(x, v);
  if (terms_.inertia) terms_.inertia->set_scale((newmark ? 4.0 : 1.0) / (h * h));
  for (Tether* d : terms_.damping) d->set_scale((newmark ? 2.0 : 1.0) / h);
  const Index steps = time_step_count(options_);
  for (Index n = 0; n < steps; ++n) {
    const auto start = std::chrono::steady_clock::now();
    const double t = (n + 1) * h;
    const Points predicted = newmark ? Points(x + h * v + (0.25 * h * h) * a) : Points(x + h * v);
    if (terms_.inertia) terms_.inertia->set_anchor(predicted);
    const Points damping_anchor = newmark ? Points(x + 0.5 * h * v) : x;
    for (Tether* d : terms_.damping) d->set_anchor(damping_anchor);
    Points next = predicted;
    constraints_.impose(t / options_.duration, next);
    system_.begin_step(x, t / options_.duration);
    NewtonResult r = newton_.solve(next);
    if (!r.converged) {
      throw SolveError("time step " + std::to_string(n) + " (t = " + std::to_string(t) +
                       " s) failed: " + r.failure);
    }
    if (newmark) {
      const Points a_next = (4.0 / (h * h)) * (next - predicted);
      v += (0.5 * h) * (a + a_next);
      a = a_next;
    } else {
      v = (next - x) / h;
    }
    x = next;
    report_time_step(system_, tethers_, n, t, std::move(r), x, v, start, on_step);
  }
}

}  // namespace depthfem
