"""The same yarns as YADE PFacet ribbons (yade.gridpfacet, Effeindzourou et al. 2016), the baseline a
YADE user would build for a fabric: a yarn is a strip of triangles as wide as woven's section.

    O.engines = woven.yade_pfacet.engines()
    p = woven.yade_pfacet.build(w.engine, w.warp_yarns + w.weft_yarns, lines=2)   # after woven.weave(...)
    p.fix_ends(yarns)                      # clamps: every line's end node held
    O.dt = p.stable_dt(dt_factor=0.5)      # from the stiffest bonds and contacts at the lightest node

Mapping (docs/yade_grid.md, "PFacet ribbons", has the measured figures):
- stations: the grid baseline's node places on woven's polyline (woven.yade_grid._nodes_of_yarn: at
  1/4 and 3/4 of every woven element and the two yarn ends, so every crossing lies mid-chord).
- lines: at each station `lines` (>= 2) GridNodes across the yarn, on the horizontal perpendicular
  to the yarn's local direction (ez x tangent: in the fabric plane, across the yarn axis), evenly
  from -s to +s with s = (width - thickness)/2: the outer lines' nodes, half a thickness inside the
  section's edge, put the ribbon's rounded edge at woven's section width.
- connections: along each line (station j to j+1), across between neighbouring lines at every
  station, and one diagonal in every quad; each quad is two PFacets (gridpfacet.pfacet on the
  existing connections). Only PFacets are bounded for yarn contacts (gridpfacet.pfacet unbounds their
  nodes and connections).
- axial bonds: a line's bond gets kn = E*A/(lines*L) (L its node distance), so at every gap the lines
  together have woven's E*A/L (measured by a static pull in tests/python/test_yade_pfacet.py). The
  across bonds get the stiffness of the line bonds beside them, E*A/(lines*L_station) (L_station:
  the mean of the station's line gaps): they hold the width about as stiffly as a line holds its
  length, and add no more than the line bonds to the time step's Gershgorin sum. The diagonals get
  kn = 0: at an angle to the axis any stiffness there adds k_d*cos^2 to the axial stiffness; they
  only close the PFacets. So a quad shears in plane and twists (its lines move apart out of plane)
  freely, as a strip of loose parallel fibres would. Shear, bending and twist springs of every bond
  are zeroed (woven's yarns have none): a shear spring on the across bonds, tried to keep the section
  flat, also resisted the bond's rigid rotation (YADE's shear increment is the relative motion of
  unturning nodes) and lost 2.7 % of the energy in 4 us. Bonds are set on the interactions after
  gridpfacet.gridConnection (which gives young*pi*r^2/L); YADE's bonds also push, woven's yarns are
  tension-only.
- rotations: the nodes do not turn (blocked, as woven's nodes): with friction a contact's shear
  would spin a node of inertia 0.4*m*r^2 faster than the Gershgorin step allows for, and nothing in
  the ribbon needs the rotation.
- masses: a line carries rho*A/lines per length of woven yarn; half of the woven length each chord
  stands for (yade_grid's material length) goes to each of its two nodes, so the total is woven's to
  rounding (b.state.mass set after gridpfacet's own volume lumping).
- breakage: with `failure_strain` > 0 the line bonds are fragile with normalAdhesion =
  E*A*eps_f/lines (YADE breaks a fragile bond when its tensile force passes normalAdhesion): a line
  breaks at the failure strain (raw, not time-filtered as woven's); the across and diagonal bonds
  never break. Each bond's adhesion is set on its interaction, so engines() has the cohesive Ip2
  with setCohesionNow off (on, it resets every bond to the nodes' material at the first step).
  remove_broken() erases, for a broken line bond, the two PFacets of each quad beside it, the
  quads' diagonals and the line's connection (the across connections stay: the quads on their
  other side still use them).
- radius: one radius for nodes, connections and PFacets (YADE requires it), half the yarn thickness
  unless warp and weft ribbons would then overlap as built: then half their smallest distance (they
  just touch). Flat ribbons of a crimped weave come closest at the corners of a crossing's patch,
  where both yarns slope towards each other: for KM2 706 the distance there is t*(1 - 2s/spacing),
  so the radius is 15 um, not 55 um (a lenticular section, which PFacets cannot have, would fit).
- contacts: PFacet-PFacet between warp and weft (Ig2_PFacet_PFacet_ScGeom hands each pair to its
  nodes, node-PFacet through Ig2_Sphere_PFacet_ScGridCoGeom, and to its connections,
  Ig2_GridConnection_GridConnection_GridCoGridCoGeom); FrictPhys from FrictMat, YADE's
  kn = 2*E1*r1*E2*r2/(E1*r1 + E2*r2) = young*r for equal radii and moduli, so nodes, connections and
  PFacets all get the contact young = kn/r. Masks as in yade_grid: a ribbon's PFacets never meet
  those of its own family.
- projectile: YADE 2023.02a has no Box-PFacet functor, so a box meets only the nodes, as spheres of
  radius r (Ig2_Box_Sphere_ScGeom, as in the grid baseline). A sphere meets the PFacets
  (Ig2_Sphere_PFacet_ScGridCoGeom, mask CONNECTION_MASK) or the nodes (Ig2_Sphere_Sphere_ScGeom, mask
  BOX_MASK): the PFacet functor picks the edge it measures from the barycentric signs of the sphere
  centre's projection, which for a sphere millimetres across lands far off these sub-millimetre,
  crimp-tilted triangles; the depth then jumped between edges (7 to 79 um in one step) and flung a
  node at 5-6 times the impact speed at any time step. projectile_material() picks the young that
  gives kn.
SI units throughout.
"""
import math

