"""Reliability from Python: refused input changes nothing and does not crash later, state
files round-trip the books and refuse bad contents, writes report errors, queries move nothing,
absurd values and wrong types are refused naming the argument, nothing is attached or coupled twice."""
import math
import os
import subprocess
import sys

import pytest

from conftest import ROOT, run_refused


def chain(n=20, L=0.02):
    import woven
    from yade import Vector3
    f = woven.Fabric()
    f.add_yarn([Vector3(L * i / n, 0, 0) for i in range(n + 1)], woven.YarnMaterial(), woven.YarnSection())
    return woven.FabricEngine(f)


def run_child(code):
    """Runs `code` in a fresh interpreter (a crash must not take pytest down); returns (rc, output)."""
    env = dict(os.environ)
    r = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, timeout=120, env=env)
    return r.returncode, r.stdout + r.stderr


# --- defect 1 ---
def test_refused_add_yarn_then_step_does_not_crash():
    # The old code left the NaN yarn's nodes without an inverse mass: the step was a segfault.
    rc, out = run_child('''
import woven
from yade import Vector3
f = woven.Fabric()
f.add_yarn([Vector3(0, 0, 0), Vector3(1e-3, 0, 0)], woven.YarnMaterial(), woven.YarnSection())
try:
    f.add_yarn([Vector3(0, 1e-3, 0), Vector3(float('nan'), 1e-3, 0), Vector3(2e-3, 1e-3, 0)],
               woven.YarnMaterial(), woven.YarnSection())
except ValueError as e:
    assert 'points' in str(e), e
assert f.n_nodes == 2 and f.n_yarns == 1, (f.n_nodes, f.n_yarns)
e = woven.FabricEngine(f)
e.step(1e-9)
woven.contact.enable(e)
e.settle_sections()
print('survived')
''')
    assert rc == 0 and 'survived' in out, out


# --- defect 2 ---
def test_load_state_and_set_vel_keep_the_books_consistent(tmp_path):
    import woven
    from yade import Vector3
    a = chain()
    for i in range(21):
        a.set_vel(i, Vector3(0, 0.5 * math.sin(i), 0.3))
    dt = 0.8 * a.dt_crit
    a.run(dt, 40)
    path = str(tmp_path / 'a.state')
    a.save_state(path)
    b = chain()
    b.run(dt, 3)  # at rest: initial energy 0, the old load kept it
    b.load_state(path)
    assert b.energy() == a.energy()
    b.run(dt, 10)  # no false "energy blow-up"
    a.run(dt, 10)
    assert woven.positions(a).tobytes() == woven.positions(b).tobytes()
    # A push from rest by hand is a new initial energy, not an instability.
    c = chain()
    c.run(dt, 2)
    c.set_vel(10, Vector3(0, 50, 0))
    c.run(dt, 20)
    assert abs(c.energy()['balance_error']) < 1e-3 * c.energy()['initial']


# --- defect 3 ---
def test_bad_state_files_are_refused_and_change_nothing(tmp_path):
    import woven
    a = chain()
    a.run(0.5 * a.dt_crit, 5)
    path = str(tmp_path / 'a.state')
    a.save_state(path)
    good = open(path, 'rb').read()
    b = chain()
    b.run(0.5 * b.dt_crit, 9)
    before = woven.positions(b).tobytes(), b.iter
    for bad in (good + b'\0', good[:-3], good[:100] + bytes([good[100] ^ 4]) + good[101:], b''):
        open(path, 'wb').write(bad)
        with pytest.raises(ValueError, match='state'):
            b.load_state(path)
        assert (woven.positions(b).tobytes(), b.iter) == before
    other = chain(20, 0.021)  # another weave, the same node count
    other.save_state(path)
    with pytest.raises(ValueError, match='another weave'):
        b.load_state(path)
    assert (woven.positions(b).tobytes(), b.iter) == before
    with pytest.raises(ValueError, match='path'):
        b.load_state(str(tmp_path / 'missing.state'))


# --- defect 4 ---
def test_save_state_reports_errors_and_refuses_nul(tmp_path):
    e = chain()
    with pytest.raises(RuntimeError, match='/dev/full'):
        e.save_state('/dev/full')
    with pytest.raises(ValueError, match='path'):
        e.save_state(str(tmp_path / 'a.state') + '\0tail')
    assert os.listdir(str(tmp_path)) == []


