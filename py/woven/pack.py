"""Multi-ply packs: copies of one built ply, each turned about the ply's centre by its own in-plane
angle and stacked below the first at a pitch of the ply's thickness plus a gap, all in one Fabric.

    pack = woven.pack.stack(w, plies=4, gap=0.11e-3, angles=[0, 45, 0, 45])
    pack.weave      # woven.weave.Weave over the whole pack (warp/weft yarn lists of every ply)
    pack.nodes[k]   # (first, end) node range of ply k; .elements[k], .yarns[k] likewise

The plies are more yarns of one fabric, so ply-ply contact goes through the same collision
pipeline as yarn-yarn contact within a ply (docs/ballistic.md, "Packs and standard projectiles").
Ply 0 is the top one (the projectile comes from +z); ply k lies k pitches below it. SI units.
"""
import math

import numpy as np

from . import _woven, arrays
from ._args import finite as _finite
from .weave import Weave

MAX_PLIES = 40
# The single ply's sweeps (scripts/ballistic.py's max_iterations): with the sweeps' active set the
# rows past the tenth sweep are few, and 20 leave under 1 % of them unresolved (docs/ballistic.md).
PLY_SWEEPS = 20


def sweeps_for(plies, per_ply=10, at_least=PLY_SWEEPS):
    """Gauss-Seidel sweeps for a pack of `plies`: `per_ply` per ply, never fewer than `at_least`
    (the single ply's). A sweep carries a push one contact layer further, and each ply stacks two
    yarn layers between the projectile and the last ply (measured, docs/ballistic.md: 4 plies at 10
    sweeps let the projectile 0.48 yarn thickness into the yarns before the first break, at 40
    sweeps 0.007)."""
    return max(int(at_least), int(per_ply) * int(plies))


def parse_angles(text, plies):
    """ply_angles as given ('0,45' or a list; one value applies to every ply) -> a list of `plies`
    finite angles [deg]; ValueError naming ply_angles and what is allowed."""
    items = [s for s in text.replace(' ', '').split(',') if s] if isinstance(text, str) else list(text)
    allowed = ('one finite angle in [-360, 360] deg per ply (%d), comma-separated, or one for all' % plies)
    if len(items) not in (1, plies):
        raise ValueError('ply_angles = %r is invalid: allowed %s; %d given' % (text, allowed, len(items)))
    out = []
    for v in items:
        try:
            a = float(v)
        except (TypeError, ValueError):
            raise ValueError('ply_angles = %r is invalid: allowed %s' % (text, allowed)) from None
        if not (math.isfinite(a) and -360 <= a <= 360):
            raise ValueError('ply_angles = %r is invalid: allowed %s' % (text, allowed))
        out.append(a)
    return out * plies if len(out) == 1 else out


def vertical_reach(engine):
    """Each node's section reach along z [m]: the support of its ellipse (semi-axes a, b; minor axis
    along the stored direction made normal to the yarn, the tangent from the neighbouring nodes)
    along z, sqrt(a^2 (u.z)^2 + b^2 (d.z)^2) with u = t x d."""
    X = arrays.positions(engine)
    ab = arrays.section_semi_axes(engine)
    D = arrays.section_dirs(engine).copy()
    T = np.zeros_like(X)
    for y in range(engine.n_yarns):
        info = engine.yarn(y)
        i0, n = info['first_node'], info['n_nodes']
        P = X[i0:i0 + n]
        t = np.empty_like(P)
        t[1:-1] = P[2:] - P[:-2]
        t[0], t[-1] = P[1] - P[0], P[-1] - P[-2]
        T[i0:i0 + n] = t / np.linalg.norm(t, axis=1)[:, None]
    D -= np.sum(D * T, axis=1)[:, None] * T
    nd = np.linalg.norm(D, axis=1)
    D = np.where(nd[:, None] > 1e-9, D / np.maximum(nd, 1e-300)[:, None], 0.0)
    U = np.cross(T, D)
    return np.sqrt((ab[:, 0] * U[:, 2]) ** 2 + (ab[:, 1] * D[:, 2]) ** 2)


class Pack:
    """A stacked pack: .weave (Weave over every ply), .plies, .pitch [m], .angles [deg], and the
    node, element and yarn ranges of each ply (.nodes, .elements, .yarns: lists of (first, end))."""

    def __init__(self, w, plies, pitch, angles, nodes, elements, yarns):
        self.weave, self.plies, self.pitch, self.angles = w, plies, pitch, angles
        self.nodes, self.elements, self.yarns = nodes, elements, yarns

    def ply_of_nodes(self):
        """Ply index of every node, shape (n_nodes,)."""
        out = np.empty(self.nodes[-1][1], dtype=np.int64)
        for k, (a, b) in enumerate(self.nodes):
            out[a:b] = k
        return out


