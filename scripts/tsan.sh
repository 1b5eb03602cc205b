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
# halt_on_error=0: list every report; second_deadlock_stack for lock reports; Archer and the
# suppressions only for clang.
supp=
if [ "$mode" = clang ]; then supp="suppressions=$PWD/scripts/tsan.supp print_suppressions=1"; fi  # libomp's own mutexes (the file says why)
export TSAN_OPTIONS="halt_on_error=0 second_deadlock_stack=1 history_size=4 $supp ${TSAN_OPTIONS:-}"
export OMP_NUM_THREADS=3 OMP_WAIT_POLICY=passive
if [ -n "$archer" ]; then export OMP_TOOL_LIBRARIES="$archer" ARCHER_OPTIONS="verbose=1"; fi
echo "== $mode: $dir/tsan_threads --gtest_filter=$filter (OMP_NUM_THREADS=3${archer:+, Archer $archer})"
set +e
"$dir/tsan_threads" --gtest_filter="$filter" 2>&1 | tee "$dir/tsan.log"
rc=${PIPESTATUS[0]}
set -e
reports=$(grep -c '^WARNING: ThreadSanitizer' "$dir/tsan.log" || true)
suppressed=$(grep -o 'ThreadSanitizer: Matched [0-9]* suppressions' "$dir/tsan.log" || true)
echo "== $mode: exit $rc, $reports ThreadSanitizer report(s)${suppressed:+ ($suppressed)}; log $dir/tsan.log"
exit "$rc"
