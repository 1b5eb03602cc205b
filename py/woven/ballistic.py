"""The ballistic scene's pieces, shared by scripts/ballistic.py and scripts/bench_ballistic.py: a
clamped ply with breakage, and a projectile as an ordinary YADE body coupled to it. SI units.

    ply = woven.ballistic.build_ply(weave_args, contact_args, side=0.0508, clamp=4)
    proj = woven.ballistic.add_projectile(ply, shape='box', mass=1.1e-3, size=5.59e-3, V=200, standoff=5e-5)
"""
import math

import numpy as np
import yade.wrapper
from yade import utils
from yade._minieigenHP import Matrix3, Quaternion, Vector3

from . import arrays, coupling, pack
from ._woven import MAX_WEAVE_NODES
from .weave import weave, pattern

_O = yade.wrapper.Omega()


class Ply:
    """A built ply or pack: weave (woven.weave.Weave), engine, pack (woven.pack.Pack, or None for a
    single ply), and its geometry at the start (SI)."""

    def __init__(self, w, settle_left, pk=None):
        self.weave, self.engine, self.settle_left, self.pack = w, w.engine, settle_left, pk
        X0 = arrays.positions(w.engine).copy()
        self.X0 = X0
        first = X0 if pk is None else X0[pk.nodes[0][0]:pk.nodes[0][1]]
        last = X0 if pk is None else X0[pk.nodes[-1][0]:pk.nodes[-1][1]]
        self.centre = first.mean(axis=0)
        self.z_mid = float(np.median(first[:, 2]))  # [m] the (top) ply's mid-plane
        self.z_exit = float(np.median(last[:, 2]))  # [m] the last ply's mid-plane: below it, through the pack
        ab = arrays.section_semi_axes(w.engine)
        self.z_top = float(np.max(X0[:, 2] + ab[:, 0]))  # [m] above every section, whatever its turn
        self.thickness = max(w.engine.yarn(y)['thickness'] for y in (w.warp_yarns[0], w.weft_yarns[0]))


def build_ply(weave_args, contact_args, side=0.0508, clamp=4, state='', breakage=None, plies=1, ply_gap=None,
              ply_angles='0'):
    """Builds the ply: weave_args as woven.weave's keys (nx or ny <= 0: from `side` [m], rounded to whole
    pattern repeats), collisions on with contact_args (woven.contact keys), sections settled, `state`
    loaded when given, yarn ends held on `clamp` = 4 (all), 2 (warp) or 0 edges, and breakage
    (dict of FabricEngine.enable_breakage's keys; None: off). With plies > 1 (or a ply angle other
    than 0) a pack (woven.pack.stack): `plies` copies, each turned by its angle of `ply_angles`
    [deg] ('0,45' or a list; one applies to all), `ply_gap` [m] apart (None: one yarn thickness),
    every ply clamped alike. Returns a Ply."""
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
    pk = None
    if plies > 1 or any(a != 0 for a in pack.parse_angles(ply_angles, plies)):
        # The settled ply's thickness (its sections' reach along z) plus the gap is the pitch; the
        # pack is built from the same node positions and settles like the single ply.
        gap = thickness_of(w) if ply_gap is None else ply_gap
        reach = pack.vertical_reach(e)
        X = arrays.positions(e)
        pitch = float(np.max(X[:, 2] + reach) - np.min(X[:, 2] - reach)) + gap
        pk = pack.stack(w, plies, pitch, ply_angles)
        w = pk.weave
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
    return Ply(w, left, pk)


def thickness_of(w):
    """The yarn thickness of a weave [m] (the larger of warp and weft)."""
    return max(w.engine.yarn(y)['thickness'] for y in (w.warp_yarns[0], w.weft_yarns[0]))