def stack(w, plies, pitch, angles):
    """The pack of `plies` copies of the built weave `w` (its engine's nodes as built: stacking
    uses positions only, sections start circular as in any new fabric), ply k turned by angles[k]
    [deg] about the ply's centre (its nominal lengths' middle) and moved -k * pitch [m] along z.
    A ply at angle 0 and no shift keeps its positions bit for bit. Returns a Pack; collisions,
    settling, clamps and breakage are the caller's (woven.ballistic.build_ply)."""
    plies = int(_finite('plies', plies, 1, MAX_PLIES, integer=True))
    pitch = _finite('ply_pitch', pitch, 0, 1, 'm')
    angles = parse_angles(angles, plies)
    e1 = w.engine
    X = arrays.positions(e1)
    cx, cy = 0.5 * w.summary['length_x'], 0.5 * w.summary['length_y']
    fabric = _woven.Fabric()
    mats, secs = [], []
    for y in range(e1.n_yarns):
        info = e1.yarn(y)
        m = _woven.YarnMaterial()
        m.E, m.rho, m.area, m.damping = info['E'], info['rho'], info['area'], info['damping']
        m.failure_strain, m.tension_only = info['failure_strain'], info['tension_only']
        s = _woven.YarnSection()
        s.width, s.thickness = info['width'], info['thickness']
        mats.append(m), secs.append(s)
    nodes, elements, yarns, warp, weft = [], [], [], [], []
    n1, m1, y1 = e1.n_nodes, e1.n_elements, e1.n_yarns
    for k in range(plies):
        a = math.radians(angles[k])
        c, s = math.cos(a), math.sin(a)
        P = X.copy()
        if angles[k] != 0:
            dx, dy = X[:, 0] - cx, X[:, 1] - cy
            P[:, 0], P[:, 1] = cx + c * dx - s * dy, cy + s * dx + c * dy
        if k > 0:
            P[:, 2] = X[:, 2] - k * pitch
        for y in range(y1):
            info = e1.yarn(y)
            i0 = info['first_node']
            fabric.add_yarn([_woven_vec(p) for p in P[i0:i0 + info['n_nodes']]], mats[y], secs[y])
        nodes.append((k * n1, (k + 1) * n1)), elements.append((k * m1, (k + 1) * m1)), yarns.append((k * y1, (k + 1) * y1))
        warp += [k * y1 + y for y in w.warp_yarns]
        weft += [k * y1 + y for y in w.weft_yarns]
    engine = _woven.FabricEngine(fabric)
    summary = dict(w.summary)
    summary.update({'plies': plies, 'ply_pitch': pitch, 'ply_angles': angles, 'nodes': engine.n_nodes,
                    'elements': engine.n_elements, 'areal_density_ply': w.summary['areal_density'],
                    'areal_density': plies * w.summary['areal_density']})
    return Pack(Weave(engine, summary, warp, weft, w.params, w.pattern), plies, pitch, angles, nodes, elements, yarns)


def _woven_vec(p):
    from yade._minieigenHP import Vector3
    return Vector3(float(p[0]), float(p[1]), float(p[2]))


def clear_gaps(engine, pack):
    """Clear gap between neighbouring plies as built [m], one per pair (k, k+1): the lowest section
    reach of ply k minus the highest of ply k+1 (vertical_reach), < 0 where they overlap."""
    X = arrays.positions(engine)
    r = vertical_reach(engine)
    out = []
    for k in range(pack.plies - 1):
        (a0, b0), (a1, b1) = pack.nodes[k], pack.nodes[k + 1]
        out.append(float(np.min(X[a0:b0, 2] - r[a0:b0]) - np.max(X[a1:b1, 2] + r[a1:b1])))
    return out


def ply_books(engine, pack):
    """Per ply at the current state: kinetic and elastic energy of its nodes and CPs, the energy its
    broken CPs released, its broken CPs and yarns. Sums over the plies give the engine's kinetic,
    elastic and released entries (the contact, damping and projection entries are shared between
    plies and stay whole). SI units."""
    X, V, M = arrays.positions(engine), arrays.velocities(engine), arrays.masses(engine)
    l0, alive = arrays.rest_lengths(engine), arrays.alive(engine)
    kin = 0.5 * M * np.sum(V * V, axis=1)
    elastic = np.zeros(engine.n_elements)
    released = np.zeros(engine.n_yarns)
    for b in engine.break_log():
        released[b['yarn']] += b['energy']
    broken_yarn = np.zeros(engine.n_yarns, dtype=bool)
    for y in range(engine.n_yarns):
        info = engine.yarn(y)
        i0, n = info['first_node'], info['n_nodes']
        j0, m = info['first_element'], info['n_elements']
        P = X[i0:i0 + n]
        stretch = np.linalg.norm(P[1:] - P[:-1], axis=1) - l0[j0:j0 + m]
        K = info['E'] * info['area'] / l0[j0:j0 + m]
        live = alive[j0:j0 + m] != 0
        if info['tension_only']:
            stretch = np.maximum(stretch, 0.0)
        elastic[j0:j0 + m] = np.where(live, 0.5 * K * stretch * stretch, 0.0)
        broken_yarn[y] = not live.all()
    out = []
    for k in range(pack.plies):
        (a, b), (c, d), (y0, y1) = pack.nodes[k], pack.elements[k], pack.yarns[k]
        out.append({'kinetic': float(np.sum(kin[a:b])), 'elastic': float(np.sum(elastic[c:d])),
                    'released_breakage': float(np.sum(released[y0:y1])),
                    'absorbed': float(np.sum(kin[a:b]) + np.sum(elastic[c:d]) + np.sum(released[y0:y1])),
                    'broken_elements': int(np.sum(alive[c:d] == 0)), 'broken_yarns': int(np.sum(broken_yarn[y0:y1]))})
    return out
