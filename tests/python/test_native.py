"""The native YADE plugin (docs/yade_native.md): woven.attach puts yade.wrapper.WovenFabricEngine into
O.engines, the scenes give the same bits as with the PyRunner adapter (and as the default build when
WOVEN_DEFAULT_SITE names its installed package folder), and O.save / O.load continue bit for bit.

Skipped unless the plugin is built and loaded: configure with -DYADE_SOURCE_DIR=<YADE's source>,
`cmake --install`, `bash scripts/yade_prefix.sh <prefix>`, and run pytest with YADE_PREFIX=<prefix>
and PYTHONPATH=<the native build's package folder> (README, "Native YADE plugin")."""
import json
import os
import subprocess

import numpy as np
import pytest

from conftest import ROOT

import woven  # noqa: E402  (imports yade)
from woven import _native  # noqa: E402

REASON = _native.why_not()
pytestmark = pytest.mark.skipif(bool(REASON), reason='native YADE plugin not in use (enable: cmake -DYADE_SOURCE_DIR=<YADE '
                                'source>, install, YADE_PREFIX=<prefix>; docs/yade_native.md): ' + REASON)

# Keys of summary.json that are wall-clock times (they differ run to run in any build).
TIMING = ('seconds', 'wall', 'time_s', 'per_s', 'elapsed', 'speed', '_us')


def _numbers(d, prefix=''):
    """Flattened {key: value} of the numbers and strings in a summary, without timings."""
    out = {}
    for k, v in d.items():
        key = prefix + k
        if any(t in k for t in TIMING) or (isinstance(v, str) and v.startswith('/')) or key == 'build':
            continue  # wall-clock times and output paths differ run to run; the builds compared differ
        if isinstance(v, dict):
            out.update(_numbers(v, key + '.'))
        elif isinstance(v, (int, float, str, bool)) or v is None:
            out[key] = v
        elif isinstance(v, list):
            out[key] = json.dumps(v)
    return out


def _scene(script, out, args, native, site=None):
    """Runs a scene in yade; native: WOVEN_NATIVE=1 (must use the plugin) or 0 (PyRunner)."""
    env = dict(os.environ, WOVEN_NATIVE='1' if native else '0', OMP_NUM_THREADS='1')
    if site:  # the default build: its package, Debian's YADE without the plugin
        env['PYTHONPATH'] = site
        env.pop('YADE_PREFIX', None)
        env.pop('WOVEN_NATIVE')
    os.makedirs(out, exist_ok=True)
    cmd = ['yade', '-n', '-x', os.path.join(ROOT, 'scripts', script), 'out=%s' % out] + list(args)
    r = subprocess.run(cmd, cwd=str(out), capture_output=True, text=True, timeout=900, env=env)
    assert r.returncode == 0, r.stdout + r.stderr
    s = json.load(open(os.path.join(str(out), 'summary.json')))
    files = {}
    for name in sorted(os.listdir(str(out))):
        if name.endswith(('.csv', '.state')) and 'bench' not in name:
            files[name] = open(os.path.join(str(out), name), 'rb').read()
    return s, files


SCENES = {
    'smith': ('smith.py', ['elements=1000', 'levels=1', 'duration=0.5']),
    'tension': ('tension.py', ['nx=3', 'ny=3', 'samples=20']),
    # pictures=0: the rendered pictures are paths, not figures (and 7 s a run)
    'ballistic': ('ballistic.py', ['side=0.004', 't_end=3e-6', 'vtk_every=-1', 'progress=0', 'samples=20', 'pictures=0']),
    # what came after the plugin's first tests: a pack of plies, an FSP (cylinder parts with a chisel
    # nose), yarn-yarn and projectile-yarn friction, the coloured sweep order
    'ballistic_pack': ('ballistic.py', ['side=0.004', 't_end=3e-6', 'vtk_every=-1', 'progress=0', 'samples=20',
                                        'pictures=0', 'plies=2', 'shape=fsp', 'friction=0.2', 'body_friction=0.3',
                                        'sweep_order=coloured']),
}


# YADE's other bodies: a mesh projectile (an STL, as woven.mesh reads it), a frame of clumped
# Facets holding the edges, a Wall behind (the file is written by the test: RCC_MESH).
RCC_MESH = 'rcc_mesh.stl'
SCENES['ballistic_bodies'] = ('ballistic.py', ['side=0.006', 't_end=3e-6', 'vtk_every=-1', 'progress=0', 'samples=20',
                                               'pictures=0', 'shape=mesh', 'mesh=' + RCC_MESH, 'mass=1e-3', 'V=300',
                                               'clamp=0', 'frame=mesh', 'frame_width=1.2e-3', 'backing=wall',
                                               'backing_standoff=1e-4'])


