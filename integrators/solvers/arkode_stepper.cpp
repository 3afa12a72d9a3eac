#include "integrators/solvers/arkode_stepper.hpp"

#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <cmath>
#include <cstdlib>
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
struct StepperDeleter {
  void operator()(void* mem) const { ERKStepFree(&mem); }
};

// What the right-hand side needs, and the first error it or ARKODE reports.
struct RhsData {
  StepLifecycle& lifecycle;
  const VectorX& mass;
  double alpha, duration;
  Index nodes;
  double target = 0;  ///< end of the output interval being integrated [s]
  std::string error;
};

Eigen::Map<VectorX> view(N_Vector v) {
  return {N_VGetArrayPointer(v), N_VGetLength_Serial(v)};
}

// y = (x, v) interleaved per block; ydot = (P v, P M^-1 (-g - alpha M v)).
int rhs(realtype t, N_Vector y_vec, N_Vector ydot_vec, void* user) {
  auto& d = *static_cast<RhsData*>(user);
  const Eigen::Map<VectorX> y = view(y_vec);
  Eigen::Map<VectorX> ydot = view(ydot_vec);
  const Index n = 3 * d.nodes;
  Points x = as_points(y.head(n));
  const Constraints& constraints = d.lifecycle.constraints();
  constraints.impose(t / d.duration, x);
  d.lifecycle.set_load(t / d.duration);
  VectorX g;
  if (!std::isfinite(d.lifecycle.gradient(x, g))) {
    d.error = "an element inverted at t = " + std::to_string(t) + " s";
    return -1;  // unrecoverable: ERKStep has no step retry on right-hand-side failures
  }
  VectorX velocity = y.tail(n);
  VectorX accel(n);
  for (Index i = 0; i < d.nodes; ++i)
    accel.segment<3>(3 * i) =
        -g.segment<3>(3 * i) / d.mass(i) - d.alpha * velocity.segment<3>(3 * i);
  constraints.project(velocity);
  constraints.project(accel);
  ydot.head(n) = velocity;
  ydot.tail(n) = accel;
  return 0;
}

// After every accepted internal step up to the output time: the modules' internal variables (a
// viscoelastic history) move to it, so that the next stages relax from there. A step past the
// output time (ARK_NORMAL steps past it and interpolates) is left to the step's completion at
// the output time, which must not lie behind the history.
int internal_step_done(realtype t, N_Vector y_vec, void* user) {
  auto& d = *static_cast<RhsData*>(user);
  if (t > d.target) return 0;
  Points x = as_points(view(y_vec).head(3 * d.nodes));
  d.lifecycle.constraints().impose(t / d.duration, x);
  d.lifecycle.set_load(t / d.duration);
  d.lifecycle.system().complete_step(x);
  return 0;
}

void capture_error(int /*code*/, const char* /*module*/, const char* function, char* message,
                   void* user) {
  auto& d = *static_cast<RhsData*>(user);
  if (d.error.empty()) d.error = std::string(function) + ": " + message;
}

void check(int flag, const char* call) {
  if (flag < 0)
    throw SolveError(std::string("arkode: ") + call + " failed with flag " + std::to_string(flag));
}

}  // namespace

ArkodeStepper::ArkodeStepper(StepLifecycle& lifecycle, VectorX mass, DynamicOptions options)
    : lifecycle_(lifecycle), mass_(std::move(mass)), options_(options) {
  if (!has_erk_table(options_.arkode.order)) {
    throw InputError("arkode: no explicit Runge-Kutta table of order " +
                     std::to_string(options_.arkode.order) + " (expected 2, 3, 4, 5, 6 or 8)");
  }
  if (options_.damping.stiffness != 0) {
    throw InputError("arkode: stiffness-proportional damping needs an implicit integrator");
  }
  if (options_.mass != MassMatrix::kLumped)
    throw InputError("arkode: a consistent mass matrix needs an implicit integrator");
}

void ArkodeStepper::run(Points& x, Points& v) {
  const Constraints& constraints = lifecycle_.constraints();
  const Index nodes = static_cast<Index>(x.rows());
  const Index n = 3 * nodes;
  SUNContext raw_ctx = nullptr;
  check(SUNContext_Create(nullptr, &raw_ctx), "SUNContext_Create");
  const std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextDeleter> ctx(raw_ctx);
  const std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorDeleter> y(
      N_VNew_Serial(2 * n, ctx.get()));
  view(y.get()) << as_dofs(x), as_dofs(v);

  RhsData data{lifecycle_, mass_, options_.damping.mass, options_.duration, nodes, 0.0, {}};
  const std::unique_ptr<void, StepperDeleter> mem(ERKStepCreate(rhs, 0.0, y.get(), ctx.get()));
  if (!mem) throw SolveError("arkode: ERKStepCreate failed");
  const ArkodeOptions& o = options_.arkode;
  check(ERKStepSetUserData(mem.get(), &data), "ERKStepSetUserData");
  check(ERKStepSetErrHandlerFn(mem.get(), capture_error, &data), "ERKStepSetErrHandlerFn");
  check(ERKStepSStolerances(mem.get(), o.relative_tolerance, o.absolute_tolerance),
        "ERKStepSStolerances");
  check(ERKStepSetOrder(mem.get(), o.order), "ERKStepSetOrder");
  check(ERKStepSetMaxNumSteps(mem.get(), o.max_steps), "ERKStepSetMaxNumSteps");
  check(ERKStepSetStopTime(mem.get(), options_.duration), "ERKStepSetStopTime");
  check(ERKStepSetPostprocessStepFn(mem.get(), internal_step_done), "ERKStepSetPostprocessStepFn");

  const Index steps = time_step_count(options_);
  long internal_before = 0;
  double t_start = 0;
  for (Index k = 0; k < steps; ++k) {
    const double target = step_end_time(options_, k);
    lifecycle_.begin(x, t_start / options_.duration);
    data.target = target;
    realtype t = 0;
    const int flag = ERKStepEvolve(mem.get(), target, y.get(), &t, ARK_NORMAL);
    if (flag < 0) {
      char* name = ERKStepGetReturnFlagName(flag);
      const std::string message = "arkode: " + std::string(name) + " at t = " + std::to_string(t) +
                                  " s" + (data.error.empty() ? "" : ": " + data.error);
      std::free(name);
      throw SolveError(message);
    }
    const Points before = x;
    x = as_points(view(y.get()).head(n));
    constraints.impose(t / options_.duration, x);
    // Free directions take ARKODE's velocity, constrained ones the prescribed motion over the
    // interval.
    VectorX velocity = view(y.get()).tail(n);
    VectorX prescribed = as_dofs(x - before) / (t - t_start);
    constraints.project(velocity);
    VectorX free_part = prescribed;
    constraints.project(free_part);
    v = as_points(velocity + prescribed - free_part);
    long internal = 0;
    ERKStepGetNumSteps(mem.get(), &internal);
    NewtonResult
        explicit_step;  // no solve; iterations = internal Runge-Kutta steps of the interval
    explicit_step.converged = true;
    explicit_step.iterations = static_cast<int>(internal - internal_before);
    explicit_step.residuals.push_back(0.0);
    internal_before = internal;
    t_start = t;
    lifecycle_.set_load(t / options_.duration);
    lifecycle_.complete(t, explicit_step, x, &v);
  }
}

}  // namespace depthfem
