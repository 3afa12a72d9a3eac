// The time steppers on one mass: free fall under gravity and a mass on a linear spring (the
// harmonic oscillator), each against its closed form: implicit Euler's and symplectic Euler's
// discrete solutions, Newmark's exactness for constant acceleration and its discrete frequency
// with exact energy conservation, ARKODE and CVODE to their tolerances.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "core/error.hpp"
#include "integrators/forces/gravity.hpp"
#include "integrators/run_stepper.hpp"

namespace depthfem {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// One node of mass m [kg], on a spring k [N/m] to the origin (none for k = 0), under gravity g
// [m/s^2], starting at x0 with velocity v0.
struct Problem {
  double m = 2.0;
  double k = 0;
  Vec3 g = Vec3::Zero();
  Vec3 x0 = Vec3::Zero(), v0 = Vec3::Zero();
  double omega() const { return std::sqrt(k / m); }
};

// Every completed step: its record, positions and velocities.
struct Trajectory {
  std::vector<StepRecord> steps;
  std::vector<Vec3> x, v;
  std::vector<SundialsInternalStep> internal;  ///< SUNDIALS steppers: the internal steps
  /// The internal steps that reached an output at time t: those ending before it and the one
  /// ending at or past it.
  double internal_steps_to(double t) const {
    return 1.0 + static_cast<double>(std::count_if(internal.begin(), internal.end(),
                                                   [t](const auto& s) { return s.time < t; }));
  }
  /// The total energy of step n: potential (spring and gravity) plus kinetic.
  double energy(size_t n) const { return steps[n].energy + steps[n].kinetic_energy; }
};

DynamicOptions options_for(Integrator scheme, double h, double duration) {
  DynamicOptions o;
  o.integrator = scheme;
  o.time_step = h;
  o.duration = duration;
  // The incremental potentials here are quadratic: one Newton step lands on the minimiser up to
  // round-off, and the tolerance only has to be above the round-off of the residual so that
  // Newton stops there (a step stiffness m / (beta h^2) = 3200 N/m times an ulp of 10 m is
  // 6e-12 N; a tolerance below it fails the line search).
  o.newton.tolerance = 1e-9;
  o.arkode.relative_tolerance = 1e-8;
  o.arkode.absolute_tolerance = 1e-12;
  o.cvode.relative_tolerance = 1e-8;
  o.cvode.absolute_tolerance = 1e-12;
  return o;
}

Trajectory simulate(const Problem& p, const DynamicOptions& o) {
  PhaseTimers timers;
  System system(1, timers);
  if (p.k > 0) {
    auto spring = std::make_unique<NodalSpring>("spring", VectorX::Constant(1, p.k));
    spring->set_anchor(Points::Zero(1, 3));
    system.add(std::move(spring));
  }
  if (!p.g.isZero()) system.add(std::make_unique<Gravity>(VectorX::Constant(1, p.m), p.g, false));
  const bool implicit =
      o.integrator != Integrator::kSymplecticEuler && o.integrator != Integrator::kArkode;
  NodalSpring* inertia =
      implicit ? &system.add(std::make_unique<NodalSpring>("inertia", VectorX::Constant(1, p.m)))
               : nullptr;
  const NodalSpring mass("mass", VectorX::Constant(1, p.m));  // 1/2 m v^2 for the records
  LifecycleTerms terms;
  if (inertia) terms.excluded = {inertia};
  terms.mass = &mass;
  const Constraints none;
  Trajectory out;
  StepLifecycle lifecycle(system, none, terms,
                          [&](const StepRecord& s, const Points& x, const Points* v) {
                            out.steps.push_back(s);
                            out.x.push_back(x.row(0).transpose());
                            out.v.push_back(v->row(0).transpose());
                          });
  Points x = p.x0.transpose(), v = p.v0.transpose();
  const VectorX m = VectorX::Constant(1, p.m);
  // A spring is stable below h = 2 / omega (symplectic Euler); free fall at any step.
  out.internal =
      testing::run_stepper(lifecycle, m, o, {inertia, {}}, p.k > 0 ? 2 / p.omega() : kInf, x, v);
  return out;
}

Problem free_fall() {
  Problem p;
  p.g = Vec3(0, 0, -9.81);
  p.x0 = Vec3(0, 0, 10);
  p.v0 = Vec3(1, 0, 2);
  return p;
}

// Implicit Euler (v_(n+1) = v_n + h g, x_(n+1) = x_n + h v_(n+1)) and symplectic Euler (the
// same two updates for a constant force) land on x_n = x0 + n h v0 + h^2 g n (n + 1) / 2,
// v_n = v0 + n h g: h^2 g n / 2 further along g than the exact parabola.
void expect_discrete_free_fall(Integrator scheme) {
  const Problem p = free_fall();
  const double h = 0.05;
  const Trajectory run = simulate(p, options_for(scheme, h, 1.0));
  ASSERT_EQ(run.steps.size(), 20u);
  for (size_t i = 0; i < run.x.size(); ++i) {
    const double n = static_cast<double>(i + 1);
    EXPECT_EQ(run.steps[i].load, n / 20);  // the decimal times, the last exactly 1 s
    const Vec3 x = p.x0 + n * h * p.v0 + 0.5 * h * h * n * (n + 1) * p.g;
    const Vec3 v = p.v0 + n * h * p.g;
    // Round-off only (coordinates of 10 m, 20 steps; measured 1.2e-13 m): 1e-12 m, and
    // 1e-12 m / h for velocities taken as (x_(n+1) - x_n) / h.
    EXPECT_LE((run.x[i] - x).norm(), 1e-12) << "step " << i;
    EXPECT_LE((run.v[i] - v).norm(), 1e-12 / h) << "step " << i;
  }
  // The discrete solution is not the exact parabola (the test tells them apart).
  const Vec3 exact = p.x0 + p.v0 + 0.5 * p.g;
  EXPECT_GT((run.x.back() - exact).norm(), 0.2);
}

TEST(ImplicitStepper, ImplicitEulerFreeFallIsItsDiscreteSolution) {
  expect_discrete_free_fall(Integrator::kImplicitEuler);
}

TEST(SymplecticEuler, FreeFallIsItsDiscreteSolution) {
  expect_discrete_free_fall(Integrator::kSymplecticEuler);
}

// Newmark's average acceleration and ERKStep of order >= 2 integrate a constant acceleration
// without truncation error: x = x0 + v0 t + g t^2 / 2, v = v0 + g t.
void expect_exact_free_fall(Integrator scheme, double tolerance, double velocity_tolerance) {
  const Problem p = free_fall();
  const Trajectory run = simulate(p, options_for(scheme, 0.05, 1.0));
  ASSERT_EQ(run.steps.size(), 20u);
  for (size_t i = 0; i < run.x.size(); ++i) {
    const double t = run.steps[i].load;
    EXPECT_LE((run.x[i] - (p.x0 + t * p.v0 + 0.5 * t * t * p.g)).norm(), tolerance) << "t = " << t;
    EXPECT_LE((run.v[i] - (p.v0 + t * p.g)).norm(), velocity_tolerance) << "t = " << t;
  }
}

TEST(ImplicitStepper, NewmarkFreeFallIsExact) {
  // Round-off only. Velocities come from accelerations (x_(n+1) - x_pred) / (beta h^2): an ulp
  // of 10 m over beta h^2, times gamma h, is 7e-14 m/s per step (measured 1.0e-12 m/s after 20:
  // allowed 1e-12 m / h); positions integrate that drift, h n^2 / 2 x 7e-14 m/s = 7e-13 m after
  // n = 20 steps (measured 5.5e-13 m: allowed 1e-11 m).
  expect_exact_free_fall(Integrator::kNewmark, 1e-11, 1e-12 / 0.05);
}

// Generalized-alpha, a Newmark scheme on weighted mid-step forces, starts from the acceleration
// the forces give (here g): a constant acceleration is integrated exactly, up to the same
// round-off as Newmark's.
TEST(ImplicitStepper, GeneralizedAlphaFreeFallIsExact) {
  for (const double rho : {0.0, 0.5, 1.0}) {
    SCOPED_TRACE(rho);
    const Problem p = free_fall();
    DynamicOptions o = options_for(Integrator::kGeneralizedAlpha, 0.05, 1.0);
    o.generalized_alpha.rho_inf = rho;
    const Trajectory run = simulate(p, o);
    ASSERT_EQ(run.steps.size(), 20u);
    for (size_t i = 0; i < run.x.size(); ++i) {
      const double t = run.steps[i].load;
      EXPECT_LE((run.x[i] - (p.x0 + t * p.v0 + 0.5 * t * t * p.g)).norm(), 1e-11) << "t = " << t;
      EXPECT_LE((run.v[i] - (p.v0 + t * p.g)).norm(), 1e-12 / 0.05) << "t = " << t;
    }
  }
}

TEST(SundialsStepper, FreeFallWithinItsTolerance) {
  // No truncation error, so well within one step's error allowance rtol |y| + atol
  // (1e-8 x 10 m + 1e-12 m), for the explicit and the diagonally implicit methods.
  const double allowance = 1e-8 * 10 + 1e-12;
  expect_exact_free_fall(Integrator::kArkode, allowance, allowance);
  expect_exact_free_fall(Integrator::kArkodeDirk, allowance, allowance);
}

// CVODE's BDF integrates a constant acceleration exactly from order 2 on, but it starts at order
// 1 (backward Euler, whose positions lag by h^2 g / 2 a step): its error in x stays within the
// local errors it allowed, each component below sqrt(6) (rtol |y|_max + atol) per internal step,
// summed over the steps (velocities, linear in t, are exact at every order: round-off and the
// Newton test only).
TEST(SundialsStepper, CvodeBdfFreeFallWithinItsTolerance) {
  const Problem p = free_fall();
  const Trajectory run = simulate(p, options_for(Integrator::kCvodeBdf, 0.05, 1.0));
  ASSERT_EQ(run.steps.size(), 20u);
  const double per_step = std::sqrt(6.0) * (1e-8 * 10 + 1e-12);
  double worst_x = 0, worst_v = 0;
  for (size_t i = 0; i < run.x.size(); ++i) {
    const double t = run.steps[i].load;
    const double ex = (run.x[i] - (p.x0 + t * p.v0 + 0.5 * t * t * p.g)).norm();
    const double ev = (run.v[i] - (p.v0 + t * p.g)).norm();
    EXPECT_LE(ex, run.internal_steps_to(t) * per_step) << "t = " << t;
    EXPECT_LE(ev, 1e-9) << "t = " << t;
    worst_x = std::max(worst_x, ex);
    worst_v = std::max(worst_v, ev);
  }
  std::printf("largest error %.3e m, %.3e m/s after %zu internal steps\n", worst_x, worst_v,
              run.internal.size());
}

// The oscillator: omega = 2 pi (period 1 s), motion along x.
Problem oscillator() {
  Problem p;
  p.k = p.m * 4 * std::numbers::pi * std::numbers::pi;
  p.x0 = Vec3(0.3, 0, 0);
  p.v0 = Vec3(0.5, 0, 0);
  return p;
}

// In the plane (x, y = v / omega), one step of implicit Euler on the oscillator is
// (x, y) -> (x + c y, y - c x) / (1 + c^2) with c = omega h: a turn by atan(c) scaled by
// rho = 1 / sqrt(1 + c^2). The amplitude sqrt(x^2 + y^2) shrinks by rho per step exactly, the
// energy (which is k / 2 (x^2 + y^2)) by rho^2.
TEST(ImplicitStepper, ImplicitEulerOscillatorLosesAmplitudeAsItsClosedForm) {
  const Problem p = oscillator();
  const double h = 0.05, w = p.omega(), c = w * h;
  const Trajectory run = simulate(p, options_for(Integrator::kImplicitEuler, h, 2.0));
  ASSERT_EQ(run.steps.size(), 40u);
  const double rho = 1 / std::sqrt(1 + c * c), theta = std::atan(c);
  const double x0 = p.x0.x(), y0 = p.v0.x() / w, amplitude = std::hypot(x0, y0);
  const double energy0 = 0.5 * p.k * amplitude * amplitude;
  double previous = amplitude;
  for (size_t i = 0; i < run.x.size(); ++i) {
    const double n = static_cast<double>(i + 1), scale = std::pow(rho, n);
    const double x = scale * (x0 * std::cos(n * theta) + y0 * std::sin(n * theta));
    const double y = scale * (-x0 * std::sin(n * theta) + y0 * std::cos(n * theta));
    // Round-off of 40 steps of one exact Newton step each (measured 1e-15): 1e-12 of the
    // amplitude.
    EXPECT_NEAR(run.x[i].x(), x, 1e-12 * amplitude) << "step " << i;
    EXPECT_NEAR(run.v[i].x() / w, y, 1e-12 * amplitude) << "step " << i;
    const double a = std::hypot(run.x[i].x(), run.v[i].x() / w);
    EXPECT_NEAR(a / previous, rho, 1e-12) << "step " << i;
    previous = a;
    // The records' potential plus kinetic energy (the inertia tether left out).
    EXPECT_NEAR(run.energy(i), energy0 * scale * scale, 1e-12 * energy0) << "step " << i;
  }
  EXPECT_LT(run.energy(39), 0.2 * energy0) << "dissipative: 40 steps keep rho^80 = 2.4 %";
}

// The angle (x, y) turns through per step, averaged over the run (y = v / omega), unwrapped.
double turn_per_step(const Problem& p, const Trajectory& run) {
  const double w = p.omega();
  double angle = 0, x = p.x0.x(), y = p.v0.x() / w;
  for (size_t i = 0; i < run.x.size(); ++i) {
    const double xn = run.x[i].x(), yn = run.v[i].x() / w;
    angle += std::atan2(x * yn - y * xn, x * xn + y * yn);  // signed angle between the two
    x = xn;
    y = yn;
  }
  return -angle / static_cast<double>(run.x.size());  // the motion turns clockwise
}

// Newmark's average acceleration (the trapezoidal rule) on the oscillator: in (x, y = v / omega)
// each step is the Cayley transform of the rotation generator, a turn by exactly
// Omega h = 2 atan(omega h / 2) with no change of amplitude. So the energy is conserved to
// round-off and the period is T_h = 2 pi / Omega, longer than 2 pi / omega by
// omega h / (2 atan(omega h / 2)) - 1 = (omega h)^2 / 12 + O(h^4).
TEST(ImplicitStepper, NewmarkOscillatorConservesEnergyAndHasItsDiscreteFrequency) {
  const Problem p = oscillator();
  const double w = p.omega(), x0 = p.x0.x(), y0 = p.v0.x() / w;
  const double amplitude = std::hypot(x0, y0), energy0 = 0.5 * p.k * amplitude * amplitude;
  double period_error[2];
  for (int refine = 0; refine < 2; ++refine) {
    const double h = refine ? 0.025 : 0.05, c = w * h;
    const Trajectory run = simulate(p, options_for(Integrator::kNewmark, h, 10.0));
    ASSERT_EQ(run.steps.size(), refine ? 400u : 200u);
    const double turn = 2 * std::atan(c / 2);
    for (size_t i = 0; i < run.x.size(); ++i) {
      const double n = static_cast<double>(i + 1);
      // Round-off over up to 400 steps (measured 2e-14): 1e-12 of the amplitude and of the
      // energy.
      EXPECT_NEAR(run.x[i].x(), x0 * std::cos(n * turn) + y0 * std::sin(n * turn),
                  1e-12 * amplitude)
          << "h " << h << " step " << i;
      EXPECT_NEAR(run.v[i].x() / w, -x0 * std::sin(n * turn) + y0 * std::cos(n * turn),
                  1e-12 * amplitude)
          << "h " << h << " step " << i;
      EXPECT_NEAR(run.energy(i), energy0, 1e-12 * energy0) << "h " << h << " step " << i;
    }
    // The period measured from the motion (the mean turn per step over 10 periods) against
    // the closed form: round-off (measured 5e-15 of the turn, so 1e-12 of the period error).
    const double measured = turn_per_step(p, run);
    EXPECT_NEAR(measured, turn, 1e-12 * turn) << "h " << h;
    period_error[refine] = c / measured - 1;
    const double expected = c / turn - 1;  // 0.82 % at h = 0.05 s
    EXPECT_NEAR(period_error[refine], expected, 1e-9 * expected) << "h " << h;
  }
  // Second order: halving h quarters the period error, 4 (1 - c^2 / 20 + O(h^4)) from the
  // series c^2 / 12 - c^4 / 180 (3.98 at these steps).
  EXPECT_NEAR(period_error[0] / period_error[1], 4.0, 0.05);
}

// Symplectic Euler on the oscillator: (x, v) -> (x + h v', v') with v' = v - h omega^2 x, a map
// of determinant 1 and trace 2 - c^2 (c = omega h): a turn by Omega h with
// cos(Omega h) = 1 - c^2 / 2, so x_n = x0 cos(n Omega h) + B sin(n Omega h) with B from x_1 =
// (1 - c^2) x0 + h v0. It conserves not the energy but the modified energy
// m / 2 v^2 + k / 2 x^2 - h k / 2 x v.
TEST(SymplecticEuler, OscillatorHasItsDiscreteFrequencyAndModifiedEnergy) {
  const Problem p = oscillator();
  const double h = 0.05, w = p.omega(), c = w * h;
  const Trajectory run = simulate(p, options_for(Integrator::kSymplecticEuler, h, 10.0));
  ASSERT_EQ(run.steps.size(), 200u);
  const double x0 = p.x0.x(), v0 = p.v0.x(), turn = std::acos(1 - c * c / 2);
  const double B = ((1 - c * c) * x0 + h * v0 - x0 * std::cos(turn)) / std::sin(turn);
  const double amplitude = std::hypot(x0, B);
  const auto modified = [&](double x, double v) {
    return 0.5 * p.m * v * v + 0.5 * p.k * x * x - 0.5 * h * p.k * x * v;
  };
  const double invariant = modified(x0, v0);
  double energy_min = kInf, energy_max = 0;
  for (size_t i = 0; i < run.x.size(); ++i) {
    const double n = static_cast<double>(i + 1);
    // Round-off over 200 steps, velocities re-derived as (x_(n+1) - x_n) / h (measured 3e-14):
    // 1e-12 relative.
    EXPECT_NEAR(run.x[i].x(), x0 * std::cos(n * turn) + B * std::sin(n * turn), 1e-12 * amplitude)
        << "step " << i;
    EXPECT_NEAR(modified(run.x[i].x(), run.v[i].x()), invariant, 1e-12 * invariant) << "step " << i;
    energy_min = std::min(energy_min, run.energy(i));
    energy_max = std::max(energy_max, run.energy(i));
  }
  // The energy itself oscillates by about c of itself (measured 32 %): the invariant is not
  // the energy.
  EXPECT_GT(energy_max - energy_min, 0.1 * invariant);
  // Beyond the stability limit h = 2 / omega the stepper refuses to start.
  PhaseTimers timers;
  System system(1, timers);
  const Constraints none;
  StepLifecycle lifecycle(system, none, {}, [](const StepRecord&, const Points&, const Points*) {});
  EXPECT_THROW(SymplecticEuler(lifecycle, VectorX::Ones(1),
                               options_for(Integrator::kSymplecticEuler, 0.33, 1.0), 2 / w),
               InputError);
}

// ARKODE ERKStep (order 4) and CVODE's BDF (orders up to 5) on the oscillator against the exact
// motion x0 cos(omega t) + v0 / omega sin(omega t).
TEST(SundialsStepper, OscillatorWithinItsTolerance) {
  const Problem p = oscillator();
  const double w = p.omega(), x0 = p.x0.x(), y0 = p.v0.x() / w, amplitude = std::hypot(x0, y0);
  for (Integrator scheme : {Integrator::kArkode, Integrator::kArkodeDirk, Integrator::kCvodeBdf}) {
    SCOPED_TRACE(static_cast<int>(scheme));
    double error[2];
    for (int tight = 0; tight < 2; ++tight) {
      DynamicOptions o = options_for(scheme, 0.1, 2.0);
      ErrorControl& control = scheme == Integrator::kCvodeBdf
                                  ? static_cast<ErrorControl&>(o.cvode)
                                  : static_cast<ErrorControl&>(o.arkode);
      control.relative_tolerance = tight ? 1e-10 : 1e-6;
      // BDF: each step's Newton solve stops at a force residual of its own test (quadratic
      // potential: one step is exact up to round-off).
      o.newton.tolerance = 1e-12;
      const Trajectory run = simulate(p, o);
      ASSERT_EQ(run.steps.size(), 20u);
      error[tight] = 0;
      for (size_t i = 0; i < run.x.size(); ++i) {
        const double t = run.steps[i].load;
        const double x = x0 * std::cos(w * t) + y0 * std::sin(w * t);
        const double y = -x0 * std::sin(w * t) + y0 * std::cos(w * t);
        error[tight] =
            std::max({error[tight], std::abs(run.x[i].x() - x), std::abs(run.v[i].x() / w - y)});
        // Each internal step's estimated local error stays below 1 in the weighted RMS norm over
        // the six components, so each component below sqrt(6) (rtol |y_i| + atol); the global
        // error of this non-expanding motion is at most their sum over the steps so far (in
        // (x, v / omega), where velocities of omega A weigh like positions of A). A bound, not
        // an estimate.
        const double allowance = std::sqrt(6.0) * (control.relative_tolerance * amplitude +
                                                   control.absolute_tolerance / std::min(1.0, w));
        EXPECT_LE(error[tight], run.internal_steps_to(t) * allowance) << "t = " << t;
      }
      std::printf("rtol %g: largest error %.3e after %zu internal steps\n",
                  control.relative_tolerance, error[tight], run.internal.size());
    }
    // A tighter tolerance gives a closer answer (four orders of tolerance: two orders at least).
    EXPECT_LT(error[1], 1e-2 * error[0]);
  }
}

}  // namespace
}  // namespace depthfem
