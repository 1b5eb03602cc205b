"""Multi-ply packs and standard projectiles: bad keys refused naming the key and
its range, a small 2-ply pack built apart with its per-ply books summing to the engine's entries, the
cylinder's mass and inertia against the closed form, the RCC and FSP in a short impact."""
import math

import pytest
from conftest import run_scene, run_refused


@pytest.mark.parametrize('args,key', [
    (['plies=0'], 'plies'), (['plies=41'], 'plies'), (['plies=-3'], 'plies'),
    (['plies=2', 'ply_angles=0,nan'], 'ply_angles'), (['plies=2', 'ply_angles=inf'], 'ply_angles'),
    (['plies=3', 'ply_angles=0,45'], 'ply_angles'), (['ply_angles=abc'], 'ply_angles'),
    (['ply_gap=-0.5'], 'ply_gap'), (['ply_gap=nan'], 'ply_gap'),
    (['yaw=91'], 'yaw'), (['yaw=nan'], 'yaw'), (['obliquity=-1'], 'obliquity'), (['obliquity=85'], 'obliquity'),
    (['shape=cylinder'], 'shape'), (['shape=fsp', 'size=5e-3'], 'size'), (['shape=rcc', 'density=0'], 'density'),
    (['shape=rcc', 'contact_model=paper'], 'shape'),
    (['plies=2', 'standoff=-1e-3'], 'standoff'),  # a projectile that starts inside the pack
    (['model=yade', 'plies=2'], 'model'), (['model=yade', 'shape=rcc'], 'model'),
])
def test_bad_pack_and_projectile_keys_name_the_key(script_server, tmp_path, args, key):
    rc, log, s = run_refused(script_server, 'ballistic.py', tmp_path, 'side=0.004', 'progress=0', *args, timeout=120)
    assert rc != 0 and ('%s = ' % key) in log and 'allowed' in log, log[-2000:]


def test_two_ply_pack_starts_apart_and_its_books_sum_to_the_total(tmp_path):
    # 2 plies at 0 and 45 degrees, 1 yarn thickness apart, an RCC at 300 m/s for 12 us (breaks included)
    rc, log, s = run_scene('ballistic.py', tmp_path, 'side=0.0127', 'plies=2', 'ply_angles=0,45', 't_end=1.2e-5',
                           'V=300', 'shape=rcc', 'vtk_every=-1', 'progress=0', 'stop=0', timeout=300)
    assert rc == 0, log[-3000:]
    m = s['measured']
    pk = m['pack']
    thickness = m['yarn_thickness']
    # Built without overlap, measured at step 0: the plies' clear gap is the key's (one thickness)
    # within the settled sections' spread, and no CP of the pack overlaps another.
    assert pk['start']['clear_gap_min'] > 0.5 * thickness
    assert pk['start']['overlap'] <= 1e-9
    assert s['checks']['pack_built_apart']['passed']
    assert [b['angle'] for b in pk['per_ply']] == [0.0, 45.0]
    assert m['max_iterations'] == 20  # 10 per ply, and the single ply's 20
    # The per-ply books add up to the engine's kinetic, elastic and released entries.
    E = m['energy']
    books = pk['per_ply']
    assert sum(b['kinetic'] for b in books) == pytest.approx(E['fabric_kinetic'], rel=1e-9)
    assert sum(b['elastic'] for b in books) == pytest.approx(E['fabric_elastic'], rel=1e-9, abs=1e-15)
    assert sum(b['released_breakage'] for b in books) == pytest.approx(E['released_breakage'], rel=1e-9, abs=1e-15)
    assert sum(b['broken_elements'] for b in books) == m['broken_elements']
    assert sum(b['broken_yarns'] for b in books) == m['broken_yarns']
    assert books[0]['touched_by_projectile'] and books[0]['absorbed'] > 0
    # Overlaps within the contact model's limits, energy closed.
    assert m['overlap']['yarn_max_before_break_rel'] <= 0.1 and m['overlap']['body_max_before_break_rel'] <= 0.1
    assert abs(m['energy_balance_error']) <= 0.01
    assert m['projectile']['mass'] == pytest.approx(7850 * math.pi * 2.794e-3 ** 2 * 5.588e-3, rel=1e-12)


