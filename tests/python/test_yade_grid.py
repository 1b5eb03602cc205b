"""The same fabric in YADE's grid elements (woven.yade_grid): measured against woven's figures and
conservation laws, not against the mapping's own formulas."""
import math

import numpy as np
import pytest
from conftest import run_scene, run_refused


@pytest.fixture
def grid(yade_ns):
    """A fresh YADE scene with the grid engines; returns (O, woven, yade_grid)."""
    import woven
    from woven import yade_grid
    O = yade_ns.wrapper.Omega()
    O.reset()
    O.engines = yade_grid.engines()
    return O, woven, yade_grid


def test_mass_length_and_crossings(grid):
    O, woven, yg = grid
    w = woven.weave(nx=2, ny=2, cp_per_span=1)
    e = w.engine
    g = yg.build(e, w.warp_yarns + w.weft_yarns)
    # the total mass is woven's lumped mass (sum over nodes of both models)
    assert g.total_mass() == pytest.approx(float(woven.masses(e).sum()), rel=1e-12)
    # every crossing (4 x 4) falls in the middle of a grid connection, in plan view
    assert len(g.crossing_fraction) == 16
    assert np.allclose(g.crossing_fraction, 0.5, atol=1e-9)
    # no crossing lies on a grid node: every node is at least a quarter element from every crossing
    X = woven.positions(e)
    cross = [X[e.yarn(y)['first_node'] + 1 + k] for y in w.warp_yarns for k in range(4)]
    nodes = np.array([list(O.bodies[i].state.pos) for i in g.node_ids()])
    l0 = float(woven.rest_lengths(e).min())
    d = np.linalg.norm(nodes[:, None, :2] - np.array(cross)[None, :, :2], axis=2)
    assert d.min() > 0.24 * l0
    # the yarns at crossings just touch: one step later no grid-grid contact overlaps by more than
    # a rounding error, and some are in contact (gap within 1e-12 m)
    O.dt = g.stable_dt(0.5)
    O.step()
    assert g.max_overlap() < 1e-12
    n_contacts = sum(1 for i in O.interactions if isinstance(i.geom, yg.GridCoGridCoGeom))
    assert n_contacts >= 8
    # grid yarn length: the chords cut woven's corners at the crossings by a quarter element either
    # side, shorter by less than the crimp (KM2 706: 1.08 %)
    info = e.yarn(w.warp_yarns[0])
    L_woven = float(woven.rest_lengths(e)[info['first_element']:info['first_element'] + info['n_elements']].sum())
    assert 0 < 1 - g.yarn_length(0) / L_woven < w.summary['warp_crimp_built']


def test_axial_stiffness_static_pull(grid):
    """Pulling one connection by a strain eps (the rest of the yarn moved along rigidly) gives the
    force E*A*eps: K = E*A/l0 per element, within 1 %."""
    O, woven, yg = grid
    w = woven.weave(nx=2, ny=1, cp_per_span=2)
    e = w.engine
    g = yg.build(e, [w.warp_yarns[0]], radius=4e-5)
    info = e.yarn(w.warp_yarns[0])
    EA = info['E'] * info['area']
    ids = g.nodes[0]
    for i in ids:
        O.bodies[i].state.blockedDOFs = 'xyzXYZ'
    O.dt = 1e-9
    for j in (1, 3):
        a, b = ids[j], ids[j + 1]
        pa, pb = O.bodies[a].state.pos, O.bodies[b].state.pos
        L = (pb - pa).norm()
        u = (pb - pa) / L
        for eps in (1e-4, 2e-2):
            shift = pa + u * L * (1 + eps) - O.bodies[b].state.pos
            for k in ids[j + 1:]:
                O.bodies[k].state.pos = O.bodies[k].state.pos + shift
            O.step()
            F = -O.forces.f(b).dot(u)
            assert F == pytest.approx(EA * eps, rel=0.01)
            assert F / (L * eps) == pytest.approx(EA / L, rel=0.01)  # K = E A / l0 of this connection


def test_bond_breaks_at_failure_strain(grid):
    O, woven, yg = grid
    w = woven.weave(nx=1, ny=1, cp_per_span=2)
    g = yg.build(w.engine, [w.warp_yarns[0]], radius=4e-5, failure_strain=0.05)
    ids = g.nodes[0]
    for i in ids:
        O.bodies[i].state.blockedDOFs = 'xyzXYZ'
    O.dt = 1e-9
    a, b = ids[1], ids[2]
    L = (O.bodies[b].state.pos - O.bodies[a].state.pos).norm()
    u = (O.bodies[b].state.pos - O.bodies[a].state.pos) / L
    for eps, whole in ((0.049, True), (0.051, False)):
        shift = O.bodies[a].state.pos + u * L * (1 + eps) - O.bodies[b].state.pos
        for k in ids[2:]:
            O.bodies[k].state.pos = O.bodies[k].state.pos + shift
        O.step()
        assert (O.interactions.has(a, b) and O.interactions[a, b].isReal) == whole
    assert g.remove_broken() == 1


