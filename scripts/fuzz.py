# Fuzz test of woven's public Python API and of the scene keys.
#   yade -n -x scripts/fuzz.py [cases=2000] [seed=1] [timeout=30] [scene_every=50] [out=DIR]
# Generates `cases` cases from `seed` (the same seed, the same cases): weave keys, contact keys,
# FabricEngine methods and properties (indices, vectors, steps, loads, breakage, bodies, state files
# with mutated bytes), Fabric.add_yarn, patterns, Peirce and theory functions, and every
# `scene_every`-th case a scene script run with one mutated key. Values are valid ones, boundaries
# and absurd ones (NaN, inf, 1e300, 1e-300, negative, strings, None, lists, 2^31, 2^70, 1.7 for an
# integer). Each API case runs in a worker process; a worker that dies (a crash: a signal) or does
# not answer within `timeout` s (a hang) is counted against its case and restarted for the next one,
# so a crash is counted, not fatal.
# Each case ends as: a clean error (ValueError / RuntimeError / woven.InstabilityError; whether its
# message names a mutated key is counted), an unclean error (any other exception type: TypeError,
# ZeroDivisionError, MemoryError, ...), accepted (then every number the case produced, and the engine's
# positions, velocities and energy books after a few steps, must be finite: else a silent non-finite
# state), a crash or a hang. Cases of the classes an earlier fuzz found accepted know they must be
# refused (`must_refuse`): a bool for a real argument (a step size), a step outside [0, 1] s or
# velocities past 1e5 m/s in the single-pair contact helpers (obb_first_contact), a body added, coupled
# or moved into the fabric, a state path that is a device, a folder or another file (/dev/zero
# read until memory ran out); accepted, they count as wrongly accepted, a failure; refused, their
# error must name the argument (counted with the others).
# Output: out/fuzz/summary.json (counts, the failing cases with their descriptions), cases.csv.
import json
import math
import os
import random
import select
import subprocess
import sys
import time

# The worker gets its settings from the environment: importing yade parses sys.argv.
WORKER = os.environ.get('WOVEN_FUZZ_WORKER', '')
# Under `yade -x`, __file__ is YADE's launcher; the script is sys.argv[0].
SCRIPT = os.path.abspath(sys.argv[0] if sys.argv and sys.argv[0].endswith('.py') else __file__)

ABSURD = [float('nan'), float('inf'), -float('inf'), 0, -1, 1e300, -1e300, 1e-300, 'abc', '', None, [1, 2],
          2 ** 31, 2 ** 63, 2 ** 70, 1.7, True, b'x', -0.0]


def mutate(rng, valid):
    """A valid value (40 %), a scaled one (20 %) or an absurd one (40 %)."""
    r = rng.random()
    if r < 0.4:
        return valid
    if r < 0.6 and isinstance(valid, (int, float)) and not isinstance(valid, bool):
        return type(valid)(valid * rng.choice([1e6, 1e-6, -1, 10, 0.1])) if isinstance(valid, float) else \
            int(valid * rng.choice([1000, -1, 10, 0]))
    return rng.choice(ABSURD)


# ---------------------------------------------------------------------------------------------
# Cases: case(i) -> (kind, description dict). Both the worker and the parent derive it from seed, i.
# ---------------------------------------------------------------------------------------------
WEAVE_VALID = {'pattern': 'plain', 'twill_over': 2, 'twill_under': 1, 'satin_n': 5, 'satin_step': 2, 'basket_n': 2,
               'nx': 1, 'ny': 1, 'spacing': 0.8e-3, 'warp_spacing': 0.8e-3, 'weft_spacing': 0.8e-3, 'width': 0.6e-3,
               'thickness': 0.1e-3, 'E': 90e9, 'rho': 1440.0, 'area': 4.6e-8, 'linear_density': 6.7e-5,
               'damping': 0.1, 'failure_strain': 0.05, 'tension_only': 1, 'crimp': 0.01, 'warp_crimp': -1.0,
               'weft_crimp': -1.0, 'cp_per_span': 2, 'fine_radius': 1e-3, 'cp_coarse': 1, 'fine_x': 0.0, 'fine_y': 0.0,
               'preset': 'km2_706'}
PATTERNS = ['plain', 'twill', 'satin', 'basket', '1,0;0,1', '1,0;0,1.7', [[1, 0], [0, 1]], [[1, 0], [0, 2]], [[1]],
            [], '1,0;1', 'weird', [[1, 0, 1], [0, 1, 0]]]
