#include "integrators/solvers/implicit_stepper.hpp"

#include <stdexcept>

#include "core/error.hpp"

namespace depthfem {

ImplicitStepper::ImplicitStepper(StepLifecycle& lifecycle, ImplicitTerms terms,
                                 DynamicOptions options)
    : lifecycle_(lifecycle),
      terms_(std::move(terms)),
      options_(options),
      newton_(lifecycle.system(), lifecycle.constraints(), options.newton) {
  if (options_.integrator != Integrator::kImplicitEuler &&
      options_.integrator != Integrator::kNewmark)
    throw std::logic_error("ImplicitStepper: not an implicit integrator");
  if (options_.integrator == Integrator::kNewmark && !terms_.inertia)
    throw std::logic_error("ImplicitStepper: Newmark needs inertia");
}

Points ImplicitStepper::initial_acceleration(const Points& x, const Points& v) {
  System& system = lifecycle_.system();
  const Constraints& constraints = lifecycle_.constraints();
  terms_.inertia->set_scale(0.0);
  terms_.inertia->set_anchor(x);
  for (Tether* d : terms_.damping) {  // gradient s C (x - x_c) = C v with s = 1, x_c = x - v
    d->set_scale(1.0);
    d->set_anchor(x - v);
  }
  lifecycle_.begin(x, 0.0);
  system.prepare(x);
  VectorX g;  // hessian(), not gradient(): it binds the pattern the mass matrix assembles into
  if (!std::isfinite(system.hessian(x, g)))
    throw SolveError("the initial configuration is illegal");
  constraints.project(g);
  // M a = -g on the free directions: the mass matrix alone, in the System's pattern.
  BlockSparseMatrix M = system.matrix();
  M.set_zero();
  terms_.inertia->set_scale(1.0);
  terms_.inertia->evaluate(x, nullptr, &M);
  constraints.project(M);
  VectorX a;
  LinearSolverOptions direct_options;
  direct_options.kind = LinearSolverKind::kDirect;
  LinearSolver direct(direct_options);
  if (!direct.solve(M, -g, a).reached_tolerance || !a.allFinite())
    throw SolveError("the mass matrix is singular on the free directions");
  return as_points(a);
}

void ImplicitStepper::run(Points& x, Points& v) {
  const bool newmark = options_.integrator == Integrator::kNewmark;
  const double beta = options_.newmark.beta, gamma = options_.newmark.gamma;
  Points a;
  if (newmark) a = initial_acceleration(x, v);
  const Index steps = time_step_count(options_);
  double t = 0;
  for (Index n = 0; n < steps; ++n) {
    const double t_next = step_end_time(options_, n), h = t_next - t;
    Points predicted, damping_anchor;
    if (newmark) {
      predicted = x + h * v + ((0.5 - beta) * h * h) * a;
      damping_anchor = predicted - (beta * h / gamma) * (v + ((1 - gamma) * h) * a);
    } else {
      predicted = x + h * v;
      damping_anchor = x;
    }
    if (terms_.inertia) {
      terms_.inertia->set_scale(newmark ? 1 / (beta * h * h) : 1 / (h * h));
      terms_.inertia->set_anchor(predicted);
    }
    for (Tether* d : terms_.damping) {
      d->set_scale(newmark ? gamma / (beta * h) : 1 / h);
      d->set_anchor(damping_anchor);
    }
    Points next = predicted;
    lifecycle_.constraints().impose(t_next / options_.duration, next);
    lifecycle_.begin(x, t_next / options_.duration);
    NewtonResult r = newton_.solve(next);
    if (!r.converged) {
      throw SolveError("time step " + std::to_string(n) + " (t = " + std::to_string(t_next) +
                       " s) failed: " + r.failure);
    }
    if (newmark) {
      const Points a_next = (next - predicted) / (beta * h * h);
      v += h * ((1 - gamma) * a + gamma * a_next);
      a = a_next;
    } else {
      v = (next - x) / h;
    }
    x = next;
    t = t_next;
    lifecycle_.complete(t, r, x, &v);
  }
}

}  // namespace depthfem
