"""scripts/compare.py in its quick mode: every method runs on the same scene, the reference converges
in the time step, the stability map finds the penalty method's blow-up where theory puts it and
the guard refusing woven's over-critical steps, and the outputs of the contract are written."""
import csv
import math
import os

import pytest
from conftest import run_scene, run_refused


FINE_RADII = [1]


@pytest.fixture(scope='module')
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp('compare')
    # quick=1 with the stability map at 1000 m/s and of the impulse and penalty methods only (the cells the
    # test below checks), the adaptive cases at one fine radius (the default is two): 45 YADE processes
    # instead of 80, and 8 us of impact instead of quick's 15 (in contact from ~2 us; CI time)
    rc, log, s = run_scene('compare.py', out, 'quick=1', 'map_speeds=1000', 'map_methods=impulse,penalty',
                           'fine_radii=%s' % ','.join(map(str, FINE_RADII)), 't_end=8e-6', timeout=1500)
    return out, rc, log, s


def test_every_method_runs_and_the_outputs_are_written(quick):
    out, rc, log, s = quick
    assert rc == 0, log[-3000:]
    assert s['status'] == 'ok'
    rows = s['measured']['rows']
    assert {r['method'] for r in rows} == {'impulse', 'impulse_adaptive', 'chords', 'paper', 'penalty', 'no_flattening',
                                           'section_springs', 'yade_grid'}
    for name in ('cases.csv', 'table.md', 'scenes.md', 'pareto.png', 'stability.csv', 'stability.png'):
        assert os.path.getsize(out / name) > 100, name
    with open(out / 'cases.csv') as f:
        assert len(list(csv.DictReader(f))) == len(rows)


def test_reference_converges_in_the_time_step(quick):
    out, rc, log, s = quick
    rows = s['measured']['rows']
    ref = [r for r in rows if r['reference']]
    assert len(ref) == 1 and ref[0]['velocity_error'] == 0
    # the same resolution at twice the reference's time step: within 5 % of its velocity drop
    same = [r for r in rows if r['method'] == 'impulse' and not r['reference'] and r['cp_per_span'] == ref[0]['cp_per_span']
            and r['substeps'] == 1]
    assert same and all(r['velocity_error'] < 0.05 for r in same), same
    assert all(r['energy_error'] < 0.01 for r in rows if r['method'] == 'impulse')


def test_stability_map_finds_the_penalty_limit_and_the_guard(quick):
    out, rc, log, s = quick
    cells = s['measured']['stability']
    # woven refuses a step above the chain's critical one (ballistic.py: safety in (0, 1])
    assert all(c['result'] == 'refused' for c in cells if c['method'] == 'impulse' and c['dt_over_dt_crit'] > 1)
    # penalty: stable only below dt = 2 sqrt(m_eff / k). Node mass of a 0.75 mm CP of KM2 706 yarn:
    m = 1440 * 4.63e-8 * 0.747e-3
    dt_crit = 0.747e-3 / math.sqrt(90e9 / 1440)
    checked = 0
    for c in cells:
        if c['method'] != 'penalty' or c['dt_over_dt_crit'] > 1:
            continue
        dt = c['dt_over_dt_crit'] * dt_crit
        limit = 2 * math.sqrt(0.5 * m / c['stiffness'])  # two equal nodes: m_eff = m / 2
        if dt > limit:
            assert c['result'] == 'blow-up', c
            checked += 1
        elif dt < 0.25 * limit:
            assert c['result'] != 'blow-up', c
            checked += 1
    assert checked >= 2


