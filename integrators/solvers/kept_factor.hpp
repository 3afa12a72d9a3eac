#pragma once

#include <algorithm>

namespace depthfem {

// When a direct solver keeps its last factor as the preconditioner of CG on the matrices after it
// (DirectSolver with CHOLMOD's factor, DistributedSolver with MUMPS'), and when it factors anew.
//
// A factor's cycle is the factored solve and the CG solves on it. Its mean cost per solve,
// (factorisation + CG iterations) / solves, is least where one solve costs as much as the mean
// (the CG iterations grow as the matrices drift from the factored one): once a solve costs more,
// the next matrix is factored without trying CG. A factorisation of F flops is worth
// F / (40 nnz(L)) CG iterations (about 4 nnz(L) flops an iteration, ten times slower for being
// memory bound), clamped to 2-50; CG gets at most that many iterations.
class KeptFactor {
 public:
  // A new factor of `flops` flops with `entries` stored entries.
  void start(double flops, double entries) {
    worth_ = std::clamp(flops / (40 * std::max(entries, 1.0)), 2.0, 50.0);
    kept_ = true;
    refactor_ = false;
    solves_ = 1;
    cost_ = worth_;
  }
  // No factor is kept (a new pattern, a failed factorisation).
  void drop() { kept_ = false; }
  // Whether the next matrix tries CG on the kept factor first.
  bool try_cg() const { return kept_ && !refactor_; }
  // The most CG iterations a solve on the factor may take.
  int max_iterations() const { return static_cast<int>(worth_); }
  // A solve that CG finished on the kept factor in `iterations`.
  void record(int iterations) {
    ++solves_;
    cost_ += iterations;
    refactor_ = iterations * solves_ > cost_;
  }

 private:
  double worth_ = 2;  // a factorisation's cost in CG iterations
  bool kept_ = false, refactor_ = false;
  int solves_ = 0;   // of the cycle, the factored one included
  double cost_ = 0;  // of the cycle in CG iterations, the factorisation counted as worth_
};

}  // namespace depthfem
