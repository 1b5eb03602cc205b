"""Closed triangle meshes as rigid bodies: an STL reader and the mass properties of the solid.

A mesh projectile's mass, centre of mass and inertia are those of the solid its closed surface
bounds, from the surface alone by the divergence theorem: each triangle with the origin spans a
signed tetrahedron, and the volume integrals of 1, x, y, z, x^2, y^2, z^2, xy, yz, zx are sums of
polynomials of its vertices (Eberly, "Polyhedral Mass Properties (Revisited)", Geometric Tools 2002,
after Mirtich, "Fast and Accurate Computation of Polyhedral Mass Properties", JGT 1996). The sums are
exact only for a closed, consistently oriented surface, so an open or non-manifold mesh is refused.
SI units throughout; a file in millimetres is read with scale=1e-3.
"""
import struct

import numpy as np


def read_stl(path, scale=1.0):
    """(vertices (n, 3), triangles (m, 3) int) of an ASCII or binary STL, vertices welded exactly
    (STL stores each triangle's corners on their own), scaled by `scale`."""
    with open(path, 'rb') as fh:
        data = fh.read()
    corners = None
    if len(data) >= 84:
        (count,) = struct.unpack_from('<I', data, 80)
        if 84 + 50 * count == len(data):  # binary: 80-byte header, count, 50 bytes a triangle
            rec = np.frombuffer(data, dtype=np.dtype([('n', '<f4', 3), ('v', '<f4', (3, 3)), ('a', '<u2')]),
                                count=count, offset=84)
            corners = rec['v'].astype(float).reshape(-1, 3)
    if corners is None:
        text = data.decode('ascii', errors='replace')
        if not text.lstrip().startswith('solid'):
            raise ValueError('mesh = %r is invalid: allowed an ASCII or binary STL file' % (path,))
        vals = [line.split()[1:4] for line in text.splitlines() if line.strip().startswith('vertex')]
        if not vals or len(vals) % 3:
            raise ValueError('mesh = %r is invalid: allowed an STL with whole triangles (3 vertices each)' % (path,))
        corners = np.array(vals, dtype=float)
    verts, inverse = np.unique(corners, axis=0, return_inverse=True)
    return verts * float(scale), inverse.reshape(-1, 3).astype(np.int64)


def check_closed(triangles, name='mesh'):
    """Refuses (ValueError naming `name`) a surface that is not closed and consistently oriented:
    every directed edge must appear once and its reverse once (a 2-manifold without boundary)."""
    t = np.asarray(triangles)
    if len(t) < 4 or np.any(t[:, 0] == t[:, 1]) or np.any(t[:, 1] == t[:, 2]) or np.any(t[:, 2] == t[:, 0]):
        raise ValueError('%s is invalid: allowed a closed triangle mesh (at least 4 non-degenerate triangles)' % name)
    directed = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    uniq, counts = np.unique(directed, axis=0, return_counts=True)
    if np.any(counts > 1):
        raise ValueError('%s is invalid: allowed a closed, consistently oriented mesh (%d edges used twice in the '
                         'same sense: non-manifold or flipped triangles)' % (name, int(np.sum(counts > 1))))
    fwd = {tuple(e) for e in uniq.tolist()}
    open_edges = sum(1 for a, b in fwd if (b, a) not in fwd)
    if open_edges:
        raise ValueError('%s is invalid: allowed a closed mesh (%d boundary edges: the surface is open)'
                         % (name, open_edges))


def mass_properties(vertices, triangles, density=None, mass=None):
    """(mass [kg], centre of mass (3,) [m], inertia tensor about the centre of mass (3, 3) [kg m^2])
    of the solid bounded by a closed, outward-oriented triangle mesh (Eberly 2002, see the module).
    Give the density [kg/m^3] or the mass [kg] (then the density is mass / volume)."""
    v = np.asarray(vertices, dtype=float)
    t = np.asarray(triangles)
    p0, p1, p2 = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    d = np.cross(p1 - p0, p2 - p0)
    # Eberly's subexpressions per coordinate w of the three corners.
    w0, w1, w2 = p0, p1, p2
    temp0 = w0 + w1
    f1 = temp0 + w2
    temp1 = w0 * w0
    temp2 = temp1 + w1 * temp0
    f2 = temp2 + w2 * f1
    f3 = w0 * temp1 + w1 * temp2 + w2 * f2
    g0 = f2 + w0 * (f1 + w0)
    g1 = f2 + w1 * (f1 + w1)
    g2 = f2 + w2 * (f1 + w2)
    x, y, z = 0, 1, 2
    i1 = np.sum(d[:, x] * f1[:, x]) / 6
    ix = np.sum(d * f2, axis=0) / 24               # integrals of x, y, z
    ixx = np.sum(d * f3, axis=0) / 60              # of x^2, y^2, z^2
    ixy = np.sum(d[:, x] * (p0[:, y] * g0[:, x] + p1[:, y] * g1[:, x] + p2[:, y] * g2[:, x])) / 120
    iyz = np.sum(d[:, y] * (p0[:, z] * g0[:, y] + p1[:, z] * g1[:, y] + p2[:, z] * g2[:, y])) / 120
    izx = np.sum(d[:, z] * (p0[:, x] * g0[:, z] + p1[:, x] * g1[:, z] + p2[:, x] * g2[:, z])) / 120
    volume = i1
    if not volume > 0:
        raise ValueError('mesh is invalid: allowed an outward-oriented closed mesh (its volume is %g m^3)' % volume)
    if (density is None) == (mass is None):
        raise ValueError('density, mass are invalid: allowed exactly one of them')
    rho = float(density) if density is not None else float(mass) / volume
    if not rho > 0 or not np.isfinite(rho):
        raise ValueError('%s = %r is invalid: allowed (0, inf)' % (('density', density) if density is not None
                                                                   else ('mass', mass)))
    cm = ix / volume
    # Second moments about the centre of mass (parallel-axis theorem), unit density, then scaled.
    sxx, syy, szz = ixx - volume * cm * cm
    sxy = ixy - volume * cm[x] * cm[y]
    syz = iyz - volume * cm[y] * cm[z]
    szx = izx - volume * cm[z] * cm[x]
    inertia = rho * np.array([[syy + szz, -sxy, -szx],
                              [-sxy, szz + sxx, -syz],
                              [-szx, -syz, sxx + syy]])
    return rho * volume, cm, inertia


