#!/usr/bin/env bash
# Runs every test: the C++ suite (Release), the C++ suite again under AddressSanitizer and
# UndefinedBehaviorSanitizer, and the Python tests (pytest under Debian's python3, driving YADE).
# Run scripts/setup.sh first (the README's test command does both).
set -euo pipefail
cd "$(dirname "$0")/.."
# ctest runs several test programs at once, each with OpenMP's threads: spinning idle threads on a
# full machine slowed a test 6x (docs/design.md, Threads); the tests check bits, not speed.
export OMP_WAIT_POLICY=passive
echo "== C++ tests (Release)"
ctest --test-dir build --output-on-failure -j"$(nproc)"
echo "== C++ tests (AddressSanitizer + UndefinedBehaviorSanitizer)"
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DWOVEN_SANITIZE=address,undefined \
      -DWOVEN_PYTHON=OFF -DWOVEN_BENCH=OFF > /dev/null
cmake --build build-asan -j"$(nproc)"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-asan --output-on-failure -j"$(nproc)"
echo "== Python tests under YADE"
/usr/bin/python3 -m pytest -q tests/python
