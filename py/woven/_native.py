"""The native engine of the YADE plugin (docs/yade_native.md), when it is there.

A build with -DYADE_SOURCE_DIR=... installs libwoven_yade.so where yade loads plugins from; its
yade.wrapper.WovenFabricEngine is a GlobalEngine that steps the very woven.FabricEngine a script made
(the plugin and woven._woven share one core library), so no Python runs in the loop and O.save /
O.load keep the whole fabric. woven.attach uses it when:
  - yade.wrapper has WovenFabricEngine (the plugin is loaded), and
  - woven._woven is of the same native build as the plugin (_woven._build_id(), a literal in the
    module, equals the plugin's WovenFabricEngine.coreBuild, the id of the core library it calls; a
    default-build module says 'default'), and
  - WOVEN_NATIVE is not '0' in the environment (WOVEN_NATIVE=0 forces the PyRunner adapter).
WOVEN_NATIVE=1 makes a missing or mismatched plugin an error instead of a silent fallback.
"""
import os

import yade.wrapper

from . import _woven


def why_not():
    """'' when the native engine can be used, else the reason it cannot."""
    if not hasattr(yade.wrapper, 'WovenFabricEngine'):
        return ('yade.wrapper has no WovenFabricEngine: the plugin libwoven_yade.so is not loaded (build with '
                '-DYADE_SOURCE_DIR=..., install, and run yade with YADE_PREFIX set to its prefix; docs/yade_native.md)')
    build = getattr(_woven, '_build_id', None)
    mine, plugin = (build() if build else 'unknown'), yade.wrapper.WovenFabricEngine().coreBuild
    if mine != plugin:
        return ('woven._woven (build %s) is not of the plugin\'s build (%s): put the woven package of the same '
                '-DYADE_SOURCE_DIR build on PYTHONPATH (a default-build package runs with the PyRunner)' % (mine, plugin))
    return ''


def wanted():
    """True when woven.attach should put the native engine into O.engines (see the module's doc)."""
    flag = os.environ.get('WOVEN_NATIVE', '')
    if flag == '0':
        return False
    reason = why_not()
    if reason and flag == '1':
        raise RuntimeError('WOVEN_NATIVE=1 but the native engine cannot be used: ' + reason)
    return not reason


def attached(engine, engines):
    """The WovenFabricEngine of `engines` that steps `engine` already, or None."""
    for e in engines:
        if type(e).__name__ == 'WovenFabricEngine' and e.fabric is not None and e.fabric._same(engine):
            return e
    return None


def make(engine, rewind, label=None):
    """A WovenFabricEngine stepping `engine` (rewind: coupled bodies were moved by a NewtonIntegrator first)."""
    n = yade.wrapper.WovenFabricEngine()
    n.adopt(engine)
    n.rewind = bool(rewind)
    if label:
        n.label = label
    return n


def _failed(kind, message, step, node, element, cause):
    """Called by the native engine when a step raises: sets woven.engine.last_error as the PyRunner
    adapter does, so scene scripts tell an instability from other errors the same way in both builds."""
    from . import engine
    if kind == 'instability':
        err = _woven.InstabilityError(message)
        err.step, err.node, err.element, err.cause = step, node, element, cause
    elif kind == 'parameter':
        err = ValueError(message)
    else:
        err = RuntimeError(message)
    engine.last_error = err


def view(segments=12, scale=1.0, max_strain=0.05):
    """Opens YADE's 3D view (yade.qt) with the yarns of every WovenFabricEngine drawn as tubes of their
    elliptic sections (yade.wrapper.WovenGlDrawer, coloured by strain), framed on the fabric.
    Needs the native plugin and a display (e.g. xvfb-run). Returns the view."""
    reason = why_not()
    if reason:
        raise RuntimeError('woven view: ' + reason)
    import numpy as np
    from yade import qt
    from .arrays import positions
    O = yade.wrapper.Omega()
    r = qt.Renderer()
    r.extraDrawers = [d for d in r.extraDrawers if type(d).__name__ != 'WovenGlDrawer'] + [
        yade.wrapper.WovenGlDrawer(segments=segments, scale=scale, maxStrain=max_strain)]
    v = qt.View()
    fabrics = [e.fabric for e in O.engines if type(e).__name__ == 'WovenFabricEngine' and e.fabric is not None]
    if fabrics:
        X = np.vstack([positions(f) for f in fabrics])
        lo, hi = X.min(axis=0), X.max(axis=0)
        from yade import Vector3
        c = Vector3(*(0.5 * (lo + hi)))
        radius = 0.5 * float(np.linalg.norm(hi - lo))
        # YADE sizes its clipping planes from the bodies' bounds; the fabric is not made of bodies.
        qt.center(suggestedRadius=radius, gridOrigin=c, suggestedCenter=c)
        v.fitAABB(Vector3(*lo), Vector3(*hi))
    return v
