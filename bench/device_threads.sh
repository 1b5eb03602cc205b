#!/usr/bin/env bash
# The thread figures on a bare node (no YADE, no compiler, no network), from one command.
#   bash bench/device_threads.sh build          # here: static bench_impact into .device/ (git-ignored)
#   bash bench/device_threads.sh run [DIR]      # on the node: every measurement, JSON + table into DIR
#   bash bench/device_threads.sh quick [DIR]    # here: the same harness, tiny sizes, threads 1,2 (seconds)
# DIR defaults to $OUT (the device tool's output folder), else out/device_threads. `run` takes ~5 min
# on 16 cores (an estimate from one-thread rates measured on the developers' machine: not yet run
# there); ONLY=tension|impact runs one half. BENCH=path runs another bench_impact (the test runs the
# cmake-built one); JOBS=n for the build (default nproc).
# build: cmake builds the core's static archive (Release: -O3 -DNDEBUG, no -march) in .device/core,
# then g++ links bench/bench_impact.cpp statically (glibc, libstdc++, libgomp inside): .device/bin/
# bench_impact runs on any x86-64 Linux (the node: Ubuntu, glibc 2.39). .device/ is added to
# .git/info/exclude, so the device tool carries it only when asked: carry [".device"] (7 MB).
# run: the tension scene at 100 and 200 yarns per family (80 000 and 320 000 CPs) and the struck ply
# (bench_impact's default impact) at ~1e4, 1e5 and 1e6 CPs, each on 1, 2, 4, 8 and 16 threads in one
# process (OMP_NUM_THREADS = the largest count, so idle threads spin: docs/design.md, Threads). Each
# driver prints per-phase times, the speed-up of each count against one thread beside the ideal
# loop's (core/ThreadCeiling.hpp, measured in the same run) and whether every count ended in the same
# bits; it exits 1 when they differ, and this script then exits 1 after the table.
set -uo pipefail
cd "$(dirname "$0")/.."
mode=${1:-}
dir=${2:-${OUT:-out/device_threads}}
bin=${BENCH:-.device/bin/bench_impact}

build() {
  set -e
  local exclude
  exclude=$(git rev-parse --git-path info/exclude 2>/dev/null || echo .git/info/exclude)
  mkdir -p "$(dirname "$exclude")"
  grep -qxF '.device/' "$exclude" 2>/dev/null || echo '.device/' >> "$exclude"
  cmake -S . -B .device/core -DCMAKE_BUILD_TYPE=Release -DWOVEN_PYTHON=OFF -DWOVEN_TESTS=OFF -DWOVEN_BENCH=OFF > /dev/null
  cmake --build .device/core -j"${JOBS:-$(nproc)}" --target woven_core
  mkdir -p .device/bin
  # (libgomp's offload plugins make the linker warn about dlopen in a static program: not used here)
  g++ -O3 -DNDEBUG -std=c++17 -fopenmp -static -Ipkg -isystem /usr/include/eigen3 bench/bench_impact.cpp \
      .device/core/libwoven_core.a -o .device/bin/bench_impact 2> .device/link.log || { cat .device/link.log; exit 1; }
  grep -v -e "statically linked applications requires" -e "in function .gomp_target_init" .device/link.log || true
  file .device/bin/bench_impact 2>/dev/null || ls -l .device/bin/bench_impact
  echo "device_threads: built .device/bin/bench_impact from $(git rev-parse --short HEAD)$([ -z "$(git status --porcelain -- pkg bench)" ] || echo ' with uncommitted changes in pkg/ or bench/')"
}

# One driver run: name, then bench_impact's keys. Log and JSON into $dir; status 1 if the bits differ.
bench() {
  local name=$1; shift
  echo "== $name: $bin $* threads=$threads"
  "$bin" "$@" threads="$threads" baseline=0 out="$dir/$name.json" 2>&1 | tee "$dir/$name.log"
  local rc=${PIPESTATUS[0]}
  [ "$rc" -eq 0 ] || { echo "device_threads: $name exited $rc"; failed=1; }
}