import numpy as np
import yade.wrapper
from yade._minieigenHP import Vector3
from yade.wrapper import (CohFrictMat, FrictMat, ForceResetter, InsertionSortCollider, Bo1_PFacet_Aabb,
                          Bo1_Sphere_Aabb, Bo1_Box_Aabb, InteractionLoop, Ig2_GridNode_GridNode_GridNodeGeom6D,
                          Ig2_GridConnection_GridConnection_GridCoGridCoGeom, Ig2_Sphere_PFacet_ScGridCoGeom,
                          Ig2_PFacet_PFacet_ScGeom, Ig2_Box_Sphere_ScGeom, Ig2_Sphere_Sphere_ScGeom,
                          Ip2_CohFrictMat_CohFrictMat_CohFrictPhys,
                          Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom6D_CohFrictPhys_CohesionMoment,
                          Law2_GridCoGridCoGeom_FrictPhys_CundallStrack, Law2_ScGridCoGeom_FrictPhys_CundallStrack,
                          Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator, GridCoGridCoGeom, ScGridCoGeom)

from . import arrays
from .yade_grid import CONNECTION_MASK, WARP_MASK, WEFT_MASK, NODE_MASK, BOX_MASK, _nodes_of_yarn  # noqa: F401

_O = yade.wrapper.Omega()

#: allowed numbers of node lines across a ribbon
LINES_RANGE = (2, 16)
# An adhesion no force reaches: bonds that must not break.
_NEVER = 1e30


