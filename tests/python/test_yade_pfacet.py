"""The same fabric as YADE PFacet ribbons (woven.yade_pfacet): measured against closed forms (E*A/L of a
straight yarn, woven's mass, the section's width) and conservation laws, not against the mapping's
own formulas."""
import numpy as np
import pytest
from conftest import run_scene, run_refused


@pytest.fixture
def pf(yade_ns):
    """A fresh YADE scene with the PFacet engines; returns (O, woven, yade_pfacet)."""
    import woven
    from woven import yade_pfacet
    O = yade_ns.wrapper.Omega()
    O.reset()
    O.engines = yade_pfacet.engines()
    return O, woven, yade_pfacet


def straight_yarn(woven, n=10, length=0.01):
    """A FabricEngine of one straight yarn along x (woven's default material and section)."""
    from yade._minieigenHP import Vector3
    f = woven.Fabric()
    f.add_yarn([Vector3(length * i / n, 0, 0) for i in range(n + 1)], woven.YarnMaterial(), woven.YarnSection())
    return woven.FabricEngine(f)


@pytest.mark.parametrize('lines', [2, 3])
def test_static_pull_of_a_straight_ribbon(pf, lines):
    """One ribbon held at one end, its other end's nodes moved by eps*L along the yarn and the rest
    relaxed (NewtonIntegrator damping) to rest: the reaction on each end is E*A*eps, i.e. the ribbon's
    force/extension is E*A/L, within 2 %; the width does not change."""
    O, woven, yp = pf
    from yade._minieigenHP import Vector3
    O.engines = yp.engines(damping=0.8)  # YADE's non-viscous damping: only the static end state counts
    e = straight_yarn(woven)
    p = yp.build(e, [0], lines=lines, radius=2e-5, crossings=[])
    info = e.yarn(0)
    EA = info['E'] * info['area']
    first, last = p.end_nodes(0)
    assert len(first) == len(last) == lines
    L = O.bodies[last[0]].state.pos[0] - O.bodies[first[0]].state.pos[0]
    assert L == pytest.approx(0.01, rel=1e-12)
    width0 = max(O.bodies[i].state.pos[1] for i in p.node_ids()) - min(O.bodies[i].state.pos[1] for i in p.node_ids())
    p.fix_ends()
    eps = 1e-3
    for i in last:
        O.bodies[i].state.pos = O.bodies[i].state.pos + Vector3(eps * L, 0, 0)
    O.dt = p.stable_dt(0.5, extra_contacts=0)

    def kinetic():
        return sum(0.5 * O.bodies[i].state.mass * O.bodies[i].state.vel.squaredNorm() for i in p.node_ids())

    for _ in range(40):  # to rest: the forces below are then static
        O.run(500, True)
        if kinetic() < 1e-12 * 0.5 * EA * eps ** 2 * L:
            break
    assert kinetic() < 1e-12 * 0.5 * EA * eps ** 2 * L
    F_first = sum(O.forces.f(i)[0] for i in first)
    F_last = -sum(O.forces.f(i)[0] for i in last)
    assert F_first == pytest.approx(EA * eps, rel=0.02)
    assert F_last == pytest.approx(EA * eps, rel=0.02)
    assert F_first / (eps * L) == pytest.approx(EA / L, rel=0.02)
    width = max(O.bodies[i].state.pos[1] for i in p.node_ids()) - min(O.bodies[i].state.pos[1] for i in p.node_ids())
    assert width == pytest.approx(width0, rel=1e-6)