def fine_radius_from_waves(weave_args, V, t_end, shape, size):
    """Radius [m] of the fine region for adaptive resolution: how far the transverse wave of Smith's
    impact at V [m/s] travels in t_end [s] (lab-frame U_E of the weave's warp material,
    physics-reference.md), plus the projectile's in-plane reach from its centre (a cube of edge `size`
    [m] face on: size/sqrt(2); a sphere of diameter `size`: size/2)."""
    from . import theory
    probe = weave(**dict(weave_args, nx=1, ny=1, fine_radius=-1))
    info = probe.engine.yarn(probe.warp_yarns[0])
    U = theory.smith(V, info['E'], info['rho'])['U_E']
    return U * t_end + (size / 2 ** 0.5 if shape == 'box' else 0.5 * size)  # rcc, fsp: size = diameter


SHAPES = ('box', 'sphere', 'rcc', 'fsp', 'mesh')
YAW_RANGE = (-90.0, 90.0)  # [deg]
OBLIQUITY_RANGE = (0.0, 80.0)  # [deg]


def projectile_pose(shape, yaw=0.0, obliquity=0.0):
    """(orientation, unit velocity direction) of a projectile: its flight turned from -z by
    `obliquity` [deg] towards +x, its axis (a cube's face normal; a cylinder's, nose first) turned from
    the flight by `yaw` [deg] in the same plane (the plane of incidence)."""
    Ry = lambda deg: Quaternion(Vector3(0, 1, 0), -math.radians(deg))
    o = math.radians(obliquity)
    direction = Vector3(math.sin(o), 0, -math.cos(o))
    ori = Ry(obliquity + yaw)
    if shape in ('rcc', 'fsp', 'mesh'):  # the part's (the mesh's nose frame's) nose is +z: turned to face -z first
        ori = ori * Quaternion(Vector3(1, 0, 0), math.pi)
    return ori, direction


def projectile_extent(shape, size, ori, solid=None):
    """How far the projectile reaches below and above its centre of mass along z [m] at orientation
    `ori`: a cube of edge `size`, a sphere of diameter `size`, or the cylinder `solid`
    (woven.projectiles.solid)."""
    if shape == 'sphere':
        return 0.5 * size, 0.5 * size
    if shape == 'box':
        R = ori.toRotationMatrix()
        h = 0.5 * size * sum(abs(R[2, k]) for k in range(3))
        return h, h
    if shape == 'mesh':  # the corners of the triangles (principal frame) turned by ori
        z = [(ori * Vector3(*c))[2] for c in solid['triangles'].reshape(-1, 3)]
        return -min(z), max(z)
    from ._woven import cylinder_min_along
    dims = (solid['radius'], solid['half_length'], solid['chisel_angle'], solid['land_half_width'])
    off = ori * Vector3(0, 0, -solid['centroid_z'])  # the part's centre from the centre of mass
    out = []
    for sign in (1, -1):
        n = ori.conjugate() * Vector3(0, 0, sign)
        out.append(-(sign * off[2] + cylinder_min_along(*dims, n=n)))
    return out[0], out[1]