def engines(damping=0.0):
    """O.engines for a PFacet fabric (set before build(): gridConnection creates the bonds through the
    InteractionLoop's functors). NewtonIntegrator damping is YADE's numerical damping (0: none)."""
    return [
        ForceResetter(),
        InsertionSortCollider([Bo1_PFacet_Aabb(), Bo1_Sphere_Aabb(), Bo1_Box_Aabb()],
                              avoidSelfInteractionMask=2 | 4 | 8, label='pfacetCollider'),
        InteractionLoop(
            [Ig2_GridNode_GridNode_GridNodeGeom6D(), Ig2_PFacet_PFacet_ScGeom(), Ig2_Sphere_PFacet_ScGridCoGeom(),
             Ig2_GridConnection_GridConnection_GridCoGridCoGeom(), Ig2_Box_Sphere_ScGeom(), Ig2_Sphere_Sphere_ScGeom()],
            # no cohesion from the materials: build() sets each bond's own (setCohesionNow would reset
            # them all to the nodes' material at the first step)
            [Ip2_CohFrictMat_CohFrictMat_CohFrictPhys(setCohesionNow=False, setCohesionOnNewContacts=False),
             Ip2_FrictMat_FrictMat_FrictPhys()],
            [Law2_ScGeom6D_CohFrictPhys_CohesionMoment(), Law2_ScGridCoGeom_FrictPhys_CundallStrack(),
             Law2_GridCoGridCoGeom_FrictPhys_CundallStrack(), Law2_ScGeom_FrictPhys_CundallStrack()],
            label='pfacetLoop'),
        NewtonIntegrator(damping=damping, gravity=(0, 0, 0), label='pfacetNewton'),
    ]


# --- geometry: distances between triangle sets, vectorised (for the just-touching radius) -------------
def _seg_seg(p0, p1, q0, q1):
    """Smallest distances [m] between segments p0p1 and q0q1, arrays of shape (n, 3) (clamped closest
    points, yade_grid._segment_distance row by row)."""
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a = np.einsum('ij,ij->i', d1, d1)
    e = np.einsum('ij,ij->i', d2, d2)
    f = np.einsum('ij,ij->i', d2, r)
    c = np.einsum('ij,ij->i', d1, r)
    b = np.einsum('ij,ij->i', d1, d2)
    den = a * e - b * b
    with np.errstate(divide='ignore', invalid='ignore'):
        s = np.where(den > 1e-30 * a * e, np.clip((b * f - c * e) / den, 0, 1), 0.0)
        t = (b * s + f) / e
        s = np.where(t < 0, np.clip(-c / a, 0, 1), np.where(t > 1, np.clip((b - c) / a, 0, 1), s))
    t = np.clip(t, 0, 1)
    return np.linalg.norm(p0 + s[:, None] * d1 - q0 - t[:, None] * d2, axis=1)


def _point_triangle_inside(P, A, B, C):
    """Distances [m] of points P from the planes of triangles ABC where P projects inside the triangle,
    inf elsewhere (there the edge-edge distances are the nearest); arrays of shape (n, 3)."""
    n = np.cross(B - A, C - A)
    n /= np.linalg.norm(n, axis=1)[:, None]
    h = np.einsum('ij,ij->i', P - A, n)
    Q = P - h[:, None] * n
    v0, v1, v2 = B - A, C - A, Q - A
    d00, d01, d11 = (np.einsum('ij,ij->i', x, y) for x, y in ((v0, v0), (v0, v1), (v1, v1)))
    d20, d21 = np.einsum('ij,ij->i', v2, v0), np.einsum('ij,ij->i', v2, v1)
    den = d00 * d11 - d01 * d01
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    inside = (v >= 0) & (w >= 0) & (v + w <= 1)
    return np.where(inside, np.abs(h), np.inf)


def _triangle_sets_distance(T, U):
    """Smallest distance [m] between any triangle of T and any of U (shape (n, 3, 3), (m, 3, 3)): the
    least of vertex-to-face (projection inside) and edge-to-edge distances, exact for triangles that
    do not intersect."""
    if len(T) == 0 or len(U) == 0:
        return math.inf
    n, m = len(T), len(U)
    Ti, Uj = np.repeat(T, m, axis=0), np.tile(U, (n, 1, 1))
    best = math.inf
    for a, b in ((Ti, Uj), (Uj, Ti)):  # vertices of one against the faces of the other
        for k in range(3):
            best = min(best, float(_point_triangle_inside(a[:, k], b[:, 0], b[:, 1], b[:, 2]).min()))
    for u in range(3):
        for v in range(3):
            best = min(best, float(_seg_seg(Ti[:, u], Ti[:, (u + 1) % 3], Uj[:, v], Uj[:, (v + 1) % 3]).min()))
    return best