# --- defect 5 ---
def test_overlap_queries_are_read_only():
    import woven
    from yade import Vector3

    def run(query):
        w = woven.weave(nx=2, ny=2, cp_per_span=2, damping=0.1)
        e = w.engine
        woven.contact.enable(e)
        e.settle_sections()
        for y in w.warp_yarns:
            info = e.yarn(y)
            e.fix(info['first_node'])
            e.prescribe_velocity(info['first_node'] + info['n_nodes'] - 1, Vector3(3, 0.4, 0.1))
        dt = 0.7 * e.dt_crit
        for k in range(40):
            e.step(dt)
            if query and k % 5 == 2:
                e.overlap()
        return woven.positions(e).tobytes(), woven.section_dirs(e).tobytes()

    assert run(True) == run(False)


# --- defect 6 ---
@pytest.mark.parametrize('key, value', [('rho', 1e-300), ('area', 1e300), ('E', 1e300), ('E', float('inf')),
                                        ('width', 1e300), ('spacing', 1e300), ('damping', float('nan'))])
def test_absurd_weave_values_name_the_key(key, value):
    import woven
    with pytest.raises(ValueError, match=key):
        woven.weave(**{key: value})


def test_absurd_loads_and_bodies_are_refused(yade_ns):
    import woven
    from yade import Vector3, Quaternion
    e = chain()
    for call, name in ((lambda: e.set_vel(1, Vector3(1e300, 0, 0)), 'velocity'),
                       (lambda: e.prescribe_velocity(1, Vector3(1e300, 0, 0)), 'velocity'),
                       (lambda: setattr(e, 'gravity', Vector3(0, 0, -1e300)), 'gravity'),
                       (lambda: e.set_pos(1, Vector3(1e300, 0, 0)), 'position')):
        with pytest.raises(ValueError, match=name):
            call()
    woven.contact.enable(e)
    I, far = Quaternion.Identity, Vector3(0, 0, 0.01)
    box = [('box', Vector3(1e-3, 1e-3, 1e-3), Vector3.Zero, I)]
    for kw, name in (({'inertia': Vector3(float('inf'), 1, 1)}, 'inertia'),
                     ({'ori': Quaternion(float('nan'), 0, 0, 0)}, 'orientation'),
                     ({'ori': Quaternion(2, 0, 0, 0)}, 'orientation'),
                     ({'vel': Vector3(0, 0, -1e300)}, 'velocity'),
                     ({'parts': [('box', Vector3(1e-3, 1e-3, 1e-3), Vector3.Zero, Quaternion(0.5, 0, 0, 0))]},
                      'part orientation')):
        args = dict(id=0, parts=box, mass=1e-3, inertia=Vector3(1e-9, 1e-9, 1e-9), pos=far, ori=I,
                    vel=Vector3.Zero, ang_vel=Vector3.Zero)
        args.update(kw)
        with pytest.raises(ValueError, match=name):
            e.add_body(**args)
    assert e.n_bodies == 0


# --- defect 8 ---
def test_wrong_types_name_the_argument():
    import woven
    from yade import Vector3
    e = chain()
    cases = [(lambda: woven.weave(E='abc'), 'E'), (lambda: woven.weave(nx=1.5), 'nx'),
             (lambda: woven.contact.enable(e, mcd='abc'), 'mcd'),
             (lambda: woven.contact.enable(e, max_iterations=2.5), 'max_iterations'),
             (lambda: woven.contact.enable(e, section_rule=3), 'section_rule'),
             (lambda: e.pos(2 ** 31), 'node'), (lambda: e.pos('a'), 'node'), (lambda: e.step('x'), 'dt'),
             (lambda: e.set_vel(0, [1, 2]), 'velocity'), (lambda: setattr(e, 'blowup_factor', 'x'), 'blowup_factor'),
             (lambda: e.enable_breakage(seed=2 ** 70), 'seed'), (lambda: e.enable_collisions(foo=1), 'foo'),
             (lambda: woven.peirce_from_height(float('inf'), 1e-4, 2e-4), 'p'),
             (lambda: woven.peirce_from_crimp(7e-4, 0.01, float('nan')), 'D'),
             (lambda: woven.theory.smith(float('nan'), 90e9, 1440), 'V'),
             (lambda: woven.theory.smith(200, 90e9, 0), 'rho'),
             (lambda: woven.theory.areal_density_plain(1e-4, 0, 0.01, 1e-4, 7e-4, 0.01), 'spacing_warp'),
             (lambda: woven.theory.smith_critical_velocity(float('inf'), 90e9, 1440), 'failure_strain'),
             (lambda: woven.theory.lambert_jonas([100, float('nan')], 90, 1, 2), 'V')]
    for call, name in cases:
        with pytest.raises(ValueError) as err:
            call()
        assert name in str(err.value), (name, str(err.value))


