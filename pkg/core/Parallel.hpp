// Threads of the hot loops (OpenMP), with results that do not depend on the thread count.
//
// Rules every parallel loop of woven follows (docs/design.md, "Threads"):
//  - a loop writes only its own items (a node, an element, a pair slot): no atomics, no scatter;
//  - sums are taken per chunk of a fixed size (independent of the thread count), each chunk in index
//    order, and the chunk sums added serially in chunk order: the same bits at any thread count;
//  - lists a loop produces are kept per chunk and joined in chunk order.
// Without OpenMP everything runs on the calling thread and gives the same bits.
#pragma once
#include "core/Types.hpp"
#include <algorithm>
#include <vector>
#ifdef _OPENMP
#include <omp.h>
#endif

namespace woven {

/// OpenMP's thread count for the next parallel region of the calling thread (OMP_NUM_THREADS,
/// YADE's -j N, omp_set_num_threads); 1 without OpenMP.
inline int openmpThreads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

namespace detail {
inline int& threadSetting() {
  static int n = 0;  // 0: follow OpenMP
  return n;
}
inline int& threadOverride() {
  thread_local int n = 0;  // ThreadCountScope of the calling thread, 0: none
  return n;
}
}  // namespace detail

/// Threads of woven's loops: n >= 1 forces that count in every thread (YADE runs the engines in its
/// own thread, where omp_set_num_threads called from the script would not reach); 0 follows
/// openmpThreads() of the thread that steps. Not for changing while a step runs.
inline void setThreads(int n) { detail::threadSetting() = n < 0 ? 0 : n; }
/// The count woven's loops use now (>= 1).
inline int threads() {
  if (const int o = detail::threadOverride(); o > 0) return o;
  const int n = detail::threadSetting();
  return n > 0 ? n : openmpThreads();
}

/// While it lives, threads() of the calling thread returns n (n >= 1; 0 changes nothing): how
/// ContactParams::threads sets the collision stage's count.
class ThreadCountScope {
 public:
  explicit ThreadCountScope(int n) : saved_(detail::threadOverride()) {
    if (n > 0) detail::threadOverride() = n;
  }
  ~ThreadCountScope() { detail::threadOverride() = saved_; }
  ThreadCountScope(const ThreadCountScope&) = delete;
  ThreadCountScope& operator=(const ThreadCountScope&) = delete;

 private:
  int saved_;
};

/// Ends the calling thread's idle OpenMP team (omp_pause_resource_all, OpenMP 5.0); the next
/// parallel region of this thread starts a new one. Call it where another thread takes over the
/// stepping (YADE's loop thread after a script built the scene): while a team idles in one thread,
/// libgomp counts more threads than cores and every team's threads sleep at once at each barrier
/// instead of spinning (measured: a region of 20 000 items in the other thread 107 us instead of
/// 6 us; the default ballistic scene on 2 threads 1.04x instead of 1.57x). Returns false inside a
/// parallel region (nothing done) and without OpenMP.
inline bool releaseThreads() {
#ifdef _OPENMP
  return omp_pause_resource_all(omp_pause_soft) == 0;
#else
  return false;
#endif
}

/// Items below which a loop of light bodies (a node, a box) stays on one thread.
constexpr Index kParallelGrain = 2048;

/// body(i) for i in [0, n), split over `nThreads` threads when n >= grain (a region costs a few us).
/// body must write only what belongs to i.
template <class Body>
inline void parallelFor(Index n, Index grain, int nThreads, Body&& body) {
#ifdef _OPENMP
  if (nThreads > 1 && n >= grain) {
#pragma omp parallel for schedule(static) num_threads(nThreads)
    for (Index i = 0; i < n; ++i) body(i);
    return;
  }
#endif
  for (Index i = 0; i < n; ++i) body(i);
}

/// parallelFor with dynamic scheduling, for bodies of uneven cost (chunks of pairs); the same rule:
/// body writes only what belongs to i, so the schedule changes no result.
template <class Body>
inline void parallelForDynamic(Index n, Index grain, int nThreads, Body&& body) {
#ifdef _OPENMP
  if (nThreads > 1 && n >= grain) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(nThreads)
    for (Index i = 0; i < n; ++i) body(i);
    return;
  }
#endif
  for (Index i = 0; i < n; ++i) body(i);
}

