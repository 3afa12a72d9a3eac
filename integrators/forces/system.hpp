#pragma once
/// The total energy of a scene: the sum of its force modules, with one shared Hessian.

#include <memory>
#include <optional>
#include <vector>

#include "core/force_module.hpp"
#include "core/phase_timer.hpp"

namespace depthfem {

/// Sums E, grad E and hess E over force modules and owns the global Hessian and its pattern.
/// The couplings of the modules whose couplings are fixed (ForceModule::fixed_couplings) are
/// gathered once; a rebuild merges them with the others' and moves the fixed modules' offsets
/// to the new pattern (rebind) rather than searching for them again. Module evaluation is timed as
/// "force/stiffness: <module>", preparation as "collision detection: <module>".
class System {
 public:
  System(Index num_nodes, PhaseTimers& timers) : num_nodes_(num_nodes), timers_(timers) {}

  /// Adds a module and returns a reference to it (the System owns it).
  template <class M>
  M& add(std::unique_ptr<M> module) {
    M& ref = *module;
    modules_.push_back(std::move(module));
    pattern_valid_ = false;
    fixed_rows_.reset();
    return ref;
  }

  Index num_nodes() const { return num_nodes_; }
  const std::vector<std::unique_ptr<ForceModule>>& modules() const { return modules_; }
  PhaseTimers& timers() { return timers_; }

  /// Calls every module's begin_step(x).
  void begin_step(const Points& x);
  /// Calls every module's set_load(load).
  void set_load(double load);
  /// Calls every module's prepare(x); a module whose couplings changed invalidates the pattern.
  void prepare(const Points& x);
  /// Total energy; +infinity when some module finds x illegal.
  double energy(const Points& x);
  /// Total energy and gradient (3 * #nodes, interleaved; overwritten).
  double gradient(const Points& x, VectorX& g);
  /// Total energy, gradient and Hessian (overwritten; read it with matrix()). The pattern is
  /// (re)built on first use or after `invalidate_pattern()`.
  double hessian(const Points& x, VectorX& g);
  /// Smallest max_step(x, dx) over the modules (+infinity when none limits the step).
  double max_step(const Points& x, const Points& dx) const;
  /// Calls every module's complete_step(x): the step at x is accepted.
  void complete_step(const Points& x);
  /// Lets every module add to the record of a converged step at x (after prepare(x)).
  void report(const Points& x, StepRecord& step) const;
  /// The modules' interface_names(), in module order: the rows report() appends.
  std::vector<std::string> interface_names() const;
  /// The Hessian filled by the last hessian() call.
  BlockSparseMatrix& matrix() { return hessian_; }
  /// Forces a rebuild of the Hessian pattern (a module's couplings changed).
  void invalidate_pattern() { pattern_valid_ = false; }

 private:
  double evaluate(const Points& x, VectorX* g, BlockSparseMatrix* H);

  Index num_nodes_;
  PhaseTimers& timers_;
  std::vector<std::unique_ptr<ForceModule>> modules_;
  void rebuild_pattern();

  BlockSparseMatrix hessian_;
  bool pattern_valid_ = false;
  bool bound_ = false;  ///< every module bound to hessian_ (the next rebuild may rebind)
  std::optional<SparsityBuilder::Rows> fixed_rows_;  ///< the fixed modules' couplings
};

}  // namespace depthfem