CONTACT_VALID = {'restitution': 0.0, 'friction': 0.1, 'mcd': 0.6, 'section_rule': 'constant_area', 'margin': 1e-6,
                 'tolerance': 1e-6, 'max_iterations': 20, 'flatten_passes': 2, 'position_correction': 0.2,
                 'correction_slop': 0.5e-6, 'self_exclude': 1, 'broad_phase': 'grid', 'skin': 5e-6, 'threads': 1,
                 'contact_cache': 1e-7, 'response': 'impulse', 'penalty_stiffness': 1e5, 'penalty_damping': 0.1,
                 'flattening': 'geometric', 'section_stiffness': 1e4, 'yarn_contacts': True}
STRINGS = {'section_rule': ['constant_area', 'paper', 'bogus'], 'broad_phase': ['tree', 'grid', 'sap', 'x'],
           'response': ['impulse', 'penalty', 'x'], 'flattening': ['geometric', 'none', 'springs', 'x']}
V3 = 'vec'
# method: [(argument, valid value)]; V3 arguments get 3-vectors (valid: small ones)
METHODS = {
    'pos': [('node', 3)], 'vel': [('node', 3)], 'mass': [('node', 3)], 'set_pos': [('node', 3), ('position', V3)],
    'set_vel': [('node', 3), ('velocity', V3)], 'element_nodes': [('element', 2)], 'yarn': [('yarn', 0)],
    'fix': [('node', 0)], 'prescribe_velocity': [('node', 1), ('velocity', V3)], 'release': [('node', 0)],
    'is_kinematic': [('node', 0)], 'set_point_force': [('node', 2), ('force', V3)], 'reaction': [('nodes', [0, 1])],
    'step': [('dt', 'dt')], 'run': [('dt', 'dt'), ('steps', 3)],
    'enable_breakage': [('strain', 0.05), ('filter_length', -4.0), ('weibull_m', 5.0), ('seed', 3)],
    'enable_collisions': [('mcd', 0.6), ('restitution', 0.2), ('broad_phase', 'grid')],
    'settle_sections': [('max_passes', 10)], 'overlap': [], 'save_state': [('path', 'PATH'), ('last_good', False)],
    'load_state': [('path', 'STATEFILE')], 'restore_last_good': [], 'energy': [],
    'add_body': [('id', 0), ('parts', 'PARTS'), ('mass', 1e-3), ('inertia', V3), ('pos', 'BODYPOS'), ('ori', 'QUAT'),
                 ('vel', V3), ('ang_vel', V3)],
    'set_body_state': [('index', 0), ('pos', 'BODYPOS'), ('ori', 'QUAT'), ('vel', V3), ('ang_vel', V3)],
    'body': [('index', 0)], 'body_overlap': [('index', 0)],
}
PROPERTIES = {'blowup_factor': 3.0, 'checkpoint_interval': 100, 'gravity': V3, 'velocity_ramp': 1e-6}
FUNCTIONS = {
    'peirce_from_height': [('p', 0.75e-3), ('h', 1e-4), ('D', 2.2e-4)],
    'peirce_from_crimp': [('p', 0.75e-3), ('crimp', 0.01), ('D', 2.2e-4)],
    'theory.smith': [('V', 200.0), ('E', 90e9), ('rho', 1440.0)],
    'theory.smith_critical_velocity': [('failure_strain', 0.05), ('E', 90e9), ('rho', 1440.0)],
    'theory.areal_density_plain': [('linear_density_warp', 6.7e-5), ('spacing_warp', 7.5e-4), ('crimp_warp', 0.01),
                                   ('linear_density_weft', 6.7e-5), ('spacing_weft', 7.5e-4), ('crimp_weft', 0.01)],
    'theory.lambert_jonas': [('V', [100.0, 200.0]), ('V_bl', 90.0), ('a', 0.9), ('p', 2.0)],
    'theory.fit_lambert_jonas': [('V', [80.0, 120.0, 160.0, 200.0]), ('vr', [0.0, 60.0, 120.0, 170.0])],
    'set_threads': [('n', 1)], 'penalty_dt_limit': [('m', 1e-6), ('k', 1e5)],
}
# Scene runs: a short valid base and one mutated key (the base keeps each run to seconds). The base
# must pass on its own (tests/python/test_fuzz.py checks): smith.py's duration 0.2 left fewer than 4 nodes on
# the transverse front at 800 elements, so every smith case was refused for the base, not its key.
SCENES = {
    'weave.py': ({'nx': 2, 'ny': 2, 'picture': 0}, ['nx', 'ny', 'cp_per_span', 'E', 'rho', 'spacing', 'pattern',
                                                       'crimp', 'picture', 'colour']),
    'smith.py': ({'elements': 800, 'levels': 1, 'duration': 0.6}, ['V', 'E', 'rho', 'length', 'elements', 'levels',
                                                                    'duration', 'safety', 'strain_tol', 'colour']),
    'ballistic.py': ({'side': 4e-3, 't_end': 2e-6, 'vtk_every': -1, 'progress': 0}, [
        'V', 'mass', 'size', 'side', 'clamp', 't_end', 'shape', 'break_strain', 'weibull_m', 'seed', 'mcd', 'safety',
        'samples', 'colour']),
    'tension.py': ({'nx': 1, 'ny': 1, 'strain_end': 0.001, 'samples': 20}, [
        'mode', 'velocity', 'strain_end', 'ramp', 'safety', 'samples', 'nx', 'mcd', 'colour']),
}
SCENE_TEXT = ['nan', 'inf', '-1', '0', '1e300', '1e-300', 'abc', '', '1.7', '2147483648', '1e20']
HELPER_DT = [0.1, 0.0, 1.0, 1e-9, True, False, 1e300, -1e-3, 2.0, float('nan'), float('inf')]