def test_adaptive_cases_coarsen_away_from_the_impact(quick):
    out, rc, log, s = quick
    rows = s['measured']['rows']
    uniform = {(r['cp_per_span'], r['dt_over_dt_crit']): r for r in rows if r['method'] == 'impulse' and not r['reference']}
    coarse = [r for r in rows if r['method'] == 'impulse' and r['cp_per_span'] == 1][0]
    adaptive = [r for r in rows if r['method'] == 'impulse_adaptive']
    # fine_radius = the fine radii asked (in projectile sizes: a 3 mm sphere), at 2 and 4 CPs per span only
    assert sorted({r['fine_radius'] for r in adaptive}) == pytest.approx([3e-3 * x for x in FINE_RADII])
    assert {r['cp_per_span'] for r in adaptive} == {2, 4}
    for r in [r for r in adaptive if r['substeps'] == 1]:
        # fewer CPs than the uniform case of its resolution, more than the coarse ply (a fine patch)
        assert coarse['cps'] < r['cps'] < uniform[(r['cp_per_span'], r['dt_over_dt_crit'])]['cps'], r
        assert r['status'] == 'ok' and r['energy_error'] < 0.01, r
    # the headline pools both resolutions; the uniform-only ratio is never the larger
    m = s['measured']
    assert m['speed_ratio_woven_case'] is not None
    assert m['speed_ratio_at_matched_accuracy'] >= m['speed_ratio_uniform_only']


def test_substep_cases_meet_the_contacts_less_often(quick):
    out, rc, log, s = quick
    rows = s['measured']['rows']
    for method in ('impulse', 'impulse_adaptive'):
        runs = [r for r in rows if r['method'] == method and not r['reference']]
        plain = {(r['cp_per_span'], r['dt_over_dt_crit'], r['fine_radius']): r for r in runs if r['substeps'] == 1}
        sub = [r for r in runs if r['substeps'] > 1]
        # s = 2 and 4, never more than the case's CPs per span
        assert {r['substeps'] for r in sub} == {2, 4} and all(r['substeps'] <= r['cp_per_span'] for r in sub)
        for r in sub:
            q = plain[(r['cp_per_span'], r['dt_over_dt_crit'], r['fine_radius'])]
            # the contact step (YADE's O.dt) is s times the plain case's, the ply the same
            assert r['dt'] == pytest.approx(r['substeps'] * q['dt'], rel=1e-12) and r['cps'] == q['cps']
            assert r['status'] == 'ok' and r['energy_error'] < 0.01, r


def test_bad_fine_radii_names_the_key(script_server, tmp_path):
    rc, log, s = run_refused(script_server, 'compare.py', tmp_path, 'fine_radii=1,-2')
    assert rc != 0 and 'fine_radii = ' in log and 'allowed' in log


def test_smith_error_of_woven_chain_is_small(quick):
    out, rc, log, s = quick
    smith = [r for r in s['measured']['scenes'] if r['scene'] == 'smith' and r['model'] == 'woven']
    assert smith and all(r['strain_error'] < 0.01 for r in smith)
    assert min(r['wave_speed_error'] for r in smith) < 0.02


def test_bad_method_names_the_key(script_server, tmp_path):
    rc, log, s = run_refused(script_server, 'compare.py', tmp_path, 'methods=impulse,magic')
    assert rc != 0 and 'methods = ' in log and 'allowed' in log


def test_bad_map_method_names_the_key(script_server, tmp_path):
    # chords has no map of its own; a method not run has none either
    for arg in ('map_methods=chords', 'map_methods=penalty methods=impulse,paper'):
        rc, log, s = run_refused(script_server, 'compare.py', tmp_path, *arg.split())
        assert rc != 0 and 'map_methods = ' in log and 'allowed' in log, arg


def test_adaptive_substep_cases_also_run_multi_rate(quick):
    out, rc, log, s = quick
    rows = s['measured']['rows']
    key = lambda r: (r['cp_per_span'], r['dt_over_dt_crit'], r['fine_radius'], r['substeps'])  # noqa: E731
    adaptive = [r for r in rows if r['method'] == 'impulse_adaptive' and r['substeps'] > 1]
    twins = [r for r in adaptive if r['multirate']]
    # each adaptive case with substeps has its multi-rate twin, and nothing else is multi-rate
    assert twins and sorted(map(key, twins)) == sorted(key(r) for r in adaptive if not r['multirate'])
    assert not [r for r in rows if r['multirate'] and r not in twins]
    for r in twins:
        assert r['status'] == 'ok' and r['energy_error'] < 0.01, r
        assert r['max_yarn_penetration'] < 0.1 * 0.11e-3 and r['max_body_penetration'] < 0.1 * 0.11e-3, r