/// Number of fixed chunks of `chunk` items covering [0, n).
inline Index chunkCount(Index n, Index chunk) { return n > 0 ? (n + chunk - 1) / chunk : 0; }

/// Sum of body(begin, end) over the fixed chunks [k*chunk, min(n, (k+1)*chunk)), each chunk's sum
/// taken by body in index order and the chunk sums added in chunk order: bit-identical for any thread
/// count. T: Real, Vec3 or a struct with operator+=; zero its neutral value.
template <class T, class Body>
inline T chunkedSum(Index n, Index chunk, int nThreads, const T& zero, Body&& body) {
  const Index nc = chunkCount(n, chunk);
  std::vector<T> part(static_cast<std::size_t>(nc), zero);
  parallelFor(nc, 2, nThreads, [&](Index k) {
    const Index b = k * chunk;
    part[k] = body(b, b + chunk < n ? b + chunk : n);
  });
  T sum = zero;
  for (const T& p : part) sum += p;
  return sum;
}

/// Lists made per fixed chunk joined in chunk order into `out` (the same list at any thread count),
/// each chunk copied to its place on the threads (a serial copy of a step's pairs or contacts held
/// the other threads idle).
template <class T>
inline void joinChunks(const std::vector<std::vector<T>>& parts, std::vector<T>& out, int nThreads) {
  const Index n = static_cast<Index>(parts.size());
  std::vector<std::size_t> start(parts.size() + 1, 0);
  for (Index t = 0; t < n; ++t) start[t + 1] = start[t] + parts[t].size();
  out.resize(start[n]);
  parallelFor(n, 2, nThreads, [&](Index t) { std::copy(parts[t].begin(), parts[t].end(), out.begin() + start[t]); });
}

/// The elements of `in` that keep(element) accepts, in order, into `out` (which may be `in`): fixed
/// chunks of `chunk` elements filtered on the threads into `parts` (scratch kept between calls),
/// then joined in chunk order (the same list at any thread count).
template <class T, class Keep>
inline void keepChunked(const std::vector<T>& in, std::vector<T>& out, Index chunk, std::vector<std::vector<T>>& parts,
                        int nThreads, Keep&& keep) {
  const Index n = static_cast<Index>(in.size());
  parts.resize(static_cast<std::size_t>(chunkCount(n, chunk)));
  parallelFor(static_cast<Index>(parts.size()), 2, nThreads, [&](Index t) {
    std::vector<T>& kept = parts[t];
    kept.clear();
    for (Index k = t * chunk, end = std::min(n, k + chunk); k < end; ++k)
      if (keep(in[k])) kept.push_back(in[k]);
  });
  joinChunks(parts, out, nThreads);
}

/// std::merge of the sorted lists a and b into out, on the threads: fixed chunks of a, each merged
/// with the part of b that std::merge puts before the next chunk (the elements below the chunk's
/// first, an element of a before an equal one of b), written at its place. The same list as
/// std::merge at any thread count.
template <class T>
inline void parallelMerge(const std::vector<T>& a, const std::vector<T>& b, std::vector<T>& out, int nThreads) {
  constexpr Index kChunk = 8192;
  out.resize(a.size() + b.size());
  const Index na = static_cast<Index>(a.size());
  const Index chunks = std::max<Index>(1, chunkCount(na, kChunk));
  // b's part of chunk t starts where b reaches a's first element of the chunk (all of b from 0 for the
  // first chunk, to its end for the last)
  const auto bStart = [&](Index t) {
    if (t == 0) return b.begin();
    if (t >= chunks) return b.end();
    return std::lower_bound(b.begin(), b.end(), a[t * kChunk]);
  };
  parallelFor(chunks, 2, nThreads, [&](Index t) {
    const Index a0 = std::min(na, t * kChunk), a1 = std::min(na, (t + 1) * kChunk);
    const auto b0 = bStart(t), b1 = bStart(t + 1);
    std::merge(a.begin() + a0, a.begin() + a1, b0, b1, out.begin() + (a0 + (b0 - b.begin())));
  });
}

}  // namespace woven