def _small_real(x, limit):
    """x is a real number (not a bool) of magnitude at most limit."""
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and abs(x) <= limit


def case(seed, i, scene_every):
    """(kind, spec) of case i: deterministic in (seed, i)."""
    rng = random.Random(seed * 1000003 + i)
    if scene_every > 0 and i % scene_every == scene_every - 1:
        script = rng.choice(sorted(SCENES))
        base, keys = SCENES[script]
        key = rng.choice(keys)
        return 'scene', {'script': script, 'base': base, 'key': key, 'value': rng.choice(SCENE_TEXT)}
    kind = rng.choices(['weave', 'contact', 'method', 'property', 'function', 'add_yarn', 'state', 'helper', 'body',
                        'state_path'], [20, 15, 30, 6, 12, 7, 10, 6, 6, 3])[0]
    if kind == 'helper':
        # the single-pair helpers: a step in [0, 1] s and velocities up to 1e5 m/s, else refused
        dt = rng.choice(HELPER_DT)
        va = [mutate(rng, x) for x in (0.0, 0.0, 0.0)]
        vb = [mutate(rng, x) for x in (-1.0, 0.0, 0.0)]
        first = rng.random() < 0.7
        extent = mutate(rng, 1.0)
        bad_dt = first and not (isinstance(dt, float) and 0 <= dt <= 1)
        # a velocity past 1e5 m/s (the velocities' range): refused; |v| of three components within it
        bad_v = first and not (all(_small_real(x, 1e5) for x in va + vb) and
                               max(math.sqrt(sum(x * x for x in v)) for v in (va, vb)) <= 1e5)
        bad_ext = not (_small_real(extent, 1e3) and extent >= 0)
        return kind, {'first': first, 'dt': dt, 'va': va, 'vb': vb, 'extent': extent,
                      'must_refuse': bad_dt or bad_v or bad_ext,
                      'mutated': ['dt', 'velocity_a', 'velocity_b', 'extents', 'centre']}
    if kind == 'body':
        # a body clear of the fabric (accepted) or inside it (refused, naming the body), added through
        # add_body, woven.coupling.couple or moved there by set_body_state
        how = rng.choice(['add_body', 'couple', 'set_body_state'])
        inside = rng.random() < 0.5
        shape = rng.choice(['box', 'sphere'])
        return kind, {'how': how, 'inside': inside, 'shape': shape, 'size': rng.choice([2e-4, 1e-3, 5e-3]),
                      'must_refuse': inside, 'mutated': ['body', 'pos']}
    if kind == 'state_path':
        # what load_state is pointed at: no file of woven's, never read whole
        return kind, {'path': rng.choice(['/dev/zero', '/dev/urandom', 'FOLDER', 'TEXT', 'EMPTY', 'MISSING']),
                      'must_refuse': True, 'mutated': ['path']}
    if kind == 'weave':
        keys = rng.sample(sorted(WEAVE_VALID), rng.randint(1, 3))
        kw = {}
        for k in keys:
            kw[k] = rng.choice(PATTERNS) if k == 'pattern' else mutate(rng, WEAVE_VALID[k])
        return kind, {'kw': kw, 'mutated': keys}
    if kind == 'contact':
        keys = rng.sample(sorted(CONTACT_VALID), rng.randint(1, 3))
        kw = {}
        for k in keys:
            kw[k] = rng.choice(STRINGS[k] + ABSURD[:3]) if k in STRINGS else mutate(rng, CONTACT_VALID[k])
        if rng.random() < 0.1:
            kw['no_such_key'] = 1
            keys = keys + ['no_such_key']
        return kind, {'kw': kw, 'mutated': keys}
    if kind == 'method':
        calls = []
        for _ in range(rng.randint(1, 3)):
            name = rng.choice(sorted(METHODS))
            args = [(a, mutate(rng, v) if not isinstance(v, str) or v not in (V3, 'dt', 'PATH', 'STATEFILE', 'PARTS', 'BODYPOS', 'QUAT') else
                     (v if rng.random() < 0.5 else rng.choice(ABSURD))) for a, v in METHODS[name]]
            vecs = [[mutate(rng, rng.choice([0.0, 0.5, -2.0])) for _ in range(3)] for _ in args]
            calls.append({'name': name, 'args': args, 'vecs': vecs, 'collisions': rng.random() < 0.5})
        # a bool where the signature takes a real number (a step size dt, a strain, a mass...): refused
        must = any(isinstance(v, bool) and (valid == 'dt' or (isinstance(valid, float)))
                   for c in calls for (a, v), (_, valid) in zip(c['args'], METHODS[c['name']]))
        # collisions on or off is part of the input: "collisions = off is invalid" names it
        return kind, {'calls': calls, 'must_refuse': must,
                      'mutated': [a for c in calls for a, _ in c['args']] + [c['name'] for c in calls] + ['collisions']}
    if kind == 'property':
        name = rng.choice(sorted(PROPERTIES))
        v = PROPERTIES[name]
        val = [mutate(rng, 0.0) for _ in range(3)] if v == V3 else mutate(rng, v)
        return kind, {'name': name, 'value': val, 'vector': v == V3, 'mutated': [name]}
    if kind == 'function':
        name = rng.choice(sorted(FUNCTIONS))
        args = [(a, mutate(rng, v) if not isinstance(v, list) else (v if rng.random() < 0.5 else
                                                                   [mutate(rng, x) for x in v]))
                for a, v in FUNCTIONS[name]]
        return kind, {'name': name, 'args': args, 'mutated': [a for a, _ in args]}
    if kind == 'add_yarn':
        n = rng.randint(0, 5)
        pts = [[mutate(rng, 1e-3 * k) if c == 0 else mutate(rng, 0.0) for c in range(3)] for k in range(n)]
        mat = {k: mutate(rng, v) for k, v in (('E', 90e9), ('rho', 1440.0), ('area', 4.6e-8), ('damping', 0.0),
                                                ('failure_strain', 0.05))}
        sec = {k: mutate(rng, v) for k, v in (('width', 0.6e-3), ('thickness', 0.1e-3))}
        return kind, {'points': pts, 'material': mat, 'section': sec,
                      'mutated': ['points', 'material', 'section', 'E', 'rho', 'area', 'damping', 'failure_strain',
                                  'width', 'thickness']}
    # state: a saved state with a few bytes changed, cut or appended
    ops = [(rng.choice(['flip', 'cut', 'append', 'set']), rng.random(), rng.randint(0, 255)) for _ in range(rng.randint(1, 3))]
    return 'state', {'ops': ops, 'mutated': ['state', 'path']}