@pytest.mark.parametrize('name', sorted(SCENES))
def test_scene_same_bits_native_and_pyrunner(name, tmp_path):
    if name == 'ballistic_bodies':
        from woven import mesh
        # 2 mm across: clear of the frame's 3.6 mm window
        v, t = mesh.revolve([(0.0, -1e-3), (1e-3, -1e-3), (1e-3, 1e-3), (0.0, 1e-3)], 24)
        path = str(tmp_path / RCC_MESH)
        mesh.write_stl(path, v, t)
        args = [a.replace(RCC_MESH, path) for a in SCENES[name][1]]
        script = SCENES[name][0]
    else:
        script, args = SCENES[name]
    a, fa = _scene(script, tmp_path / 'native', args, native=True)
    b, fb = _scene(script, tmp_path / 'pyrunner', args, native=False)
    na, nb = _numbers(a['measured']), _numbers(b['measured'])
    assert na == nb  # every measured figure, to the last bit (json keeps doubles exactly)
    assert fa.keys() == fb.keys() and fa == fb  # time series and state files byte for byte
    assert len(na) > 3
    site = os.environ.get('WOVEN_DEFAULT_SITE')
    if site:  # the default build (static core, Eigen aligned): the same bits too
        c, fc = _scene(script, tmp_path / 'default', args, native=False, site=site)
        assert _numbers(c['measured']) == na
        assert fc == fa


def test_attach_puts_the_native_engine(yade_ns):
    O = yade_ns.O
    O.reset()
    O.engines = []
    w = woven.weave(nx=1, ny=1)
    n = woven.attach(w.engine)
    assert type(n).__name__ == 'WovenFabricEngine' and n.fabric._same(w.engine)
    assert [type(e).__name__ for e in O.engines] == ['WovenFabricEngine']
    with pytest.raises(ValueError, match='already in O.engines'):
        woven.attach(w.engine)
    O.run(5, True)
    assert w.engine.iter == 5 and O.iter == 5


def _struck_ply(yade_ns):
    """A 6 x 6-yarn ply clamped at its yarn ends, a YADE Box at 300 m/s just above it, coupled, with
    breakage: contacts, impulses on the body and the yarns' strain filter all carry over a save."""
    O = yade_ns.O
    O.reset()
    O.engines = [yade_ns.wrapper.ForceResetter(), yade_ns.wrapper.NewtonIntegrator(damping=0)]
    w = woven.weave(nx=3, ny=3, cp_per_span=2)
    e = w.engine
    woven.contact.enable(e)
    e.enable_breakage(strain=0.02)
    for y in range(e.n_yarns):
        info = e.yarn(y)
        e.fix(info['first_node'])
        e.fix(info['first_node'] + info['n_nodes'] - 1)
    X = woven.positions(e)
    c = 0.5 * (X.min(axis=0) + X.max(axis=0))
    half = 0.8e-3
    pid = O.bodies.append(yade_ns.utils.box(yade_ns.Vector3(c[0], c[1], X[:, 2].max() + half + 0.3e-3),
                                            yade_ns.Vector3(half, half, half), fixed=False))
    O.bodies[pid].state.vel = yade_ns.Vector3(0, 0, -300)
    O.bodies[pid].state.angVel = yade_ns.Vector3(0, 1e3, 0)
    woven.coupling.couple(e, [pid])
    n = woven.attach(e)
    return e, pid, n


def _fingerprint(O, e, pid):
    s = O.bodies[pid].state
    return (woven.positions(e).tobytes(), woven.velocities(e).tobytes(), woven.alive(e).tobytes(),
            woven.section_flattening(e).tobytes(), repr(e.energy()), repr((tuple(s.pos), tuple(s.vel),
                                                                        tuple(s.ori), tuple(s.angVel))), e.iter)


@pytest.mark.parametrize('ext', ['.yade.gz', '.xml', '.yade.bz2'])
def test_save_load_continues_bit_for_bit(yade_ns, tmp_path, ext):
    O = yade_ns.O
    e, pid, n = _struck_ply(yade_ns)
    O.run(60, True)
    path = str(tmp_path / ('scene' + ext))
    O.save(path)
    O.run(120, True)
    ref = _fingerprint(O, e, pid)
    assert e.collision_stats()['contacts'] > 0 or len(e.break_log()) > 0  # the body reached the ply
    O.load(path)
    assert O.iter == 60
    e2 = O.engines[-1].fabric
    assert type(O.engines[-1]).__name__ == 'WovenFabricEngine' and e2.iter == 60 and not e2._same(e)
    O.run(120, True)
    assert _fingerprint(O, e2, pid) == ref


