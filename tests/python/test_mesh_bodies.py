"""woven.mesh: the STL reader, the closedness check and the mass properties of a closed triangle
mesh (Eberly's polyhedral mass properties) against solids in closed form: a cube off the origin, the
regular n-gon prism exactly, and a round cylinder as the n-gon's limit."""
import math

import numpy as np
import pytest

from woven import mesh


def cube(a, centre):
    v = np.array([[x, y, z] for x in (0, a) for y in (0, a) for z in (0, a)], float) - a / 2 + np.asarray(centre)
    # outward faces of the unit cube, corners indexed x*4 + y*2 + z
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    t = [(q[0], q[1], q[2]) for q in quads] + [(q[0], q[2], q[3]) for q in quads]
    return v, np.array(t)


def test_cube_closed_form():
    a, rho, c = 0.02, 7800.0, (0.3, -0.1, 0.05)
    v, t = cube(a, c)
    mesh.check_closed(t)
    m, cm, inertia = mesh.mass_properties(v, t, density=rho)
    assert m == pytest.approx(rho * a ** 3, rel=1e-12)
    assert np.allclose(cm, c, atol=1e-14)
    # the products come out as the difference of moments about the origin and m c c (parallel axis):
    # exact to the rounding of those, 1e-10 of the moments
    assert np.allclose(inertia, np.eye(3) * m * a * a / 6, rtol=1e-10, atol=1e-10 * m * a * a)


def test_prism_exact_and_cylinder_limit():
    r, h, rho = 3.5e-3, 7.0e-3, 7850.0
    for n, tol in ((64, None), (512, 1e-4)):
        v, t = mesh.revolve([(0, -h / 2), (r, -h / 2), (r, h / 2), (0, h / 2)], n)
        mesh.check_closed(t)
        m, cm, inertia = mesh.mass_properties(v, t, density=rho)
        # regular n-gon: area (n/2) r^2 sin(2 pi/n), polar moment (n r^4/12) sin(2 pi/n) (2 + cos(2 pi/n))
        s, co = math.sin(2 * math.pi / n), math.cos(2 * math.pi / n)
        area = n / 2 * r * r * s
        assert m == pytest.approx(rho * area * h, rel=1e-12)
        assert np.allclose(cm, 0, atol=1e-15)
        assert inertia[2, 2] == pytest.approx(rho * h * n * r ** 4 / 12 * s * (2 + co), rel=1e-10)
        assert inertia[0, 0] == pytest.approx(inertia[1, 1], rel=1e-10)
        assert inertia[0, 0] == pytest.approx(inertia[2, 2] / 2 + m * h * h / 12, rel=1e-10)
        if tol:  # the round cylinder: m = rho pi r^2 h, I_zz = m r^2 / 2, I_xx = m (3 r^2 + h^2) / 12
            mc = rho * math.pi * r * r * h
            assert m == pytest.approx(mc, rel=tol)
            assert inertia[2, 2] == pytest.approx(mc * r * r / 2, rel=tol)
            assert inertia[0, 0] == pytest.approx(mc * (3 * r * r + h * h) / 12, rel=tol)


def test_mass_given_and_refusals():
    v, t = cube(0.01, (0, 0, 0))
    m, _, _ = mesh.mass_properties(v, t, mass=8.0e-3)
    assert m == pytest.approx(8.0e-3)
    with pytest.raises(ValueError, match='mass = -1'):
        mesh.mass_properties(v, t, mass=-1)
    with pytest.raises(ValueError, match='exactly one'):
        mesh.mass_properties(v, t)
    with pytest.raises(ValueError, match='open'):
        mesh.check_closed(t[:-1], name='mesh = box.stl')
    flipped = t.copy()
    flipped[0] = flipped[0][::-1]
    with pytest.raises(ValueError, match='non-manifold'):
        mesh.check_closed(flipped)


