#include "integrators/thread_budget.hpp"

#include <dlfcn.h>
#include <omp.h>
#include <tbb/info.h>

namespace depthfem {

namespace {

// OpenBLAS's own controls, looked up at run time: with another BLAS there is nothing to set.
void set_blas_threads(int threads) {
  using SetThreads = void (*)(int);
  if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads")))
    set(threads);
  if (threads == 1) {
    // OpenBLAS's pthread build starts its pool when it is loaded; stop it. It starts again
    // only for a call allowed more than one thread.
    using Shutdown = int (*)();
    if (auto stop = reinterpret_cast<Shutdown>(dlsym(RTLD_DEFAULT, "blas_thread_shutdown_")))
      stop();
  }
}

}  // namespace

ThreadBudget::ThreadBudget(int threads)
    : threads_(threads > 0 ? threads : tbb::info::default_concurrency()),
      tbb_(std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                 threads_)) {
  // CHOLMOD asks for four threads in its loops whatever omp_set_num_threads says; no active
  // parallel level keeps them on the calling thread.
  omp_set_num_threads(threads_);
  omp_set_max_active_levels(0);
  set_blas_threads(threads_);
}

ThreadBudget::~ThreadBudget() = default;

}  // namespace depthfem
