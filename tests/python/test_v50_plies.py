"""Cunniff's axes (woven.cunniff) against hand-computed cases, and scripts/v50_plies.py on two tiny
campaigns (1 and 2 plies of 6.35 mm): its table's arithmetic against the campaigns' own V50s and the
hand-computed U* of KM2, and its refusals of bad folders and of campaigns of different scenes."""
import csv
import json
import math
import os
import subprocess

import pytest
from conftest import ROOT, run_refused

from woven import cunniff


def test_u_star_and_axes_hand_case():
    # Round numbers: sigma eps / (2 rho) = 2880 * 1 / 2880 = 1 m^2/s^2, sqrt(E / rho) = sqrt(1.44e9 / 1440)
    # = 1000 m/s, so U* = 1000 m^3/s^3 and U*^(1/3) = 10 m/s; A_d A_p / m_p = 2 * 3e-5 / 1e-3 = 0.06.
    us = cunniff.u_star(2880.0, 1.0, 1440.0, 1.44e9)
    assert us == pytest.approx(1000.0, rel=1e-12)
    x, y = cunniff.axes(50.0, 2.0, 3e-5, 1e-3, us)
    assert x == pytest.approx(0.06, rel=1e-12)
    assert y == pytest.approx(5.0, rel=1e-12)


def test_km2_rcc_against_the_reference():
    # KM2 as woven's preset: E = 90 GPa, rho = 1440, eps_f = 5 %, sigma_f = E eps_f = 4.5 GPa.
    # By hand: sigma eps / 2 rho = 2.25e8 / 2880 = 78125; sqrt(E / rho) = sqrt(6.25e7) = 7905.694;
    # U* = 6.17632e8 m^3/s^3; 851^3 = 6.16295e8 and 852^3 = 6.18470e8, so U*^(1/3) = 851.6 m/s.
    us = cunniff.u_star(4.5e9, 0.05, 1440.0, 90e9)
    assert us == pytest.approx(6.17632e8, rel=1e-5)
    assert us ** (1 / 3.) == pytest.approx(851.6, abs=0.1)
    # 0.22-calibre disk: pi / 4 * 5.588^2 mm^2 = 0.785398 * 31.225744 = 24.5246 mm^2.
    a = cunniff.presented_area('rcc', 5.588e-3)
    assert a == pytest.approx(24.5246e-6, rel=1e-5)
    assert cunniff.presented_area('box', 2e-3) == pytest.approx(4e-6, rel=1e-12)
    # physics-reference.md: KM2 706 at 0.180 kg/m^2, 1.1 g, 5.588 mm: A_d A_p / m_p ~ 0.0040 per ply.
    x, _ = cunniff.axes(100.0, 0.180, a, 1.1e-3, us)
    assert x == pytest.approx(0.0040, rel=0.01)


def test_power_fit_against_exact_points():
    # Points on y = 0.5 x^0.6 exactly: the fit returns c and b to rounding, rms 0.
    xs = [0.004, 0.008, 0.016, 0.032]
    c, b, rms = cunniff.power_fit(xs, [0.5 * x ** 0.6 for x in xs])
    assert c == pytest.approx(0.5, rel=1e-12) and b == pytest.approx(0.6, rel=1e-12) and rms < 1e-12
    # Two points: the line through both in log-log, b = log(y2 / y1) / log(x2 / x1) = log 1.5 / log 2.
    c, b, rms = cunniff.power_fit([0.01, 0.02], [0.1, 0.15])
    assert b == pytest.approx(math.log(1.5) / math.log(2), rel=1e-12)
    assert c * 0.01 ** b == pytest.approx(0.1, rel=1e-12) and rms < 1e-12
    # Three points off a line: least squares in logs, by hand (x = 1, e, e^2; log y = 0, 1, 1):
    # slope 0.5, intercept 1/6, residuals -1/6, 1/3, -1/6: rms sqrt((1/36 + 1/9 + 1/36) / 3) = sqrt(1/18).
    c, b, rms = cunniff.power_fit([1.0, math.e, math.e ** 2], [1.0, math.e, math.e])
    assert b == pytest.approx(0.5, rel=1e-12) and math.log(c) == pytest.approx(1 / 6, rel=1e-12)
    assert rms == pytest.approx(math.sqrt(1 / 18), rel=1e-12)
    for xs, ys, key in (([0.01], [0.1], 'xs'), ([0.01, 0.01], [0.1, 0.2], 'xs'), ([0.01, -0.02], [0.1, 0.2], 'xs'),
                        ([0.01, 0.02], [0.1, 0.0], 'ys'), ([0.01, 0.02], [0.1], 'ys')):
        with pytest.raises(ValueError, match=key):
            cunniff.power_fit(xs, ys)


def test_bad_input_names_the_key():
    for call, key in ((lambda: cunniff.u_star(-1.0, 0.05, 1440.0, 90e9), 'strength'),
                      (lambda: cunniff.u_star(4.5e9, 0.05, float('nan'), 90e9), 'density'),
                      (lambda: cunniff.axes(100.0, 0.18, 2e-5, 0.0, 1e8), 'mass'),
                      (lambda: cunniff.presented_area('rcc', 5.588e-3, yaw=10), 'yaw'),
                      (lambda: cunniff.presented_area('cone', 5.588e-3), 'shape')):
        with pytest.raises(ValueError, match=key):
            call()


