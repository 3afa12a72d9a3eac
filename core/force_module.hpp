#pragma once
/// The one interface integrators see: an energy of the current positions with derivatives.

#include <string>

#include "core/block_sparse_matrix.hpp"
#include "core/types.hpp"

namespace depthfem {

/// A force contribution written as an energy E(x) over current node positions, with gradient and
/// Hessian. Elasticity, gravity, inertia, viscosity and contact all implement it. Gradients are
/// vectors of 3 * #nodes entries, interleaved (dof 3 * node + component).
class ForceModule {
 public:
  virtual ~ForceModule() = default;

  /// Short name used in timing tables and messages.
  virtual std::string name() const = 0;

  /// Once per load increment or time step, from its converged start x towards load factor (or
  /// time) `load`: rebuild a tree, place a moving obstacle.
  virtual void begin_step(const Points& /*x*/, double /*load*/) {}

  /// Once per iterate before evaluation (refit a tree, find contact pairs). Default: nothing.
  virtual void prepare(const Points& /*x*/) {}

  /// True when the couplings changed since the last bind() (new contact pairs): the owner
  /// rebuilds the Hessian pattern before the next assembly.
  virtual bool pattern_changed() const { return false; }

  /// Adds the node couplings this module's Hessian writes to.
  virtual void add_couplings(SparsityBuilder& builder) const = 0;

  /// Called whenever the global matrix pattern is (re)built: precompute scatter offsets.
  virtual void bind(const BlockSparseMatrix& /*hessian*/) {}

  /// Returns E(x) [J] (+infinity where x is illegal for this module) and, when the pointers are
  /// non-null, adds grad E to `gradient` [N] and hess E into `hessian` [N/m] (after bind()).
  /// Gradient and Hessian are meaningful only where the energy is finite.
  virtual double evaluate(const Points& x, VectorX* gradient, BlockSparseMatrix* hessian) const = 0;
};

}  // namespace depthfem
