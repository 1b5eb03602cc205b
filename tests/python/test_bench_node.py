"""The bare-node thread benchmark kept from rotting: bench/device_threads.sh's `quick` mode runs
the cmake-built bench_impact (no YADE) on the tension scene and the struck ply, small, on 1 and 2 threads:
the same bits at both counts, the per-phase times and speed-ups in its JSON, the cores' handoff costs, and
the script's table.
A few seconds; the node's own run (`run`) and static build (`build`) are not exercised here."""
import json
import os
import subprocess

import pytest

from conftest import ROOT

BENCH = os.path.join(ROOT, 'build', 'bench_impact')


def _bench():
    if not os.path.exists(BENCH):
        cache = os.path.join(ROOT, 'build', 'CMakeCache.txt')
        if os.path.exists(cache) and 'WOVEN_BENCH:BOOL=OFF' in open(cache).read():
            pytest.skip('build/ was configured with WOVEN_BENCH=OFF')
        pytest.fail('%s is missing: cmake --build build --target bench_impact' % BENCH)
    return BENCH


def test_device_threads_quick_same_bits(tmp_path):
    env = dict(os.environ, BENCH=_bench(), OMP_WAIT_POLICY='passive')
    env.pop('OMP_NUM_THREADS', None)
    env.pop('ONLY', None), env.pop('THREADS', None)
    r = subprocess.run(['bash', os.path.join(ROOT, 'bench', 'device_threads.sh'), 'quick', str(tmp_path)], cwd=ROOT,
                       env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    table = (tmp_path / 'table.txt').read_text()
    assert 'same bits at every count: yes' in table, table
    assert len([l for l in table.splitlines() if l.startswith('cores: ')]) == 1, table
    for name, scene in (('tension_20', 'tension'), ('impact_5k', 'impact')):
        s = json.loads((tmp_path / (name + '.json')).read_text())
        assert s['scene'] == scene and s['same_bits'] is True
        assert s['cps'] > 2048  # more than one chunk of CPs: the threads split the loops
        assert s['phase_names'] == ['refit', 'broad', 'narrow', 'respond', 'project', 'rest']
        assert [run['threads'] for run in s['runs']] == [1, 2]
        for run in s['runs']:
            assert run['same_bits'] is True and run['bits'] == s['runs'][0]['bits']
            assert len(run['phase_s']) == 6 and all(t >= 0 for t in run['phase_s'])
            assert run['wall_s'] > 0 and run['speedup'] > 0 and run['ideal_speedup'] > 0 and run['steps'] > 0
        # the cores' handoff costs beside the ideal loop: a line's round trip takes at least the two
        # stores and loads (tens of ns anywhere), a line another core wrote is never read faster than
        # by 3x one's own (the ratio of two timings of the same reads: noise, not a cache, below 1)
        assert s['handoff_round_trip_ns'] > 10 and s['remote_read_ratio'] > 0.33, s
        # one row per count in the table, with its speed-up and the ideal loop's
        assert len([l for l in table.splitlines() if l.startswith(name + ' ')]) == 2, table


def test_bench_impact_refuses_bad_keys():
    for arg, text in (('scene=bogus', 'scene = bogus is invalid'), ('yarns=7', 'yarns = 7 is invalid'),
                      ('sweep_order=x', 'sweep_order = x is invalid')):
        r = subprocess.run([_bench(), arg], capture_output=True, text=True, timeout=30)
        assert r.returncode == 2 and text in r.stderr, r.stderr