# ---------------------------------------------------------------------------------------------
# Worker: runs cases it reads from stdin, one JSON line per case on stdout.
# ---------------------------------------------------------------------------------------------
def worker_main(seed, scene_every, tmpdir):
    import numpy as np
    import woven
    from yade import Vector3, Quaternion, Matrix3

    def small_engine(collisions=False):
        w = woven.weave(nx=1, ny=1, cp_per_span=2)
        e = w.engine
        if collisions:
            woven.contact.enable(e, broad_phase='grid')
            e.settle_sections()
        return e

    def vec(v):
        return Vector3(*v) if isinstance(v, list) and len(v) == 3 and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v) else v

    numbers = []

    def note(x):
        """Collects every float a case returns (nested), for the non-finite check."""
        if isinstance(x, bool) or x is None:
            return
        if isinstance(x, (int, float)):
            numbers.append(float(x))
        elif isinstance(x, dict):
            for v in x.values():
                note(v)
        elif isinstance(x, (list, tuple)):
            for v in x:
                note(v)
        elif hasattr(x, '__len__') and type(x).__name__ in ('Vector3', 'Quaternion'):
            numbers.extend(float(x[k]) for k in range(len(x)))
        elif isinstance(x, np.ndarray):
            numbers.extend(np.asarray(x, dtype=float).ravel().tolist())

    def engine_finite(e, steps=5):
        """After a few stable steps: positions, velocities, energy books finite. Errors in these
        steps are part of the case (raised)."""
        if e.n_nodes == 0:
            return True
        dt = 0.5 * e.dt_crit
        if math.isfinite(dt) and dt > 0:
            e.run(dt, steps)
        ok = bool(np.all(np.isfinite(woven.positions(e))) and np.all(np.isfinite(woven.velocities(e))))
        return ok and all(math.isfinite(v) for v in e.energy().values())

    state_bytes = {}

    def good_state():
        if 'b' not in state_bytes:
            e = small_engine()
            e.enable_breakage(strain=0.05)
            e.set_vel(3, Vector3(0, 0, 1.0))
            e.run(0.5 * e.dt_crit, 7)
            p = os.path.join(tmpdir, 'good.state')
            e.save_state(p)
            state_bytes['b'] = open(p, 'rb').read()
        return state_bytes['b']

    def run_case(kind, spec):
        finite = True
        if kind == 'weave':
            w = woven.weave(**spec['kw'])
            note(w.summary)
            if w.engine.n_nodes <= 20000:
                finite = engine_finite(w.engine)
        elif kind == 'contact':
            e = small_engine()
            woven.contact.enable(e, **spec['kw'])
            note(e.settle_sections())
            finite = engine_finite(e)
        elif kind == 'method':
            e = None
            for c in spec['calls']:
                if e is None:
                    e = small_engine(c['collisions'])
                args = []
                for (a, v), vv in zip(c['args'], c['vecs']):
                    if v == V3:
                        v = vec(vv)
                    elif v == 'dt':
                        v = 0.5 * e.dt_crit
                    elif v == 'PATH':
                        v = os.path.join(tmpdir, 'saved.state')
                    elif v == 'STATEFILE':
                        v = os.path.join(tmpdir, 'good.state')
                        open(v, 'wb').write(good_state())
                    elif v == 'PARTS':
                        v = [('box', Vector3(1e-3, 1e-3, 1e-3), Vector3.Zero, Quaternion.Identity)]
                    elif v == 'BODYPOS':
                        v = Vector3(0, 0, 5e-3)
                    elif v == 'QUAT':
                        v = Quaternion.Identity
                    elif isinstance(v, list) and a in ('position', 'velocity', 'force', 'inertia', 'vel', 'ang_vel', 'pos'):
                        v = vec(v)
                    args.append(v)
                # by keyword: the names are the bindings' (a positional mix-up would be the fuzz's error)
                note(getattr(e, c['name'])(**{a: v for (a, _), v in zip(c['args'], args)}))
            finite = engine_finite(e)
        elif kind == 'property':
            e = small_engine()
            v = vec(spec['value']) if spec['vector'] else spec['value']
            setattr(e, spec['name'], v)
            note(getattr(e, spec['name']))
            finite = engine_finite(e)
        elif kind == 'function':
            name = spec['name']
            fn = getattr(woven.theory, name.split('.')[1]) if name.startswith('theory.') else \
                getattr(woven.contact, name) if name == 'penalty_dt_limit' else getattr(woven, name)
            r = fn(*[v for _, v in spec['args']])
            if name == 'set_threads':
                woven.set_threads(0)
            if type(r).__name__ == 'PeirceState':
                r = [r.p, r.h, r.D, r.theta, r.l, r.crimp]
            note(r)
        elif kind == 'add_yarn':
            f = woven.Fabric()
            m, s = woven.YarnMaterial(), woven.YarnSection()
            for k, v in spec['material'].items():
                setattr(m, k, v)
            for k, v in spec['section'].items():
                setattr(s, k, v)
            f.add_yarn([vec(p) for p in spec['points']], m, s)
            e = woven.FabricEngine(f)
            note(e.dt_crit)
            finite = engine_finite(e)
        elif kind == 'helper':
            I = Matrix3.Identity
            ext = vec([spec['extent']] * 3) if isinstance(spec['extent'], (int, float)) else spec['extent']
            if spec['first']:
                r = woven.obb_first_contact(Vector3(0, 0, 0), I, Vector3(1, 1, 1), vec(spec['va']),
                                            Vector3(3, 0, 0), I, ext, vec(spec['vb']), spec['dt'])
            else:
                r = woven.obb_contact(Vector3(0, 0, 0), I, Vector3(1, 1, 1), Vector3(3, 0, 0), I, ext)
            note({k: v for k, v in r.items() if k != 'contact'})
        elif kind == 'body':
            from yade import utils, O
            e = small_engine(True)
            X = woven.positions(e)
            c = X[np.argmin(np.linalg.norm(X - X.mean(axis=0), axis=1))]  # a yarn node near the middle
            top = X[:, 2].max()
            r = spec['size']
            # inside: centred on that node; clear: its lowest point 1 mm above the top yarn
            z = float(c[2]) if spec['inside'] else float(top) + r + 1e-3
            pos = Vector3(float(c[0]), float(c[1]), z)
            part = ('box', Vector3(r, r, r), Vector3.Zero, Quaternion.Identity) if spec['shape'] == 'box' else \
                ('sphere', r, Vector3.Zero, Quaternion.Identity)
            if spec['how'] == 'couple':
                O.reset()
                b = utils.box(tuple(pos), (r, r, r)) if spec['shape'] == 'box' else utils.sphere(tuple(pos), r)
                woven.coupling.couple(e, [O.bodies.append(b)])
            elif spec['how'] == 'add_body':
                e.add_body(0, [part], 1e-3, Vector3(1e-9, 1e-9, 1e-9), pos, Quaternion.Identity, Vector3.Zero, Vector3.Zero)
            else:
                above = Vector3(pos[0], pos[1], float(top) + r + 1e-3)
                k = e.add_body(0, [part], 1e-3, Vector3(1e-9, 1e-9, 1e-9), above, Quaternion.Identity, Vector3.Zero,
                               Vector3.Zero)
                e.set_body_state(k, pos, Quaternion.Identity, Vector3.Zero, Vector3.Zero)
            finite = engine_finite(e)
        elif kind == 'state_path':
            path = spec['path']
            if path == 'FOLDER':
                path = tmpdir
            elif path in ('TEXT', 'EMPTY'):
                p = os.path.join(tmpdir, 'not_a_state.txt')  # a scratch input of the case, as the states above
                open(p, 'w').write('' if spec['path'] == 'EMPTY' else 'hello, this is no woven state\n' * 100)
                path = p
            elif path == 'MISSING':
                path = os.path.join(tmpdir, 'no', 'such.state')
            e = small_engine()
            e.load_state(path)
            finite = engine_finite(e)
        elif kind == 'state':
            b = bytearray(good_state())
            for op, where, byte in spec['ops']:
                k = int(where * max(len(b) - 1, 0))
                if op == 'flip' and b:
                    b[k] ^= 1 << (byte % 8)
                elif op == 'cut':
                    del b[k:]
                elif op == 'append':
                    b += bytes([byte]) * (1 + byte % 9)
                elif op == 'set' and b:
                    b[k] = byte
            p = os.path.join(tmpdir, 'mutated.state')
            open(p, 'wb').write(bytes(b))
            e = small_engine()
            e.load_state(p)
            finite = engine_finite(e)
        return finite

    for line in sys.stdin:
        i = int(line)
        kind, spec = case(seed, i, scene_every)
        sys.stdout.write(json.dumps({'start': i}) + '\n')
        sys.stdout.flush()
        numbers.clear()
        res = {'case': i, 'kind': kind}
        try:
            finite = run_case(kind, spec)
            finite = finite and all(math.isfinite(x) for x in numbers)
            res['outcome'] = 'accepted' if finite else 'nonfinite'
            if spec.get('must_refuse'):
                res['outcome'] = 'wrongly_accepted'
        except (ValueError, RuntimeError) as ex:  # woven.InstabilityError is a RuntimeError
            msg = str(ex)
            res['outcome'] = 'error'
            res['names_key'] = any(str(k) in msg for k in spec.get('mutated', []))
            res['message'] = msg[:300]
            res['type'] = type(ex).__name__
        except Exception as ex:  # noqa: BLE001 - what is left is what the fuzz is for
            res['outcome'] = 'unclean'
            res['message'] = ('%s: %s' % (type(ex).__name__, ex))[:300]
        sys.stdout.write(json.dumps(res) + '\n')
        sys.stdout.flush()


