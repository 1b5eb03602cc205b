"""YADE bodies that collide with the fabric: a projectile, clamps, any Box, Sphere, Wall, Facet or clump of these.

    pid = O.bodies.append(utils.box(centre, half_extents))
    woven.coupling.couple(engine, [pid])     # before woven.attach(engine)

YADE keeps owning and integrating the bodies (its NewtonIntegrator must run before the woven
adapter, which attach ensures by appending it); each step the adapter reads their pose and
velocities, the fabric's collision stage gives them and the yarns the same impulses (opposite signs,
with the body's mass and inertia), and their new velocities and pose are written back. The cost is a
few attribute reads and writes per body per step, nothing per yarn node. Units SI.
"""
import math
import numbers
import yade.wrapper
from yade._minieigenHP import Quaternion, Vector3

_O = yade.wrapper.Omega()
WALL_DEPTH = 10.0  # [m] half-size of the box that stands for a YADE Wall (see _parts_of)


def _parts_of(body):
    """[('box', half_extents, offset, ori) | ('sphere', radius, offset, ori) | ('facet', corners, offset, ori)
    | ('triangle', corners, offset, ori)] in the body's frame."""
    shape = body.shape
    kind = type(shape).__name__
    I = Quaternion.Identity
    zero = Vector3.Zero
    if kind == 'Box':
        return [('box', shape.extents, zero, I)]
    if kind == 'Sphere':
        return [('sphere', shape.radius, zero, I)]
    if kind == 'Wall':
        # YADE's Wall is the infinite plane through the body's position normal to the global axis
        # `axis`, acting on the side `sense`. For the fabric it is the face of a box behind the plane
        # (the box form takes the face that leaves the CP the most room: this one, the others lie
        # WALL_DEPTH away), fixed in the global frame. WALL_DEPTH bounds the rounding of the gap to
        # 1e-16 WALL_DEPTH = 1e-15 m.
        if shape.sense not in (-1, 1):
            raise ValueError('sense = %r of wall %d is invalid: allowed -1 or +1 (the side the fabric is on)'
                             % (shape.sense, body.id))
        if shape.axis not in (0, 1, 2):
            raise ValueError('axis = %r of wall %d is invalid: allowed 0, 1 or 2' % (shape.axis, body.id))
        inv = body.state.ori.conjugate()
        n = Vector3.Zero
        n[shape.axis] = 1.0
        half = Vector3(WALL_DEPTH, WALL_DEPTH, WALL_DEPTH)
        return [('box', half, inv * (-shape.sense * WALL_DEPTH * n), inv)]
    if kind == 'Facet':
        # A lone facet: outside on both faces (its corners in the body frame, as YADE keeps them).
        return [('facet', tuple(Vector3(v) for v in shape.vertices), zero, I)]
    if kind == 'Clump':
        parts = []
        for mid, (rel_pos, rel_ori) in sorted(shape.members.items()):
            sub = _parts_of(_O.bodies[mid])
            parts += [(k, size, rel_pos + rel_ori * off, rel_ori * ori) for (k, size, off, ori) in sub]
        return _closed_faces(parts)
    raise ValueError('body %d has shape %s: woven collides yarns with Box, Sphere, Wall, Facet and clumps of these'
                     % (body.id, kind))


def _closed_faces(parts):
    """A clump's facets that close a solid (yade.ymport.stl of a closed mesh) become the faces of that
    solid: one-sided, outward (the corners reversed where the mesh winds inward), so a yarn pressed
    into it is pushed out, not through. Facets that close nothing stay two-sided."""
    facets = [k for k, p in enumerate(parts) if p[0] == 'facet']
    if len(facets) < 4:
        return parts
    import numpy as np
    from . import mesh
    # The corners in the clump frame, welded where they coincide to 1e-12 m (YADE stores each
    # facet's corners on their own).
    corners = np.array([[tuple(parts[k][2] + parts[k][3] * v) for v in parts[k][1]] for k in facets])
    keys = np.round(corners.reshape(-1, 3) / 1e-12).astype(np.int64)
    _, inverse = np.unique(keys, axis=0, return_inverse=True)
    tris = inverse.reshape(-1, 3)
    try:
        mesh.check_closed(tris)
    except ValueError:
        return parts
    verts = np.zeros((tris.max() + 1, 3))
    verts[tris.reshape(-1)] = corners.reshape(-1, 3)
    flip = mesh.volume(verts, tris) < 0
    out = list(parts)
    for k in facets:
        kind, v, off, ori = parts[k]
        out[k] = ('triangle', (v[0], v[2], v[1]) if flip else v, off, ori)
    return out


def couple(engine, ids, parts=None, friction=None):
    """Makes the YADE bodies `ids` collide with the fabric of `engine` (collisions must be on).

    `parts` (optional) maps a body id to its woven parts, for a body whose YADE shape is a stand-in
    (YADE has no cylinder: woven.projectiles), else the parts come from the YADE shape.
    `friction` (optional): these bodies' own Coulomb coefficient with the yarns, in [0, 2] (a
    clamp's jaws); None: the engine's body_friction (woven.contact), as for every other body.

    A body that YADE does not integrate (b.dynamic False) is kinematic for the fabric: impulses do
    not change its motion. Returns the woven body indices. Raises ValueError for an unknown id, a
    shape other than Box/Sphere/Wall/Facet/Clump, non-positive mass of a dynamic body, non-finite velocity,
    or a body that starts inside the fabric.
    """
    if not engine.collisions_enabled:
        raise ValueError('collisions = off is invalid: allowed on (woven.contact.enable(engine) before couple)')
    ids = list(ids)
    if friction is not None and not (isinstance(friction, numbers.Real) and 0 <= friction <= 2):
        raise ValueError('friction = %r is invalid: allowed [0, 2] (or None: body_friction)' % (friction,))
    coupled = {engine.body(k)['id'] for k in range(engine.n_bodies)}
    out = []
    for i in ids:
        if isinstance(i, bool) or not isinstance(i, numbers.Integral):
            raise ValueError('body id = %r is invalid: allowed an integer id of O.bodies' % (i,))
        # Coupled twice, a body would take every impulse twice.
        if i in coupled:
            raise ValueError('body id = %d is invalid: allowed a body not coupled to this engine yet (each body once)' % i)
        i = int(i)
        coupled.add(i)
        if not (0 <= i < len(_O.bodies)) or _O.bodies[i] is None:
            raise ValueError('body id = %r is invalid: allowed an id of O.bodies (0..%d)' % (i, len(_O.bodies) - 1))
        b = _O.bodies[i]
        if b.clumpId >= 0 and b.clumpId != b.id:
            raise ValueError('body id = %d is invalid: it is a member of clump %d; couple the clump' % (i, b.clumpId))
        s = b.state
        for name in ('vel', 'angVel', 'pos'):
            v = getattr(s, name)
            if not all(math.isfinite(c) for c in v):
                raise ValueError('%s = %s of body %d is invalid: allowed finite values (SI)' % (name, v, i))
        mass = s.mass if b.dynamic else 0.0
        if b.dynamic and not (s.mass > 0 and math.isfinite(s.mass)):
            raise ValueError('mass = %r of body %d is invalid: allowed (0, inf) kg for a dynamic body' % (s.mass, i))
        # add_body refuses a body that starts inside the fabric, naming it
        out.append(engine.add_body(i, parts[i] if parts and i in parts else _parts_of(b), mass, s.inertia, s.pos, s.ori,
                                   s.vel, s.angVel))
        if friction is not None:
            engine.set_body_friction(out[-1], float(friction))
    return out
