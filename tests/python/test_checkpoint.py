"""Checkpoints in YADE's habit (woven.checkpoint, docs/reliability.md): a plain O.save / O.load brings
the fabric back with the scene and the run continues bit for bit, in the same process and in a fresh
one; a missing, corrupted, truncated or foreign sidecar is refused with an error naming it, and the
loaded scene's adapter then refuses to step."""
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from conftest import ROOT

# The scene of every test: a 4 x 4-yarn weave with collisions on, warp ends pulled, weft ends held,
# and a YADE sphere (NewtonIntegrator, gravity) dropped onto it, coupled to the fabric: so the
# state that must come back includes contacts, sections, the books and a YADE body.
SCENE = '''
import os
# The PyRunner adapter, which woven.checkpoint is for (a native YADE engine, where installed, is saved
# by YADE itself: docs/yade_native.md); WOVEN_NATIVE=0 makes woven.attach use it.
os.environ['WOVEN_NATIVE'] = '0'
import woven
from yade import Vector3
from yade.wrapper import Omega, ForceResetter, NewtonIntegrator
from yade.utils import sphere
O = Omega()


def build(nx=2):
    w = woven.weave(nx=nx, ny=2, cp_per_span=2, damping=0.02)
    e = w.engine
    woven.contact.enable(e)
    e.settle_sections()
    for y in w.warp_yarns:
        i = e.yarn(y)
        e.fix(i['first_node'])
        e.prescribe_velocity(i['first_node'] + i['n_nodes'] - 1, Vector3(2, 0, 0))
    for y in w.weft_yarns:
        i = e.yarn(y)
        e.fix(i['first_node'])
        e.fix(i['first_node'] + i['n_nodes'] - 1)
    O.engines = [ForceResetter(), NewtonIntegrator(gravity=(0, 0, -9.81))]
    b = O.bodies.append(sphere((0.0015, 0.0015, 0.0006), 2e-4))
    O.bodies[b].state.vel = Vector3(0, 0, -20)
    woven.coupling.couple(e, [b])
    woven.attach(e)
    return e


def snapshot(e):
    b = O.bodies[0].state
    # Every energy book too: what the adapter books from the body between steps must continue.
    return (woven.positions(e).tobytes() + woven.velocities(e).tobytes() + woven.section_flattening(e).tobytes(),
            tuple(b.pos) + tuple(b.vel), e.iter, O.iter, O.time, sorted(e.energy().items()), len(e.break_log()))
'''
N, M = 300, 300


@pytest.fixture
def scene(tmp_path, yade_ns):
    path = tmp_path / 'woven_ckp_scene.py'
    path.write_text(SCENE)
    sys.path.insert(0, str(tmp_path))
    import importlib
    import woven_ckp_scene
    importlib.reload(woven_ckp_scene)
    yield woven_ckp_scene
    sys.path.remove(str(tmp_path))
    yade_ns.O.reset()


def test_plain_save_load_continues_bit_for_bit(scene, tmp_path, yade_ns):
    import woven
    O = yade_ns.O
    path = str(tmp_path / 'run.yade.gz')
    # The uninterrupted run.
    O.reset()
    e = scene.build()
    O.run(N + M, True)
    ref = scene.snapshot(e)
    assert e.energy()['body_work'] != 0  # the sphere did touch the fabric
    # Saved at N with YADE's own call, run on, loaded back, run again: the same bits each time.
    O.reset()
    e = scene.build()
    O.run(N, True)
    O.save(path)
    left = set(os.listdir(str(tmp_path))) - {'woven_ckp_scene.py', '__pycache__'}
    assert left == {'run.yade.gz', 'run.yade.gz.woven'}  # no temporaries left
    O.run(M, True)
    assert scene.snapshot(e) == ref
    O.load(path)
    assert O.iter == N and e.iter == N
    O.run(M, True)
    assert scene.snapshot(e) == ref
    # A fresh process: the script builds and attaches the fabric as before, then O.load.
    script = tmp_path / 'cont.py'
    script.write_text('import sys\nsys.path.insert(0, %r)\nfrom woven_ckp_scene import *\ne = build()\n'
                      'O.load(%r)\nO.run(%d, True)\nopen(%r, "wb").write(repr(snapshot(e)).encode())\n'
                      % (str(tmp_path), path, M, str(tmp_path / 'snap')))
    r = subprocess.run(['yade', '-n', '-x', str(script)], capture_output=True, text=True, timeout=120,
                       cwd=str(tmp_path))
    assert r.returncode == 0, r.stdout + r.stderr
    assert (tmp_path / 'snap').read_bytes() == repr(ref).encode()
    # O.saveTmp / O.loadTmp and O.reload too.
    O.reset()
    e = scene.build()
    O.run(N, True)
    O.saveTmp('ckp')
    O.run(M, True)
    O.loadTmp('ckp')
    O.run(M, True)
    assert scene.snapshot(e) == ref
    O.load(path)
    O.run(10, True)
    O.reload()
    assert e.iter == N
    O.run(M, True)
    assert scene.snapshot(e) == ref
    assert woven.checkpoint.hooked()


