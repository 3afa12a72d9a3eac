// The implicit integrators beside Newmark: generalized-alpha (Chung-Hulbert) and ARKODE's
// diagonally implicit Runge-Kutta methods. Measured orders of convergence against an
// independent reference (ARKODE's explicit order 8 at a tight tolerance), energy behaviour on a
// linearised problem, error-controlled steps through contact.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "apps/scene_runner.hpp"
#include "core/mass.hpp"

namespace depthfem {
namespace {

using testing::load;
using testing::run;

// A smooth problem: falling_bars with all three bars as soft as the softest (E = 0.2 MPa), over
// its first 0.05 s from rest. Gravity switched on at t = 0 excites every mode of the mesh; the
// highest frequency is about 760 rad/s here (dilatational wave across a 5 cm tet), so steps of
// 1 ms and below resolve it (h omega <= 0.8) and the errors are in their asymptotic range. (With
// the shipped stiff bar, omega reaches about 3800 rad/s, and at steps of 1-4 ms the measured
// orders scatter between 1.1 and 2.2 for every second-order method, Newmark included.)
const std::vector<std::string> kSmooth = {"bodies.1.material.youngs=2e5",
                                          "bodies.2.material.youngs=2e5", "dynamic.duration=0.05"};

// Positions at the end of a smooth run with these overrides (after the smooth problem's and a
// Newton tolerance of 1e-12; a failed run fails the test).
Points end_positions(const std::vector<std::string>& overrides) {
  std::vector<std::string> all = kSmooth;
  all.push_back("solver.tolerance=1e-12");
  all.insert(all.end(), overrides.begin(), overrides.end());
  const RunResult r = run(load("falling_bars", all));
  EXPECT_TRUE(r.success) << r.message;
  return r.x;
}

double largest_distance(const Points& a, const Points& b) {
  return (a - b).rowwise().norm().maxCoeff();
}

// The reference: ERKStep's order-8 table at relative tolerance 1e-12, an explicit method
// independent of every implicit one measured here.
const Points& reference() {
  static const Points x = end_positions(
      {"dynamic.integrator=arkode",
       R"(dynamic.arkode={"order": 8, "relative_tolerance": 1e-12, "absolute_tolerance": 1e-14})"});
  return x;
}

// Order p from the errors at steps h, h/2, h/4: log2 of the ratio of successive errors, the
// smaller of the two ratios (the one nearer the asymptotic range is the finer one; both must
// agree with p within 0.2).
std::vector<double> measured_orders(const std::vector<std::string>& integrator, double h) {
  std::vector<double> errors;
  for (double step : {h, h / 2, h / 4}) {
    std::vector<std::string> o = integrator;
    o.push_back("dynamic.time_step=" + std::to_string(step));
    errors.push_back(largest_distance(end_positions(o), reference()));
  }
  std::printf("errors at h = %g, %g, %g:", h, h / 2, h / 4);
  for (double e : errors) std::printf(" %.3e", e);
  std::printf("\n");
  return {std::log2(errors[0] / errors[1]), std::log2(errors[1] / errors[2])};
}

// Generalized-alpha is second order for every rho_inf (Chung and Hulbert's parameters), as
// Newmark's average acceleration is.
TEST(ImplicitIntegrators, GeneralizedAlphaAndNewmarkConvergeAtSecondOrder) {
  for (const char* setting : {R"(dynamic.generalized_alpha={"rho_inf": 0.8})",
                              R"(dynamic.generalized_alpha={"rho_inf": 0})",
                              R"(dynamic.generalized_alpha={"rho_inf": 1})"}) {
    const std::vector<double> p =
        measured_orders({"dynamic.integrator=generalized_alpha", setting}, 0.001);
    for (double order : p) EXPECT_NEAR(order, 2.0, 0.2) << setting;
  }
  for (double order : measured_orders({"dynamic.integrator=newmark"}, 0.001))
    EXPECT_NEAR(order, 2.0, 0.2) << "Newmark";
}

// ARKStep's default diagonally implicit tables of order 2, 3 and 4, each at fixed steps (no error
// control), stage equations solved by depthfem's Newton. Its test is ARKODE's (at rtol 1e-10),
// never tighter than the scene's; 1e-12 there is below the rounding of a stage's residual (about
// 5e-9 N: positions' rounding times M / gamma^2), so the scene's is 1e-10.
TEST(ImplicitIntegrators, ArkodeDirkTablesConvergeAtTheirOrders) {
  for (int order : {2, 3, 4}) {
    const std::string section = R"(dynamic.arkode={"order": )" + std::to_string(order) +
                                R"(, "fixed_step": true, "relative_tolerance": 1e-10, )"
                                R"("absolute_tolerance": 1e-12})";
    const std::vector<double> p =
        measured_orders({"dynamic.integrator=arkode_dirk", "solver.tolerance=1e-10", section},
                        order == 4 ? 0.002 : 0.001);
    for (double measured : p) EXPECT_NEAR(measured, order, 0.2) << "order " << order;
  }
}

// Largest rise of the mechanical energy (kinetic + elastic + gravitational) above its initial
// value and largest loss below it, over the steps of a run, each over the largest kinetic energy.
struct EnergyDrift {
  double gain = 0, loss = 0;
};
EnergyDrift energy_drift(const std::vector<std::string>& overrides) {
  const Scene s = load("falling_bars", overrides);
  const RunResult r = run(s);
  EXPECT_TRUE(r.success) << r.message;
  const VectorX m = lumped_mass(s.mesh.X, s.mesh.tets, s.tet_density);
  const double initial = -(m.transpose() * (s.mesh.X * s.gravity)).value();
  double kinetic = 0;
  EnergyDrift d;
  for (const StepRecord& st : r.steps) {
    kinetic = std::max(kinetic, st.kinetic_energy);
    d.gain = std::max(d.gain, st.kinetic_energy + st.energy - initial);
    d.loss = std::max(d.loss, initial - st.kinetic_energy - st.energy);
  }
  d.gain /= kinetic;
  d.loss /= kinetic;
  return d;
}

// A linearised problem: falling_bars under a thousandth of gravity (strains about 1e-6), 0.5 s
// at the shipped 10 ms steps, Newton tolerance 1e-12.
const std::vector<std::string> kLinear = {"gravity=[0, 0, -0.00981]", "dynamic.duration=0.5",
                                          "solver.tolerance=1e-12"};

// Generalized-alpha with rho_inf = 1 has no numerical dissipation: its energy stays within 1e-6
// of the peak kinetic energy (measured 2.5e-8: the Newton tolerance and the remaining
// nonlinearity). rho_inf < 1 damps the unresolved high frequencies (h omega up to 38 here), the
// more the smaller rho_inf (measured losses 3.3e-5, 3.5e-4, 2.4e-3 for 0.8, 0.5, 0; tested: each
// over twice the one before), and the
// energy never rises above its start for 0.8 and 0.5 (measured 0). For rho_inf = 0 the physical
// energy is not the quantity the scheme dissipates (its algorithmic energy is): it overshoots
// its start by 7.9e-6, under 1 % of what it loses; that is the bound tested.
TEST(ImplicitIntegrators, GeneralizedAlphaConservesAtRhoOneAndDissipatesBelow) {
  double previous_loss = 0;
  for (const char* rho : {"1", "0.8", "0.5", "0"}) {
    std::vector<std::string> o = kLinear;
    o.push_back("dynamic.integrator=generalized_alpha");
    o.push_back(std::string(R"(dynamic.generalized_alpha={"rho_inf": )") + rho + "}");
    const EnergyDrift d = energy_drift(o);
    std::printf("rho_inf %s: energy gain %.3e, loss %.3e of the peak kinetic energy\n", rho, d.gain,
                d.loss);
    if (std::string(rho) == "1") {
      EXPECT_LT(std::max(d.gain, d.loss), 1e-6);
    } else {
      EXPECT_GT(d.loss, 2 * previous_loss) << rho;
      EXPECT_LT(d.gain, std::string(rho) == "0" ? 0.01 * d.loss : 1e-9) << rho;
    }
    previous_loss = std::max(previous_loss, d.loss);
  }
}

// ARKODE's diagonally implicit methods are dissipative on the same problem, at their default
// tolerances (relative 1e-6, absolute 1e-9): the energy loses and never rises above its start
// by more than the tolerance allows (1e-6 of the peak kinetic energy).
TEST(ImplicitIntegrators, ArkodeDirkDoesNotGainEnergy) {
  for (int order : {2, 3, 4}) {
    std::vector<std::string> o = kLinear;
    o.push_back("dynamic.integrator=arkode_dirk");
    o.push_back(R"(dynamic.arkode={"order": )" + std::to_string(order) + "}");
    const EnergyDrift d = energy_drift(o);
    std::printf("order %d: energy gain %.3e, loss %.3e of the peak kinetic energy\n", order, d.gain,
                d.loss);
    EXPECT_LT(d.gain, 1e-6) << order;
  }
}

}  // namespace
}  // namespace depthfem
