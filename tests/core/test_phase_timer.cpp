// Phase timers: wall-clock and CPU seconds accumulate per phase, apart from each other.
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>

#include "core/phase_timer.hpp"

namespace depthfem {
namespace {

TEST(PhaseTimers, AddsWallAndCpuSecondsPerPhase) {
  PhaseTimers t;
  t.add("solve", 1.0, 2.0);
  t.add("search", 0.25);
  t.add("solve", 0.5, 0.25);
  EXPECT_EQ(t.seconds("solve"), 1.5);
  EXPECT_EQ(t.cpu_seconds("solve"), 2.25);
  EXPECT_EQ(t.seconds("search"), 0.25);
  EXPECT_EQ(t.cpu_seconds("search"), 0.0);
  EXPECT_EQ(t.cpu_seconds("none"), 0.0);
  ASSERT_EQ(t.phases().size(), 2u);
  EXPECT_EQ(t.phases()[0].first, "solve");  // in the order of first use
}

TEST(PhaseTimers, AScopeCountsTheCpuTimeOfEveryThread) {
  // Work that takes CPU time on whichever threads run it: the scope's CPU seconds are the
  // process clock's advance over the scope, so positive and within its advance around the
  // scope (no bound on speed: only on what the clocks must show).
  PhaseTimers t;
  std::atomic<double> sink{0};
  const double before = process_cpu_seconds();
  {
    PhaseTimers::Scope scope(t, "work");
    tbb::parallel_for(0, 64, [&](int k) {
      double s = 0;
      for (int i = 1; i < 2000000; ++i) s += std::sqrt(double(i + k));
      sink.store(s);
    });
  }
  const double after = process_cpu_seconds();
  EXPECT_GT(sink.load(), 0.0);
  EXPECT_GT(t.cpu_seconds("work"), 0.0);
  EXPECT_LE(t.cpu_seconds("work"), after - before);
  EXPECT_GT(t.seconds("work"), 0.0);
}

}  // namespace
}  // namespace depthfem
