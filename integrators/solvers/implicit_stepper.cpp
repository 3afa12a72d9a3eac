#include "integrators/solvers/implicit_stepper.hpp"

#include <stdexcept>

#include "core/error.hpp"
#include "integrators/solvers/ranks.hpp"

namespace depthfem {

ImplicitStepper::ImplicitStepper(StepLifecycle& lifecycle, ImplicitTerms terms,
                                 DynamicOptions options)
    : lifecycle_(lifecycle),
      terms_(std::move(terms)),
      options_(options),
      newton_(lifecycle.system(), lifecycle.constraints(), options.newton) {
  if (options_.integrator != Integrator::kImplicitEuler &&
      options_.integrator != Integrator::kNewmark &&
      options_.integrator != Integrator::kGeneralizedAlpha)
    throw std::logic_error("ImplicitStepper: not a one-step implicit integrator");
  if (options_.integrator != Integrator::kImplicitEuler && !terms_.inertia)
    throw std::logic_error("ImplicitStepper: Newmark and generalized-alpha need inertia");
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
  // M a = -g on the free directions: the mass matrix alone, in the System's pattern. In a
  // distributed run rank 0 adds the mass matrix (it evaluates the inertia, a whole module) and
  // every rank its part of nothing else; MUMPS solves the sum, and a is whole on every rank.
  BlockSparseMatrix M = system.matrix();
  M.set_zero();
  terms_.inertia->set_scale(1.0);
  Ranks* ranks = system.ranks();
  if (!ranks || ranks->rank() == 0) terms_.inertia->evaluate(x, nullptr, &M);
  constraints.project(M);
  VectorX a;
  LinearSolverOptions direct_options;
  direct_options.kind = LinearSolverKind::kDirect;
  LinearSolver direct(direct_options);
  if (ranks) direct.distribute(*ranks);
  if (!direct.solve(M, -g, a).reached_tolerance || !a.allFinite())
    throw SolveError("the mass matrix is singular on the free directions");
  return as_points(a);
}

void ImplicitStepper::run(Points& x, Points& v, const DynamicStart& start) {
  const bool second_order = options_.integrator != Integrator::kImplicitEuler;
  const AlphaParameters p =
      options_.integrator == Integrator::kGeneralizedAlpha
          ? chung_hulbert(options_.generalized_alpha.rho_inf)
          : AlphaParameters{0, 0, options_.newmark.beta, options_.newmark.gamma};
  const double beta = p.beta, gamma = p.gamma, af = p.alpha_f, am = p.alpha_m;
  Points a;
  if (second_order) a = start.acceleration.size() ? start.acceleration : initial_acceleration(x, v);
  const Index steps = time_step_count(options_);
  double t = start.time;
  for (Index n = first_step_after(options_, t); n < steps; ++n) {
    const double t_next = step_end_time(options_, n), h = t_next - t;
    // Newton's unknown is x^{n+1-alpha_f} (x^{n+1} itself for implicit Euler and Newmark).
    // With Newmark's predictor x~ = x^n + h v^n + h^2 (1/2 - beta) a^n, a^{n+1} = (x^{n+1} - x~) /
    // (beta h^2) and v^{n+1} = v^n + h ((1 - gamma) a^n + gamma a^{n+1}), both linear in
    // x^{n+1} = (x_af - alpha_f x^n) / (1 - alpha_f):
    //   a^{n+1-alpha_m} = s_m (x_af - anchor_m),  s_m = (1 - alpha_m) / (beta h^2 (1 - alpha_f)),
    //     anchor_m = alpha_f x^n + (1 - alpha_f) x~ - alpha_m a^n / s_m;
    //   v^{n+1-alpha_f} = s_c (x_af - anchor_c),  s_c = gamma / (beta h),
    //     anchor_c = alpha_f x^n + (1 - alpha_f) x~ - (v^n + (1 - alpha_f) h (1 - gamma) a^n) /
    //     s_c.
    // The inertia and damping tethers with these scales and anchors make the balance
    // M a^{n+1-alpha_m} + C v^{n+1-alpha_f} + grad E(x_af) = 0 the stationarity of the step's
    // potential (Newmark: alpha_m = alpha_f = 0).
    Points newmark, predicted, damping_anchor;
    double inertia_scale, damping_scale;
    if (second_order) {
      newmark = x + h * v + ((0.5 - beta) * h * h) * a;
      inertia_scale = (1 - am) / (beta * h * h * (1 - af));
      damping_scale = gamma / (beta * h);
      const Points mid = af * x + (1 - af) * newmark;
      predicted = mid - (am / inertia_scale) * a;
      damping_anchor = mid - (v + ((1 - af) * h * (1 - gamma)) * a) / damping_scale;
    } else {
      predicted = x + h * v;
      damping_anchor = x;
      inertia_scale = 1 / (h * h);
      damping_scale = 1 / h;
    }
    if (terms_.inertia) {
      terms_.inertia->set_scale(inertia_scale);
      terms_.inertia->set_anchor(predicted);
    }
    for (Tether* d : terms_.damping) {
      d->set_scale(damping_scale);
      d->set_anchor(damping_anchor);
    }
    // The prescribed motion at t^{n+1}, and the unknown's constrained part from it.
    Points target = predicted;
    lifecycle_.constraints().impose(t_next / options_.duration, target);
    Points next = af == 0 ? target : ((1 - af) * target + af * x).eval();
    const double t_af = t_next - af * h;
    lifecycle_.begin(x, t_af / options_.duration);
    NewtonResult r = newton_.solve(next);
    if (!r.converged) {
      throw SolveError("time step " + std::to_string(n) + " (t = " + std::to_string(t_next) +
                       " s) failed: " + r.failure);
    }
    if (af != 0) {
      next = (next - af * x) / (1 - af);
      lifecycle_.constraints().impose(t_next / options_.duration, next);  // exact, not rounded
      lifecycle_.set_load(t_next / options_.duration);
    }
    if (second_order) {
      const Points a_next = (next - newmark) / (beta * h * h);
      v += h * ((1 - gamma) * a + gamma * a_next);
      a = a_next;
      lifecycle_.set_acceleration(a);
    } else {
      v = (next - x) / h;
    }
    x = next;
    t = t_next;
    lifecycle_.complete(t, r, x, &v);
  }
}

}  // namespace depthfem
