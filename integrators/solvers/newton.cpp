#include "integrators/solvers/newton.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/decimal.hpp"

namespace depthfem {

namespace {
// Fraction of the largest legal step the line search starts from (the energy barrier is
// infinite at the step itself).
constexpr double kMaxStepFraction = 0.9;
}  // namespace

double scaled_residual(const NewtonOptions& options, const VectorX& g) {
  return options.force_scale.size() == 0 ? g.norm() : g.cwiseQuotient(options.force_scale).norm();
}

bool NewtonSolver::line_search(Points& x, const Points& step, double energy, double residual) {
  VectorX g_trial;
  // Start below the first step length at which some module turns illegal (an element would
  // invert): the energy is infinite there, and halving from 1 would waste trials on it; or, as
  // the paper does, at the full step (full_step_first).
  double alpha =
      options_.full_step_first ? 1.0 : std::min(1.0, kMaxStepFraction * system_.max_step(x, step));
  for (int k = 0; k <= options_.max_line_search; ++k, alpha *= 0.5) {
    const Points trial = x + alpha * step;
    system_.prepare(trial);
    const double e = system_.gradient(trial, g_trial);
    if (!std::isfinite(e)) continue;
    constraints_.project(g_trial);
    const double r = g_trial.norm();
    // Energy rule: a drop in energy or, where the energies agree to their round-off, in residual.
    // Near a converged state an energy sum loses digits twice: small-strain energy densities come
    // from invariants such as I1 - 3 ~ 1e-4 (four digits lost per element), and gravity and
    // tether terms cancel the elastic part. Measured scatter between trial points was 3e-11 of
    // |E| on a 3840-tet bar; the band is 1e-9 of |E|.
    const bool lower_energy = e < energy || (e <= energy + 1e-9 * std::abs(energy) && r < residual);
    if (options_.line_search == LineSearchRule::kEnergy ? lower_energy : r < residual) {
      x = trial;
      return true;
    }
  }
  system_.prepare(x);
  return false;
}

Points NewtonSolver::linearised_step(const Points& x, const Points& u) {
  VectorX g, Hu, dx;
  system_.prepare(x);
  system_.hessian(x, g);
  BlockSparseMatrix& H = system_.matrix();
  H.multiply(as_dofs(u), Hu);
  system_.sum_over_ranks(Hu);  // each rank holds its part of H
  VectorX rhs = -(g + Hu);
  constraints_.project(rhs);
  constraints_.project(H);
  {
    PhaseTimers::Scope t(system_.timers(), "linear solve");
    linear_.solve(H, rhs, dx);
  }
  constraints_.project(dx);  // an inexact solve may leak into the prescribed directions
  return x + u + as_points(dx);
}

NewtonResult NewtonSolver::solve(Points& x) {
  NewtonResult result;
  VectorX g, dx;
  system_.prepare(x);
  double energy = system_.hessian(x, g);
  if (!std::isfinite(energy)) {
    result.failure = "the starting configuration is illegal (an element is inverted)";
    return result;
  }
  if (!(std::isfinite(options_.tolerance) && options_.tolerance > 0)) {
    result.failure =
        "the Newton tolerance " + shown(options_.tolerance) + " is not a finite positive number";
    return result;
  }
  constraints_.project(g);
  double residual = g.norm();
  result.residuals.push_back(residual);
  double forcing = 0;  // the first step as exact as the solver makes it
  for (;;) {
    result.energy = energy;
    // A non-finite residual (overflowing forces) never counts as converged.
    const double scaled = scaled_residual(options_, g);
    if (std::isfinite(scaled) && scaled <= options_.tolerance) {
      result.converged = true;
      return result;
    }
    if (result.iterations == options_.max_iterations) {
      result.failure = "no convergence in " + std::to_string(options_.max_iterations) +
                       " Newton iterations (residual " + shown(residual) + " N, " +
                       (options_.force_scale.size() ? "scaled " + shown(scaled) + ", " : "") +
                       "tolerance " + shown(options_.tolerance) + ")";
      return result;
    }
    BlockSparseMatrix& H = system_.matrix();
    constraints_.project(H);
    LinearSolveStats stats;
    {
      PhaseTimers::Scope t(system_.timers(), "linear solve");
      stats = linear_.solve(H, -g, dx, &x, forcing);
    }
    // An iterative solve is exact on the constrained directions only up to its tolerance (a
    // multigrid preconditioner couples them with the free ones); keep the step free of them.
    constraints_.project(dx);
    result.linear_iterations += stats.iterations;
    ++result.linear_solves;
    result.factorizations += stats.factored ? 1 : 0;
    if (!dx.allFinite()) {
      result.failure = "the linear solver failed (" + to_string(linear_.options().kind) + ")";
      return result;
    }
    // Line search along the Newton direction; if it is not a descent direction (an indefinite
    // Hessian) or finds no acceptable step, along the Jacobi-scaled gradient instead.
    const bool energy_rule = options_.line_search == LineSearchRule::kEnergy;
    bool accepted =
        (!energy_rule || g.dot(dx) < 0) && line_search(x, as_points(dx), energy, residual);
    if (!accepted && options_.gradient_fallback) {
      VectorX d = H.diagonal();
      system_.sum_over_ranks(d);
      d = d.cwiseAbs().cwiseMax(1e-300);
      dx = -g.cwiseQuotient(d);
      accepted = line_search(x, as_points(dx), energy, residual);
    }
    ++result.iterations;
    if (!accepted) {
      result.failure = std::string("line search found no legal step that lowers the ") +
                       (energy_rule ? "energy" : "residual") + " (residual " + shown(residual) +
                       " N)";
      return result;
    }
    energy = system_.hessian(x, g);
    constraints_.project(g);
    const double ratio = g.norm() / residual;
    residual = g.norm();
    result.residuals.push_back(residual);
    // Eisenstat and Walker's choice 2 (gamma 0.9, alpha 2) with their safeguard.
    const double safeguard = 0.9 * forcing * forcing;
    forcing = std::min(options_.forcing_max,
                       std::max(0.9 * ratio * ratio, safeguard > 0.1 ? safeguard : 0.0));
  }
}

}  // namespace depthfem