@pytest.mark.parametrize('binary', [True, False])
def test_stl_round_trip(tmp_path, binary):
    v, t = mesh.revolve([(0, 0), (1.0, 0), (1.0, 2.0), (0, 3.0)], 24)
    path = tmp_path / 'part.stl'
    if binary:
        mesh.write_stl(str(path), v, t)
    else:
        with open(path, 'w') as fh:
            fh.write('solid part\n')
            for tri in t:
                fh.write(' facet normal 0 0 0\n  outer loop\n')
                for k in tri:
                    fh.write('   vertex %.17g %.17g %.17g\n' % tuple(v[k]))
                fh.write('  endloop\n endfacet\n')
            fh.write('endsolid part\n')
    v2, t2 = mesh.read_stl(str(path), scale=1e-3)
    mesh.check_closed(t2)
    m1, c1, i1 = mesh.mass_properties(v * 1e-3, t, density=1000)
    m2, c2, i2 = mesh.mass_properties(v2, t2, density=1000)
    rel = 1e-6 if binary else 1e-12  # binary STL stores float32
    assert m2 == pytest.approx(m1, rel=rel)
    assert np.allclose(i2, i1, rtol=10 * rel, atol=1e-6 * abs(i1).max())
    bad = tmp_path / 'junk.stl'
    bad.write_text('not an stl')
    with pytest.raises(ValueError, match='junk.stl'):
        mesh.read_stl(str(bad))


def test_make_meshes_script(tmp_path):
    """scripts/make_meshes.py writes closed STLs: the ~2000-triangle 9 mm bullet of 8.0 g and the RCC,
    whose mesh mass is the 48-gon's share of the exact cylinder's (n/(2 pi) sin(2 pi/n))."""
    from conftest import run_scene
    from woven import projectiles
    rc, out, _ = run_scene('make_meshes.py', tmp_path, timeout=120)
    assert rc == 0, out
    v, t = mesh.read_stl(str(tmp_path / 'bullet9mm.stl'))
    mesh.check_closed(t)
    assert 1800 <= len(t) <= 2200
    m, cm, _ = mesh.mass_properties(v, t, mass=8.0e-3)
    assert m == pytest.approx(8.0e-3)
    assert 0 < cm[2] < 15.6e-3 / 2  # the nose is lighter than the base
    v, t = mesh.read_stl(str(tmp_path / 'rcc.stl'))
    mesh.check_closed(t)
    m, _, _ = mesh.mass_properties(v, t, density=projectiles.STEEL_DENSITY)
    n = 48
    assert m == pytest.approx(projectiles.solid('rcc')['mass'] * n / (2 * math.pi) * math.sin(2 * math.pi / n), rel=1e-5)
    rc, out, _ = run_scene('make_meshes.py', tmp_path, 'segments=3', timeout=120)
    assert rc != 0 and 'segments = 3 is invalid' in out


def _settled_ply(yade_ns):
    """A settled 3 x 3 KM2 ply with collisions in a fresh scene: (engine, positions, a height 0.2 mm
    below its lowest node)."""
    import woven
    O = yade_ns.O
    O.reset()
    O.engines = []
    e = woven.weave(preset='km2_706', nx=3, ny=3, cp_per_span=2).engine
    woven.contact.enable(e, position_correction=0)
    e.settle_sections()
    X = woven.positions(e)
    return e, X, X[:, 2].min() - 0.2e-3


def test_wall_stops_the_fabric(yade_ns):
    """A YADE Wall (sense +1) under a ply, moving up at 20 m/s as a kinematic body, lifts the ply
    without letting it through; a two-sided wall (sense 0) is refused naming sense."""
    import woven
    from yade import utils, Vector3
    O = yade_ns.O
    e, _, z0 = _settled_ply(yade_ns)
    bad = O.bodies.append(utils.wall((0, 0, z0), axis=2, sense=0))
    with pytest.raises(ValueError, match='sense = 0 of wall'):
        woven.coupling.couple(e, [bad])
    wid = O.bodies.append(utils.wall((0, 0, z0), axis=2, sense=1))
    O.bodies[wid].state.vel = Vector3(0, 0, 20.0)
    woven.coupling.couple(e, [wid])
    O.engines = [yade_ns.wrapper.ForceResetter(), yade_ns.wrapper.NewtonIntegrator(damping=0, gravity=(0, 0, 0))]
    woven.attach(e)
    O.run(400, True)
    zw = O.bodies[wid].state.pos[2]
    assert zw > z0 + 1e-4  # the wall moved up into where the ply was
    kin = np.array([e.is_kinematic(i) for i in range(e.n_nodes)])
    vz = woven.velocities(e)[~kin, 2]
    assert vz.mean() > 1.0  # the ply was pushed up
    assert e.collision_stats()['max_body_penetration'] < 0.05e-3