# --- defect 9 ---
def test_nothing_is_attached_or_coupled_twice_and_patterns_are_exact(yade_ns):
    import woven
    from yade import utils
    O = yade_ns.O
    O.reset()
    O.engines = []
    e = chain()
    woven.attach(e)
    with pytest.raises(ValueError, match='engine'):
        woven.attach(e)
    assert len(O.engines) == 1
    O.run(3, True)
    assert e.iter == 3  # one step per iteration
    woven.contact.enable(e)
    pid = O.bodies.append(utils.sphere((0.01, 0, 0.01), 1e-3))
    woven.coupling.couple(e, [pid])
    with pytest.raises(ValueError, match='body id'):
        woven.coupling.couple(e, [pid])
    with pytest.raises(ValueError, match='id'):  # the C++ side refuses it too
        e.add_body(pid, [('sphere', 1e-3, yade_ns.Vector3.Zero, yade_ns.Quaternion.Identity)], 1e-3,
                   yade_ns.Vector3(1e-9, 1e-9, 1e-9), yade_ns.Vector3(0.01, 0, 0.01), yade_ns.Quaternion.Identity,
                   yade_ns.Vector3.Zero, yade_ns.Vector3.Zero)
    assert e.n_bodies == 1
    for pat in ([[1, 0], [0, 1.7]], '1,0;0,1.7', [[1, 0], [0, 0.5]]):
        with pytest.raises(ValueError, match='pattern'):
            woven.weave(pattern=pat)
    O.reset()


# --- defect 7 ---
@pytest.mark.parametrize('script, args, key', [('smith.py', ['elements=16', 'levels=1'], 'elements'),
                                               ('smith.py', ['elements=1e300'], 'elements'),
                                               ('ballistic.py', ['side=10'], 'side'),
                                               ('weave.py', ['nx=100000', 'ny=100000'], 'nx')])
def test_oversized_scenes_are_refused_up_front(script_server, tmp_path, script, args, key):
    rc, log, _ = run_refused(script_server, script, tmp_path, *args, timeout=120)
    assert rc != 0
    last = [l for l in log.splitlines() if 'Error' in l][-1]
    assert 'ValueError: %s = ' % key in last and 'allowed' in last and 'MemoryError' not in log, last


# --- what an outside fuzz found accepted ---
def test_a_bool_is_no_step_size(yade_ns):
    import woven
    from yade import Vector3, Matrix3
    e = chain()
    I = Matrix3.Identity
    # True read as 1 s: refused naming the argument, for methods, functions, setters and keys alike
    for call, name in [(lambda: e.step(True), 'dt'), (lambda: e.run(dt=False, steps=2), 'dt'),
                       (lambda: woven.obb_first_contact(Vector3(0, 0, 0), I, Vector3(1, 1, 1), Vector3(0, 0, 0),
                                                        Vector3(3, 0, 0), I, Vector3(1, 1, 1), Vector3(-1, 0, 0), True), 'dt'),
                       (lambda: setattr(e, 'velocity_ramp', True), 'velocity_ramp'),
                       (lambda: e.set_vel(1, [True, 0.0, 0.0]), 'velocity'),
                       (lambda: woven.contact.penalty_dt_limit(1e-6, True), 'k')]:
        with pytest.raises(ValueError, match=r'%s = .*(True|False).* is invalid' % name):
            call()
    assert e.iter == 0 and e.velocity_ramp == 0
    e.step(0.5 * e.dt_crit)  # a real number still works
    assert e.iter == 1


