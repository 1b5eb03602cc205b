"""scripts/bench_scaling.py: wall time per step against CPs, and the fitted exponent."""
import json
import math
import os

from conftest import run_scene, run_refused


def test_bench_scaling_two_sizes_and_its_fit(tmp_path):
    rc, out, s = run_scene('bench_scaling.py', tmp_path, 'cps=300,1200', 'steps=3', 'warmup=2', timeout=300)
    assert rc == 0, out
    cases = s['measured']['cases']
    assert [c['scene'] for c in cases] == ['tension', 'tension', 'ballistic', 'ballistic']
    for c, target in zip(cases, [300, 1200, 300, 1200]):
        assert 0.6 * target < c['cps'] < 1.6 * target  # the side rounds to whole pattern repeats
        assert c['seconds_per_step'] > 0 and c['contacts'] > 0
    assert all(c['body_contacts'] > 0 for c in cases if c['scene'] == 'ballistic')  # timed after the first contact
    # Two points: the least-squares line is the line through them (closed form).
    for scene in ('tension', 'ballistic'):
        a, b = [c for c in cases if c['scene'] == scene]
        slope = math.log(b['seconds_per_step'] / a['seconds_per_step']) / math.log(b['cps'] / a['cps'])
        assert abs(s['measured']['fits'][scene]['exponent'] - slope) < 1e-9
    assert os.path.exists(os.path.join(str(tmp_path), 'scaling.png'))
    assert open(os.path.join(str(tmp_path), 'scaling.csv')).readline().startswith('scene,cps,')


def test_bench_scaling_refuses_bad_keys(script_server, tmp_path):
    for arg, text in (('cps=50', 'cps = '), ('scenes=drop', 'scenes = '), ('steps=0', 'steps = 0 is invalid')):
        rc, out, _ = run_refused(script_server, 'bench_scaling.py', tmp_path, arg, timeout=120)
        assert rc != 0 and text in out and 'allowed' in out, out