def test_ballistic_backing_wall(tmp_path):
    """ballistic.py backing=wall: a fixed wall below the pack, reported in the summary; the run keeps
    its energy books. Bad values are refused naming the key and its range."""
    from conftest import run_scene
    rc, out, s = run_scene('ballistic.py', tmp_path, 'side=0.004', 't_end=3e-6', 'V=100', 'backing=wall',
                           'backing_standoff=1e-4', 'progress=0', 'vtk_every=-1', timeout=120)
    assert rc == 0, out
    b = s['measured']['backing']
    assert b['kind'] == 'wall' and b['standoff'] == pytest.approx(1e-4) and b['z'] < 0
    assert abs(s['measured']['energy_balance_error']) < 1e-3
    for arg, key in (('backing=plate', 'backing'), ('backing_standoff=0', 'backing_standoff'),
                     ('backing_standoff=1', 'backing_standoff')):
        rc, out, _ = run_scene('ballistic.py', tmp_path, arg, 'side=0.004', 't_end=1e-7', timeout=120)
        assert rc != 0 and ('%s = ' % key) in out and 'is invalid: allowed' in out, out


def _facets_of(v, t):
    """YADE Facet bodies of the triangles t of vertices v (each a body of its own)."""
    from yade import utils
    return [utils.facet([tuple(map(float, v[i])) for i in tri], fixed=True) for tri in t]


def test_facet_sheet_stops_the_fabric(yade_ns):
    """Two YADE Facets (a lone sheet: outside on both faces) under a ply, moving up at 20 m/s as
    kinematic bodies, lift the ply without letting it through, as the Wall does."""
    import woven
    from yade import Vector3
    O = yade_ns.O
    e, X, z0 = _settled_ply(yade_ns)
    lo, hi = X.min(axis=0) - 1e-3, X.max(axis=0) + 1e-3
    v = np.array([[lo[0], lo[1], z0], [hi[0], lo[1], z0], [hi[0], hi[1], z0], [lo[0], hi[1], z0]])
    ids = [O.bodies.append(b) for b in _facets_of(v, [(0, 1, 2), (0, 2, 3)])]
    for i in ids:
        O.bodies[i].state.vel = Vector3(0, 0, 20.0)
    woven.coupling.couple(e, ids)
    assert [e._body_parts(k)[0][0] for k in range(e.n_bodies)] == ['facet', 'facet']
    O.engines = [yade_ns.wrapper.ForceResetter(), yade_ns.wrapper.NewtonIntegrator(damping=0, gravity=(0, 0, 0))]
    woven.attach(e)
    O.run(400, True)
    assert O.bodies[ids[0]].state.pos[2] > z0 + 1e-4  # the sheet moved up into where the ply was
    kin = np.array([e.is_kinematic(i) for i in range(e.n_nodes)])
    assert woven.velocities(e)[~kin, 2].mean() > 1.0  # the ply was pushed up
    assert e.collision_stats()['max_body_penetration'] < 0.05e-3


def test_clump_of_facets_is_a_closed_solid(yade_ns):
    """A clump of the 12 facets of a cube (as yade.ymport.stl makes of a closed mesh) is coupled as the
    one-sided, outward faces of a solid, also when the file winds inward (the corners reversed);
    11 of them close nothing and stay two-sided facets."""
    import woven
    O = yade_ns.O
    v, t = cube(4e-3, (0, 0, 0))

    def parts_of(tris):
        O.reset()
        O.engines = []
        w = woven.weave(preset='km2_706', nx=1, ny=1, cp_per_span=1)
        woven.contact.enable(w.engine, position_correction=0)
        facets = _facets_of(v + np.array([0, 0, 5e-3]), tris)
        for b in facets:  # YADE's clump asserts a positive mass of its members: a share of a 1 g solid
            b.state.mass, b.state.inertia = 1e-3 / len(facets), (1e-12, 1e-12, 1e-12)
        cid = O.bodies.appendClumped(facets)[0]
        O.bodies[cid].dynamic = False
        woven.coupling.couple(w.engine, [cid])
        return w.engine._body_parts(0)

    for tris in (t, t[:, ::-1]):
        parts = parts_of(tris)
        assert len(parts) == 12 and {p[0] for p in parts} == {'triangle'}
        for kind, corners, centre, axes in parts:  # outward: the normal points away from the cube's centre
            a, b, c = (np.array(list(x)) for x in corners)
            n = np.cross(b - a, c - a)
            assert np.dot(n, (a + b + c) / 3 - np.array([0, 0, 5e-3])) > 0
    assert {p[0] for p in parts_of(t[:11])} == {'facet'}


