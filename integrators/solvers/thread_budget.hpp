#pragma once
/// One bound on the threads of every pool in the process: TBB, OpenMP and BLAS.

#include <tbb/global_control.h>

#include <memory>

namespace depthfem {

/// While alive, at most `threads` threads work at a time, and the results do not depend on
/// how many: TBB (assembly, products, contact search, the direct solver's factorisation) runs at
/// most that many, on work cut by its sizes alone. BLAS runs on the calling thread: a threaded
/// BLAS cuts its work by its thread count (OpenBLAS gives other bits on two threads than on
/// one), so the factorisation shares its dense blocks in tiles of its own (solvers/tiled_blas.hpp),
/// and PETSc's vector operations (AMG), which OpenBLAS would share over more than 10,000 entries,
/// stay on the calling thread (no slower: bench/results/thread_scaling_16core.md). OpenBLAS's
/// pool, started when the library is loaded, is stopped. CHOLMOD's OpenMP loops (four threads
/// when left alone) run on the calling thread. MPI, which PETSc starts on first use, adds a helper
/// thread of its own (Open MPI as an isolated singleton: one, asleep while a run computes). The
/// command line, the benchmarks and the tests all set their threads through this.
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
/// nothing changes), also outside a ThreadBudget. The direct and AMG solvers hold one around
/// their BLAS calls: a BLAS thread count other than one would make their results depend on it.
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
