#pragma once
// CPU-time measurement shared by the benchmarks (CPU time per unit of work, best of
// N). On a shared machine wall time counts other processes' work; a thread's CPU time does not.

#include <time.h>

#include <algorithm>
#include <limits>

namespace scanplan::bench {

/// CPU time of the calling thread, seconds.
inline double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// CPU time of the whole process (all threads), seconds: the measure for parallel work.
inline double processCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// The smallest time by `clock` (seconds) of `runs` calls of `f`: the run least disturbed by the
/// rest of the machine (caches, frequency, interrupts).
template <class Clock, class F>
double bestOf(int runs, Clock clock, F&& f) {
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < runs; ++r) {
    const double start = clock();
    f();
    best = std::min(best, clock() - start);
  }
  return best;
}

/// The smallest thread CPU time of `runs` calls of `f`, seconds.
template <class F>
double bestThreadCpuSeconds(int runs, F&& f) {
  return bestOf(runs, threadCpuSeconds, f);
}

/// The same with the process's CPU time, for work spread over threads.
template <class F>
double bestProcessCpuSeconds(int runs, F&& f) {
  return bestOf(runs, processCpuSeconds, f);
}

}  // namespace scanplan::bench
