"""The ballistic scene's pieces, shared by scripts/ballistic.py and scripts/bench_ballistic.py: a
clamped ply with breakage, and a projectile as an ordinary YADE body coupled to it. SI units.

    ply = woven.ballistic.build_ply(weave_args, contact_args, side=0.0508, clamp=4)
    proj = woven.ballistic.add_projectile(ply, shape='box', mass=1.1e-3, size=5.59e-3, V=200, standoff=5e-5)
"""
import numpy as np
import yade.wrapper
from yade import utils
from yade._minieigenHP import Vector3

from . import arrays, coupling
from ._woven import MAX_WEAVE_NODES
from .weave import weave, pattern

_O = yade.wrapper.Omega()


class Ply:
    """A built ply: weave (woven.weave.Weave), engine, and its geometry at the start (SI)."""

    def __init__(self, w, settle_left):
        self.weave, self.engine, self.settle_left = w, w.engine, settle_left
        X0 = arrays.positions(w.engine).copy()
        self.X0 = X0
        self.centre = X0.mean(axis=0)
        self.z_mid = float(np.median(X0[:, 2]))  # [m] the ply's mid-plane
        ab = arrays.section_semi_axes(w.engine)
        self.z_top = float(np.max(X0[:, 2] + ab[:, 0]))  # [m] above every section, whatever its turn
        self.thickness = max(w.engine.yarn(y)['thickness'] for y in (w.warp_yarns[0], w.weft_yarns[0]))


def build_ply(weave_args, contact_args, side=0.0508, clamp=4, state='', breakage=None):
    """Builds the ply: weave_args as woven.weave's keys (nx or ny <= 0: from `side` [m], rounded to whole
    pattern repeats), collisions on with contact_args (woven.contact keys), sections settled, `state`
    loaded when given, yarn ends held on `clamp` = 4 (all), 2 (warp) or 0 edges, and breakage
    (dict of FabricEngine.enable_breakage's keys; None: off). Returns a Ply."""
    from . import contact
    args = dict(weave_args)
    if args.get('nx', 0) <= 0 or args.get('ny', 0) <= 0:
        pat = pattern(args.get('pattern', 'plain'), args.get('twill_over', 2), args.get('twill_under', 1),
                      args.get('satin_n', 5), args.get('satin_step', 2), args.get('basket_n', 2))
        probe = weave(**dict(args, nx=1, ny=1))
        if args.get('nx', 0) <= 0:
            args['nx'] = max(1, int(round(side / (probe.summary['length_x'] / len(probe.weft_yarns)) / pat.cols)))
        if args.get('ny', 0) <= 0:
            args['ny'] = max(1, int(round(side / (probe.summary['length_y'] / len(probe.warp_yarns)) / pat.rows)))
    # Size before building: side = 10 m gave 13400 x 13400 yarns and an empty MemoryError.
    pat = pattern(args.get('pattern', 'plain'), args.get('twill_over', 2), args.get('twill_under', 1),
                  args.get('satin_n', 5), args.get('satin_step', 2), args.get('basket_n', 2))
    n = args.get('cp_per_span') or 4
    nw, nf = float(args['ny']) * pat.rows, float(args['nx']) * pat.cols
    nodes = nw * (nf * n + n + 1) + nf * (nw * n + n + 1)
    if nodes > MAX_WEAVE_NODES:
        key = 'side' if weave_args.get('nx', 0) <= 0 or weave_args.get('ny', 0) <= 0 else 'nx'
        raise ValueError('%s = %r is invalid: allowed a ply of at most %d nodes (about %g GB; side, nx, ny and '
                         'cp_per_span give %.3g nodes here)' % (key, side if key == 'side' else args['nx'],
                                                                 MAX_WEAVE_NODES, MAX_WEAVE_NODES * 800 / 1e9, nodes))
    w = weave(**args)
    e = w.engine
    contact.enable(e, **contact_args)
    left = e.settle_sections()
    held = w.warp_yarns + w.weft_yarns if clamp == 4 else (w.warp_yarns if clamp == 2 else [])
    for y in held:
        info = e.yarn(y)
        e.fix(info['first_node'])
        e.fix(info['first_node'] + info['n_nodes'] - 1)
    if breakage is not None:
        e.enable_breakage(**breakage)
    if state:
        # Last: a state saved with breakage brings its broken elements, strengths and filter back
        # (enabling breakage after it would restart them); one saved without keeps these settings.
        e.load_state(state)
    return Ply(w, left)


def fine_radius_from_waves(weave_args, V, t_end, shape, size):
    """Radius [m] of the fine region for adaptive resolution: how far the transverse wave of Smith's
    impact at V [m/s] travels in t_end [s] (lab-frame U_E of the weave's warp material,
    physics-reference.md), plus the projectile's in-plane reach from its centre (a cube of edge `size`
    [m] face on: size/sqrt(2); a sphere of diameter `size`: size/2)."""
    from . import theory
    probe = weave(**dict(weave_args, nx=1, ny=1, fine_radius=-1))
    info = probe.engine.yarn(probe.warp_yarns[0])
    U = theory.smith(V, info['E'], info['rho'])['U_E']
    return U * t_end + (size / 2 ** 0.5 if shape == 'box' else 0.5 * size)


def add_projectile(ply, shape='box', mass=1.1e-3, size=5.59e-3, V=200.0, standoff=5e-5):
    """A projectile over the ply's centre, `standoff` [m] above its top, moving at V [m/s] along -z:
    a cube of edge `size` [m], face on, or a sphere of diameter `size`, of `mass` [kg], appended to
    O.bodies and coupled to the ply's engine. Returns the YADE body."""
    half = 0.5 * size
    start = (ply.centre[0], ply.centre[1], ply.z_top + half + standoff)
    if shape == 'box':
        body = utils.box(start, (half, half, half), fixed=False)
        inertia = mass * size ** 2 / 6  # cube about its centre
    else:
        body = utils.sphere(start, half, fixed=False)
        inertia = 0.4 * mass * half ** 2
    body.mask = 0  # no YADE contacts with the mirrored yarn bodies
    pid = _O.bodies.append(body)
    b = _O.bodies[pid]
    b.state.mass = mass
    b.state.inertia = Vector3(inertia, inertia, inertia)
    b.state.vel = Vector3(0, 0, -V)
    coupling.couple(ply.engine, [pid])  # refuses a projectile that starts inside the ply
    return b
