// What the cores give: the wall time of an ideal parallel loop (independent arithmetic per item, no
// memory traffic beyond the first-level cache, no serial part), for the benchmarks' thread speed-ups,
// and what moving data between two threads costs (coreHandoff), which the ideal loop never pays.
// On a shared or virtual machine the second core is often not a whole core: measured here
// 1.33-2.04x for this loop on "2 cores" from one run to the next. A benchmark that times a loop of
// woven on 1 and N threads times this one beside it, in the same process, and prints both ratios.
#pragma once
#include "core/Parallel.hpp"
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <thread>
#include <vector>

namespace woven {

/// Seconds taken by `rounds` rounds of the ideal loop on nThreads threads (1 << 16 items, 20 square
/// roots each, a parallel region per round as woven's loops have). Ends the calling thread's team
/// after (releaseThreads): the benchmarks call it from the script's thread, whose idle team would
/// slow the stepping thread's regions (core/Parallel.hpp).
inline double idealLoopSeconds(int nThreads, int rounds) {
  constexpr Index kItems = 1 << 16;
  std::vector<double> x(kItems, 1.0);
  const auto t0 = std::chrono::steady_clock::now();
  for (int r = 0; r < rounds; ++r)
    parallelFor(kItems, 1, nThreads, [&](Index i) {
      double v = x[i];
      for (int k = 0; k < 20; ++k) v = std::sqrt(v * 1.0000001 + 0.5);
      x[i] = v;
    });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  releaseThreads();
  return x[0] > 0 ? seconds : -1;  // x read: the loop is not optimised away
}

/// What moving data between two threads costs on this machine, beside the ideal loop (which moves
/// none): the round trip of one cache line bounced between threads 0 and 1 [ns], and how many times
/// longer thread 0 takes to read 16 384 scattered lines (1 MiB) that thread 1 wrote last than the
/// same lines written by itself (the best of 5 each). The step hands its data between the threads at
/// every serial phase (the sweeps) and every gather by node (contacts, rows): where these two are
/// large, its speed-up stays far below the ideal loop's whatever the loops (docs/design.md,
/// Threads). Where other processes hold the cores the round trip measures the scheduler instead
/// (microseconds and more): read it beside the ideal loop of the same run. NaN without OpenMP or
/// where the region gets fewer than 2 threads.
struct CoreHandoff {
  double roundTripNs = std::numeric_limits<double>::quiet_NaN();
  double remoteReadRatio = std::numeric_limits<double>::quiet_NaN();
};

inline CoreHandoff coreHandoff() {
  CoreHandoff h;
#ifdef _OPENMP
  using Clock = std::chrono::steady_clock;
  constexpr int kBounces = 20000, kLines = 1 << 14, kRepeats = 5;
  struct alignas(64) Line {
    std::atomic<int> v{0};
    double pad[7];
  };
  Line flag;
  std::vector<Line> lines(kLines);
  std::vector<std::uint32_t> order(kLines);
  for (std::uint32_t k = 0, x = 12345; k < kLines; ++k) x = x * 1664525u + 1013904223u, order[k] = x % kLines;
  double local = 1e300, remote = 1e300, sum = 0;
#pragma omp parallel num_threads(2) reduction(+ : sum)
  {
    const int t = omp_get_thread_num();
    if (omp_get_num_threads() == 2) {
      // Thread 0 writes 2k + 1, thread 1 answers 2k + 2; thread 0 ends the bounces with -1 after
      // kBounces or 50 ms (two threads on one busy core take a time slice a bounce: the waits
      // yield after a while, so the measure ends instead of spinning out the slices).
      const auto wait = [&](auto&& until) {
        for (int spins = 0; !until(flag.v.load(std::memory_order_acquire)); ++spins)
          if (spins > 4096) std::this_thread::yield();
      };
      if (t == 0) {
        const auto t0 = Clock::now();
        int k = 0;
        double seconds = 0;
        while (k < kBounces && seconds < 0.05) {
          flag.v.store(2 * k + 1, std::memory_order_release);
          wait([k](int v) { return v == 2 * k + 2; });
          if (++k % 64 == 0 || k == kBounces) seconds = std::chrono::duration<double>(Clock::now() - t0).count();
        }
        flag.v.store(-1, std::memory_order_release);
        h.roundTripNs = 1e9 * seconds / k;
      } else {
        for (int v = 0;;) {
          wait([&v](int now) { return (v = now) == -1 || now % 2 == 1; });
          if (v == -1) break;
          flag.v.store(v + 1, std::memory_order_release);
        }
      }
#pragma omp barrier
      for (int r = 0; r < 2 * kRepeats; ++r) {
        const int writer = r % 2;  // even rounds: thread 0 wrote the lines; odd: thread 1
        if (t == writer)
          for (Line& l : lines) l.pad[0] += 1;
#pragma omp barrier
        if (t == 0) {
          const auto t0 = Clock::now();
          double s = 0;
          for (std::uint32_t k : order) s += lines[k].pad[0];
          const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
          (writer == 0 ? local : remote) = std::min(writer == 0 ? local : remote, dt);
          sum += s;
        }
#pragma omp barrier
      }
      if (t == 0 && sum > 0) h.remoteReadRatio = remote / local;
    }
  }
  releaseThreads();
#endif
  return h;
}

}  // namespace woven
