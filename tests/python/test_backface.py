"""Back-face deformation (woven.backface) on constructed fields with a known cone and known fronts
(the oracles), Smith's relation for a fabric (theory.smith_fabric), the off-screen VTK pictures
(woven.render), and the friction and back-face keys of scripts/ballistic.py refused out of range."""
import math
import os

import numpy as np
import pytest

import woven
import woven.backface as bfd
import woven.render
import woven.theory as theory
from conftest import run_refused

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def grid(side=40e-3, step=0.25e-3):
    """Nodes of a square of lines (both families) in the plane z = 0, centred on the origin."""
    u = np.arange(-0.5 * side, 0.5 * side + 1e-12, step)
    xx, yy = np.meshgrid(u, u)
    return np.column_stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)])


def rotation(axis, angle):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


@pytest.mark.parametrize('tilt', [0.0, 0.7])
def test_cone_of_a_constructed_field(tilt):
    # A cone w = D (1 - r / R) pushed along d: the apex is D at the axis node, and the nodes moved by
    # more than a threshold h lie within R (1 - h / D) of the axis (to one node spacing). A tilted
    # copy of the same field (ply and direction turned together) measures the same.
    D, R, h, step = 5e-3, 15e-3, 1e-5, 0.25e-3
    X0 = grid(step=step)
    r = np.hypot(X0[:, 0], X0[:, 1])
    w = D * np.clip(1 - r / R, 0, None)
    d = np.array([0.0, 0.0, -1.0])
    X = X0 + w[:, None] * d
    Q = rotation((1, 2, 0.5), tilt)
    centre = Q @ np.array([0.0, 0.0, 0.0]) + np.array([1e-3, -2e-3, 3e-3])
    shift = centre
    apex, radius = bfd.cone(X0 @ Q.T + shift, X @ Q.T + shift, centre, Q @ d, h)
    assert apex == pytest.approx(D, rel=1e-12)
    assert abs(radius - R * (1 - h / D)) <= step
    # with a threshold above the apex nothing counts as moved
    assert bfd.cone(X0, X, (0, 0, 0), d, 2 * D)[1] == 0.0


def test_front_along_a_yarn_is_interpolated_exactly_on_a_linear_cone():
    # A yarn along x (nodes every 0.75 mm, the impact point between two of them) under a cone
    # w = D (1 - |x| / R): linear between the two nodes around the crossing (the cone's edge at R lies
    # beyond the next node), so the interpolated front is R (1 - h / D) exactly, on either arm; with
    # every node above the threshold, the arm's end.
    D, R, h = 4e-3, 9.1e-3, 4e-4
    x = (np.arange(-30, 31) + 0.37) * 0.75e-3
    w = D * np.clip(1 - np.abs(x) / R, 0, None)
    assert bfd.arm_front(np.abs(x), w, h) == pytest.approx(R * (1 - h / D), rel=1e-12)
    assert bfd.arm_front(np.abs(x[:40]), w[:40], h) == pytest.approx(R * (1 - h / D), rel=1e-12)  # one arm cut short
    assert bfd.arm_front(np.abs(x), np.full(len(x), 2 * h), h) == pytest.approx(np.abs(x).max())
    assert bfd.arm_front(np.abs(x), np.zeros(len(x)), h) == 0.0


def test_strain_front_of_a_constructed_yarn():
    # A yarn along x in elements of 0.5 mm, strained by 0.4 % within |x| < L: the front lies between
    # the last strained element's midpoint and the next one, within an element of L.
    l0, L = 0.5e-3, 7.3e-3
    X = np.column_stack([np.arange(-40, 41) * l0, np.zeros(81), np.zeros(81)])
    first = np.arange(80)
    mid = 0.5 * (X[first, 0] + X[first + 1, 0])
    eps = np.where(np.abs(mid) < L, 4e-3, 1e-5)
    front = bfd.strain_front(X, eps, first, (0, 0, 0), (0, 0, -1), 5e-4)
    assert abs(front - L) <= l0
    assert bfd.strain_front(X, np.zeros(80), first, (0, 0, 0), (0, 0, -1), 5e-4) == 0.0


