#!/usr/bin/env bash
# Runs every test: the C++ suite (Release), the C++ suite again under AddressSanitizer and
# UndefinedBehaviorSanitizer, and the Python tests (pytest under Debian's python3, driving YADE).
# Run scripts/setup.sh first (the README's test command does both).
#
# The sanitizer tier (its own build from scratch, then its run) goes on beside the other two, at a
# lower priority: the Python tests run one YADE process at a time most of the while, and the two
# tiers one after the other left a core idle for half of CI's 30 minutes. Its output goes
# to build-asan/tier.log and is shown when it fails. Each tier's time is printed at the end; the exit
# status is non-zero when any tier fails.
set -uo pipefail
cd "$(dirname "$0")/.."
# ctest runs several test programs at once, each with OpenMP's threads: spinning idle threads on a
# full machine slowed a test 6x (docs/design.md, Threads); the tests check bits, not speed.
export OMP_WAIT_POLICY=passive
jobs=$(nproc)
start=$(date +%s)
since() { echo $(( $(date +%s) - $1 )); }

mkdir -p build-asan
asan_log=build-asan/tier.log
(
  renice -n 10 -p "$BASHPID" > /dev/null 2>&1 || true  # what it starts inherits it
  set -e
  t=$(date +%s)
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DWOVEN_SANITIZE=address,undefined \
        -DWOVEN_PYTHON=OFF -DWOVEN_BENCH=OFF > /dev/null
  cmake --build build-asan -j"$jobs"
  echo "asan build: $(since "$t") s"
  t=$(date +%s)
  # One OpenMP thread unless a test asks for more (the thread tests do): beside the other tiers, the
  # barriers of two threads per test on two busy cores were a sixth of the tier's time.
  OMP_NUM_THREADS=1 ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir build-asan --output-on-failure -j"$jobs"
  echo "asan run: $(since "$t") s"
) > "$asan_log" 2>&1 &
asan_pid=$!

echo "== C++ tests (Release)"
t=$(date +%s)
ctest --test-dir build --output-on-failure -j"$jobs"; release_rc=$?
release_s=$(since "$t")

echo "== Python tests under YADE"
t=$(date +%s)
/usr/bin/python3 -m pytest -q tests/python; pytest_rc=$?
pytest_s=$(since "$t")

echo "== C++ tests (AddressSanitizer + UndefinedBehaviorSanitizer), built and run beside the others"
wait "$asan_pid"; asan_rc=$?
if [ "$asan_rc" -ne 0 ]; then tail -n 200 "$asan_log"; else grep -E "tests passed|Total Test time|^asan " "$asan_log"; fi

echo "== times: C++ Release ${release_s} s (rc $release_rc), Python ${pytest_s} s (rc $pytest_rc), sanitizer tier" \
     "(rc $asan_rc, beside them): $(grep -E '^asan ' "$asan_log" | tr '\n' ' ')total $(since "$start") s"
[ "$release_rc" -eq 0 ] && [ "$pytest_rc" -eq 0 ] && [ "$asan_rc" -eq 0 ]