# Two tiny campaigns (the campaign test's 6.35 mm ply, 2 mm 0.2 g cube, its 5 % energy limit; 1-3 s
# a run, mostly YADE's start): seed 1, Weibull m = 10, velocities around each V50 (measured: 1 ply
# perforated from 60 m/s on, 2 plies from 80 m/s on).
SCENE = 'side=0.00635 size=2e-3 mass=0.2e-3 samples=10 clear_steps=20 backface=0 energy_limit=0.05'
PLIES = {1: '30,40,50,60,80,110', 2: '50,65,80,110,160'}


def yade(script, *args, cwd):
    r = subprocess.run(['yade', '-n', '-x', os.path.join(ROOT, 'scripts', script)] + list(args),
                       cwd=str(cwd), capture_output=True, text=True, timeout=900)
    return r.returncode, r.stdout + r.stderr


@pytest.fixture(scope='module')
def campaigns(tmp_path_factory):
    out = tmp_path_factory.mktemp('v50_plies')
    for n, vel in PLIES.items():
        rc, log = yade('campaign.py', 'out=%s' % (out / ('p%d' % n)), 'velocities=' + vel, 'seeds=1',
                       'weibull_m=10', 't_end=1e-4', 'boot=50', 'scene=%s plies=%d' % (SCENE, n), cwd=out)
        assert rc == 0, log[-2000:]
    return out


def test_table_arithmetic(campaigns):
    out = campaigns
    rc, log = yade('v50_plies.py', 'campaigns=%s,%s' % (out / 'p1', out / 'p2'), 'out=%s' % (out / 'chart'), cwd=out)
    assert rc == 0, log[-2000:]
    s = json.load(open(out / 'chart' / 'summary.json'))
    m = s['measured']
    assert m['U_star_cbrt'] == pytest.approx(851.6, abs=0.1)          # hand value above
    assert m['presented_area'] == pytest.approx(4e-6, rel=1e-12)      # the 2 mm cube face on
    assert m['projectile_mass'] == pytest.approx(0.2e-3, rel=1e-12)
    rows = list(csv.DictReader(open(out / 'chart' / 'v50_plies.csv')))
    assert [int(r['plies']) for r in rows] == [1, 2]
    for r in rows:
        camp = json.load(open(out / ('p%s' % r['plies']) / 'summary.json'))['measured']
        v50 = float(r['V50_m_s'])
        assert v50 == pytest.approx(camp['V50'], rel=1e-5)
        ad = float(r['areal_density_kg_m2'])
        assert ad == pytest.approx(int(r['plies']) * m['ply_areal_density'], rel=1e-5)
        assert float(r['cunniff_x']) == pytest.approx(ad * 4e-6 / 0.2e-3, rel=1e-5)
        assert float(r['cunniff_y']) == pytest.approx(v50 / 851.6, rel=1e-4)
    # KM2 706 (physics-reference.md: 178.5 (1 + crimp) g/m^2, crimp about 1 %).
    assert m['ply_areal_density'] == pytest.approx(0.1804, rel=0.01)
    assert float(rows[1]['cunniff_x']) == pytest.approx(2 * float(rows[0]['cunniff_x']), rel=1e-9)
    assert s['checks']['v50_rises_with_plies']['passed']
    assert os.path.getsize(out / 'chart' / 'v50_plies.png') > 10000
    # Cunniff's power law through the two packs: the line through both points in log-log.
    (x1, y1), (x2, y2) = [(r['cunniff_x'], r['cunniff_y']) for r in m['plies']]  # unrounded, as fitted
    fit = m['cunniff_fit']
    assert fit['points'] == 2 and fit['b'] == pytest.approx(math.log(y2 / y1) / math.log(x2 / x1), rel=1e-9)
    assert fit['c'] * x1 ** fit['b'] == pytest.approx(y1, rel=1e-9) and fit['rms_log'] < 1e-9
    assert m['cunniff_fit_beside'] is None
    # The chart's own CSV beside it: the same points (rounded to the CSV's digits), the same fit.
    rc, log = yade('v50_plies.py', 'campaigns=%s,%s' % (out / 'p1', out / 'p2'), 'out=%s' % (out / 'beside'),
                   'beside=%s' % (out / 'chart' / 'v50_plies.csv'), cwd=out)
    assert rc == 0, log[-2000:]
    m2 = json.load(open(out / 'beside' / 'summary.json'))['measured']
    assert m2['cunniff_fit_beside']['b'] == pytest.approx(fit['b'], rel=1e-4)
    assert m2['cunniff_fit_beside']['c'] == pytest.approx(fit['c'], rel=1e-4)


def test_refusals(script_server, campaigns):
    out = campaigns
    rc, log, _ = run_refused(script_server, 'v50_plies.py', out / 'bad1', 'campaigns=%s' % (out / 'nowhere'))
    assert rc != 0 and 'campaigns' in log and 'nowhere' in log
    # The 2-ply campaign is not the 1-ply scene at another friction: refused naming plies.
    rc, log, _ = run_refused(script_server, 'v50_plies.py', out / 'bad2', 'campaigns=%s' % (out / 'p1'),
                             'friction=%s' % (out / 'p2'))
    assert rc != 0 and 'friction' in log and 'plies' in log
    rc, log, _ = run_refused(script_server, 'v50_plies.py', out / 'bad3', 'campaigns=%s,%s' % (out / 'p1', out / 'p1'))
    assert rc != 0 and 'one campaign per ply count' in log
    # A beside file that is not a v50_plies.csv: refused naming the key.
    rc, log, _ = run_refused(script_server, 'v50_plies.py', out / 'bad4', 'campaigns=%s' % (out / 'p1'),
                             'beside=%s' % (out / 'p1' / 'summary.json'))
    assert rc != 0 and 'beside' in log