def test_single_pair_helpers_refuse_absurd_steps_and_sizes(yade_ns):
    import woven
    from yade import Vector3, Matrix3
    I = Matrix3.Identity
    a, b = Vector3(0, 0, 0), Vector3(3, 0, 0)
    one = Vector3(1, 1, 1)
    for dt in (1e300, 2.0, -1e-9, float('inf')):
        with pytest.raises(ValueError, match=r'dt = .* is invalid: allowed \[0, 1\] s'):
            woven.obb_first_contact(a, I, one, Vector3(0, 0, 0), b, I, one, Vector3(-1, 0, 0), dt)
    with pytest.raises(ValueError, match=r'velocity_b = .* is invalid: allowed \|v\| <= 1e5 m/s'):
        woven.obb_first_contact(a, I, one, Vector3(0, 0, 0), b, I, one, Vector3(-2e5, 0, 0), 1e-6)
    with pytest.raises(ValueError, match=r'centre = .* is invalid: allowed coordinates within \+-1e3 m'):
        woven.obb_contact(Vector3(1e300, 0, 0), I, one, b, I, one)
    with pytest.raises(ValueError, match=r'extents = .* is invalid: allowed \[0, 1e3\] m'):
        woven.obb_contact(a, I, Vector3(1e300, 1, 1), b, I, one)
    # the largest step allowed: 1 s at 1 m/s closes the 1 m gap at 1 s, exactly
    s = woven.obb_first_contact(a, I, one, Vector3(0, 0, 0), b, I, one, Vector3(-1, 0, 0), 1.0)
    assert s['hit'] and s['time'] == pytest.approx(1.0, abs=1e-12)


def test_a_body_inside_the_fabric_is_refused_naming_it(yade_ns):
    import numpy as np
    import woven
    from yade import Vector3, Quaternion
    w = woven.weave(nx=2, ny=2, cp_per_span=2)
    e = w.engine
    woven.contact.enable(e)
    e.settle_sections()
    X = woven.positions(e)
    c = X[np.argmin(np.linalg.norm(X - X.mean(axis=0), axis=1))]
    box = [('box', Vector3(5e-4, 5e-4, 5e-4), Vector3.Zero, Quaternion.Identity)]
    args = (1e-3, Vector3(1e-9, 1e-9, 1e-9))
    inside = Vector3(*map(float, c))
    with pytest.raises(ValueError, match=r'body = id 7 at .* is invalid: allowed a body clear of every yarn \(it starts '
                                         r'inside the fabric: overlap [0-9.e-]+ m\)'):
        e.add_body(7, box, *args, inside, Quaternion.Identity, Vector3.Zero, Vector3.Zero)
    assert e.n_bodies == 0  # nothing added
    above = Vector3(inside[0], inside[1], float(X[:, 2].max()) + 1.5e-3)
    k = e.add_body(7, box, *args, above, Quaternion.Identity, Vector3.Zero, Vector3.Zero)
    with pytest.raises(ValueError, match=r'pos = .* of body 0 \(id 7\) is invalid: allowed a pose no deeper'):
        e.set_body_state(k, inside, Quaternion.Identity, Vector3.Zero, Vector3.Zero)
    assert e.body(k)['pos'] == above  # unchanged
    e.set_body_state(k, above + Vector3(0, 0, 1e-3), Quaternion.Identity, Vector3.Zero, Vector3.Zero)  # away: fine


@pytest.mark.parametrize('which', ['/dev/zero', '/dev/urandom', 'folder', 'text', 'empty'])
def test_a_state_path_that_is_no_state_is_refused_naming_it(tmp_path, which):
    e = chain()
    path = {'folder': str(tmp_path), 'text': str(tmp_path / 'notes.txt'), 'empty': str(tmp_path / 'empty.state')}.get(which, which)
    if which == 'text':
        open(path, 'w').write('not a state\n' * 1000)
    elif which == 'empty':
        open(path, 'w').close()
    # /dev/zero was read until memory ran out: MemoryError with no message
    with pytest.raises(ValueError, match=r"path = '%s' is invalid: allowed .*not a woven state" % path):
        e.load_state(path)
    assert e.iter == 0