def test_save_load_keeps_facet_bodies(yade_ns, tmp_path):
    """A clump of the 12 facets of a cube (a closed mesh, one-sided faces) strikes the ply over a
    lone Facet sheet and a Wall, the sheet with its own friction: O.save / O.load continue bit for bit."""
    O, utils, V3 = yade_ns.O, yade_ns.utils, yade_ns.Vector3
    O.reset()
    O.engines = [yade_ns.wrapper.ForceResetter(), yade_ns.wrapper.NewtonIntegrator(damping=0)]
    w = woven.weave(nx=3, ny=3, cp_per_span=2)
    e = w.engine
    woven.contact.enable(e)
    for y in range(e.n_yarns):
        info = e.yarn(y)
        e.fix(info['first_node'])
        e.fix(info['first_node'] + info['n_nodes'] - 1)
    X = woven.positions(e)
    c, a = 0.5 * (X.min(axis=0) + X.max(axis=0)), 1.6e-3
    v = np.array([[x, y, z] for x in (0, a) for y in (0, a) for z in (0, a)]) - a / 2 + c + [0, 0, X[:, 2].max() + a / 2 + 3e-4 - c[2]]
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = [(q[0], q[1], q[2]) for q in quads] + [(q[0], q[2], q[3]) for q in quads]
    facets = [utils.facet([tuple(map(float, v[i])) for i in tri], fixed=False) for tri in tris]
    for b in facets:
        b.state.mass, b.state.inertia = 1e-3 / 12, V3(1e-12, 1e-12, 1e-12)
    pid = O.bodies.appendClumped(facets)[0]
    O.bodies[pid].state.vel = V3(0, 0, -300)
    lo, hi, z = X.min(axis=0) - 1e-3, X.max(axis=0) + 1e-3, X[:, 2].min() - 2e-4
    k = [(lo[0], lo[1], z), (hi[0], lo[1], z), (hi[0], hi[1], z), (lo[0], hi[1], z)]
    sheet = [O.bodies.append(utils.facet([k[0], k[1], k[2]], fixed=True)), O.bodies.append(utils.facet([k[0], k[2], k[3]], fixed=True))]
    wall = O.bodies.append(utils.wall((0, 0, z - 2e-4), axis=2, sense=1))
    woven.coupling.couple(e, [pid, wall])
    woven.coupling.couple(e, sheet, friction=0.5)
    assert [e.body(i)['friction'] for i in range(e.n_bodies)] == [-1, -1, 0.5, 0.5]
    woven.attach(e)
    O.run(60, True)
    path = str(tmp_path / 'facets.yade.gz')
    O.save(path)
    O.run(120, True)
    ref = _fingerprint(O, e, pid)
    assert e.collision_stats()['contacts'] > 0
    O.load(path)
    e2 = O.engines[-1].fabric
    assert [e2.body(i)['friction'] for i in range(e2.n_bodies)] == [-1, -1, 0.5, 0.5]
    O.run(120, True)
    assert _fingerprint(O, e2, pid) == ref


def test_snapshot_round_trip_in_memory(yade_ns):
    """O.saveTmp / O.loadTmp (binary archive in memory) keep the fabric too."""
    O = yade_ns.O
    e, pid, n = _struck_ply(yade_ns)
    O.run(30, True)
    O.saveTmp('woven')
    O.run(50, True)
    ref = _fingerprint(O, e, pid)
    O.loadTmp('woven')
    O.run(50, True)
    assert _fingerprint(O, O.engines[-1].fabric, pid) == ref


def test_instability_sets_last_error_as_the_pyrunner(yade_ns):
    O = yade_ns.O
    O.reset()
    O.engines = []
    f = woven.Fabric()
    f.add_yarn([yade_ns.Vector3(1e-3 * i, 0, 0) for i in range(51)], woven.YarnMaterial(), woven.YarnSection())
    e = woven.FabricEngine(f)
    woven.attach(e)
    e.fix(0)
    e.fix(50)
    for i in range(1, 50):
        e.set_vel(i, yade_ns.Vector3(0, np.sin(np.pi * i / 50), 0))
    e.blowup_factor = 0.25
    with pytest.raises(RuntimeError, match='unstable at step'):
        O.run(100, True)
    err = woven.engine.last_error
    assert isinstance(err, woven.InstabilityError) and err.step > 0 and 'energy blow-up' in err.cause
    assert 'unstable' in O.engines[-1].lastError


# --- the collision stage's settings as YADE objects (pkg/yade/WovenStage.hpp) ---