def test_bad_sidecars_are_refused(scene, tmp_path, yade_ns):
    from woven.checkpoint import CheckpointError
    O = yade_ns.O
    path, other = str(tmp_path / 'a.yade.gz'), str(tmp_path / 'b.yade.gz')
    O.reset()
    e = scene.build()
    O.run(20, True)
    O.save(path)
    O.run(5, True)
    O.save(other)
    good = open(path + '.woven', 'rb').read()
    cases = [(None, 'missing'), (good[:-40], 'checksum|truncated|past'), (good[:500], 'checksum|truncated|past'),
             (good[:200] + bytes([good[200] ^ 1]) + good[201:], 'checksum'), (b'garbage' * 20, 'not a woven checkpoint'),
             (b'', 'truncated'), (open(other + '.woven', 'rb').read(), 'another save')]
    for data, what in cases:
        if data is None:
            os.remove(path + '.woven')
        else:
            open(path + '.woven', 'wb').write(data)
        with pytest.raises(CheckpointError, match=what) as err:
            O.load(path)
        assert 'a.yade.gz.woven' in str(err.value)
        # The loaded scene's adapter refuses to step rather than run on with a fabric of another time.
        with pytest.raises(RuntimeError, match='not restored'):
            O.run(1, True)
        assert e.iter == 25
        O.reset()
        e = scene.build()
        O.run(25, True)
    # Another weave attached before the load: its engine refuses the state file (fingerprint).
    open(path + '.woven', 'wb').write(good)
    O.reset()
    scene.build(nx=3)
    with pytest.raises(CheckpointError, match='this fabric|another weave'):
        O.load(path)
    # A fresh process that did not build the fabric is told what to do.
    script = tmp_path / 'bare.py'
    script.write_text('import woven\nO.load(%r)\n' % path)
    r = subprocess.run(['yade', '-n', '-x', str(script)], capture_output=True, text=True, timeout=120,
                       cwd=str(tmp_path))
    assert r.returncode != 0 and 'woven.attach the fabric as before the save' in r.stdout + r.stderr
    # The good pair still loads after all that.
    O.reset()
    e = scene.build()
    O.load(path)
    O.run(3, True)
    assert e.iter == 23


def test_scene_without_fabric_drops_a_stale_sidecar(tmp_path, yade_ns):
    O = yade_ns.O
    O.reset()
    O.engines = []
    path = str(tmp_path / 'plain.xml')
    open(path + '.woven', 'wb').write(b'old')
    O.save(path)
    assert os.path.exists(path) and not os.path.exists(path + '.woven')
    O.load(path)  # no woven adapter: nothing to restore, nothing refused
    O.reset()