def _triangles(R, j0, j1):
    """Triangles of ribbon R (node positions, shape (lines, stations, 3)) between stations j0 and j1:
    the two PFacets of every quad, as build() makes them. Shape (n, 3, 3)."""
    T = []
    for k in range(R.shape[0] - 1):
        for j in range(max(j0, 0), min(j1, R.shape[1] - 1)):
            a, b, c, d = R[k, j], R[k + 1, j], R[k + 1, j + 1], R[k, j + 1]
            T.append((a, b, c))
            T.append((a, c, d))
    return np.array(T).reshape(-1, 3, 3)


def _ribbon(pts, lines, s):
    """Node positions (lines, stations, 3) of a ribbon on the station points `pts` (stations, 3):
    line k at -s + 2 s k/(lines - 1) along ez x tangent, the horizontal across the yarn."""
    t = np.gradient(pts, axis=0)  # central differences inside, one-sided at the ends
    t /= np.linalg.norm(t, axis=1)[:, None]
    across = np.cross(np.array([0.0, 0.0, 1.0]), t)
    norm = np.linalg.norm(across, axis=1)
    if not np.all(norm > 1e-6):
        raise ValueError('a yarn runs vertically: no horizontal across-direction for its ribbon')
    across /= norm[:, None]
    return np.array([pts + c * across for c in np.linspace(-s, s, lines)])


