// What the cores give: the wall time of an ideal parallel loop (independent arithmetic per item, no
// memory traffic beyond the first-level cache, no serial part), for the benchmarks' thread speed-ups.
// On a shared or virtual machine the second core is often not a whole core: measured here
// 1.33-2.04x for this loop on "2 cores" from one run to the next. A benchmark that times a loop of
// woven on 1 and N threads times this one beside it, in the same process, and prints both ratios.
#pragma once
#include "core/Parallel.hpp"
#include <chrono>
#include <cmath>
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

}  // namespace woven