# A projectile in the fabric at the save: the continued run's books (body work, contact, work,
# balance) are the straight run's only if what the adapter measures the host's kick from (the
# velocities the fabric left the body with) comes back with the state. The cube is still pressing
# into the ply at step 120; with breakage, elements have broken by then.
BALLISTIC = '''
import os, sys
import numpy as np
os.environ['WOVEN_NATIVE'] = '0'
import woven
from woven import ballistic
from yade.wrapper import Omega, ForceResetter, NewtonIntegrator
O = Omega()
breakage = sys.argv[1] == '1'
ply = ballistic.build_ply(dict(preset='km2_706', nx=4, ny=4, cp_per_span=2), {}, clamp=4,
                          breakage={'strain': 0.0} if breakage else None)
O.engines = [ForceResetter(), NewtonIntegrator(damping=0, gravity=(0, 0, 0))]
e = ply.engine
if sys.argv[5] == 'mesh':
    # A mesh projectile (the triangles of a cube's STL), a YADE Facet sheet close under the ply and a
    # Wall below it: the triangle form's held sides and supports must come back with the state.
    from yade import utils
    from woven import mesh
    v = np.array([[x, y, z] for x in (0, 2e-3) for y in (0, 2e-3) for z in (0, 2e-3)]) - 1e-3
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    path = os.path.join(os.path.dirname(sys.argv[3]), 'cube.stl')
    mesh.write_stl(path, v, [(q[0], q[1], q[2]) for q in quads] + [(q[0], q[2], q[3]) for q in quads])
    p = ballistic.add_projectile(ply, shape='mesh', mass=1.1e-3, V=300.0, solid=mesh.solid(path, mass=1.1e-3))
    X = woven.positions(e)
    lo, hi, z = X.min(axis=0) - 1e-3, X.max(axis=0) + 1e-3, X[:, 2].min() - ply.thickness - 2e-5
    c = [(lo[0], lo[1], z), (hi[0], lo[1], z), (hi[0], hi[1], z), (lo[0], hi[1], z)]
    sheet = [O.bodies.append(utils.facet([c[0], c[1], c[2]], fixed=True)),
             O.bodies.append(utils.facet([c[0], c[2], c[3]], fixed=True))]
    wall = O.bodies.append(utils.wall((0, 0, z - 3e-4), axis=2, sense=1))
    for i in sheet + [wall]:
        O.bodies[i].dynamic = False
    woven.coupling.couple(e, sheet + [wall])
else:
    p = ballistic.add_projectile(ply, shape='box', mass=1.1e-3, size=2e-3, V=300.0)
woven.attach(e, set_dt=True)
if sys.argv[2] == 'straight':
    O.run(120, True)
    O.save(sys.argv[3])
    O.run(120, True)
else:
    O.load(sys.argv[3])
    O.run(120, True)
b = O.bodies[p.id].state
open(sys.argv[4], 'w').write(repr((sorted(e.energy().items()), len(e.break_log()), e.iter,
                                   woven.positions(e).tobytes(), tuple(b.pos) + tuple(b.vel))))
'''


@pytest.mark.parametrize('breakage,bodies', [('0', 'box'), ('1', 'box'), ('1', 'mesh')])
def test_continued_run_keeps_every_energy_book(tmp_path, breakage, bodies):
    script = tmp_path / 'ballistic_ckp.py'
    script.write_text(BALLISTIC)
    ckp, a, b = str(tmp_path / 'run.yade.gz'), str(tmp_path / 'straight'), str(tmp_path / 'continued')
    for mode, out in (('straight', a), ('continued', b)):
        r = subprocess.run(['yade', '-n', '-x', str(script), breakage, mode, ckp, out, bodies], capture_output=True,
                           text=True, timeout=180, cwd=str(tmp_path))
        assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    straight, continued = eval(open(a).read()), eval(open(b).read())
    assert (straight[1] > 0) == (breakage == '1')
    assert dict(straight[0])['body_work'] > 0
    for (k, x), (_, y) in zip(straight[0], continued[0]):
        assert x == y, 'book %s: straight %r, continued %r' % (k, x, y)
    assert straight == continued


def test_snapshot_after_new_contact_settings_continues(yade_ns):
    """New contact settings between steps (woven.contact.enable again, or a native stage attribute set
    from YADE) drop the collision stage's memories; a snapshot taken then carries none of them, so
    the restored engine steps on as the one that took it, bit for bit (it carried the body contacts'
    measure memory, which the running engine had dropped)."""
    import woven
    from woven import _woven
    from yade import utils, Vector3
    O = yade_ns.O
    for change in (False, True):
        O.reset()
        w = woven.weave(nx=3, ny=3, cp_per_span=2)
        e = w.engine
        woven.contact.enable(e)
        for y in range(e.n_yarns):
            info = e.yarn(y)
            e.fix(info['first_node'])
            e.fix(info['first_node'] + info['n_nodes'] - 1)
        X = woven.positions(e)
        c, half = 0.5 * (X.min(axis=0) + X.max(axis=0)), 0.8e-3
        pid = O.bodies.append(utils.box(Vector3(c[0], c[1], X[:, 2].max() + half + 0.3e-3), Vector3(half, half, half)))
        O.bodies[pid].state.vel = Vector3(0, 0, -300)
        woven.coupling.couple(e, [pid])
        dt = 0.7 * e.dt_crit
        for _ in range(60):
            e.step(dt)
        assert e.collision_stats()['body_contacts'] > 0  # the box is in the ply: memories to drop
        if change:
            woven.contact.enable(e, friction=0.3)
        e2 = _woven._engine_from_snapshot(e._snapshot())
        for _ in range(120):
            e.step(dt), e2.step(dt)
        assert woven.positions(e).tobytes() == woven.positions(e2).tobytes(), change
        assert sorted(e.energy().items()) == sorted(e2.energy().items())
    O.reset()
