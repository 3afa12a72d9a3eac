#pragma once
/// The one interface integrators see: an energy of the current positions with derivatives.

#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/block_sparse_matrix.hpp"
#include "core/step_record.hpp"
#include "core/types.hpp"

namespace depthfem {

/// A force contribution written as an energy E(x) over current node positions, with gradient and
/// Hessian. Elasticity, gravity, inertia, viscosity and contact all implement it. Gradients are
/// vectors of 3 * #nodes entries, interleaved (dof 3 * node + component).
///
/// The step lifecycle calls, per step: begin_step and set_load once; then prepare before every
/// evaluation at a new configuration; then prepare, evaluate, complete_step and report at the
/// converged state.
class ForceModule {
 public:
  virtual ~ForceModule() = default;

  /// Short name used in timing tables and messages.
  virtual std::string name() const = 0;

  /// Once per load increment or time step, from its converged start x: rebuild a tree, take a
  /// matrix at the start of the step.
  virtual void begin_step(const Points& /*x*/) {}

  /// The load factor (static) or fraction of the duration (time-dependent) at which the next
  /// evaluations hold: places a moving obstacle, scales a ramped load. Cheap; explicit
  /// integrators call it at every stage.
  virtual void set_load(double /*load*/) {}

  /// Once per iterate before evaluation (refit a tree, find contact pairs). Default: nothing.
  virtual void prepare(const Points& /*x*/) {}

  /// True when the couplings changed since the last bind() (new contact pairs): the owner
  /// rebuilds the Hessian pattern before the next assembly.
  virtual bool pattern_changed() const { return false; }

  /// Adds the node couplings this module's Hessian writes to.
  virtual void add_couplings(SparsityBuilder& builder) const = 0;

  /// Called whenever the global matrix pattern is (re)built: precompute scatter offsets.
  virtual void bind(const BlockSparseMatrix& /*hessian*/) {}

  /// True when add_couplings() adds the same couplings all run long (the elements, not contact
  /// pairs): the owner gathers them once and, when other modules' couplings change, moves this
  /// module's offsets with rebind() instead of binding it anew.
  virtual bool fixed_couplings() const { return false; }

  /// After bind() (or rebind()) to a pattern P: binds to `hessian`, whose pattern holds every
  /// coupling this module adds, block k of P now being block moved[k] (-1 for blocks of P that
  /// `hessian` lacks, none of them this module's). Default: bind(hessian).
  virtual void rebind(const BlockSparseMatrix& hessian, std::span<const Index> /*moved*/) {
    bind(hessian);
  }

  /// Returns E(x) [J] (+infinity where x is illegal for this module) and, when the pointers are
  /// non-null, adds grad E to `gradient` [N] and hess E into `hessian` [N/m] (after bind()).
  /// Gradient and Hessian are meaningful only where the energy is finite.
  virtual double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const = 0;

  /// Largest alpha > 0 such that every x + a dx with 0 <= a < alpha is legal for this module
  /// (finite energy); +infinity where no step along dx is illegal. The line search starts below it.
  virtual double max_step(const Points& /*x*/, const Points& /*dx*/) const {
    return std::numeric_limits<double>::infinity();
  }

  /// Once per accepted step (load increment or time step) at its converged x, after its energy
  /// and gradient there and before report(): a module with internal variables (the viscoelastic
  /// history) writes them. A rejected attempt never gets here, so it leaves them untouched.
  virtual void complete_step(const Points& /*x*/) {}

  /// Adds what this module knows about the converged state x (after prepare(x)) to the step's
  /// record: contact modules append one row per interface, in a fixed order.
  virtual void report(const Points& /*x*/, StepRecord& /*step*/) const {}

  /// The names of the rows report() appends to StepRecord::contact, in their order; known before
  /// the first step, so that a results file can be laid out up front.
  virtual std::vector<std::string> interface_names() const { return {}; }
};

/// Moves block indices found in one pattern to another (ForceModule::rebind): each index k
/// becomes moved[k]. Throws std::logic_error, naming `module`, where the other pattern lacks one.
inline void move_block_indices(std::vector<Index>& indices, std::span<const Index> moved,
                               const std::string& module) {
  for (Index& k : indices) {
    k = moved[static_cast<size_t>(k)];
    if (k < 0) throw std::logic_error(module + ": the new Hessian pattern lacks a coupling");
  }
}

}  // namespace depthfem