STAGE = {'shape': 'WovenCPShape', 'bound': 'WovenCPBound', 'collider': 'WovenCollider', 'geom': 'WovenGeomFunctor',
         'phys': 'WovenPhys', 'law': 'WovenImpulseLaw'}


def test_stage_objects_show_the_core_settings(yade_ns):
    """The engine's stage objects are registered YADE classes; reading them shows the fabric's collision
    stage as woven's Python API set it (before and after attach), their defaults are the core's."""
    O, wrapper = yade_ns.O, yade_ns.wrapper
    O.reset()
    O.engines = []
    w = woven.weave(nx=1, ny=1)
    e = w.engine
    n = woven.attach(e)
    assert not n.collisions
    for attr, cls in STAGE.items():
        assert hasattr(wrapper, cls) and type(getattr(n, attr)).__name__ == cls
    e.enable_collisions()  # the core's defaults (ContactParams())
    assert n.collisions
    for attr, cls in STAGE.items():  # a fresh object's defaults are the core's defaults
        fresh = getattr(wrapper, cls)().dict()
        shown = getattr(n, attr).dict()
        fresh.pop('cellSize', None), shown.pop('cellSize', None)
        assert shown == fresh, attr
    # changed through the Python module after attach: shown on the YADE side
    woven.contact.enable(e, friction=0.25, restitution=0.1, broad_phase='grid', sweep_order='coloured', mcd=0.5,
                         margin=2e-6, contact_model='paper', penalty_stiffness=2e5)
    assert (n.law.friction, n.law.restitution, n.law.sweepOrder) == (0.25, 0.1, 'coloured')
    assert (n.collider.kind, n.shape.mcd, n.bound.margin, n.geom.model, n.phys.penaltyStiffness) == \
        ('grid', 0.5, 2e-6, 'paper', 2e5)
    O.run(3, True)
    assert n.collider.cellSize > 0  # the grid collider ran: its cell, read back from the core


def test_stage_attribute_applies_to_the_core(yade_ns):
    """An attribute set from YADE changes the core's stage at the next step (the run differs from one
    without it), a bad value stops the run naming the attribute and its range, the core unchanged."""
    O = yade_ns.O
    e, pid, n = _struck_ply(yade_ns)
    O.run(60, True)
    O.saveTmp('stage0')
    O.run(60, True)
    plain = _fingerprint(O, e, pid)
    assert e.energy()['friction'] == 0  # the ply as built: frictionless
    O.loadTmp('stage0')
    n, e = O.engines[-1], O.engines[-1].fabric
    n.law.friction = 0.4
    n.law.bodyFriction = 0.3
    O.run(60, True)
    assert e.energy()['friction'] > 0  # the impulses' tangential parts worked: friction is on in the core
    assert _fingerprint(O, e, pid) != plain
    n.law.restitution = 5.0
    with pytest.raises(RuntimeError, match=r'WovenFabricEngine\.law\.restitution = 5 is invalid: allowed \[0, 1\]'):
        O.run(1, True)
    assert isinstance(woven.engine.last_error, ValueError)
    n.law.restitution = 0.0
    assert n.law.friction == 0.4  # the rest of the stage as set
    O.run(1, True)


@pytest.mark.parametrize('ext', ['.xml', '.yade.gz'])
def test_stage_attributes_survive_save_load(yade_ns, tmp_path, ext):
    """Stage attributes set from YADE are saved by O.save and hold after O.load, in the objects and in
    the core, and the loaded run continues bit for bit as the one that saved."""
    O = yade_ns.O
    e, pid, n = _struck_ply(yade_ns)
    O.run(60, True)
    n.law.friction = 0.3
    n.law.bodyFriction = 0.2
    n.law.sweepOrder = 'coloured'
    n.collider.kind = 'grid'
    n.shape.flattenPasses = 6
    path = str(tmp_path / ('scene' + ext))
    O.save(path)  # preSave applies them to the core first
    O.run(120, True)
    ref = _fingerprint(O, e, pid)
    assert e.energy()['friction'] > 0
    O.load(path)
    n2 = O.engines[-1]
    e2 = n2.fabric
    assert not e2._same(e) and e2.iter == 60
    assert (n2.law.friction, n2.law.bodyFriction, n2.law.sweepOrder, n2.collider.kind, n2.shape.flattenPasses) == \
        (0.3, 0.2, 'coloured', 'grid', 6)
    if ext == '.xml':  # the file holds them as the engine's attributes
        text = open(path).read()
        assert '<law ' in text and '<sweepOrder>coloured</sweepOrder>' in text and '<kind>grid</kind>' in text
    O.run(120, True)
    assert _fingerprint(O, e2, pid) == ref
