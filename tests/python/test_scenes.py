"""Scene scripts keep the output contract (yade -n -x, key=value, out=DIR, summary.json, exit
status) and their figures agree with theory."""
import math
import os

import pytest
from conftest import run_refused, run_scene


def smith_velocity(eps, E, rho):
    """Smith's relation written forward (independent of woven.theory's bisection)."""
    c = math.sqrt(E / rho)
    return c * math.sqrt(2 * eps * math.sqrt(eps * (1 + eps)) - eps * eps)


def test_smith_matches_theory(tmp_path):
    rc, log, s = run_scene('smith.py', tmp_path, 'elements=2000', 'levels=3', 'V=300', 'E=70e9')
    assert rc == 0, log
    assert s['status'] == 'ok'
    eps = s['measured']['strain']
    # the measured strain, put back into Smith's relation, gives the impact speed within 1.5 %
    assert smith_velocity(eps, 70e9, 1440) == pytest.approx(300, rel=0.015)
    assert eps == pytest.approx(s['reference']['strain'], rel=0.01)
    c = math.sqrt(70e9 / 1440)
    assert s['measured']['U_E'] == pytest.approx(c * (math.sqrt(eps * (1 + eps)) - eps), rel=0.03)
    conv = s['measured']['convergence']
    assert [r['elements'] for r in conv] == [500, 1000, 2000]
    assert abs(conv[-1]['U_E_error']) < abs(conv[0]['U_E_error'])  # converges with element length
    assert os.path.exists(tmp_path / 'smith.png') and os.path.exists(tmp_path / 'convergence.csv')


def test_weave_script(tmp_path):
    rc, log, s = run_scene('weave.py', tmp_path, 'nx=4', 'ny=4', 'cp_per_span=3')
    assert rc == 0, log
    assert s['checks']['crossing_clearance']['passed'] and s['checks']['areal_density']['passed']
    assert s['measured']['warp_yarns'] == 8 and s['units']['areal_density'] == 'kg/m^2'
    assert os.path.getsize(tmp_path / 'weave.png') > 10000


@pytest.mark.parametrize('script, arg, name', [('smith.py', 'colour=red', 'colour'), ('smith.py', 'V=-3', 'V'),
                                               ('weave.py', 'pattern=zigzag', 'pattern'),
                                               ('tension.py', 'friction=3', 'friction'),
                                               ('tension.py', 'body_friction=-1', 'body_friction'),
                                               ('contact_sweep.py', 'jobs=0', 'jobs')])
def test_bad_key_fails_with_its_name(script_server, tmp_path, script, arg, name):
    rc, log, s = run_refused(script_server, script, tmp_path, arg)
    assert rc != 0 and name in log and 'allowed' in log


# A time step so small that the run's step count overflowed YADE's C long (an OverflowError, found by
# `scripts/fuzz.py seed=20261205`) is refused naming the key that set it (woven.params.check_steps).
@pytest.mark.parametrize('script, args, name', [
    ('smith.py', ['safety=1e-300'], 'safety'),
    ('tension.py', ['nx=1', 'ny=1', 'safety=1e-300'], 'safety'),
    ('pullout.py', ['safety=1e-300'], 'safety'),
    ('ballistic.py', ['side=0.0127', 'safety=1e-300'], 'safety'),
    ('ballistic.py', ['side=0.0127', 'guard_safety=1e-300'], 'guard_safety'),
    ('soak.py', ['nx=1', 'ny=1', 'safety=1e-300'], 'safety')])
def test_a_run_of_more_than_a_billion_steps_is_refused_naming_the_key(script_server, tmp_path, script, args, name):
    rc, log, s = run_refused(script_server, script, tmp_path, *args)
    assert rc != 0 and ('%s = 1e-300 is invalid' % name) in log and 'more than 1000000000' in log, log
    assert 'OverflowError' not in log


def test_the_grid_baselines_tiny_step_is_refused_naming_dt_factor(tmp_path):
    # in its own YADE process (the grid model labels its engines in YADE's own namespace)
    rc, log, s = run_scene('tension.py', tmp_path, 'nx=1', 'ny=1', 'model=yade', 'dt_factor=1e-300')
    assert rc != 0 and 'dt_factor = 1e-300 is invalid' in log and 'OverflowError' not in log and s is None


def test_check_steps_refuses_past_the_limit_with_the_least_value():
    from woven.params import MAX_STEPS, check_steps
    assert check_steps(1e-4, 1e-8, 'safety', 0.7) == pytest.approx(1e4)
    with pytest.raises(ValueError) as e:
        check_steps(1.0, 1e-10, 'safety', 0.5)  # 1e10 steps: the least safety is 0.5 x 10 = 5
    assert 'safety = 0.5 is invalid' in str(e.value) and 'safety >= 5' in str(e.value)
    with pytest.raises(ValueError):
        check_steps(1.0, 0.0, 'dt_factor', 0.0)
    assert check_steps(MAX_STEPS * 1e-9, 1e-9, 'safety', 1.0) == pytest.approx(MAX_STEPS)


def test_a_refused_key_stops_yade_with_a_non_zero_exit(tmp_path):
    # the contract as a user meets it: yade -x exits non-zero, the log names the key (the other
    # refusals are checked in one process: conftest.run_refused)
    rc, log, s = run_scene('smith.py', tmp_path, 'V=-3')
    assert rc != 0 and 'V = -3.0 is invalid' in log and 'allowed' in log and s is None


# yade-batch with a table: tests/python/test_doc_commands.py runs the README's
# `yade-batch --job-threads=1 scripts/batch/smith.table scripts/smith.py` as written.


@pytest.mark.parametrize('pattern, n, crossings', [('plain', 2, 16), ('satin', 1, 25)])
def test_tension_scene(tmp_path, pattern, n, crossings):
    """KM2 706 pulled along the warp (4 x 4 yarns plain, 5 x 5 satin with its floats): the crimp
    comes out first (toe), then the straightened warp yarns carry the load with their own n E A."""
    rc, log, s = run_scene('tension.py', tmp_path, 'pattern=%s' % pattern, 'nx=%d' % n, 'ny=%d' % n, 'samples=60')
    assert rc == 0, log
    m, ref = s['measured'], s['reference']
    assert m['strain_end'] == pytest.approx(ref['warp_crimp_built'] + 0.003)
    assert 0.8 * ref['warp_crimp_built'] < m['toe_strain'] <= 1.05 * ref['warp_crimp_built']
    assert m['final_stiffness'] == pytest.approx(ref['straight_yarns_stiffness'], rel=0.2)
    assert abs(m['stiffness_ratio']) < 0.05  # the free weft does not resist decrimping
    assert m['crossing_order_flips'] == 0 and m['crossings'] == crossings
    assert m['final_overlap'] < 0.01 * ref['yarn_thickness']
    assert m['state_roundtrip_bitwise'] is True
    for f in ('curve.csv', 'tension.png', 'pretensioned.state'):
        assert os.path.exists(tmp_path / f)