@pytest.mark.parametrize('lines', [2, 3])
def test_mass_width_and_touching_crossings(pf, lines):
    O, woven, yp = pf
    w = woven.weave(nx=2, ny=2, cp_per_span=1)
    e = w.engine
    p = yp.build(e, w.warp_yarns + w.weft_yarns, lines=lines)
    # the total mass is woven's lumped mass
    assert p.total_mass() == pytest.approx(float(woven.masses(e).sum()), rel=1e-9)
    assert p.woven_mass == pytest.approx(float(woven.masses(e).sum()), rel=1e-12)
    # the ribbon spans the section's width: its outer node lines at +-(width - thickness)/2 across a
    # warp (along y), its PFacets' rounded edges within the width
    info = e.yarn(w.warp_yarns[0])
    X = woven.positions(e)
    y0 = X[info['first_node']:info['first_node'] + info['n_nodes'], 1].mean()
    Y = np.array([O.bodies[i].state.pos[1] for i in p.nodes[0]]) - y0
    s = 0.5 * (info['width'] - info['thickness'])
    assert Y.max() == pytest.approx(s, rel=1e-9) and Y.min() == pytest.approx(-s, rel=1e-9)
    assert 2 * s + 2 * p.radius <= info['width'] * (1 + 1e-12)
    assert sorted(set(np.round(Y / s, 9))) == pytest.approx(list(np.linspace(-1, 1, lines)))
    # warp and weft ribbons touch as built: one step later no yarn-yarn contact overlaps by more than a
    # rounding error, and some are in contact
    O.dt = p.stable_dt(0.5)
    O.step()
    O.step()  # Ig2_PFacet_PFacet_ScGeom creates the node / connection contacts it hands a pair to
    assert p.max_overlap() < 1e-12
    n_contacts = sum(1 for i in O.interactions
                     if (isinstance(i.geom, yp.GridCoGridCoGeom) or isinstance(i.geom, yp.ScGridCoGeom)))
    assert n_contacts >= 4
    # no thicker than the yarn, and within the crimp's reach of woven's crossing gap: flat ribbons
    # meet at the crossing patches' corners at t (1 - 2 s / spacing)
    spacing = w.summary['length_x'] / 4
    assert p.radius <= 0.5 * info['thickness']
    assert p.radius == pytest.approx(0.5 * info['thickness'] * (1 - 2 * s / spacing), rel=0.05)


def test_bond_breaks_at_failure_strain(pf):
    """One gap of a ribbon stretched rigidly: its line bonds hold at 4.9 % and break at 5.1 %; the
    broken gap's PFacets are erased with them."""
    O, woven, yp = pf
    w = woven.weave(nx=1, ny=1, cp_per_span=2)
    p = yp.build(w.engine, [w.warp_yarns[0]], lines=2, radius=2e-5, failure_strain=0.05)
    ids = p.node_ids()
    for i in ids:
        O.bodies[i].state.blockedDOFs = 'xyzXYZ'
    O.dt = 1e-9
    (a0, b0), (a1, b1) = [(ln[1], ln[2]) for ln in p.lines[0]]
    u = O.bodies[b0].state.pos - O.bodies[a0].state.pos
    L = u.norm()
    u = u / L
    later = [ln[k] for ln in p.lines[0] for k in range(2, len(ln))]
    for eps, whole in ((0.049, True), (0.051, False)):
        # both lines' nodes beyond the gap move rigidly so that the gap is stretched by eps
        shift = O.bodies[a0].state.pos + u * L * (1 + eps) - O.bodies[b0].state.pos
        for k in later:
            O.bodies[k].state.pos = O.bodies[k].state.pos + shift
        O.step()
        for a, b in ((a0, b0), (a1, b1)):
            assert (O.interactions.has(a, b) and O.interactions[a, b].isReal) == whole
    n_pf = len(p.pfacet_ids())
    assert p.remove_broken() == 2  # both lines of the gap
    assert len(p.pfacet_ids()) == n_pf - 2  # the gap's quad, two PFacets
    assert sorted((k, j) for _, k, j, _ in p.broken) == [(0, 1), (1, 1)]