def write_stl(path, vertices, triangles, name='woven'):
    """A binary STL of the mesh (the normals from the corners' order, outward for an outward mesh)."""
    v = np.asarray(vertices, dtype=float)
    t = np.asarray(triangles)
    rec = np.zeros(len(t), dtype=np.dtype([('n', '<f4', 3), ('v', '<f4', (3, 3)), ('a', '<u2')]))
    n = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    rec['n'] = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    rec['v'] = v[t]
    from .output import atomic_open
    with atomic_open(path, 'wb') as fh:
        fh.write(name.encode('ascii')[:80].ljust(80, b' '))
        fh.write(struct.pack('<I', len(t)))
        fh.write(rec.tobytes())


def revolve(profile, segments):
    """A closed, outward-oriented mesh of the solid of revolution about z of a profile
    [(r, z), ...] from the tail (z least) to the nose, r = 0 at both ends (poles)."""
    prof = [(float(r), float(z)) for r, z in profile]
    if prof[0][0] != 0 or prof[-1][0] != 0:
        raise ValueError('profile is invalid: allowed r = 0 at both ends')
    rings = prof[1:-1]
    phi = 2 * np.pi * np.arange(segments) / segments
    verts = [(0.0, 0.0, prof[0][1])]
    for r, z in rings:
        verts += [(r * np.cos(a), r * np.sin(a), z) for a in phi]
    verts.append((0.0, 0.0, prof[-1][1]))
    tail, nose = 0, len(verts) - 1
    tris = []
    ring = lambda k, j: 1 + k * segments + (j % segments)
    for j in range(segments):
        tris.append((tail, ring(0, j + 1), ring(0, j)))
        for k in range(len(rings) - 1):
            a, b, c, d = ring(k, j), ring(k, j + 1), ring(k + 1, j + 1), ring(k + 1, j)
            tris += [(a, b, c), (a, c, d)]
        tris.append((nose, ring(len(rings) - 1, j), ring(len(rings) - 1, j + 1)))
    return np.array(verts), np.array(tris, dtype=np.int64)


def square_ring(centre, inner_half, outer_half, z0, z1, round_top=0.0, round_bottom=0.0, segments=8):
    """A closed, outward-oriented mesh of a square frame: the slab z0 < z < z1 between the squares of
    half-sides `inner_half` < `outer_half` [m] about `centre` (x, y), its window open. The window's
    top and bottom edges may be rounded to radii `round_top`, `round_bottom` [m] (`segments` facets
    a quarter circle), so that a yarn drawn over the edge into the window bends over a curve as over
    a test rig's rounded jaw, not over a right angle. The section profile is swept round the square
    with mitred corners."""
    if not (0 < inner_half < outer_half and z0 < z1):
        raise ValueError('frame ring is invalid: allowed 0 < inner half-side < outer half-side and z0 < z1')
    W, T = outer_half - inner_half, z1 - z0
    if not (0 <= round_top and 0 <= round_bottom and round_top + round_bottom <= T and max(round_top, round_bottom) <= W):
        raise ValueError('frame ring is invalid: allowed edge radii >= 0, together at most the slab thickness and each '
                         'at most its width')
    cx, cy = float(centre[0]), float(centre[1])
    # The profile (u: outward from the window's edge, z), counter-clockwise in the (u, z) plane:
    # window side bottom to top over the rounded edges, the top, the outer side, the bottom.
    prof = []
    for a in np.linspace(-0.5 * np.pi, -np.pi, segments + 1) if round_bottom > 0 else []:
        prof.append((round_bottom * (1 + np.cos(a)), z0 + round_bottom * (1 + np.sin(a))))
    if round_bottom == 0:
        prof.append((0.0, z0))
    for a in np.linspace(np.pi, 0.5 * np.pi, segments + 1) if round_top > 0 else []:
        prof.append((round_top * (1 + np.cos(a)), z1 - round_top * (1 - np.sin(a))))
    if round_top == 0:
        prof.append((0.0, z1))
    prof += [(W, z1), (W, z0)]
    sq = [(-1, -1), (1, -1), (1, 1), (-1, 1)]  # counter-clockwise seen from above
    n = len(prof)
    v = np.array([(cx + (inner_half + u) * sx, cy + (inner_half + u) * sy, z) for sx, sy in sq for u, z in prof])
    idx = lambda k, j: (k % 4) * n + (j % n)
    t = []
    for k in range(4):
        for j in range(n):
            a, b, c, d = idx(k, j), idx(k + 1, j), idx(k + 1, j + 1), idx(k, j + 1)
            t += [(a, b, c), (a, c, d)]
    t = np.array(t, dtype=np.int64)
    if volume(v, t) < 0:
        t = t[:, ::-1]
    return v, t