def add_projectile(ply, shape='box', mass=1.1e-3, size=5.59e-3, V=200.0, standoff=5e-5, yaw=0.0, obliquity=0.0,
                   solid=None):
    """A projectile aimed at the ply's centre, its lowest point `standoff` [m] above the ply's top,
    moving at V [m/s] along -z turned by `obliquity` [deg] towards +x, its axis `yaw` [deg] off its
    flight in that plane (projectile_pose): a cube of edge `size` [m], a sphere of diameter `size`, of
    `mass` [kg], or (shape 'rcc' or 'fsp') the exact cylinder `solid` (woven.projectiles.solid; its
    mass and inertia scaled to `mass`), or (shape 'mesh') the triangle mesh `solid` (woven.mesh.solid,
    nose first, its mass and inertia scaled to `mass`), shown in YADE by a box stand-in around it. Appended to
    O.bodies and coupled to the ply's engine (which refuses a projectile that starts inside the
    ply). Returns the YADE body."""
    if shape not in SHAPES:
        raise ValueError('shape = %r is invalid: allowed %s' % (shape, ', '.join(SHAPES)))
    if not YAW_RANGE[0] <= yaw <= YAW_RANGE[1]:
        raise ValueError('yaw = %r is invalid: allowed [%g, %g] deg' % ((yaw,) + YAW_RANGE))
    if not OBLIQUITY_RANGE[0] <= obliquity <= OBLIQUITY_RANGE[1]:
        raise ValueError('obliquity = %r is invalid: allowed [%g, %g] deg' % ((obliquity,) + OBLIQUITY_RANGE))
    half = 0.5 * size
    if shape in ('box', 'sphere') and yaw == 0 and obliquity == 0:  # the scene as it always was, bit for bit
        start = (ply.centre[0], ply.centre[1], ply.z_top + half + standoff)
        if shape == 'box':
            body = utils.box(start, (half, half, half), fixed=False)
            inertia = mass * size ** 2 / 6  # cube about its centre
        else:
            body = utils.sphere(start, half, fixed=False)
            inertia = 0.4 * mass * half ** 2
        inertia, velocity, ori, parts = Vector3(inertia, inertia, inertia), Vector3(0, 0, -V), None, None
    else:
        ori, direction = projectile_pose(shape, yaw, obliquity)
        if shape == 'mesh':  # the body frame is the mesh's principal frame within its nose frame
            P = solid['frame']
            ori = ori * Quaternion(Matrix3(*[float(P[i, j]) for i in range(3) for j in range(3)]))
        low, _ = projectile_extent(shape, size, ori, solid)
        # On the line of flight through the ply's centre at the height where the lowest point is
        # `standoff` above the top.
        lam = standoff / math.cos(math.radians(obliquity))
        start = Vector3(ply.centre[0], ply.centre[1], ply.z_top + low) - lam * direction
        if shape == 'box':
            body = utils.box(start, (half, half, half), fixed=False)
            inertia = Vector3.Ones * (mass * size ** 2 / 6)
        elif shape == 'sphere':
            body = utils.sphere(start, half, fixed=False)
            inertia = Vector3.Ones * (0.4 * mass * half ** 2)
        elif shape == 'mesh':
            tri = solid['triangles']
            half = np.abs(tri.reshape(-1, 3)).max(axis=0)
            body = utils.box(start, tuple(float(h) for h in half), fixed=False)
            inertia = Vector3(*solid['inertia']) * (mass / solid['mass'])
            parts = [('triangle', tuple(Vector3(*map(float, c)) for c in t), Vector3.Zero, Quaternion.Identity)
                     for t in tri]
        else:
            scale = mass / solid['mass']
            body = utils.box(start, (solid['radius'], solid['radius'], solid['half_length']), fixed=False)
            inertia = Vector3(*solid['inertia']) * scale
            from . import projectiles
            parts = projectiles.parts(solid)
        velocity = direction * V
        if shape in ('box', 'sphere'):
            parts = None
    body.mask = 0  # no YADE contacts with the mirrored yarn bodies
    pid = _O.bodies.append(body)
    b = _O.bodies[pid]
    b.state.mass = mass
    b.state.inertia = inertia
    if ori is not None:
        b.state.ori = ori
        b.aspherical = True  # YADE integrates its rotation through the angular momentum
    b.state.vel = velocity
    coupling.couple(ply.engine, [pid], parts={pid: parts} if parts else None)  # refuses a start inside the ply
    return b


FRAME_KICK = 0.05  # [m/s] what a pressed jaw's load adds to its velocity in a critical step (add_frame)