# The table from the logs: one row per scene and count (CPs, steps, wall, speed-up, ideal loop, their
# ratio, bits, phases), then the cores' handoff costs (core/ThreadCeiling.hpp's coreHandoff).
table() {
  printf '%-12s %8s %6s %4s %9s %8s %8s %6s %5s  %s\n' scene CPs steps thr wall_s speedup ideal ratio bits \
         'refit/broad/narrow/respond/project/rest [s]'
  for log in "$dir"/*.log; do
    awk -v name="$(basename "$log" .log)" '
      / CPs, [0-9]+ timed steps/ { cps = $1 }
      / thread\(s\): / { thr = $1; wall = $3; steps = $6; sp = "1.00"; id = "1.00"; bits = "-"
        if (match($0, /speed-up [0-9.]+x/)) sp = substr($0, RSTART + 9, RLENGTH - 10)
        if (match($0, /ideal loop [0-9.]+x/)) id = substr($0, RSTART + 11, RLENGTH - 12)
        if ($0 ~ /bits the same/) bits = "same"; if ($0 ~ /bits DIFFER/) bits = "DIFF" }
      /by phase \[s\]:/ { printf "%-12s %8s %6s %4s %9s %8s %8s %6.2f %5s  %s/%s/%s/%s/%s/%s\n", name, cps, steps, thr, wall,
                          sp, id, (id > 0 ? sp / id : 0), bits, $5, $7, $9, $11, $13, $15 }' "$log"
  done
  # what moving data between two threads costs on this machine (the first driver's measure)
  grep -h -m1 'the cores:' "$dir"/*.log | head -1 | sed 's/^ *the cores: /cores: /'
}

measure() {
  mkdir -p "$dir"
  [ -x "$bin" ] || { echo "device_threads: $bin is missing: run 'bash bench/device_threads.sh build' first" >&2; exit 2; }
  failed=0
  local max=${threads##*,}
  export OMP_NUM_THREADS=${OMP_NUM_THREADS:-$max}
  { echo "device_threads $mode: $(date -u +%FT%TZ), $(nproc) cores, $(uname -srm), OMP_NUM_THREADS=$OMP_NUM_THREADS" \
         "OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-unset} OMP_PROC_BIND=${OMP_PROC_BIND:-unset}, load: $(cut -d' ' -f1-3 /proc/loadavg)"
    grep -m1 'model name' /proc/cpuinfo; } | tee "$dir/machine.txt"
  [ "$(nproc)" -ge "$max" ] || echo "device_threads: WARNING: $(nproc) cores for $max threads: the largest counts are oversubscribed"
  local t0=$SECONDS
  if [ "$mode" = quick ]; then
    [ "${ONLY:-tension}" = tension ] && bench tension_20 scene=tension yarns=20 steps=40   # 3 200 CPs: two chunks
    [ "${ONLY:-impact}" = impact ] && bench impact_5k side=0.0381 t_end=3e-6 sweep_order=blocked   # 5 512 CPs
  else
    # Step counts: 10-25 s on one thread each on the developers' machine (one thread: tension 100 at
    # 4.2e6 CP-steps/s, 200 at 3.8e6; the ply at 1e4 CPs 0.8e6, at 1e5 2.0e6, at 1e6 1.3e6), so about
    # 1-2 s on 16 threads; all of it an estimated 5.5-6 min at that machine's speed, a third of it
    # building the 1e6 ply five times. The ply runs in sweep_order=blocked (bench_ballistic's order
    # with threads >= 2: the sequential sweeps are serial), the tension scene in its default order.
    [ "${ONLY:-tension}" = tension ] && { bench tension_100 scene=tension yarns=100 steps=500
                                          bench tension_200 scene=tension yarns=200 steps=250; }
    [ "${ONLY:-impact}" = impact ] && { bench impact_1e4 side=0.0508 sweep_order=blocked                # the default impact, 1496 steps (100 us)
                                        bench impact_1e5 side=0.166 steps=300 warmup=2 sweep_order=blocked   # 99 012 CPs
                                        bench impact_1e6 side=0.52 steps=30 warmup=2 sweep_order=blocked; }  # 970 224 CPs, 2.9 GB, 22 s to build
  fi
  table | tee "$dir/table.txt"
  echo "device_threads: $mode took $((SECONDS - t0)) s; same bits at every count: $([ $failed -eq 0 ] && echo yes || echo NO)" \
    | tee -a "$dir/table.txt"
  if [ "$mode" = run ]; then  # the thread goals at 16 threads
    awk '$1 == "tension_200" && $4 == 16 { print "goal: tension 200 yarns, 16 threads: " $6 "x (>= 12x)" }
         $1 == "impact_1e6" && $4 == 16 { print "goal: struck ply 1e6 CPs, 16 threads: " $6 "x (>= 10x)" }' \
      "$dir/table.txt" | tee -a "$dir/table.txt"
  fi
  exit $failed
}

case "$mode" in
  build) build ;;
  run) threads=${THREADS:-1,2,4,8,16}; measure ;;
  quick) threads=${THREADS:-1,2}; measure ;;
  *) echo "usage: bash bench/device_threads.sh build|run|quick [DIR]" >&2; exit 2 ;;
esac