def test_pack_sweeps_are_ten_per_ply_never_fewer_than_the_single_plys():
    import woven.pack as K
    assert K.sweeps_for(1) == K.PLY_SWEEPS == 20
    assert [K.sweeps_for(n) for n in (2, 3, 4, 8)] == [20, 30, 40, 80]
    assert K.sweeps_for(4, at_least=50) == 50 and K.sweeps_for(4, per_ply=5, at_least=1) == 20


def test_cylinder_mass_and_inertia_match_the_closed_form():
    import woven.projectiles as P
    for D, rho in ((5.588e-3, 7850.0), (3e-3, 2700.0)):
        s = P.solid('rcc', D, rho)
        R = L = D
        R = D / 2
        m = rho * math.pi * R * R * L
        assert s['mass'] == pytest.approx(m, rel=1e-13)
        assert s['centroid_z'] == 0.0
        Ix, Iy, Iz = s['inertia']
        assert Iz == pytest.approx(0.5 * m * R * R, rel=1e-13)
        assert Ix == pytest.approx(m * (3 * R * R + L * L) / 12, rel=1e-13) and Iy == pytest.approx(Ix, rel=1e-13)


def test_fsp_is_17_grains_and_its_chisel_takes_metal_from_the_nose():
    import woven.projectiles as P
    s = P.solid('fsp')
    assert s['mass'] == pytest.approx(17 * 64.79891e-6, rel=1e-9)
    # A full cylinder of the same size is heavier; the centre of mass moves back, away from the nose.
    full = P.mass_properties(s['radius'], s['half_length'])
    assert full['mass'] > s['mass'] and s['centroid_z'] < 0
    # Gauss-Legendre along the chisel: 64 and 128 points agree to rounding.
    a = P.mass_properties(s['radius'], s['half_length'], s['chisel_angle'], s['land_half_width'], order=64)
    b = P.mass_properties(s['radius'], s['half_length'], s['chisel_angle'], s['land_half_width'], order=128)
    assert a['volume'] == pytest.approx(b['volume'], rel=1e-13)
    assert all(x == pytest.approx(y, rel=1e-12) for x, y in zip(a['inertia'], b['inertia']))
    # The flats end on the round surface before the tail.
    assert (s['radius'] - s['land_half_width']) / math.tan(s['chisel_angle']) < 2 * s['half_length']


def test_cylinder_support_from_python():
    import woven
    from yade._minieigenHP import Vector3
    R, H = 2e-3, 3e-3
    n = Vector3(1, 0, 1).normalized()
    assert woven._woven.cylinder_min_along(R, H, 0.0, 0.0, n) == pytest.approx(-(R + H) / math.sqrt(2), rel=1e-14)
    with pytest.raises(ValueError, match='chisel_angle'):
        woven._woven.cylinder_min_along(R, H, 0.1, 0.0, n)  # flats that would run past the tail


def test_yawed_oblique_fsp_on_a_pack(tmp_path):
    # The FSP, 5 degrees of yaw, 30 degrees of obliquity, on 2 plies at 0/90: its flight and its
    # lowest point at the start as asked, the contact limits and the books kept.
    rc, log, s = run_scene('ballistic.py', tmp_path, 'side=0.0127', 'plies=2', 'ply_angles=0,90', 'shape=fsp',
                           'yaw=5', 'obliquity=30', 'V=300', 't_end=8e-6', 'stop=0', 'vtk_every=-1', 'progress=0',
                           timeout=300)
    assert rc == 0, log[-3000:]
    m = s['measured']
    import numpy as np
    series = np.genfromtxt(tmp_path / 'series.csv', delimiter=',', names=True)
    assert series['vz'][0] == pytest.approx(-300 * math.cos(math.radians(30)), rel=1e-9)
    P = m['projectile']
    assert P['shape'] == 'fsp' and P['mass'] == pytest.approx(1.1016e-3, rel=1e-4)
    # nose first, turned by 35 degrees from -z: the chisel's tip corner is the lowest point
    assert P['start_reach_below'] > P['half_length'] * math.cos(math.radians(35))
    assert m['overlap']['yarn_max_before_break_rel'] <= 0.1 and m['overlap']['body_max_before_break_rel'] <= 0.1
    assert abs(m['energy_balance_error']) <= 0.01
    assert m['pack']['per_ply'][0]['touched_by_projectile']