# ---------------------------------------------------------------------------------------------
# Parent: hands out cases, restarts the worker after a crash or a hang, runs the scene cases.
# ---------------------------------------------------------------------------------------------
def describe(kind, spec):
    return json.dumps({'kind': kind, **spec}, default=repr)[:600]


class Worker:
    def __init__(self, seed, scene_every, tmpdir):
        py = sys.executable if sys.executable and os.path.basename(sys.executable).startswith('python') else '/usr/bin/python3'
        env = dict(os.environ, OMP_NUM_THREADS='1', OMP_WAIT_POLICY='passive',
                   WOVEN_FUZZ_WORKER='%d,%d,%s' % (seed, scene_every, tmpdir))
        self.p = subprocess.Popen([py, '-u', SCRIPT],
                                  stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=open(os.path.join(tmpdir, "worker.log"), "ab"),
                                  text=True, bufsize=1, env=env, cwd=tmpdir)  # relative paths land in tmpdir
        self.fd, self.buf = self.p.stdout.fileno(), b''

    def ask(self, i, timeout):
        """('done', result) | ('crash', returncode) | ('hang', None)."""
        try:
            self.p.stdin.write('%d\n' % i)
            self.p.stdin.flush()
        except BrokenPipeError:
            return 'crash', self.p.wait()
        deadline = time.time() + timeout
        while True:
            # Lines are split from raw reads: select() does not see what a buffered reader holds.
            while b'\n' in self.buf:
                line, self.buf = self.buf.split(b'\n', 1)
                if not line.startswith(b'{'):  # YADE's banner ("Using python version ...") and other prints
                    continue
                msg = json.loads(line.decode())
                if 'start' not in msg:
                    return 'done', msg
            left = deadline - time.time()
            if left <= 0:
                self.kill()
                return 'hang', None
            ready, _, _ = select.select([self.fd], [], [], left)
            if not ready:
                continue
            chunk = os.read(self.fd, 65536)
            if not chunk:
                return 'crash', self.p.wait()
            self.buf += chunk

    def kill(self):
        if self.p.poll() is None:
            self.p.kill()  # only the worker this script started, by its handle
        self.p.wait()

    def close(self):
        try:
            self.p.stdin.close()
        except Exception:
            pass
        try:
            self.p.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.kill()


