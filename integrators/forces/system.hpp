#pragma once
/// The total energy of a scene: the sum of its force modules, with one shared Hessian.

#include <memory>
#include <optional>
#include <vector>

#include "core/force_module.hpp"
#include "core/phase_timer.hpp"

namespace depthfem {

class Ranks;

/// Which ranks of a distributed run (Ranks) evaluate a module.
enum class Share {
  kWhole,    ///< rank 0 evaluates all of it (modules over nodes: gravity, tethers, obstacles)
  kOwnPart,  ///< every rank evaluates its own part (the tets it owns, the contact pairs of them)
};

/// Sums E, grad E and hess E over force modules and owns the global Hessian and its pattern.
/// The couplings of the modules whose couplings are fixed (ForceModule::fixed_couplings) are
/// gathered once; a rebuild merges them with the others' and moves the fixed modules' offsets
/// to the new pattern (rebind) rather than searching for them again. Module evaluation is timed as
/// "force/stiffness: <module>", preparation as "collision detection: <module>".
/// In a distributed run (distribute()) every rank holds all positions; each sums the modules'
/// parts it evaluates (Share) and the energies, gradients and step bounds are then summed over
/// the ranks, so that every rank sees the totals. The Hessian stays each rank's own part: its
/// sum is assembled by the linear solver (DistributedSolver).
class System {
 public:
  System(Index num_nodes, PhaseTimers& timers) : num_nodes_(num_nodes), timers_(timers) {}

  /// Adds a module and returns a reference to it (the System owns it). `share`: which ranks of a
  /// distributed run evaluate it (without ranks: this process, all of it).
  template <class M>
  M& add(std::unique_ptr<M> module, Share share = Share::kWhole) {
    M& ref = *module;
    modules_.push_back(std::move(module));
    shares_.push_back(share);
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
  /// The energy of `module` (one of this System's) at x; in a distributed System its parts
  /// summed over the ranks.
  double module_energy(const ForceModule& module, const Points& x) const;
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

  /// Makes this a distributed System over `ranks` (which must outlive it), or a serial one (null).
  void distribute(Ranks* ranks) { ranks_ = ranks; }
  /// The ranks of a distributed System, or null.
  Ranks* ranks() const { return ranks_; }
  /// Sums `v` over the ranks in a distributed System (a product with this rank's part of the
  /// Hessian, its diagonal); nothing otherwise.
  void sum_over_ranks(VectorX& v) const;

 private:
  double evaluate(const Points& x, VectorX* g, BlockSparseMatrix* H);

  Index num_nodes_;
  PhaseTimers& timers_;
  std::vector<std::unique_ptr<ForceModule>> modules_;
  std::vector<Share> shares_;  ///< per module
  Ranks* ranks_ = nullptr;
  /// Whether this process evaluates module m (all of it, or its own part).
  bool evaluates(size_t m) const;
  void rebuild_pattern();

  BlockSparseMatrix hessian_;
  bool pattern_valid_ = false;
  bool bound_ = false;  ///< every module bound to hessian_ (the next rebuild may rebind)
  std::optional<SparsityBuilder::Rows> fixed_rows_;  ///< the fixed modules' couplings
};

}  // namespace depthfem