@pytest.mark.parametrize('meets', ['nodes', 'pfacets'])
def test_projectile_momentum_is_conserved(pf, meets):
    """A sphere at 200 m/s into a free (unclamped) ribbon ply, meeting the nodes or the PFacets: the
    projectile's momentum lost is the fabric's gained, to rounding (every YADE contact and bond acts
    on both sides, a PFacet's share spread over its three nodes)."""
    O, woven, yp = pf
    w = woven.weave(nx=3, ny=3, cp_per_span=1)
    p = yp.build(w.engine, w.warp_yarns + w.weft_yarns)
    X = np.array([list(O.bodies[i].state.pos) for i in p.node_ids()])
    R, m, V = 1e-3, 1e-4, 200.0
    c = X.mean(axis=0)
    from yade import utils
    from yade._minieigenHP import Vector3
    s = utils.sphere((c[0], c[1], X[:, 2].max() + p.radius + R + 1e-6), R, material=yp.projectile_material(p, 'sphere', 2 * R))
    s.mask = yp.BOX_MASK if meets == 'nodes' else yp.CONNECTION_MASK
    pid = O.bodies.append(s)
    O.bodies[pid].state.mass = m
    O.bodies[pid].state.vel = Vector3(0, 0, -V)
    O.dt = p.stable_dt(0.5)
    O.run(400, True)
    p_nodes = sum(O.bodies[i].state.mass * O.bodies[i].state.vel[2] for i in p.node_ids())
    p_proj = m * O.bodies[pid].state.vel[2]
    assert p_proj > -m * V * (1 - 1e-3)  # it was slowed: there was an exchange to conserve
    assert p_nodes + p_proj == pytest.approx(-m * V, rel=1e-9)


def test_bad_lines_refused(pf):
    O, woven, yp = pf
    w = woven.weave(nx=1, ny=1, cp_per_span=1)
    for bad in (1, 17, 2.5, True):
        with pytest.raises(ValueError, match=r'pfacet_lines = .* is invalid: allowed an integer in \[2, 16\]'):
            yp.build(w.engine, w.warp_yarns, lines=bad, radius=2e-5)


@pytest.mark.parametrize('script,args,key', [
    ('ballistic.py', ['model=yade_pfacet', 'pfacet_lines=1'], 'pfacet_lines'),
    ('ballistic.py', ['model=yade_pfacet', 'pfacet_lines=40'], 'pfacet_lines'),
    ('ballistic.py', ['model=yade_pfacet', 'pfacet_projectile=facets'], 'pfacet_projectile'),
    ('ballistic.py', ['model=yade_pfacet', 'bending=1'], 'bending'),
    ('ballistic.py', ['model=yade_pfacet', 'backing=wall'], 'backing'),
    ('ballistic.py', ['model=yade_pfacet', 'dt_factor=20'], 'dt_factor'),
    ('tension.py', ['model=yade_pfacet', 'pfacet_lines=0'], 'pfacet_lines'),
])
def test_bad_pfacet_keys_name_the_key(script_server, tmp_path, script, args, key):
    rc, log, s = run_refused(script_server, script, tmp_path, *args)
    assert rc != 0 and s is None and ('%s = ' % key) in log and 'allowed' in log, log


@pytest.mark.parametrize('script', ['ballistic.py', 'tension.py', 'smith.py'])
def test_bad_model_lists_pfacet(script_server, tmp_path, script):
    rc, log, s = run_refused(script_server, script, tmp_path, 'model=abaqus')
    assert rc != 0 and "allowed 'woven', 'yade' or 'yade_pfacet'" in log and s is None


def test_ballistic_pfacet_quick(tmp_path):
    """A short ballistic run in PFacet ribbons: the same mass, a closed energy balance and a
    projectile that was slowed, the yarns kept apart."""
    rc, log, s = run_scene('ballistic.py', tmp_path, 'model=yade_pfacet', 'side=0.00635', 't_end=4e-6', 'size=1.5e-3',
                           'mass=0.05e-3', 'shape=sphere', 'progress=0')
    assert rc == 0 and s['status'] == 'ok', log
    m = s['measured']
    assert m['model'] == 'yade_pfacet' and m['pfacet_lines'] == 2 and m['pfacets'] > 0
    assert m['fabric_mass'] == pytest.approx(m['woven_fabric_mass'], rel=1e-9)
    assert abs(m['energy_balance_error']) < 0.01
    assert 0 < m['absorbed_energy'] < 0.5 * 0.05e-3 * 200 ** 2
    assert m['dt'] < s['reference']['woven_dt_crit']
    assert 0 < m['max_body_penetration'] < 2 * m['grid_radius'] + 1e-3  # touched, not through a node
    assert m['max_yarn_penetration'] < 2 * m['grid_radius']