def test_cube_mesh_strikes_as_the_box(tmp_path):
    """shape=mesh with the STL of a cube gives the box's impact: the same residual velocity within 1 %
    and energy books within 1 % (the triangle form against the box form, two independent gap
    functions of the same solid)."""
    from conftest import run_scene
    a = 5.59e-3
    v, t = cube(a, (0, 0, 0))
    path = str(tmp_path / 'cube.stl')
    mesh.write_stl(path, v, t)
    (tmp_path / 'box').mkdir(), (tmp_path / 'mesh').mkdir()
    common = ('side=0.0127', 'V=600', 'pictures=0', 'progress=0', 'vtk_every=-1', 'mass=1.1e-3')
    rc, out, box = run_scene('ballistic.py', tmp_path / 'box', 'shape=box', *common, timeout=300)
    assert rc == 0, out
    rc, out, tri = run_scene('ballistic.py', tmp_path / 'mesh', 'shape=mesh', 'mesh=' + path, *common, timeout=300)
    assert rc == 0, out
    mb, mt = box['measured'], tri['measured']
    assert mt['projectile']['triangles'] == 12
    assert mb['outcome'] == mt['outcome'] == 'perforated'
    assert mt['residual_velocity'] == pytest.approx(mb['residual_velocity'], rel=0.01)
    assert abs(mt['energy_balance_error']) < 0.01
    assert mt['max_body_penetration'] < 0.1 * mt['yarn_thickness']


def test_mesh_projectile_keys(tmp_path):
    """shape=mesh refuses, naming the key: no file, a file with another shape, size given, a bad
    nose_axis or mesh_scale, an open mesh (naming the file), contact_model paper."""
    from conftest import run_scene
    v, t = cube(5e-3, (0, 0, 0))
    good, open_ = str(tmp_path / 'cube.stl'), str(tmp_path / 'open.stl')
    mesh.write_stl(good, v, t)
    mesh.write_stl(open_, v, t[:-1])
    for args, key in ((('shape=mesh',), "mesh = ''"), (('shape=box', 'mesh=' + good), 'mesh = '),
                      (('shape=mesh', 'mesh=' + good, 'size=0.01'), 'size = '),
                      (('shape=mesh', 'mesh=' + good, 'nose_axis=+w'), 'nose_axis = '),
                      (('shape=mesh', 'mesh=' + good, 'mesh_scale=0'), 'mesh_scale = '),
                      (('shape=mesh', 'mesh=' + open_), 'open.stl'),
                      (('shape=mesh', 'mesh=' + good, 'contact_model=paper'), 'shape = ')):
        rc, out, _ = run_scene('ballistic.py', tmp_path, *args, 'side=0.004', 't_end=1e-7', timeout=120)
        assert rc != 0 and key in out and 'is invalid' in out, (args, out[-800:])


def test_mesh_solid_frames():
    """woven.mesh.solid: a box 2 x 4 x 8 mm along x read with nose_axis=+x is 8 mm long along the
    flight (half_length 4 mm) and 2-4 mm across (radius the corner's distance from the axis), its
    principal moments the box's in closed form; the triangles are in the principal frame (centred)."""
    import tempfile, os
    a = np.array([8e-3, 2e-3, 4e-3])
    v, t = cube(1.0, (0, 0, 0))
    v = v * a
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, 'box.stl')
        mesh.write_stl(path, v * 1e3, t)  # in mm
        s = mesh.solid(path, scale=1e-3, mass=1e-3, nose_axis='+x')
    assert s['half_length'] == pytest.approx(4e-3, rel=1e-6)
    assert s['radius'] == pytest.approx(math.hypot(1e-3, 2e-3), rel=1e-6)
    m = 1e-3
    expect = sorted([m * (a[1] ** 2 + a[2] ** 2) / 12, m * (a[0] ** 2 + a[2] ** 2) / 12, m * (a[0] ** 2 + a[1] ** 2) / 12])
    assert np.allclose(sorted(s['inertia']), expect, rtol=1e-5)
    assert np.allclose(s['triangles'].reshape(-1, 3).mean(axis=0), 0, atol=1e-9)
    with pytest.raises(ValueError, match='nose_axis'):
        mesh.solid(path, nose_axis='x')


