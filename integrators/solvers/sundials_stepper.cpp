#include "integrators/solvers/sundials_stepper.hpp"

#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_erkstep.h>
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_nonlinearsolver.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>

#include "core/error.hpp"

namespace depthfem {

namespace {

// Owners of the SUNDIALS objects (C handles with their own free functions).
struct ContextDeleter {
  void operator()(SUNContext ctx) const { SUNContext_Free(&ctx); }
};
struct VectorDeleter {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
struct NonlinearSolverDeleter {
  void operator()(SUNNonlinearSolver nls) const { SUNNonlinSolFree(nls); }
};

// The calls that differ between ERKStep, ARKStep and CVODE, all with the same signatures. CVODE
// has neither a post-step hook nor fixed steps (nullptr): it is advanced one internal step at a
// time instead.
struct Api {
  const char* name;  // the package, for messages
  int (*evolve)(void*, realtype, N_Vector, realtype*, int);
  int (*num_steps)(void*, long*);
  int (*last_step)(void*, realtype*);
  char* (*flag_name)(long);
  void (*free)(void**);
  int (*set_user_data)(void*, void*);
  int (*set_error_handler)(void*, ARKErrHandlerFn, void*);
  int (*tolerances)(void*, realtype, realtype);
  int (*set_order)(void*, int);
  int (*set_max_steps)(void*, long);
  int (*set_stop_time)(void*, realtype);
  int (*set_postprocess)(void*, ARKPostProcessFn);
  int (*set_fixed_step)(void*, realtype);
};
constexpr Api kErk{"arkode",
                   ERKStepEvolve,
                   ERKStepGetNumSteps,
                   ERKStepGetLastStep,
                   ERKStepGetReturnFlagName,
                   ERKStepFree,
                   ERKStepSetUserData,
                   ERKStepSetErrHandlerFn,
                   ERKStepSStolerances,
                   ERKStepSetOrder,
                   ERKStepSetMaxNumSteps,
                   ERKStepSetStopTime,
                   ERKStepSetPostprocessStepFn,
                   ERKStepSetFixedStep};
constexpr Api kArk{"arkode",
                   ARKStepEvolve,
                   ARKStepGetNumSteps,
                   ARKStepGetLastStep,
                   ARKStepGetReturnFlagName,
                   ARKStepFree,
                   ARKStepSetUserData,
                   ARKStepSetErrHandlerFn,
                   ARKStepSStolerances,
                   ARKStepSetOrder,
                   ARKStepSetMaxNumSteps,
                   ARKStepSetStopTime,
                   ARKStepSetPostprocessStepFn,
                   ARKStepSetFixedStep};
constexpr Api kCvode{"cvode",
                     CVode,
                     CVodeGetNumSteps,
                     CVodeGetLastStep,
                     CVodeGetReturnFlagName,
                     CVodeFree,
                     CVodeSetUserData,
                     CVodeSetErrHandlerFn,
                     CVodeSStolerances,
                     CVodeSetMaxOrd,
                     CVodeSetMaxNumSteps,
                     CVodeSetStopTime,
                     nullptr,
                     nullptr};

Eigen::Map<VectorX> view(N_Vector v) {
  return {N_VGetArrayPointer(v), N_VGetLength_Serial(v)};
}

// What the right-hand side and the stage solves need, their counts, and the first error.
struct Data {
  StepLifecycle& lifecycle;
  const VectorX& mass;
  const ImplicitTerms& implicit;  // empty for ERKStep
  const Api& api;
  double alpha, duration;
  Index nodes;
  NewtonSolver* newton = nullptr;  // the stage (step) solves of ARKStep (CVODE)
  NewtonOptions scene_test;        // the scene's Newton test, the floor of the stage solves'
  void* mem = nullptr;             // the stepper, for its step size and stage data
  NewtonResult interval;           // Newton work of the current output interval
  std::vector<SundialsInternalStep>* history = nullptr;
  double target = 0;  // end of the output interval being integrated [s]
  std::string error, stage_failure;