def add_frame(ply, width, gap=1e-6, friction=0.3, edge=5e-4, force=0.0, slab=1e-3, margin=1e-3):
    """A clamping frame of two fixed jaws (YADE Facets of a closed square-ring mesh each, clumped, as
    yade.ymport.stl gives a CAD part) over and under the ply's (the pack's) edges: the window leaves
    `width` [m] of every edge between the jaws, which stand `gap` [m] clear of the highest and lowest
    yarn sections, `slab` [m] thick, reaching `margin` [m] past the ply, the window's edge on the ply's
    side rounded to radius `edge` [m] (the yarns drawn into the window bend over it). The jaws meet the yarns with
    their own Coulomb coefficient `friction` ([0, 2]); the yarn ends are held by the jaws alone when
    the ply is built with clamp = 0. `force` > 0 [N]: the upper jaw presses the edges with that load
    (a YADE permanent force; it moves along z only), so the jaws' friction has a normal force to act
    on; its mass is the one its load kicks by FRAME_KICK in the fabric's critical step, which the
    contacts then take back each step (a lighter jaw, kicked by tens of m/s a step, went through
    the yarns at 20 sweeps). 0: both jaws fixed, pressing nothing.
    Returns the two clump ids (upper, lower)."""
    from . import mesh
    side = float(np.ptp(ply.X0[:, 0]))
    if not (math.isfinite(width) and 0 < width <= 0.25 * side):
        raise ValueError('frame_width = %r is invalid: allowed (0, %g] m (a quarter of the ply side)' % (width, 0.25 * side))
    if not (math.isfinite(gap) and 0 < gap <= 1e-3):
        raise ValueError('frame_gap = %r is invalid: allowed (0, 1e-3] m' % (gap,))
    if not (math.isfinite(force) and 0 <= force <= 1e6):
        raise ValueError('frame_force = %r is invalid: allowed [0, 1e6] N (0: fixed jaws)' % (force,))
    if not (math.isfinite(edge) and 0 <= edge <= min(slab, width)):
        raise ValueError('frame_edge = %r is invalid: allowed [0, %g] m (the jaw thickness and the frame width)'
                         % (edge, min(slab, width)))
    # Each section's reach along z: the ellipse's support sqrt(a^2 u_z^2 + b^2 d_z^2), d its minor axis,
    # u_z^2 at most 1 - d_z^2 (the jaws touch the flat ply's sections, not its Ply.z_top, which
    # allows every section its major semi-axis).
    ab, d = arrays.section_semi_axes(ply.engine), arrays.section_dirs(ply.engine)
    reach = np.sqrt(ab[:, 0] ** 2 * np.clip(1 - d[:, 2] ** 2, 0, 1) + ab[:, 1] ** 2 * d[:, 2] ** 2)
    z_low, z_high = float(np.min(ply.X0[:, 2] - reach)), float(np.max(ply.X0[:, 2] + reach))
    lo, hi = ply.X0[:, :2].min(axis=0), ply.X0[:, :2].max(axis=0)
    centre, half = 0.5 * (lo + hi), 0.5 * float(np.max(hi - lo))
    ids = []
    for z0, z1, top, bottom in ((z_high + gap, z_high + gap + slab, 0, edge), (z_low - gap - slab, z_low - gap, edge, 0)):
        v, t = mesh.square_ring(centre, half - width, half + margin, z0, z1, round_top=top, round_bottom=bottom)
        facets = [utils.facet([tuple(map(float, v[k])) for k in tri], fixed=True) for tri in t]
        for b in facets:  # YADE's clump asserts a positive mass of its members; the jaw is fixed
            b.state.mass, b.state.inertia = 1.0 / len(facets), Vector3(1e-9, 1e-9, 1e-9)
        cid = _O.bodies.appendClumped(facets)[0]
        _O.bodies[cid].dynamic = False
        ids.append(cid)
    if force > 0:
        up = _O.bodies[ids[0]]
        up.dynamic = True
        up.state.mass = force * ply.engine.dt_crit / FRAME_KICK
        # Along z only: YADE keeps the other velocity components, woven's impulses find no rotation
        # (an inertia far above the mass's times the jaw's size squared) and the symmetric frame none
        # in the plane to speak of (measured.frame's drift).
        up.state.inertia = Vector3(1e6, 1e6, 1e6)
        up.state.blockedDOFs = 'xyXYZ'
        _O.forces.setPermF(ids[0], Vector3(0, 0, -force))
    coupling.couple(ply.engine, ids, friction=friction)
    return ids


