"""The YADE side of a FabricEngine: one woven step per YADE iteration, with YADE's O.dt.

YADE's C++ Engine cannot be subclassed here (Debian ships no YADE headers), so the adapter is a
PyRunner with iterPeriod=1 whose command calls the C++ step with O.dt: about 30-45 us of Python per
iteration (measured with `yade -n -x scripts/bench_pyrunner.py`), independent of the fabric size.
O.time and O.iter stay the clock; the fabric's own step counter must follow O.iter.

YADE bodies coupled to the fabric (woven.coupling.couple) are read before and written after each
step; the adapter must run after YADE's NewtonIntegrator (attach appends it at the end), which has
moved them from x_n to x_n + dt v already: the step takes them back to x_n, resolves the contacts
with the fabric on the same (x_n, v_{n+1/2}) as the yarns, and moves them with the new velocities.

YADE's O.save / O.load keep the adapter (its command) but not the fabric: woven.checkpoint saves the
fabric beside the scene file and points the loaded adapters at their engines (runners() finds them).
"""
import re

import yade.wrapper

from ._woven import FabricEngine, release_threads
from . import _native  # the native YADE plugin's engine, when installed (docs/yade_native.md)

_O = yade.wrapper.Omega()
_registry = {}   # key of the PyRunner command '_woven_step(key)' -> (engine, rewind)
_unbound = {}    # key -> why no engine may step for it (woven.checkpoint: a scene loaded without its fabric)
UNBOUND_KEYS = 1 << 30  # unbound keys from here on, apart from attach's keys 0, 1, 2 ...
_COMMAND = re.compile(r'^_woven_step\((\d+)\)$')
last_error = None  #: the last exception a woven step raised (InstabilityError keeps step, node, cause)


def runners(engines=None):
    """[(position in engines, PyRunner, key)] of the woven adapters in `engines` (default O.engines),
    found by their command '_woven_step(key)' (woven.checkpoint uses it after O.load)."""
    found = []
    for i, e in enumerate(_O.engines if engines is None else engines):
        if isinstance(e, yade.wrapper.PyRunner):
            m = _COMMAND.match(e.command)
            if m:
                found.append((i, e, int(m.group(1))))
    return found


def _step(key):
    global last_error
    try:
        engine, rewind = _registry[key]
    except KeyError:
        last_error = RuntimeError(_unbound.get(key, 'woven: no engine is attached as _woven_step(%d) in this process '
                                                    '(a scene loaded without woven.checkpoint? docs/reliability.md)' % key))
        raise last_error from None
    try:
        if engine.n_bodies:
            # Coupled YADE bodies: their state in, one step, their new state out (C++, a few
            # attribute reads and writes per body; none per node).
            engine._yade_step(_O.dt, _O.bodies, rewind)
        else:
            engine.step(_O.dt)
    except Exception as e:
        last_error = e
        raise


def attach(engine, set_dt=True, safety=0.7, label=None, append=True):
    """Puts `engine` (a woven.FabricEngine) into O.engines and returns the PyRunner that drives it,
    or, with the native YADE plugin installed, the yade.wrapper.WovenFabricEngine that steps it
    (woven._native; WOVEN_NATIVE=0 forces the PyRunner).

    set_dt: set O.dt = safety * engine.dt_max [s] (dt_max = substeps x dt_crit; safety in (0, 1]; 0.7 by
            default because slack/taut switching of tension-only yarns gains energy near dt_crit, docs/design.md);
            otherwise O.dt must already be <= engine.dt_max, else ValueError naming dt and the allowed range
            (before any step).
    label:  YADE label of the PyRunner.
    append: add to the end of O.engines (else the caller places the returned PyRunner).
    """
    steppers = [type(e).__name__ for e in _O.engines
                 if isinstance(e, yade.wrapper.TimeStepper) and not e.dead]
    if steppers:
        raise ValueError('O.engines holds %s, which changes O.dt; woven needs O.dt <= dt_crit: set '
                         'O.engines yourself (a fresh scene has YADE\'s defaults) or make it dead' % ', '.join(steppers))
    if not isinstance(engine, FabricEngine):
        raise ValueError('engine = %r is invalid: allowed a woven.FabricEngine' % (engine,))
    if isinstance(safety, bool) or not isinstance(safety, (int, float)) or not (0 < safety <= 1):
        raise ValueError('safety = %r is invalid: allowed (0, 1]' % (safety,))
    if set_dt:
        _O.dt = safety * engine.dt_max
    elif not (0 < _O.dt <= engine.dt_max * (1 + 1e-12)):
        raise ValueError('dt = %.12g is invalid: allowed (0, substeps x dt_crit = %.12g] s (stable limit of the chain; '
                         'set O.dt below it or attach(..., set_dt=True))' % (_O.dt, engine.dt_max))
    # The same engine twice would step the fabric twice per YADE iteration (with YADE's O.dt each).
    native = _native.wanted()
    if native and _native.attached(engine, _O.engines) is not None:
        raise ValueError('engine = %r is invalid: allowed an engine not attached yet (it is already in '
                         'O.engines as a WovenFabricEngine; attach each engine once)' % (engine,))
    for e in _O.engines:
        if isinstance(e, yade.wrapper.PyRunner) and e.command.startswith('_woven_step('):
            try:
                k = int(e.command[len('_woven_step('):-1])
            except ValueError:
                continue
            if k in _registry and _registry[k][0] is engine:
                raise ValueError('engine = %r is invalid: allowed an engine not attached yet (it is already in '
                                 'O.engines as %r; attach each engine once)' % (engine, e.command))
    # Bodies coupled to the fabric (woven.coupling) were already moved over this iteration's step
    # when a NewtonIntegrator runs before the adapter: the step rewinds them to x_n first.
    newton = [i for i, e in enumerate(_O.engines) if isinstance(e, yade.wrapper.NewtonIntegrator) and not e.dead]
    rewind = bool(newton) and append
    # YADE's loop thread steps from here on: the script's thread lets its idle OpenMP team go, or it
    # would make the loop thread's team sleep at every barrier (docs/design.md, Threads).
    release_threads()
    if native:  # the plugin's GlobalEngine: the same step in C++, no Python per iteration
        runner = _native.make(engine, rewind, label)
        if append:
            _O.engines = list(_O.engines) + [runner]
        return runner
    key = len(_registry)
    _registry[key] = (engine, rewind)
    # PyRunner compiles its command every iteration: keep it short (a name put into __main__, where
    # YADE runs PyRunner commands, and a small key): measured 60-70 -> 40-45 us per iteration.
    import __main__
    __main__.__dict__['_woven_step'] = _step
    runner = yade.wrapper.PyRunner(command='_woven_step(%d)' % key, iterPeriod=1)
    runner.initRun = True  # also at O.iter 0, so the fabric's steps equal O.iter (a constructor keyword is ignored)
    if label:
        runner.label = label
    if append:
        _O.engines = list(_O.engines) + [runner]
    return runner