class PFacetFabric:
    """PFacet-ribbon version of woven yarns. For yarn y (woven's yarn order as given):
    lines[y][k][j]: node id of line k at station j; nodes[y]: all its node ids; along[y][k][j]: the
    connection of line k from station j to j+1; across[y][k][j]: the connection from line k to k+1 at
    station j; diagonal[y][k][j]: the quad's diagonal, line k station j to line k+1 station j+1;
    pfacets[y]: PFacet ids, quad_of[pfacet id] = (y, k, j); connections[y]: all its connection ids.
    K[y][k][j]: line bond stiffness [N/m] (E*A/(lines*L)); radius [m]; kn: contact stiffness [N/m];
    young_contact [Pa]; break_force: a line bond's tensile force at the failure strain [N] (inf: never);
    broken: (yarn, line, gap, time) of every line bond that broke; woven_mass [kg]."""

    def node_ids(self):
        return [i for ids in self.nodes for i in ids]

    def connection_ids(self):
        return [i for ids in self.connections for i in ids if i >= 0]

    def pfacet_ids(self):
        return [i for ids in self.pfacets for i in ids if i >= 0]

    def total_mass(self):
        """Sum of the node masses [kg] (connections and PFacets carry none in YADE's dynamics)."""
        return sum(_O.bodies[i].state.mass for i in self.node_ids())

    def end_nodes(self, k):
        """(the first station's node ids, the last station's) of yarn k: its clamp or grip."""
        return [ln[0] for ln in self.lines[k]], [ln[-1] for ln in self.lines[k]]

    def yarn_length(self, k):
        """Mean polyline length of yarn k's lines through their nodes now [m]."""
        out = []
        for ln in self.lines[k]:
            X = np.array([list(_O.bodies[i].state.pos) for i in ln])
            out.append(np.linalg.norm(np.diff(X, axis=0), axis=1).sum())
        return float(np.mean(out))

    def fix_ends(self, which=None):
        """Holds the end nodes of every line of the yarns listed (indices into lines; None: all)."""
        for k in (range(len(self.lines)) if which is None else which):
            first, last = self.end_nodes(k)
            for i in first + last:
                b = _O.bodies[i]
                b.state.blockedDOFs = 'xyzXYZ'
                b.state.vel = Vector3(0, 0, 0)

    def stable_dt(self, dt_factor=0.5, extra_contacts=4):
        """dt_factor * critical step [s]: Gershgorin's bound on the highest frequency of the free
        nodes, omega^2 <= 2*sum(k)/m, with every bond at the node (line, across, diagonal) and
        `extra_contacts` contacts of stiffness kn; dt_crit = 2/omega (yade_grid.GridFabric.stable_dt
        with the ribbon's bonds)."""
        worst = float('inf')
        for i, ks in self.bond_sum.items():
            b = _O.bodies[i]
            if b.state.blockedDOFs == 'xyzXYZ':
                continue
            w2 = 2 * (ks + extra_contacts * self.kn) / b.state.mass
            worst = min(worst, 2 / math.sqrt(w2))
        return dt_factor * worst

    def remove_broken(self):
        """Erases what a broken line bond leaves: the two PFacets of each quad beside it (a cut
        ribbon no longer collides across the cut), those quads' diagonals and its own connection; the
        across connections stay (the quads on their other side use them). Returns how many line bonds
        broke since the last call."""
        n = 0
        for y, lines in enumerate(self.along):
            for k, ids in enumerate(lines):
                for j, cid in enumerate(ids):
                    if cid < 0:
                        continue
                    a, b = self.lines[y][k][j], self.lines[y][k][j + 1]
                    i = _O.interactions[a, b] if _O.interactions.has(a, b) else None
                    if i is not None and i.isReal:
                        continue
                    # the quads beside this line gap: between lines k-1, k and k, k+1
                    for q in (k - 1, k):
                        if 0 <= q < len(self.lines[y]) - 1:
                            for pid in self.quad_pfacets[y][q][j]:
                                if pid >= 0 and _O.bodies[pid] is not None:
                                    _O.bodies.erase(pid)
                            self.quad_pfacets[y][q][j] = [-1, -1]
                            d = self.diagonal[y][q][j]
                            if d >= 0:
                                _O.bodies.erase(d)
                                self.diagonal[y][q][j] = -1
                    _O.bodies.erase(cid)
                    ids[j] = -1
                    self.broken.append((y, k, j, _O.time))
                    n += 1
        if n:
            self._refresh_lists()
        return n

    def _refresh_lists(self):
        live = set(b.id for b in _O.bodies if b is not None)
        self.connections = [[c for c in ids if c in live] for ids in self.connections]
        self.pfacets = [[f for f in ids if f in live] for ids in self.pfacets]

    def max_overlap(self):
        """Largest penetrationDepth [m] among yarn-yarn contacts now (node-PFacet and
        connection-connection; the projectile's are left out), 0 if none."""
        m = 0.0
        for i in _O.interactions:
            g = i.geom
            ids = (i.id1, i.id2)  # YADE may hold a node-PFacet pair either way round
            if isinstance(g, GridCoGridCoGeom) or (isinstance(g, ScGridCoGeom) and any(x in self.node_set for x in ids)
                                                   and any(x in self.pfacet_set for x in ids)):
                m = max(m, g.penetrationDepth)
        return m


def _touch_radius(ribbons, crossings, reach):
    """Half the smallest distance [m] between the triangles of the ribbons that cross (pairs of
    indices into `ribbons`), each near its crossing: the stations within `reach` of it in plan view."""
    best = math.inf
    for i, j in crossings:
        P, Q = ribbons[i], ribbons[j]
        cp, cq = P.mean(axis=0), Q.mean(axis=0)  # centre lines (stations, 3)
        mp, mq = 0.5 * (cp[:-1] + cp[1:]), 0.5 * (cq[:-1] + cq[1:])
        dxy = np.linalg.norm(mp[:, None, :2] - mq[None, :, :2], axis=2)
        a, b = np.unravel_index(np.argmin(dxy), dxy.shape)
        c = 0.5 * (mp[a, :2] + mq[b, :2])
        near_p = np.nonzero(np.linalg.norm(cp[:, :2] - c, axis=1) < reach)[0]
        near_q = np.nonzero(np.linalg.norm(cq[:, :2] - c, axis=1) < reach)[0]
        if len(near_p) == 0 or len(near_q) == 0:
            continue
        T = _triangles(P, near_p.min() - 1, near_p.max() + 1)
        U = _triangles(Q, near_q.min() - 1, near_q.max() + 1)
        best = min(best, _triangle_sets_distance(T, U))
    return 0.5 * best