  // Positions of the state's x part with the Dirichlet conditions at t, the modules at t.
  Points positions(const Eigen::Ref<const VectorX>& x_part, double t) const {
    Points x = as_points(x_part);
    lifecycle.constraints().impose(t / duration, x);
    lifecycle.set_load(t / duration);
    return x;
  }
  // d = x - anchor on the free directions, 0 on the constrained ones: the anchor x - P d.
  Points anchor(const Points& x, VectorX d) const {
    lifecycle.constraints().project(d);
    return x - as_points(d);
  }
};

// y = (x, v) as two halves; ydot = (P v, P M^-1 (-grad E - C v)). With ARKStep's tethers in the
// System, inertia is switched off and the damping tethers give C v (anchor x - P v, scale 1).
int rhs(realtype t, N_Vector y_vec, N_Vector ydot_vec, void* user) {
  auto& d = *static_cast<Data*>(user);
  const Eigen::Map<VectorX> y = view(y_vec);
  Eigen::Map<VectorX> ydot = view(ydot_vec);
  const Index n = 3 * d.nodes;
  const Constraints& constraints = d.lifecycle.constraints();
  const Points x = d.positions(y.head(n), t);
  VectorX velocity = y.tail(n);
  constraints.project(velocity);
  if (d.implicit.inertia) {
    d.implicit.inertia->set_scale(0.0);
    d.implicit.inertia->set_anchor(x);
    for (Tether* c : d.implicit.damping) {
      c->set_scale(1.0);
      c->set_anchor(x - as_points(velocity));
    }
  }
  VectorX g;
  if (!std::isfinite(d.lifecycle.gradient(x, g))) {
    d.error = "an element inverted at t = " + std::to_string(t) + " s";
    return d.implicit.inertia ? 1 : -1;  // ARKStep retries a smaller step; ERKStep cannot
  }
  VectorX accel(n);
  for (Index i = 0; i < d.nodes; ++i)
    accel.segment<3>(3 * i) =
        -g.segment<3>(3 * i) / d.mass(i) - d.alpha * velocity.segment<3>(3 * i);
  constraints.project(accel);
  ydot.head(n) = velocity;
  ydot.tail(n) = accel;
  return 0;
}

// The implicit equation z = b + gamma f(t, z) of an ARKStep stage or a CVODE step, solved by
// Newton on the free positions (see sundials_stepper.hpp) from the first guess `start`; the
// constrained components of z stay those of b (their derivatives vanish). `correction` takes
// z - base.
int solve_implicit(Data& d, double t, double gamma, const VectorX& b, const VectorX& start,
                   N_Vector base, N_Vector correction, N_Vector weights, double tolerance) {
  const Index n = 3 * d.nodes;
  Points x = d.positions(start.head(n), t);
  const Points bx = as_points(b.head(n));
  d.implicit.inertia->set_scale(1 / (gamma * gamma));
  d.implicit.inertia->set_anchor(d.anchor(x, as_dofs(x - bx) - gamma * b.tail(n)));
  for (Tether* c : d.implicit.damping) {
    c->set_scale(1 / gamma);
    c->set_anchor(d.anchor(x, as_dofs(x - bx)));
  }
  // SUNDIALS' test: the weighted RMS norm (weights w = 1 / (rtol |y| + atol)) of the stage's
  // remaining error at most `tolerance`. A force residual r_i leaves an error of about
  // gamma^2 r_i / m_i in x_i and gamma r_i / m_i in v_i (the Newton matrix is at least
  // M / gamma^2), so Newton stops at |r ./ s|_2 <= tolerance with
  // s_i = m_i sqrt(2 n) / (gamma sqrt(gamma^2 w_x,i^2 + w_v,i^2)). It is the error control's own
  // measure, and it stays satisfiable for steps too short for positions to resolve the forces.
  // Never tighter per dof than the scene's own Newton test (the scale s_scene tolerance_scene /
  // tolerance), nor than the rounding of the positions: an error of 8 eps |x|_max in x_i leaves
  // a residual m_i 8 eps |x|_max / gamma^2, which no Newton step can remove (steps of 1e-10 s,
  // as ARKODE's first estimate can be, put it above a newton of gravity).
  const Eigen::Map<VectorX> w = view(weights);
  NewtonOptions& test = d.newton->options();
  test.tolerance = tolerance;
  test.force_scale.resize(n);
  const double root_n = std::sqrt(static_cast<double>(n));
  const double rounding = 8 * std::numeric_limits<double>::epsilon() * x.cwiseAbs().maxCoeff() *
                          root_n / (gamma * gamma * tolerance);
  for (Index i = 0; i < n; ++i) {
    const double scene = d.scene_test.force_scale.size() ? d.scene_test.force_scale(i) : 1.0;
    const double m = d.mass(i / 3);
    test.force_scale(i) =
        std::max({m * std::sqrt(2.0) * root_n / (gamma * std::hypot(gamma * w(i), w(n + i))),
                  scene * d.scene_test.tolerance / tolerance, m * rounding});
  }
  const NewtonResult r = d.newton->solve(x);
  d.interval.iterations += r.iterations;
  d.interval.linear_iterations += r.linear_iterations;
  d.interval.linear_solves += r.linear_solves;
  d.interval.factorizations += r.factorizations;
  d.interval.residuals = r.residuals;
  if (!r.converged) {
    d.stage_failure = "an implicit solve at t = " + std::to_string(t) + " s failed: " + r.failure;
    return SUN_NLS_CONV_RECVR;
  }
  // z_x from Newton; z_v from the velocity equation z_v = b_v + gamma P M^-1 (-grad E - C v) at
  // z_x (the gradient without inertia, damping at the velocity (z_x - b_x) / gamma), not from
  // (z_x - b_x) / gamma, which would amplify the rounding of the positions by 1 / gamma.
  VectorX dx = as_dofs(x - bx);
  d.lifecycle.constraints().project(dx);
  d.implicit.inertia->set_scale(0.0);
  VectorX g;
  if (!std::isfinite(d.lifecycle.gradient(x, g))) return SUN_NLS_CONV_RECVR;
  for (Index i = 0; i < d.nodes; ++i) g.segment<3>(3 * i) /= d.mass(i);
  d.lifecycle.constraints().project(g);
  Eigen::Map<VectorX> out = view(correction);
  out.head(n) = b.head(n) + dx;
  out.tail(n) = b.tail(n) - gamma * g;
  out -= view(base);
  return SUN_NLS_SUCCESS;
}

// ARKStep's stage equation: b = zpred + sdata, the correction z - zpred.
int solve_stage(SUNNonlinearSolver nls, N_Vector predicted, N_Vector correction, N_Vector weights,
                realtype tolerance, booleantype /*setup*/, void* mem) {
  realtype t = 0, gamma = 0;
  N_Vector zpred = nullptr, z = nullptr, fi = nullptr, sdata = nullptr;
  void* user = nullptr;
  if (ARKStepGetNonlinearSystemData(mem, &t, &zpred, &z, &fi, &gamma, &sdata, &user) != 0)
    return SUN_NLS_MEM_NULL;
  return solve_implicit(*static_cast<Data*>(nls->content), t, gamma, view(zpred) + view(sdata),
                        view(predicted) + view(correction), zpred, correction, weights, tolerance);
}

// CVODE's BDF step: rl1 zn1 + ycor - gamma f(t, ypred + ycor) = 0 for the correction ycor, that
// is y = b + gamma f(t, y) with b = ypred - rl1 zn1 (zn1: the Nordsieck array's h y').
int solve_bdf_step(SUNNonlinearSolver nls, N_Vector predicted, N_Vector correction,
                   N_Vector weights, realtype tolerance, booleantype /*setup*/, void* mem) {
  realtype t = 0, gamma = 0, rl1 = 0;
  N_Vector ypred = nullptr, y = nullptr, fn = nullptr, zn1 = nullptr;
  void* user = nullptr;
  if (CVodeGetNonlinearSystemData(mem, &t, &ypred, &y, &fn, &gamma, &rl1, &zn1, &user) != 0)
    return SUN_NLS_MEM_NULL;
  return solve_implicit(*static_cast<Data*>(nls->content), t, gamma, view(ypred) - rl1 * view(zn1),
                        view(predicted) + view(correction), ypred, correction, weights, tolerance);
}

SUNNonlinearSolver_Type stage_solver_type(SUNNonlinearSolver) {
  return SUNNONLINEARSOLVER_ROOTFIND;
}
int ignore_system_function(SUNNonlinearSolver, SUNNonlinSolSysFn) {
  return SUN_NLS_SUCCESS;
}
int stage_solver_iterations(SUNNonlinearSolver nls, long* iterations) {
  *iterations = static_cast<Data*>(nls->content)->interval.iterations;
  return SUN_NLS_SUCCESS;
}
int free_stage_solver(SUNNonlinearSolver nls) {
  nls->content = nullptr;
  SUNNonlinSolFreeEmpty(nls);
  return SUN_NLS_SUCCESS;
}

// After every accepted internal step: its time and size go to the step-size history, and, up to
// the output time, the modules' internal variables (a viscoelastic history) move to it, so that
// the next stages relax from there. A step past the output time (ARK_NORMAL steps past it and
// interpolates) is left to the step's completion at the output time, which must not lie behind
// the history.
int internal_step_done(realtype t, N_Vector y_vec, void* user) {
  auto& d = *static_cast<Data*>(user);
  realtype h = 0;
  if (d.api.last_step(d.mem, &h)) return -1;
  d.history->push_back({t, h});
  if (t > d.target) return 0;
  d.lifecycle.system().complete_step(d.positions(view(y_vec).head(3 * d.nodes), t));
  return 0;
}

void capture_error(int /*code*/, const char* /*module*/, const char* function, char* message,
                   void* user) {
  auto& d = *static_cast<Data*>(user);
  if (d.error.empty()) d.error = std::string(function) + ": " + message;
}

void check(int flag, const char* call) {
  if (flag < 0)
    throw SolveError(std::string("sundials: ") + call + " failed with flag " +
                     std::to_string(flag));
}

}  // namespace

SundialsStepper::SundialsStepper(StepLifecycle& lifecycle, VectorX mass, DynamicOptions options,
                                 ImplicitTerms implicit)
    : lifecycle_(lifecycle),
      mass_(std::move(mass)),
      options_(options),
      implicit_(std::move(implicit)) {
  const int order = options_.arkode.order;
  const Integrator integrator = options_.integrator;
  if (integrator == Integrator::kCvodeBdf) {
    if (options_.cvode.max_order < 1 || options_.cvode.max_order > 5) {
      throw InputError("cvode_bdf: no BDF of order " + std::to_string(options_.cvode.max_order) +
                       " (expected 1 to 5)");
    }
  } else if (integrator == Integrator::kArkodeDirk && !has_dirk_table(order)) {
    throw InputError("arkode_dirk: no diagonally implicit table of order " + std::to_string(order) +
                     " (expected 2, 3, 4 or 5)");
  }
  if (integrator != Integrator::kArkode) {
    if (!implicit_.inertia)
      throw std::logic_error("SundialsStepper: an implicit method needs inertia");
    return;
  }
  if (!has_erk_table(order)) {
    throw InputError("arkode: no explicit Runge-Kutta table of order " + std::to_string(order) +
                     " (expected 2, 3, 4, 5, 6 or 8)");
  }
  if (options_.damping.stiffness != 0) {
    throw InputError("arkode: stiffness-proportional damping needs an implicit integrator");
  }
  if (options_.mass != MassMatrix::kLumped)
    throw InputError("arkode: a consistent mass matrix needs an implicit integrator");
}

void SundialsStepper::run(Points& x, Points& v) {
  const Integrator integrator = options_.integrator;
  const bool bdf = integrator == Integrator::kCvodeBdf;
  const bool implicit = integrator != Integrator::kArkode;
  const Api& api = bdf ? kCvode : implicit ? kArk : kErk;
  const Constraints& constraints = lifecycle_.constraints();
  const Index nodes = static_cast<Index>(x.rows());
  const Index n = 3 * nodes;
  SUNContext raw_ctx = nullptr;
  check(SUNContext_Create(nullptr, &raw_ctx), "SUNContext_Create");
  const std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextDeleter> ctx(raw_ctx);
  const std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorDeleter> y(
      N_VNew_Serial(2 * n, ctx.get()));
  view(y.get()) << as_dofs(x), as_dofs(v);

  // With an implicit method the damping is in the System's tethers, not alpha.
  NewtonSolver newton(lifecycle_.system(), constraints, options_.newton);
  Data data{.lifecycle = lifecycle_,
            .mass = mass_,
            .implicit = implicit_,
            .api = api,
            .alpha = implicit ? 0.0 : options_.damping.mass,
            .duration = options_.duration,
            .nodes = nodes,
            .newton = &newton,
            .scene_test = options_.newton,
            .mem = nullptr,
            .interval = {},
            .history = &history_,
            .error = {},
            .stage_failure = {}};
  history_.clear();
  const auto free_stepper = [&api](void* mem) { api.free(&mem); };
  std::unique_ptr<void, decltype(free_stepper)> mem(nullptr, free_stepper);
  if (bdf) {
    mem.reset(CVodeCreate(CV_BDF, ctx.get()));
    if (mem) check(CVodeInit(mem.get(), rhs, 0.0, y.get()), "CVodeInit");
  } else {
    mem.reset(implicit ? ARKStepCreate(nullptr, rhs, 0.0, y.get(), ctx.get())
                       : ERKStepCreate(rhs, 0.0, y.get(), ctx.get()));
  }
  if (!mem) throw SolveError(std::string(api.name) + ": creating the stepper failed");
  data.mem = mem.get();
  std::unique_ptr<std::remove_pointer_t<SUNNonlinearSolver>, NonlinearSolverDeleter> stage_solver;
  if (implicit) {
    stage_solver.reset(SUNNonlinSolNewEmpty(ctx.get()));
    if (!stage_solver) throw SolveError("sundials: SUNNonlinSolNewEmpty failed");
    stage_solver->content = &data;
    stage_solver->ops->gettype = stage_solver_type;
    stage_solver->ops->solve = bdf ? solve_bdf_step : solve_stage;
    stage_solver->ops->setsysfn = ignore_system_function;
    stage_solver->ops->getnumiters = stage_solver_iterations;
    stage_solver->ops->free = free_stage_solver;
  }
  if (bdf) {
    check(CVodeSetNonlinearSolver(mem.get(), stage_solver.get()), "CVodeSetNonlinearSolver");
  } else if (implicit) {
    check(ARKStepSetNonlinearSolver(mem.get(), stage_solver.get()), "ARKStepSetNonlinearSolver");
    // The stage solve leaves z with z = b + gamma f(z): f follows from it without evaluating.
    check(ARKStepSetDeduceImplicitRhs(mem.get(), SUNTRUE), "ARKStepSetDeduceImplicitRhs");
  }
  const ErrorControl& control = bdf ? static_cast<const ErrorControl&>(options_.cvode)
                                    : static_cast<const ErrorControl&>(options_.arkode);
  check(api.set_user_data(mem.get(), &data), "SetUserData");
  check(api.set_error_handler(mem.get(), capture_error, &data), "SetErrHandlerFn");
  check(api.tolerances(mem.get(), control.relative_tolerance, control.absolute_tolerance),
        "SStolerances");
  check(api.set_order(mem.get(), bdf ? options_.cvode.max_order : options_.arkode.order),
        "SetOrder");
  check(api.set_max_steps(mem.get(), control.max_steps), "SetMaxNumSteps");
  check(api.set_stop_time(mem.get(), options_.duration), "SetStopTime");
  // BDF of order 3 to 5 is not stable on the whole imaginary axis, where undamped elastic modes
  // lie: CVODE's stability limit detection lowers the order where it sees them grow.
  if (bdf) check(CVodeSetStabLimDet(mem.get(), SUNTRUE), "CVodeSetStabLimDet");
  if (api.set_postprocess)
    check(api.set_postprocess(mem.get(), internal_step_done), "SetPostprocessStepFn");
  if (!bdf && options_.arkode.fixed_step)
    check(api.set_fixed_step(mem.get(), options_.time_step), "SetFixedStep");

  // Advances y to the output time `target` (t: the time reached). ARKODE steps past it and
  // interpolates; CVODE is taken one internal step at a time (each handed to internal_step_done,
  // as ARKODE's post-step hook does; its own step limit counts within one call, so the interval's
  // is kept here), then interpolated back to the target.
  realtype reached = 0;  // CVODE: the end of its last internal step
  const auto advance = [&](double target, realtype& t) {
    if (!bdf) return api.evolve(mem.get(), target, y.get(), &t, ARK_NORMAL);
    for (long taken = 0; reached < target; ++taken) {
      t = reached;
      if (taken == control.max_steps) {
        data.error = "more than " + std::to_string(control.max_steps) +
                     " internal steps in the output interval";
        return CV_TOO_MUCH_WORK;
      }
      const int flag = api.evolve(mem.get(), target, y.get(), &reached, CV_ONE_STEP);
      if (flag < 0) return flag;
      internal_step_done(reached, y.get(), &data);
    }
    t = target;
    return CVodeGetDky(mem.get(), target, 0, y.get());
  };

  const Index steps = time_step_count(options_);
  long internal_before = 0;
  double t_start = 0;
  for (Index k = 0; k < steps; ++k) {
    const double target = step_end_time(options_, k);
    lifecycle_.begin(x, t_start / options_.duration);
    data.interval = NewtonResult();
    data.target = target;
    realtype t = 0;
    const int flag = advance(target, t);
    if (flag < 0) {
      char* name = api.flag_name(flag);
      std::string why = data.error;
      if (!data.stage_failure.empty()) why += (why.empty() ? "" : "; last ") + data.stage_failure;
      const std::string message = std::string(api.name) + ": " + name +
                                  " at t = " + std::to_string(t) + " s" +
                                  (why.empty() ? "" : ": " + why);
      std::free(name);
      throw SolveError(message);
    }
    const Points before = x;
    x = as_points(view(y.get()).head(n));
    constraints.impose(t / options_.duration, x);
    // Free directions take the stepper's velocity, constrained ones the prescribed motion over
    // the interval.
    VectorX velocity = view(y.get()).tail(n);
    VectorX prescribed = as_dofs(x - before) / (t - t_start);
    constraints.project(velocity);
    VectorX free_part = prescribed;
    constraints.project(free_part);
    v = as_points(velocity + prescribed - free_part);
    long internal = 0;
    api.num_steps(mem.get(), &internal);
    // ERKStep: no solve, iterations = internal Runge-Kutta steps of the interval; ARKStep and
    // CVODE: the Newton work of their stage (step) solves.
    NewtonResult step = data.interval;
    step.converged = true;
    const int internal_steps = static_cast<int>(internal - internal_before);
    if (!implicit) step.iterations = internal_steps;
    if (step.residuals.empty()) step.residuals.push_back(0.0);
    internal_before = internal;
    t_start = t;
    lifecycle_.set_load(t / options_.duration);
    lifecycle_.complete(t, step, x, &v, false, internal_steps);
  }
}

}  // namespace depthfem