NOSE_AXES = ('+x', '-x', '+y', '-y', '+z', '-z')
MAX_TRIANGLES = 200000


def _nose_turn(nose_axis):
    """Rotation matrix that takes the mesh's `nose_axis` onto +z (a proper rotation)."""
    if nose_axis not in NOSE_AXES:
        raise ValueError('nose_axis = %r is invalid: allowed %s' % (nose_axis, ', '.join(NOSE_AXES)))
    sign = 1.0 if nose_axis[0] == '+' else -1.0
    k = 'xyz'.index(nose_axis[1])
    a = np.zeros(3)
    a[k] = sign
    z = np.array([0.0, 0.0, 1.0])
    if np.allclose(a, z):
        return np.eye(3)
    if np.allclose(a, -z):
        return np.diag([1.0, -1.0, -1.0])  # half a turn about x
    axis = np.cross(a, z)
    axis /= np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + K + K @ K  # Rodrigues at a quarter turn (sin 1, 1 - cos 1)


def check_keys(scale, nose_axis):
    """Refuses a bad mesh_scale or nose_axis, naming the key (before any file is read)."""
    _nose_turn(nose_axis)
    if not (np.isfinite(scale) and 0 < scale <= 1e3):
        raise ValueError('mesh_scale = %r is invalid: allowed (0, 1e3] (1e-3 for a file in mm)' % (scale,))


def solid(path, scale=1.0, density=None, mass=None, nose_axis='+z'):
    """A mesh projectile from an STL file: the closed solid's triangles in its principal frame (origin
    at the centre of mass), its mass, principal inertia and frame.

    `scale` multiplies the file's coordinates (1e-3 for a file in mm); exactly one of `density`
    [kg/m^3] or `mass` [kg]; `nose_axis` ('+z', '-x', ...) the file's axis that points along the
    flight. Returns a dict: triangles (m, 3, 3) [m] in the principal frame, frame (3, 3) (columns:
    the principal axes in the nose frame, where the nose is +z), mass, volume, inertia (3,),
    radius (largest distance from the nose axis through the centre of mass) and half_length (half
    the extent along it) [m], file. Refuses an unreadable, open, non-manifold or inward mesh naming
    the file."""
    check_keys(scale, nose_axis)
    N = _nose_turn(nose_axis)
    try:
        v, t = read_stl(path, scale)
    except OSError as e:
        raise ValueError('mesh = %r is invalid: allowed a readable STL file (%s)' % (path, e.strerror))
    if len(t) > MAX_TRIANGLES:
        raise ValueError('mesh = %r is invalid: allowed at most %d triangles (it has %d)' % (path, MAX_TRIANGLES, len(t)))
    check_closed(t, 'mesh %r' % path)
    try:
        m, cm, I = mass_properties(v, t, density=density, mass=mass)
    except ValueError as e:
        raise ValueError('mesh %r: %s' % (path, e))
    x = (v - cm) @ N.T  # nose frame, origin at the centre of mass
    In = N @ I @ N.T
    moments, P = np.linalg.eigh(In)
    if np.linalg.det(P) < 0:
        P[:, 2] = -P[:, 2]
    xp = x @ P  # principal frame: x_p = P^T x
    return {'triangles': xp[t], 'frame': P, 'mass': float(m), 'volume': volume(v, t),
            'inertia': tuple(float(q) for q in moments), 'radius': float(np.max(np.hypot(x[:, 0], x[:, 1]))),
            'half_length': float(0.5 * (x[:, 2].max() - x[:, 2].min())), 'file': str(path), 'count': int(len(t))}


def volume(v, t):
    """Volume [m^3] the closed triangle mesh (vertices, triangles) bounds (negative: wound inward)."""
    p0, p1, p2 = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    return float(np.sum(np.einsum('ij,ij->i', p0, np.cross(p1, p2))) / 6)