def crossing_places(engine):
    """The persistent crossings' places, {(yarn A, yarn B): (arc A, arc B)}: each sliding coordinate
    as rest length along its yarn from the yarn's first node [m] (a material coordinate: it moves only
    when the yarns slip over each other)."""
    c = arrays.crossings(engine)
    if len(c) == 0:
        return {}
    l0 = arrays.rest_lengths(engine)
    starts, first = [], []
    for y in range(engine.n_yarns):
        info = engine.yarn(y)
        first.append(info['first_element'])
        starts.append(np.concatenate([[0.0], np.cumsum(l0[info['first_element']:info['first_element'] + info['n_elements']])]))
    first = np.array(first)
    out = {}
    for cpA, sA, cpB, sB in c[:, :4]:
        ya, yb = int(np.searchsorted(first, cpA, side='right') - 1), int(np.searchsorted(first, cpB, side='right') - 1)
        ka, kb = int(cpA) - first[ya], int(cpB) - first[yb]
        out[(ya, yb)] = (starts[ya][ka] + sA * l0[int(cpA)], starts[yb][kb] + sB * l0[int(cpB)])
    return out


def load_sharing(engine, X0, centre, half_size, places0=None):
    """Where the fabric holds the energy it took, and how its yarns slipped: the yarns' kinetic and
    elastic energy and the energy their breaks released [J], by family (along x or y at the start)
    and by the yarn's distance from the impact point at the start in projectile half-sizes
    (`half_size` [m]): principal (under the projectile, <= 1), 1-2, 2-4, > 4; the yarns that hold
    at least 1 % of the largest yarn's energy; and, given the crossings' places at the start
    (crossing_places), the mean and largest slip of the crossings under the projectile and outside
    it [m]. SI units."""
    X, V, M = arrays.positions(engine), arrays.velocities(engine), arrays.masses(engine)
    l0, alive = arrays.rest_lengths(engine), arrays.alive(engine)
    kin = 0.5 * M * np.sum(V * V, axis=1)
    released = np.zeros(engine.n_yarns)
    for b in engine.break_log():
        released[b['yarn']] += b['energy']
    bins = ('principal', '1-2', '2-4', '>4')
    table = {fam: {b: 0.0 for b in bins} for fam in ('x', 'y')}
    count = {fam: {b: 0 for b in bins} for fam in ('x', 'y')}
    energy, where = np.zeros(engine.n_yarns), []
    for y in range(engine.n_yarns):
        info = engine.yarn(y)
        i0, n = info['first_node'], info['n_nodes']
        j0, m = info['first_element'], info['n_elements']
        P0, P = X0[i0:i0 + n], X[i0:i0 + n]
        stretch = np.linalg.norm(P[1:] - P[:-1], axis=1) - l0[j0:j0 + m]
        if info['tension_only']:
            stretch = np.maximum(stretch, 0.0)
        el = np.sum(np.where(alive[j0:j0 + m] != 0, 0.5 * info['E'] * info['area'] / l0[j0:j0 + m] * stretch ** 2, 0.0))
        energy[y] = np.sum(kin[i0:i0 + n]) + el + released[y]
        span = P0[-1] - P0[0]
        fam = 'x' if abs(span[0]) >= abs(span[1]) else 'y'
        off = abs(np.mean(P0[:, 1 if fam == 'x' else 0]) - centre[1 if fam == 'x' else 0]) / half_size
        b = bins[0] if off <= 1 else bins[1] if off <= 2 else bins[2] if off <= 4 else bins[3]
        table[fam][b] += float(energy[y])
        count[fam][b] += 1
        where.append(b)
    loaded = energy >= 0.1 * energy.max() if len(energy) and energy.max() > 0 else np.zeros(len(energy), bool)
    out = {'energy': table, 'yarns': count,
           'loaded_yarns': {b: int(sum(1 for y in range(len(where)) if loaded[y] and where[y] == b)) for b in bins},
           'total': float(np.sum(energy))}
    if places0:
        now = crossing_places(engine)
        slip = {'principal': [], 'outside': []}
        for (ya, yb), (a0, b0) in places0.items():
            if (ya, yb) not in now:
                continue  # a yarn broke there
            a1, b1 = now[(ya, yb)]
            under = where[ya] == 'principal' and where[yb] == 'principal'
            slip['principal' if under else 'outside'].append(max(abs(a1 - a0), abs(b1 - b0)))
        out['crossing_slip'] = {k: {'mean': float(np.mean(v)) if v else None, 'max': float(np.max(v)) if v else None,
                                    'crossings': len(v)} for k, v in slip.items()}
    return out
