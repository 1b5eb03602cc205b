#!/usr/bin/env bash
# ThreadSanitizer on woven's OpenMP threads (docs/reliability.md, "Threads under ThreadSanitizer").
#   bash scripts/tsan.sh [clang|gcc] [gtest filter, default Threads.*]
# clang (default): woven_core and tests/cpp/test_threads.cpp built with clang++ -fsanitize=thread
#   against LLVM's OpenMP runtime (libomp, Debian's libomp-14-dev, which the clang package pulls in)
#   and run with its Archer tool (libarcher.so), which tells TSan about the runtime's own barriers,
#   locks and task hand-offs. This is the check: a report here is a race in woven.
# gcc: the same with g++ and GCC's libgomp, which Debian does not build with TSan: its barriers are
#   futexes and atomics TSan cannot see, so every parallel region's start and end look unordered and
#   TSan reports races between the master's writes before a region and the workers' reads in it
#   (false positives). Kept to show that (and to see what changes if Debian's libgomp ever does).
# Each build is a separate folder (build-tsan-clang, build-tsan-gcc); the run is slow (TSan costs
# 5-15x), so this is a script, not part of scripts/test.sh or CI. Exit status: TSan's (66 on a report).
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-clang}
filter=${2:-Threads.*}
jobs=${JOBS:-$(nproc)}
case "$mode" in
  clang) cxx=clang++; dir=build-tsan-clang; omp=-fopenmp=libomp
         archer=$(ls /usr/lib/llvm-*/lib/libarcher.so 2>/dev/null | tail -1)
         [ -n "$archer" ] || { echo "tsan.sh: libarcher.so not found (apt-get install libomp-dev clang)"; exit 2; } ;;
  gcc)   cxx=g++; dir=build-tsan-gcc; omp=-fopenmp; archer= ;;
  *)     echo "tsan.sh: mode = '$mode' is invalid: allowed clang or gcc"; exit 2 ;;
esac
# The core through CMake (its sources and flags: -fsanitize=thread via WOVEN_SANITIZE); the thread
# test alone, compiled and linked here, so the rest of the suite is not built with TSan for nothing.
CXX=$cxx cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DWOVEN_SANITIZE=thread \
      -DWOVEN_PYTHON=OFF -DWOVEN_TESTS=OFF -DWOVEN_BENCH=OFF > /dev/null
cmake --build "$dir" --target woven_core -j"$jobs"
$cxx -std=c++17 -O2 -g -fsanitize=thread -fno-omit-frame-pointer $omp -Ipkg -isystem /usr/include/eigen3 \
     tests/cpp/test_threads.cpp "$dir/libwoven_core.a" -lgtest -lgtest_main -pthread $omp \
     -o "$dir/tsan_threads"
# halt_on_error=0: list every report; second_deadlock_stack for lock reports.
# ignore_noninstrumented_modules=1 (clang; Archer asks for it): Debian's libomp is not built with TSan,
# and without it TSan reports libomp's own mutexes (one thread's pthread_mutex_init, another's
# pthread_mutex_lock, both called from libomp's frames at a team's start: 2-3 reports a run).
extra=
if [ "$mode" = clang ]; then extra="ignore_noninstrumented_modules=1"; fi
export TSAN_OPTIONS="halt_on_error=0 second_deadlock_stack=1 history_size=4 $extra ${TSAN_OPTIONS:-}"
export OMP_NUM_THREADS=3 OMP_WAIT_POLICY=passive
if [ -n "$archer" ]; then export OMP_TOOL_LIBRARIES="$archer" ARCHER_OPTIONS="verbose=1"; fi
# A canary first: an OpenMP loop that adds to one shared sum must be reported, or a clean run of the
# tests below would prove nothing (a tool that is not loaded, options that hide everything).
cat > "$dir/canary.cpp" <<'EOF_CANARY'
#include <cstdio>
int main() {
  double sum = 0;
#pragma omp parallel for
  for (int i = 0; i < 100000; ++i) sum += i;  // the race
  static double out[100000];
#pragma omp parallel for
  for (int i = 0; i < 100000; ++i) out[i] = 2.0 * i;  // no race: each iteration writes its own slot
  std::printf("%g %g\n", sum, out[99999]);
}
EOF_CANARY
$cxx -O1 -g -fsanitize=thread $omp "$dir/canary.cpp" -o "$dir/canary"
canary=$("$dir/canary" 2>&1 | grep -c '^WARNING: ThreadSanitizer' || true)
echo "== $mode: canary (one racy loop, one clean loop): $canary report(s), expected 1 (the racy loop)"
echo "== $mode: $dir/tsan_threads --gtest_filter=$filter (OMP_NUM_THREADS=3${archer:+, Archer $archer})"
set +e
"$dir/tsan_threads" --gtest_filter="$filter" 2>&1 | tee "$dir/tsan.log"
rc=${PIPESTATUS[0]}
set -e
reports=$(grep -c '^WARNING: ThreadSanitizer' "$dir/tsan.log" || true)
echo "== $mode: exit $rc, $reports ThreadSanitizer report(s); log $dir/tsan.log"
if [ "$canary" -lt 1 ]; then echo "tsan.sh: the canary's race was not reported: this run checks nothing"; exit 3; fi
exit "$rc"
