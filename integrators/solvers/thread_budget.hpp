#pragma once
/// One bound on the threads of every pool in the process: TBB, OpenMP and BLAS.

#include <tbb/global_control.h>

#include <memory>

namespace depthfem {

/// While alive, at most `threads` threads work at a time. TBB (assembly, products, contact
/// search) runs at most that many. OpenBLAS, which the direct solver's supernodal factorisation
/// calls for factorisations above DirectSolverOptions::threaded_factor_flops, runs as many in
/// its own pool (smaller ones and the triangular solves run it on one thread, SerialBlas); that
/// pool and TBB's never work at the same time (the factorisation waits for the assembly and the
/// reverse). CHOLMOD's OpenMP loops (clearing and filling supernodes: memory bound, four threads
/// when left alone) run on the calling thread. With one thread no second thread runs: the pool
/// OpenBLAS starts when it is loaded is stopped. PETSc (AMG) runs on the calling thread, but
/// for its vector operations, which it hands to BLAS: OpenBLAS shares those over more than
/// 10,000 entries with its pool (on a 16-core machine no slower or faster than on the calling
/// thread alone: bench/results/thread_scaling_16core.md). MPI, which PETSc starts on first use,
/// adds a helper thread of its own (Open MPI as an isolated singleton: one, asleep while a run
/// computes). The command line, the benchmarks and the tests all set their threads through this.
class ThreadBudget {
 public:
  /// `threads` <= 0: one per core.
  explicit ThreadBudget(int threads);
  ~ThreadBudget();
  ThreadBudget(const ThreadBudget&) = delete;
  ThreadBudget& operator=(const ThreadBudget&) = delete;

  int threads() const { return threads_; }

 private:
  int threads_;
  std::unique_ptr<tbb::global_control> tbb_;
};

/// While alive (and `serial`), BLAS runs on the calling thread (OpenBLAS; with another BLAS,
/// nothing changes). The direct solver's triangular solves and small factorisations call BLAS
/// on blocks too small to share: the pool's threads, woken for each call and put to sleep after
/// it, cost more in the kernel than they save (the 80 x 8 x 8 sag bar at two threads: linear
/// solve 2.7 s, 1.5 s of it system time, against 1.5-1.7 s with this around them).
class SerialBlas {
 public:
  explicit SerialBlas(bool serial = true);
  ~SerialBlas();
  SerialBlas(const SerialBlas&) = delete;
  SerialBlas& operator=(const SerialBlas&) = delete;

 private:
  int threads_;  ///< OpenBLAS's thread count before (1: nothing was changed)
};

}  // namespace depthfem