def run_scene_case(spec, tmpdir, timeout):
    root = os.path.dirname(os.path.dirname(SCRIPT))
    out = os.path.join(tmpdir, 'scene')
    args = ['%s=%s' % (k, v) for k, v in spec['base'].items() if k != spec['key']]
    args.append('%s=%s' % (spec['key'], spec['value']))
    cmd = ['yade', '-n', '-x', os.path.join(root, 'scripts', spec['script']), 'out=%s' % out] + args
    if os.path.exists(os.path.join(out, 'summary.json')):
        os.remove(os.path.join(out, 'summary.json'))
    env = dict(os.environ, OMP_NUM_THREADS='1', OMP_WAIT_POLICY='passive')
    env.pop('WOVEN_FUZZ_WORKER', None)
    try:
        r = subprocess.run(cmd, cwd=tmpdir, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return {'outcome': 'hang'}
    log = r.stdout + r.stderr
    if r.returncode < 0 or 'Segmentation fault' in log or 'core dumped' in log:
        return {'outcome': 'crash', 'message': 'signal %d' % -r.returncode}
    errors = [l for l in log.splitlines() if 'Error' in l and ':' in l]
    summary = os.path.join(out, 'summary.json')
    if r.returncode != 0 and not errors and os.path.exists(summary):
        return {'outcome': 'accepted'}  # a run whose checks did not pass: a result, not an input error
    if r.returncode != 0:
        last = errors[-1] if errors else log.strip().splitlines()[-1:] or ['']
        last = last if isinstance(last, str) else last[0]
        if any(t in last for t in ('ValueError', 'RuntimeError', 'InstabilityError')) or not errors:
            return {'outcome': 'error', 'names_key': spec['key'] in last, 'message': last[:300]}
        return {'outcome': 'unclean', 'message': last[:300]}
    path = os.path.join(out, 'summary.json')
    if os.path.exists(path):
        s = json.load(open(path))
        text = json.dumps(s.get('measured', {}))
        if s.get('status') == 'ok' and ('"nan"' in text or '"inf"' in text or '"-inf"' in text):
            return {'outcome': 'nonfinite', 'message': 'summary.json measured holds a non-finite value'}
    return {'outcome': 'accepted'}


def parent_main():
    import woven  # noqa: F401 (YADE's loop must not be needed here; imported to fail early if broken)
    from woven.params import read_params
    from woven.output import out_dir, write_summary, write_text_atomic
    p = read_params({
        'cases': (2000, '', 'cases to generate and run, [1, 1e6]'),
        'seed': (1, '', 'seed of the case generator, [0, 2^31)'),
        'timeout': (30.0, 's', 'a case that has not answered after this long is a hang, (0, 3600]'),
        'scene_every': (50, '', 'every this many cases a scene script run with a mutated key (0: none), [0, 1e6]'),
        'out': ('', '', 'output folder (default out/fuzz)'),
    })
    if not (1 <= p.cases <= 1000000):
        raise ValueError('cases = %r is invalid: allowed [1, 1e6]' % p.cases)
    if not (0 <= p.seed < 2 ** 31):
        raise ValueError('seed = %r is invalid: allowed [0, 2^31)' % p.seed)
    if not (math.isfinite(p.timeout) and 0 < p.timeout <= 3600):
        raise ValueError('timeout = %r is invalid: allowed (0, 3600] s' % p.timeout)
    if not (0 <= p.scene_every <= 1000000):
        raise ValueError('scene_every = %r is invalid: allowed [0, 1e6]' % p.scene_every)
    d = out_dir('fuzz', p)
    import tempfile
    tmpdir = tempfile.mkdtemp(prefix='woven_fuzz_')
    counts = {'cases': 0, 'clean_errors': 0, 'errors_naming_key': 0, 'accepted': 0, 'unclean_errors': 0,
              'crashes': 0, 'hangs': 0, 'silent_nonfinite': 0, 'wrongly_accepted': 0, 'must_refuse_cases': 0,
              'scene_cases': 0}
    failures, unnamed, rows = [], [], []
    t0 = time.time()
    w = None
    for i in range(p.cases):
        kind, spec = case(p.seed, i, p.scene_every)
        if kind == 'scene':
            counts['scene_cases'] += 1
            res = run_scene_case(spec, tmpdir, max(p.timeout, 60.0))
        else:
            if w is None:
                w = Worker(p.seed, p.scene_every, tmpdir)
            status, msg = w.ask(i, p.timeout)
            if status == 'done':
                res = msg
            else:
                res = {'outcome': status, 'message': 'exit %s' % msg if status == 'crash' else 'no answer in %g s' % p.timeout}
                w = None  # restarted for the next case
        counts['cases'] += 1
        counts['must_refuse_cases'] += bool(spec.get('must_refuse'))
        o = res['outcome']
        key = {'error': 'clean_errors', 'accepted': 'accepted', 'unclean': 'unclean_errors', 'crash': 'crashes',
               'hang': 'hangs', 'nonfinite': 'silent_nonfinite', 'wrongly_accepted': 'wrongly_accepted'}[o]
        counts[key] += 1
        if o == 'error' and res.get('names_key'):
            counts['errors_naming_key'] += 1
        elif o == 'error' and len(unnamed) < 30:
            unnamed.append({'case': i, 'spec': describe(kind, spec), 'message': res.get('message', '')})
        if o in ('unclean', 'crash', 'hang', 'nonfinite', 'wrongly_accepted') and len(failures) < 100:
            failures.append({'case': i, 'outcome': o, 'spec': describe(kind, spec), 'message': res.get('message', '')})
        rows.append('%d,%s,%s,%d' % (i, kind, o, int(bool(res.get('names_key')))))
    if w is not None:
        w.close()
    wall = time.time() - t0
    errors = counts['clean_errors']
    FAILS = ('crashes', 'hangs', 'silent_nonfinite', 'unclean_errors', 'wrongly_accepted')
    status = 'ok' if all(counts[k] == 0 for k in FAILS) else 'failed'
    measured = dict(counts, errors_naming_key_fraction=counts['errors_naming_key'] / errors if errors else 1.0,
                    wall_time=wall)
    write_text_atomic(os.path.join(d, 'cases.csv'), 'case,kind,outcome,names_key\n' + '\n'.join(rows) + '\n')
    write_summary(d, 'fuzz', p, measured, {k: 0 for k in FAILS},
                  {'wall_time': 's'}, status,
                  checks={k: {'value': counts[k], 'limit': 0, 'passed': counts[k] == 0} for k in FAILS},
                  extra={'failures': failures, 'errors_not_naming_key': unnamed})
    import shutil
    if status == 'ok':
        shutil.rmtree(tmpdir, ignore_errors=True)
    else:
        print('fuzz: worker files (worker.log) kept in', tmpdir)
    print('fuzz: %s -> %s  %s' % (status, d, json.dumps(measured)))
    return status


if WORKER:
    _seed, _every, _tmp = WORKER.split(',', 2)
    worker_main(int(_seed), int(_every), _tmp)
else:
    if parent_main() != 'ok':
        sys.exit(1)
