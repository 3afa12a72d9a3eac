#include "integrators/solvers/thread_budget.hpp"

#include <dlfcn.h>
#include <omp.h>
#include <tbb/info.h>

#include <cstdlib>

namespace depthfem {

namespace {

// OpenBLAS's own controls, looked up once at run time (null with another BLAS: nothing to set).
// dlsym searches every library the process loaded (PETSc brings a hundred), tenths of a
// millisecond a call, and SerialBlas asks around every triangular solve.
struct OpenBlas {
  template <class F>
  static F find(const char* name) {
    return reinterpret_cast<F>(dlsym(RTLD_DEFAULT, name));
  }
  void (*read_env)() = find<void (*)()>("openblas_read_env");
  void (*set_threads)(int) = find<void (*)(int)>("openblas_set_num_threads");
  int (*get_threads)() = find<int (*)()>("openblas_get_num_threads");
  int (*stop)() = find<int (*)()>("blas_thread_shutdown_");
};

const OpenBlas& openblas() {
  static const OpenBlas entries;
  return entries;
}

// OpenBLAS on the calling thread, its pthread pool (started when the library is loaded) stopped.
// Should anything later allow it more threads, the pool starts again with the shortest spin
// after a call that OpenBLAS allows (2^4 cycles, not 2^28, 0.1 s, in which its threads would
// take the cores from the work that follows), from its environment variable (unless the user
// set one), read again.
void serial_blas() {
  setenv("OPENBLAS_THREAD_TIMEOUT", "4", 0);
  const OpenBlas& blas = openblas();
  if (blas.read_env) blas.read_env();
  if (blas.set_threads) blas.set_threads(1);
  if (blas.stop) blas.stop();
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
  serial_blas();
}

ThreadBudget::~ThreadBudget() = default;

SerialBlas::SerialBlas(bool serial) {
  const OpenBlas& blas = openblas();
  threads_ = serial && blas.get_threads && blas.set_threads ? blas.get_threads() : 1;
  if (threads_ > 1) blas.set_threads(1);
}

SerialBlas::~SerialBlas() {
  if (threads_ > 1) openblas().set_threads(threads_);
}

}  // namespace depthfem