def test_front_speed_fits_the_first_passage():
    t = np.linspace(0, 20e-6, 81)
    r = 3e-3 + 400.0 * t
    r = np.where(r > 9e-3, 9e-3 + 0.1 * (r - 9e-3), r)  # slows down past 9 mm (clamps felt)
    f = bfd.front_speed(t, r, 4e-3, 8e-3)
    assert f['speed'] == pytest.approx(400.0, rel=1e-9)
    assert 4e-3 - 1e-12 <= f['intercept'] + f['speed'] * f['t0'] and f['intercept'] + f['speed'] * f['t1'] <= 8e-3 + 1e-12
    assert bfd.front_speed(t[:4], r[:4], 0, 1)['speed'] is None  # too few points
    assert bfd.front_speed(t, r, 4e-3, 4.8e-3)['speed'] is None  # moved less than 1 mm
    assert bfd.front_speed(t, r, 1.0, 2.0)['speed'] is None  # never reached


def test_smith_fabric_is_smith_for_a_bare_yarn_and_slower_for_a_fabric():
    E, rho, V = 90e9, 1440.0, 200.0
    a, b = theory.smith(V, E, rho), theory.smith_fabric(V, E, rho, 1.0)
    for k in ('strain', 'U_L', 'U_E'):
        assert b[k] == pytest.approx(a[k], rel=1e-9)
    assert a['U_E'] == pytest.approx(510, abs=1)  # physics-reference.md
    f = theory.smith_fabric(V, E, rho, 2.0)
    c, e, U = f['c'], f['strain'], f['U_L']
    # its own conditions: the kink's momentum and the straight segment's kinematics
    assert U == pytest.approx(c * math.sqrt(e / (2 * (1 + e))), rel=1e-12)
    assert (U * (1 + e)) ** 2 == pytest.approx((U * (1 + e) - c * e) ** 2 + V ** 2, rel=1e-9)
    assert f['U_E'] < a['U_E'] and f['strain'] > a['strain']
    with pytest.raises(ValueError, match='mass_ratio'):
        theory.smith_fabric(V, E, rho, 0.5)


def test_picture_is_written_and_shows_strain_and_broken_ends(tmp_path):
    # A small weave bent into a bump, one element broken: the picture is a PNG of the given size,
    # mostly not background, with coloured tubes and red balls at the broken ends.
    w = woven.weave(nx=3, ny=3)
    e = w.engine
    woven.contact.enable(e, yarn_contacts=False)  # the tubes take the collision stage's sections
    X = woven.positions(e).copy()
    c = X.mean(axis=0)
    r = np.hypot(X[:, 0] - c[0], X[:, 1] - c[1])
    for i in range(len(X)):
        e.set_pos(i, tuple(X[i] - np.array([0, 0, 1e-3 * max(0.0, 1 - r[i] / 2.5e-3)])))
    e.enable_breakage(strain=1e-4, filter_length=0)
    e.step(0.5 * e.dt_crit)
    assert e.broken_elements > 0
    paths = woven.render.write_frame(e, str(tmp_path / 'frames'), 'pack')
    assert woven.vtk_output.read(paths[2]).GetNumberOfPoints() == 2 * e.broken_elements
    png = str(tmp_path / 'pack.png')
    woven.render.render([(paths, png, 't = 0 us')], strain_max=0.01, size=(400, 300))
    import matplotlib.image
    img = matplotlib.image.imread(png)[:, :, :3]
    assert img.shape[:2] == (300, 400)
    ink = np.any(img < 0.95, axis=2)
    assert ink.mean() > 0.05  # the ply fills part of the frame
    red = (img[:, :, 0] > 0.8) & (img[:, :, 1] < 0.2) & (img[:, :, 2] < 0.2)
    assert red.sum() > 10  # broken ends