def build(engine, yarns, lines=2, kn=0.0, radius=0.0, failure_strain=0.0, friction=0.0, crossings=None,
          offset=0.25):
    """Builds the yarns `yarns` of woven FabricEngine `engine` (at their current positions) as PFacet
    ribbons of `lines` node lines and returns a PFacetFabric. Call after O.engines = engines().

    lines [-]: node lines across a ribbon, an integer in [2, 16]. kn [N/m]: contact stiffness, > 0,
    or 0 for the yarn element's E*A/l0 (the first yarn's, at its mean l0). radius [m]: > 0, or 0 for
    half the yarn thickness, less where warp and weft ribbons would overlap as built (then they just
    touch; `crossings`: pairs (yarn_a, yarn_b) of indices into `yarns` to check, default all warp-weft
    pairs). failure_strain [-]: 0 (bonds never break) or in (0, 10]. friction [-]: Coulomb coefficient
    of the contacts, >= 0. offset [-]: where the stations sit on each woven element (fraction of its
    length from either end, in (0, 0.5); 0: on woven's nodes)."""
    if not (isinstance(lines, (int, np.integer)) and not isinstance(lines, bool)
            and LINES_RANGE[0] <= lines <= LINES_RANGE[1]):
        raise ValueError('pfacet_lines = %r is invalid: allowed an integer in [%d, %d]' % ((lines,) + LINES_RANGE))
    if not (offset == 0 or 0 < offset < 0.5):
        raise ValueError('offset = %r is invalid: allowed 0 or (0, 0.5)' % offset)
    if not (math.isfinite(kn) and kn >= 0):
        raise ValueError('kn = %r is invalid: allowed [0, inf) N/m (0: E*A/l0 of the yarn element)' % kn)
    if not (math.isfinite(radius) and radius >= 0):
        raise ValueError('grid_radius = %r is invalid: allowed [0, inf) m (0: half the yarn thickness, or less '
                         'where the ribbons would overlap)' % radius)
    if not (math.isfinite(failure_strain) and 0 <= failure_strain <= 10):
        raise ValueError('failure_strain = %r is invalid: allowed 0 (no breakage) or (0, 10]' % failure_strain)
    if not (math.isfinite(friction) and friction >= 0):
        raise ValueError('friction = %r is invalid: allowed [0, inf)' % friction)
    from yade.gridpfacet import gridNode, gridConnection, pfacet
    Xall = arrays.positions(engine)
    mall = arrays.masses(engine)
    infos = [engine.yarn(y) for y in yarns]
    for info in infos:
        if not (info['width'] > info['thickness'] > 0):
            raise ValueError('yarn %s: section width %g m and thickness %g m: a ribbon needs width > thickness > 0'
                             % (info['family'], info['width'], info['thickness']))
    chains, ribbons = [], []
    for info in infos:
        a = info['first_node']
        pts, lmat = _nodes_of_yarn(Xall[a:a + info['n_nodes']], offset)
        chains.append((pts, lmat))
        ribbons.append(_ribbon(pts, lines, 0.5 * (info['width'] - info['thickness'])))
    if crossings is None:
        fam = [info['family'] for info in infos]
        crossings = [(i, j) for i in range(len(yarns)) for j in range(len(yarns)) if fam[i] == 'warp' and fam[j] == 'weft']
    r_half = 0.5 * min(info['thickness'] for info in infos)
    if radius > 0:
        r, r_touch = radius, None
    else:
        chord = max(float(np.linalg.norm(np.diff(pts, axis=0), axis=1).max()) for pts, _ in chains)
        reach = max(info['width'] for info in infos) + chord
        r_touch = _touch_radius(ribbons, crossings, reach) if crossings else math.inf
        r = min(r_half, r_touch)
    if not (math.isfinite(r) and r > 0):
        raise ValueError('grid_radius = %r is invalid: the ribbons touch as built (distance %g m); give grid_radius '
                         '> 0 m' % (radius, 2 * r))
    info0 = infos[0]
    l0_mean = float(np.mean(arrays.rest_lengths(engine)[info0['first_element']:info0['first_element'] + info0['n_elements']]))
    k_contact = kn if kn > 0 else info0['E'] * info0['area'] / l0_mean
    p = PFacetFabric()
    p.lines_per_yarn, p.radius, p.radius_touch, p.kn = lines, r, r_touch, k_contact
    p.young_contact = k_contact / r
    p.contact_material = _O.materials.append(FrictMat(young=p.young_contact, poisson=0.3, density=info0['rho'],
                                                      frictionAngle=math.atan(friction), label='pfacetContact'))
    # The nodes' material makes the bonds (their kn and adhesion are set on each interaction below)
    # and is one side of every node-PFacet contact: the contact young too, so those contacts get kn.
    p.node_material = _O.materials.append(CohFrictMat(young=p.young_contact, poisson=0.3, density=info0['rho'],
                                                      frictionAngle=math.atan(friction), normalCohesion=_NEVER,
                                                      shearCohesion=_NEVER, isCohesive=True, momentRotationLaw=False,
                                                      fragile=True, label='pfacetNodes'))
    p.bond_materials = [p.node_material]
    p.lines, p.nodes, p.along, p.across, p.diagonal = [], [], [], [], []
    p.quad_pfacets, p.pfacets, p.connections, p.K, p.length0, p.material_length = [], [], [], [], [], []
    p.broken, p.bond_sum, p.quad_of = [], {}, {}
    p.break_force = math.inf
    p.EA = [info['E'] * info['area'] for info in infos]
    p.stations = []

    def bond(i1, i2, k, adhesion, mask, ks=0.0):
        """A GridConnection i1-i2 and its bond: normal stiffness k [N/m], shear stiffness ks [N/m]
        (0 here, see the module's docstring), breaking past `adhesion` [N]."""
        cid = _O.bodies.append(gridConnection(i1, i2, r, material=p.contact_material, mask=mask))
        it = _O.interactions[i1, i2]
        it.phys.kn, it.phys.ks = k, ks
        it.phys.kr = it.phys.ktw = 0.0
        it.phys.cohesionBroken, it.phys.fragile, it.phys.initCohesion = False, True, False
        it.phys.normalAdhesion = adhesion
        it.phys.shearAdhesion = _NEVER
        # Gershgorin: the bond's stiffness matrix kn n n^T + ks (1 - n n^T) has spectral radius max(kn, ks)
        p.bond_sum[i1] = p.bond_sum.get(i1, 0.0) + max(k, ks)
        p.bond_sum[i2] = p.bond_sum.get(i2, 0.0) + max(k, ks)
        return cid

    for y, (info, (pts, lmat), R) in enumerate(zip(infos, chains, ribbons)):
        EA = info['E'] * info['area']
        mask = WEFT_MASK if info['family'] == 'weft' else WARP_MASK
        adhesion = EA * failure_strain / lines if failure_strain > 0 else _NEVER
        if failure_strain > 0:
            p.break_force = EA * failure_strain / lines
        ns = R.shape[1]
        ids = [[_O.bodies.append(gridNode(tuple(R[k, j]), r, fixed=False, material=p.node_material))
                for j in range(ns)] for k in range(lines)]
        conns = []
        Ky = np.zeros((lines, ns - 1))
        along = []
        for k in range(lines):
            row = []
            for j in range(ns - 1):
                L = float(np.linalg.norm(R[k, j + 1] - R[k, j]))
                Ky[k, j] = EA / (lines * L)
                row.append(bond(ids[k][j], ids[k][j + 1], Ky[k, j], adhesion, mask))
            along.append(row)
            conns += row
        across, diag, quads, pfs = [], [], [], []
        for k in range(lines - 1):
            arow, drow, qrow = [], [], []
            for j in range(ns):
                # the line bonds beside station j (one at an end station)
                kl = [Ky[k, jj] for jj in (j - 1, j) if 0 <= jj < ns - 1] + [Ky[k + 1, jj] for jj in (j - 1, j) if 0 <= jj < ns - 1]
                arow.append(bond(ids[k][j], ids[k + 1][j], float(np.mean(kl)), _NEVER, mask))
            for j in range(ns - 1):
                drow.append(bond(ids[k][j], ids[k + 1][j + 1], 0.0, _NEVER, mask))
            for j in range(ns - 1):
                a, b, c, d = ids[k][j], ids[k + 1][j], ids[k + 1][j + 1], ids[k][j + 1]
                two = [_O.bodies.append(pfacet(a, b, c, material=p.contact_material, mask=mask)),
                       _O.bodies.append(pfacet(a, c, d, material=p.contact_material, mask=mask))]
                for f in two:
                    p.quad_of[f] = (y, k, j)
                qrow.append(two)
                pfs += two
            across.append(arow)
            diag.append(drow)
            quads.append(qrow)
            conns += arow + drow
        # the nodes as spheres for a box projectile (mask NODE_MASK meets only BOX_MASK): gridpfacet.pfacet
        # unbounded them; they never meet each other (avoidSelfInteractionMask) nor a PFacet (no common bit)
        for row in ids:
            for i in row:
                _O.bodies[i].mask = NODE_MASK
                _O.bodies[i].bounded = True
                _O.bodies[i].state.blockedDOFs = 'XYZ'  # (module docstring: rotations)
        # masses: a line carries rho*A/lines per woven length; half of each chord's material length to
        # each of its nodes
        rhoA = info['rho'] * info['area'] / lines
        m = np.zeros(ns)
        m[:-1] += 0.5 * rhoA * lmat
        m[1:] += 0.5 * rhoA * lmat
        for row in ids:
            for i, mi in zip(row, m):
                b = _O.bodies[i]
                b.state.mass = float(mi)
                I = 0.4 * float(mi) * r * r  # a solid sphere of the node's radius: only its own rotation
                b.state.inertia = Vector3(I, I, I)
        p.lines.append(ids)
        p.nodes.append([i for row in ids for i in row])
        p.along.append(along)
        p.across.append(across)
        p.diagonal.append(diag)
        p.quad_pfacets.append(quads)
        p.pfacets.append(pfs)
        p.connections.append(conns)
        p.K.append(Ky)
        p.length0.append(np.linalg.norm(np.diff(R, axis=1), axis=2))
        p.material_length.append(lmat)
        p.stations.append(pts)
    p.node_set = set(p.node_ids())
    p.pfacet_set = set(p.pfacet_ids())
    p.woven_mass = float(sum(mall[info['first_node']:info['first_node'] + info['n_nodes']].sum() for info in infos))
    return p


def projectile_material(p, shape, size):
    """A FrictMat for a projectile ('sphere' of diameter `size` [m] or 'box') whose contacts with the
    ribbons have normal stiffness p.kn [N/m] (YADE's harmonic mean 2ab/(a+b) of the two young*radius
    products solved for the projectile's). A sphere meets the PFacets, a box the nodes (both of
    young_contact and radius r). Returns the material id."""
    b = p.young_contact * p.radius  # = kn
    a = p.kn * b / (2 * b - p.kn)   # = kn
    young = a / (0.5 * size) if shape == 'sphere' else a / p.radius  # Ig2_Box_Sphere_ScGeom: both radii the node's
    return _O.materials.append(FrictMat(young=young, poisson=0.3, density=1000.0, frictionAngle=0.0,
                                        label='projectile'))
