#!/bin/bash
# The gap contact model's speed limit (docs/ballistic.md, "The gap model's cost"): bench_ballistic of a
# baseline build and of this one, alternated N times on the same machine, and each pair's ratio.
#   bash bench/pair_ballistic.sh OLD_CHECKOUT OLD_PACKAGE_DIR [NEW_PACKAGE_DIR] [N]
# OLD_CHECKOUT: a worktree of the baseline commit (git worktree add /tmp/old ac50933), whose own
# scripts/bench_ballistic.py runs with OLD_PACKAGE_DIR on PYTHONPATH (a folder holding its woven/);
# NEW_PACKAGE_DIR: this build's package folder (default: the installed woven). Timings drift +-30 %
# on a shared machine: compare the ratios of one session.
set -e
OLD=$1; OLDPKG=$2; NEWPKG=${3:-}; N=${4:-3}
[ -f "$OLD/scripts/bench_ballistic.py" ] || { echo "OLD_CHECKOUT = '$OLD' is invalid: it must hold scripts/bench_ballistic.py" >&2; exit 2; }
[ -d "$OLDPKG/woven" ] || { echo "OLD_PACKAGE_DIR = '$OLDPKG' is invalid: it must hold woven/" >&2; exit 2; }
HERE=$(cd "$(dirname "$0")/.." && pwd)
OUT=${OUT:-/tmp/pair_ballistic}
for k in $(seq 1 "$N"); do
  (cd "$OLD" && PYTHONPATH=$OLDPKG yade -n -x scripts/bench_ballistic.py out=$OUT/old_$k > $OUT.old_$k.log 2>&1)
  (cd "$HERE" && PYTHONPATH=$NEWPKG yade -n -x scripts/bench_ballistic.py out=$OUT/new_$k > $OUT.new_$k.log 2>&1)
  /usr/bin/python3 - "$OUT" "$k" <<'PY'
import json, sys
d, k = sys.argv[1], sys.argv[2]
o = json.load(open('%s/old_%s/summary.json' % (d, k)))['measured']
n = json.load(open('%s/new_%s/summary.json' % (d, k)))['measured']
print('pair %s: baseline %.1f s, this build %.1f s: %.2fx (limit 1.3x); by phase, this build: %s' % (
    k, o['wall_seconds'], n['wall_seconds'], n['wall_seconds'] / o['wall_seconds'],
    ', '.join('%s %.1f' % kv for kv in n['phase_seconds'].items())))
PY
done