def test_square_ring_is_a_closed_frame():
    """woven.mesh.square_ring: closed and outward; its volume the slab's (2H)^2 - (2h)^2 times the
    thickness exactly with square edges, less the rounded edge's (1 - pi/4) r^2 along the window's
    perimeter (to the quarter circle's polygon) with a rounded one; bad sizes refused."""
    H, h, T, r = 6e-3, 4e-3, 1e-3, 4e-4
    v, t = mesh.square_ring((1e-3, -2e-3), h, H, 0.0, T)
    mesh.check_closed(t)
    assert mesh.volume(v, t) == pytest.approx(((2 * H) ** 2 - (2 * h) ** 2) * T, rel=1e-12)
    for top, bottom in ((r, 0.0), (0.0, r)):
        v, t = mesh.square_ring((0, 0), h, H, 0.0, T, round_top=top, round_bottom=bottom, segments=64)
        mesh.check_closed(t)
        # the rounded strip follows the window's perimeter 8 h (at the edge's centre line, 8 (h + r))
        cut = (1 - math.pi / 4) * r * r * 8 * (h + r * (1 - 2 / (3 * (4 - math.pi))))
        assert mesh.volume(v, t) == pytest.approx(((2 * H) ** 2 - (2 * h) ** 2) * T - cut, rel=2e-4)
    with pytest.raises(ValueError, match='frame ring is invalid'):
        mesh.square_ring((0, 0), H, h, 0.0, T)
    with pytest.raises(ValueError, match='frame ring is invalid'):
        mesh.square_ring((0, 0), h, H, 0.0, T, round_top=2 * T)


def test_ballistic_frame_holds_by_its_friction(tmp_path):
    """ballistic.py clamp=0 frame=mesh: the ply's edges between two fixed jaws; the jaws' own friction
    (2 against 0) works on the yarns drawn through them (the friction book, which the projectile's
    body_friction 0 leaves empty) and the ply absorbs more; the books close in both; the keys are
    refused out of range, and with clamped ends, naming the key."""
    from conftest import run_scene
    got = {}
    for mu in (0, 2):
        (tmp_path / str(mu)).mkdir()
        rc, out, s = run_scene('ballistic.py', tmp_path / str(mu), 'side=0.008', 't_end=1.2e-5', 'V=200', 'size=2e-3',
                               'mass=2e-4', 'clamp=0', 'frame=mesh', 'frame_width=2e-3', 'frame_friction=%g' % mu,
                               'stop=0', 'progress=0', 'vtk_every=-1', 'pictures=0', timeout=300)
        assert rc == 0, out
        m = s['measured']
        assert m['frame']['kind'] == 'mesh' and m['frame']['friction'] == mu and m['frame']['pull_in_max'] > 0
        assert abs(m['energy_balance_error']) < 0.01, out
        got[mu] = (m['energy']['friction'], m['absorbed_energy'])
    assert got[0][0] == 0 and got[2][0] > 0.05 * got[2][1], got
    assert got[2][1] > 1.5 * got[0][1], got
    for args, key in ((('frame=jaws', 'clamp=0'), 'frame'), (('frame=mesh',), 'clamp'),
                      (('frame=mesh', 'clamp=0', 'frame_width=0.01'), 'frame_width'),
                      (('frame=mesh', 'clamp=0', 'frame_width=2e-3', 'frame_friction=3'), 'frame_friction'),
                      (('frame=mesh', 'clamp=0', 'frame_width=2e-3', 'frame_edge=3e-3'), 'frame_edge'),
                      (('frame=mesh', 'clamp=0', 'frame_width=2e-3', 'frame_gap=0'), 'frame_gap')):
        rc, out, _ = run_scene('ballistic.py', tmp_path, 'side=0.008', 't_end=1e-7', *args, timeout=120)
        assert rc != 0 and ('%s = ' % key) in out and 'is invalid: allowed' in out, (args, out[-500:])
