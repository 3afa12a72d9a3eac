#pragma once
/// Damped Newton iteration with the paper's line search (LOOP2 and LOOP3 of section 3.2).

#include <string>
#include <vector>

#include "integrators/forces/constraints.hpp"
#include "integrators/forces/system.hpp"
#include "integrators/solvers/linear_solver.hpp"

namespace depthfem {

/// When the line search accepts a step (both also require a legal, finite-energy configuration).
enum class LineSearchRule {
  kEnergy,    ///< the energy drops (within round-off, where the residual must drop instead)
  kResidual,  ///< the residual |P grad E| drops: the paper's rule
};

struct NewtonOptions {
  int max_iterations = 30;
  LineSearchRule line_search = LineSearchRule::kEnergy;
  /// Converged when |P grad E ./ force_scale|_2 <= tolerance (P: projection onto free
  /// directions; with an empty force_scale, |P grad E|_2 <= tolerance [N]), both finite; a
  /// tolerance that is not finite and positive fails the solve at once.
  double tolerance = 1e-8;
  /// Per dof (3 * #nodes) [N]: the force each residual component is measured against (see
  /// residual_force_scale), or empty.
  VectorX force_scale;
  /// Step halvings before the line search gives up.
  int max_line_search = 30;
  /// Where the line search starts: false, at 0.9 of the largest legal step where that is below
  /// 1 (no trial is spent on an inverted configuration); true, at the full step, halving through
  /// illegal trials as the paper does.
  bool full_step_first = false;
  /// Where the Newton direction fails the line search (or, with the energy rule, is not a
  /// descent direction), search along the Jacobi-scaled gradient before giving up; false: the
  /// Newton solve fails at once (the paper's algorithm, which has no fallback).
  bool gradient_fallback = true;
  /// Inexact Newton: the linear solve of step k may stop at |b - A dx| <= eta_k |b|, with
  /// Eisenstat and Walker's second choice eta_k = 0.9 (r_k / r_(k-1))^2 (r: the residual norm;
  /// raised to 0.9 eta_(k-1)^2 where that is above 0.1), at most forcing_max; the first step is
  /// solved to the solver's own tolerance. Far from the solution, where the residual does not
  /// fall, a solve to a tenth is enough; as Newton converges, eta_k falls with the square of
  /// the residual's ratio, and Newton stays quadratic. Only the direct solver's CG on a kept
  /// factor takes it (LinearSolver::solve): there it saves factorisations. 0: every solve to
  /// the solver's own tolerance.
  double forcing_max = 0.1;
  LinearSolverOptions linear;
};

/// The norm of a (projected) residual that the Newton test compares with options.tolerance:
/// |g ./ force_scale|_2, or |g|_2 without a scale.
double scaled_residual(const NewtonOptions& options, const VectorX& g);

/// How one Newton solve went.
struct NewtonResult {
  bool converged = false;
  int iterations = 0;             ///< Newton steps taken
  int linear_iterations = 0;      ///< summed over steps
  int linear_solves = 0;          ///< one per Newton step
  int factorizations = 0;         ///< direct LL^T factorisations among those solves
  std::vector<double> residuals;  ///< |P grad E| at every iterate, the first included
  double energy = 0;              ///< at the final iterate [J]
  std::string failure;            ///< why it stopped without converging
};

/// Minimises the energy of a System over the free directions of its Constraints.
/// Each step solves (P H P + C) dx = -P g, then halves the step, starting from 1 or 0.9 of the
/// System's max_step (whichever is smaller; from 1 with full_step_first), until the configuration
/// is legal (finite energy) and the line-search rule holds (the paper's damping factor). The
/// paper asks for a lower residual; in bending that rejects good Newton steps (a linearised
/// rotation stretches fibers, so the full step raises the residual while it lowers the energy, and
/// Newton crawls), so the default asks for a lower energy. Where the Newton direction is not a
/// descent direction (an indefinite Hessian: buckling, deep contact) or its search fails, the step
/// falls back to the Jacobi-scaled gradient (unless gradient_fallback is off).
class NewtonSolver {
 public:
  NewtonSolver(System& system, const Constraints& constraints, NewtonOptions options)
      : system_(system), constraints_(constraints), options_(options), linear_(options.linear) {
    linear_.set_decoupled_nodes(constraints.fully_constrained_nodes());
    if (system.ranks()) linear_.distribute(*system.ranks());
  }

  /// Solves in place from x, whose constrained components must already hold their targets.
  NewtonResult solve(Points& x);

  /// A first guess for a new load increment: from the (legal) state x, the prescribed motion u
  /// (#nodes x 3, zero in the free directions) carried into the free directions by the stiffness
  /// at x, dx = -(P H P + C)^-1 P (g + H u); returns x + u + dx. Where imposing u alone would
  /// invert the elements beside the moved nodes, this spreads the motion over the body.
  Points linearised_step(const Points& x, const Points& u);

  NewtonOptions& options() { return options_; }

 private:
  /// Halves the step until the rule holds; moves x and returns true, or leaves x and returns false.
  bool line_search(Points& x, const Points& step, double energy, double residual);

  System& system_;
  const Constraints& constraints_;
  NewtonOptions options_;
  LinearSolver linear_;
};

}  // namespace depthfem
