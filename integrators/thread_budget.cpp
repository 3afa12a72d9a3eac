#include "integrators/thread_budget.hpp"

#include <dlfcn.h>
#include <omp.h>
#include <tbb/info.h>

#include <cstdlib>

namespace depthfem {

namespace {

// OpenBLAS's own controls, looked up at run time: with another BLAS there is nothing to set.
template <class F>
F openblas(const char* name) {
  return reinterpret_cast<F>(dlsym(RTLD_DEFAULT, name));
}

void set_blas_threads(int threads) {
  // OpenBLAS's pthread pool, started when the library is loaded, lets its threads spin for
  // 2^28 cycles (0.1 s) after every call before they sleep: after each factorisation they take
  // the cores from the assembly that follows. The shortest spin it allows (2^4 cycles) comes
  // from its environment variable (unless the user set one), read again; the pool is stopped
  // and starts with it at the next call allowed more than one thread (never, with one).
  setenv("OPENBLAS_THREAD_TIMEOUT", "4", 0);
  if (auto read_env = openblas<void (*)()>("openblas_read_env")) read_env();
  if (auto set = openblas<void (*)(int)>("openblas_set_num_threads")) set(threads);
  if (auto stop = openblas<int (*)()>("blas_thread_shutdown_")) stop();
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

SerialBlas::SerialBlas(bool serial) {
  // Looked up once: dlsym over every library the process loaded (PETSc brings a hundred) costs
  // tenths of a millisecond, and the direct solver asks twice per triangular solve.
  static const auto get = openblas<int (*)()>("openblas_get_num_threads");
  threads_ = serial && get ? get() : 1;
  if (threads_ > 1) set_threads(1);
}

SerialBlas::~SerialBlas() {
  if (threads_ > 1) set_threads(threads_);
}

void SerialBlas::set_threads(int threads) {
  static const auto set = openblas<void (*)(int)>("openblas_set_num_threads");
  set(threads);
}

}  // namespace depthfem