@pytest.mark.parametrize('arg, key', [('friction=-0.1', 'friction'), ('friction=2.5', 'friction'),
                                      ('body_friction=3', 'body_friction'), ('body_friction=nan', 'body_friction'),
                                      ('body_friction=0.2 response=penalty', 'body_friction'),
                                      ('body_friction=0.2 model=yade', 'body_friction'),
                                      ('backface_w=0', 'backface_w'), ('backface_strain=0.5', 'backface_strain'),
                                      ('pictures=-1', 'pictures'), ('front_tolerance=0', 'front_tolerance')])
def test_ballistic_refuses_bad_friction_and_backface_keys(script_server, tmp_path, arg, key):
    rc, err, _ = run_refused(script_server, 'ballistic.py', tmp_path, *arg.split())
    assert rc != 0
    assert key in err and ('[0, 2]' in err or '(0,' in err or '[0, 100]' in err)
    assert not os.path.exists(os.path.join(str(tmp_path), 'summary.json'))  # refused before anything ran


def test_friction_books_close_in_a_small_impact(tmp_path):
    # A 12.7 mm ply struck at 200 m/s with friction on both pairs, 10 us: the friction book is
    # filled and printed, and the books close within the scene's 1 % of the projectile's energy.
    from conftest import run_scene
    code, out, s = run_scene('ballistic.py', tmp_path, 'side=0.0127', 't_end=1e-5', 'friction=0.3',
                             'body_friction=0.2', 'pictures=0', 'backface=0', 'vtk_every=-1', 'progress=0',
                             timeout=300)
    assert s is not None, out
    E = s['measured']['energy']
    assert E['friction'] > 1e-3 * E['projectile_initial'], E
    assert abs(s['measured']['energy_balance_error']) <= 0.01
    assert s['checks']['energy_balance']['passed']


@pytest.mark.parametrize('friction, strain_speed_of_c, passed', [(0.0, 1.0, True), (0.0, 0.8, False),
                                                                 (0.3, 0.8, True), (0.3, 0.5, False)])
def test_compare_checks_fronts_against_smith(friction, strain_speed_of_c, passed):
    # Fronts constructed at the theory's speeds from the projectile's edge at first contact: the
    # fitted speeds are those speeds, and the checks pass; a strain front at 0.8 c fails without
    # friction (the theory is c) and passes with it (between c/sqrt(kappa) and c), at 0.5 c it fails.
    w = woven.weave(nx=2, ny=2)
    info = w.engine.yarn(w.warp_yarns[0])
    E, rho = info['E'], info['rho']

    class Series:
        engine, families, yarns = w.engine, [w.warp_yarns, w.weft_yarns], [w.warp_yarns[0], w.weft_yarns[0]]
        w_threshold, strain_threshold = 1e-4, 5e-4

    kappa = bfd.mass_ratio(w.engine, w.warp_yarns)
    assert kappa == pytest.approx(2.0, rel=0.02)
    c, U = math.sqrt(E / rho), theory.smith_fabric(200.0, E, rho, kappa)['U_E']
    reach, half, t_c = 2.8e-3, 25.4e-3, 1e-6
    t = np.linspace(0, 30e-6, 3001)
    on = t >= t_c
    s = {'time': t, 'apex': np.where(on, 200.0 * (t - t_c), 0.0),
         'transverse_front': np.where(on, reach + U * (t - t_c), 0.0),
         'strain_front': np.where(on, np.minimum(reach + strain_speed_of_c * c * (t - t_c), half), 0.0)}
    s['base_radius'] = s['transverse_front']
    Series.series = staticmethod(lambda: s)
    m, ref, checks = bfd.compare(Series, t, np.full(len(t), -200.0), reach, half, E, rho, friction=friction)
    assert m['transverse_front_speed'] == pytest.approx(U, rel=1e-6)
    assert m['strain_front_speed'] == pytest.approx(strain_speed_of_c * c, rel=1e-6)
    assert checks['transverse_front_speed']['passed']
    assert checks['strain_front_speed']['passed'] == passed
    assert ref['smith_fabric_U_E'] == pytest.approx(U)