def test_projectile_momentum_is_conserved(grid):
    """A sphere at 200 m/s into a free (unclamped) grid ply: the projectile's momentum lost is the
    fabric's gained, to rounding (action = reaction in every YADE contact and bond)."""
    O, woven, yg = grid
    w = woven.weave(nx=3, ny=3, cp_per_span=1)
    g = yg.build(w.engine, w.warp_yarns + w.weft_yarns)
    X = np.array([list(O.bodies[i].state.pos) for i in g.node_ids()])
    R, m, V = 1e-3, 1e-4, 200.0
    c = X.mean(axis=0)
    from yade import utils
    from yade._minieigenHP import Vector3
    s = utils.sphere((c[0], c[1], X[:, 2].max() + g.radius + R + 1e-6), R, material=yg.projectile_material(g, 'sphere', 2 * R))
    s.mask = yg.CONNECTION_MASK
    pid = O.bodies.append(s)
    O.bodies[pid].state.mass = m
    O.bodies[pid].state.vel = Vector3(0, 0, -V)
    O.dt = g.stable_dt(0.5)
    O.run(400, True)
    p_nodes = sum(O.bodies[i].state.mass * O.bodies[i].state.vel[2] for i in g.node_ids())
    p_proj = m * O.bodies[pid].state.vel[2]
    assert p_proj > -m * V * (1 - 1e-3)  # it was slowed: there was an exchange to conserve
    assert p_nodes + p_proj == pytest.approx(-m * V, rel=1e-9)


@pytest.mark.parametrize('script', ['ballistic.py', 'tension.py', 'smith.py'])
def test_bad_model_names_the_key(script_server, tmp_path, script):
    rc, log, s = run_refused(script_server, script, tmp_path, 'model=abaqus')
    assert rc != 0 and 'model' in log and 'allowed' in log and s is None


def test_ballistic_grid_quick(tmp_path):
    """The quick comparison scene in grid elements: the same mass, a closed energy balance (YADE's
    own books plus the bond/contact elastic energies) and a projectile that was slowed."""
    rc, log, s = run_scene('ballistic.py', tmp_path, 'model=yade', 'side=0.0127', 't_end=1.5e-5', 'shape=sphere')
    assert rc == 0, log
    m = s['measured']
    assert m['fabric_mass'] == pytest.approx(m['woven_fabric_mass'], rel=1e-9)
    assert abs(m['energy_balance_error']) < 0.01
    assert 0 < m['absorbed_energy'] < 0.5 * 1.1e-3 * 200 ** 2
    assert m['dt'] < s['reference']['woven_dt_crit']
    # the keys scripts/compare.py reads, measured: the sphere (2r = 5.59 mm) touched the yarns and
    # overlapped them by less than their diameter
    assert 0 < m['max_body_penetration'] < 2 * m['grid_radius']
    assert 0 < m['max_yarn_penetration'] < 2 * m['grid_radius']
    assert m['cps'] == m['grid_connections'] and m['yarn_thickness'] > 0 and m['max_penetration'] > 0


def test_smith_grid_chain_against_theory(tmp_path):
    """Smith's single-yarn impact as a grid chain: strain within 1 %, transverse wave speed within
    3 % of the theory at 1000 elements, and the driver's work in kinetic + bond energy within 1 %."""
    rc, log, s = run_scene('smith.py', tmp_path, 'model=yade', 'elements=1000', 'levels=1')
    assert rc == 0, log
    c = s['measured']['convergence'][0]
    assert abs(c['strain_error']) < 0.01 and abs(c['U_E_error']) < 0.03
    assert abs(c['energy_balance_error']) < 0.01


def test_ballistic_grid_blow_up_is_unstable(tmp_path):
    """Three times the critical step: the scene stops with status 'unstable' (what the stability map
    reads), not with a summary of garbage."""
    rc, log, s = run_scene('ballistic.py', tmp_path, 'model=yade', 'side=0.00635', 't_end=8e-6', 'size=1.5e-3',
                           'mass=0.05e-3', 'dt_factor=3', 'stop=0', 'vtk_every=-1', 'progress=0')
    assert rc != 0 and s is not None and s['status'] == 'unstable', log
    assert s['measured']['simulated_time'] < 8e-6


def test_tension_in_grid_elements(tmp_path):
    """The tension scene as grid elements: the straightened warp carries n E A (within 5 %), after a
    toe below woven's built crimp (the chords cut part of it), with the yarns kept apart."""
    rc, log, s = run_scene('tension.py', tmp_path, 'model=yade', 'nx=2', 'ny=2', 'samples=60')
    assert rc == 0, log
    m, ref = s['measured'], s['reference']
    assert m['final_stiffness'] == pytest.approx(ref['straight_yarns_stiffness'], rel=0.05)
    assert 0 < m['toe_strain'] < ref['warp_crimp_built']
    assert m['fabric_mass'] == pytest.approx(m['woven_fabric_mass'], rel=1e-9)
    assert m['max_transient_penetration'] < 0.05 * ref['grid_diameter']
