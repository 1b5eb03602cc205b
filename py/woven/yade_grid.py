"""The same yarns in YADE's own grid elements (yade.gridpfacet), the baseline woven is compared with.

    g = woven.yade_grid.build(w.engine, w.warp_yarns + w.weft_yarns, kn=0)   # after woven.weave(...)
    g.fix_ends(yarns)                      # clamps: the yarn's end nodes held
    O.dt = g.stable_dt(dt_factor=0.5)      # from the stiffest bond / contact at the lightest node

Mapping (docs/yade_grid.md has the measured calibration):
- nodes: on woven's yarn polyline, at 1/4 and 3/4 of every woven element (`offset`), and the two
  yarn ends. Woven puts a node on every crossing (WeaveBuilder: node q = k*cp_per_span is crossing
  k), so every crossing lies in the middle of the chord that joins the points a quarter element
  either side of it, never on a grid node, where YADE would count the contact on both connections
  that share the node. Nodes in the middle between crossings would not do: in a plain weave that
  middle is the centre line's inflection at z = 0 and the straight connections would lie flat, warp
  and weft through each other. Two connections per woven element, each about l0/2 long.
- masses: each GridConnection stands for the material length of woven's yarn it replaces (the
  middle half of a woven element, or the quarters either side of a woven node); half of its mass
  rho*A*length goes to each node, so the total is woven's up to rounding. b.state.mass is set
  after gridpfacet's own volume-based lumping.
- axial bonds: gridpfacet.gridConnection sets the node-node bond's kn = young*pi*r^2/L (L the
  node distance), so the node material's young is E*A/(pi*r^2): kn = E*A/L, woven's K = E*A/l0
  with its fibre area A (measured by a static pull in tests/python/test_yade_grid.py). Bending,
  shear and twist springs of the bond are zeroed unless `bending` (woven's yarns have none).
  YADE's bonds also push: woven's yarns are tension-only.
- breakage: with `failure_strain` > 0 the bond is fragile, normalCohesion = E*A*eps_f/r^2 (YADE's
  adhesion is normalCohesion*r^2), so it breaks when its force passes E*A*eps_f, i.e. at the failure
  strain (raw, not time-filtered as woven's). A broken connection is erased by `remove_broken`.
- radius: one circular radius for both families, half the smallest distance between crossing
  connections as built (the yarns at crossings just touch), unless given.
- contacts: GridConnection-GridConnection (Ig2_GridConnection_GridConnection_GridCoGridCoGeom,
  Law2_GridCoGridCoGeom_FrictPhys_CundallStrack) with FrictPhys from FrictMat; YADE sets
  kn = 2*E1*r1*E2*r2/(E1*r1 + E2*r2) = young*r for two equal connections, so young = kn/r.
  Sphere projectiles meet the connections (Ig2_Sphere_GridConnection_ScGridCoGeom, kn = harmonic
  mean of young_s*R and young_c*r), boxes the nodes only (YADE 2023.02a has no Box-GridConnection
  functor; Ig2_Box_Sphere_ScGeom sees a GridNode as a sphere of radius r, kn = harmonic mean of
  young_box*r and young_node*r). projectile_material() picks the young that gives kn.
SI units throughout.
"""
import math

import numpy as np
import yade.wrapper
from yade import utils
from yade._minieigenHP import Vector3
from yade.wrapper import (CohFrictMat, FrictMat, ForceResetter, InsertionSortCollider, Bo1_GridConnection_Aabb,
                          Bo1_Sphere_Aabb, Bo1_Box_Aabb, InteractionLoop, Ig2_GridNode_GridNode_GridNodeGeom6D,
                          Ig2_GridConnection_GridConnection_GridCoGridCoGeom, Ig2_Sphere_GridConnection_ScGridCoGeom,
                          Ig2_Box_Sphere_ScGeom, Ip2_CohFrictMat_CohFrictMat_CohFrictPhys, Ip2_FrictMat_FrictMat_FrictPhys,
                          Law2_ScGeom6D_CohFrictPhys_CohesionMoment, Law2_GridCoGridCoGeom_FrictPhys_CundallStrack,
                          Law2_ScGridCoGeom_FrictPhys_CundallStrack, Law2_ScGeom_FrictPhys_CundallStrack,
                          NewtonIntegrator, GridCoGridCoGeom)

from . import arrays

_O = yade.wrapper.Omega()

# Masks. YADE's collider pairs two bodies when their masks share a bit, except two bodies of one
# mask that shares a bit with avoidSelfInteractionMask. Warp connections (1|4) meet weft ones (1|8)
# and a sphere projectile (1), never another warp connection: the connections of one yarn a few
# l0/2 apart would otherwise touch (l0/2 < 2r at fine resolutions); contacts between neighbouring
# yarns of one family are lost with them. GridConnection derives from Sphere in YADE, so a box
# would meet each connection as a sphere at its first node: a box (2|16) meets only the nodes (2),
# which never meet each other.
CONNECTION_MASK = 1            # a sphere projectile's mask
WARP_MASK, WEFT_MASK = 1 | 4, 1 | 8
NODE_MASK = 2
BOX_MASK = 2 | 16

#: keys of the YADE models in the scene scripts (model=yade, and model=yade_pfacet: woven.yade_pfacet):
#: (default, unit, description)
GRID_KEYS = {
    'kn': (0.0, 'N/m', 'model=yade / yade_pfacet: normal stiffness of yarn-yarn and projectile contacts; 0: the yarn '
                       'element axial stiffness E*A/l0'),
    'grid_radius': (0.0, 'm', 'model=yade: radius of the grid cylinders; 0: half the smallest centre distance of crossing '
                              'connections (they just touch); model=yade_pfacet: the ribbons\' radius; 0: half the yarn '
                              'thickness, or less where warp and weft ribbons would overlap (they just touch)'),
    'bending': (False, '', 'model=yade: keep YADE bending/shear/twist springs of the bonds (woven yarns have none)'),
    'dt_factor': (0.5, '', 'model=yade / yade_pfacet: O.dt = dt_factor * the critical step of the stiffest bond or contact'),
    'pfacet_lines': (2, '', 'model=yade_pfacet: node lines across each PFacet ribbon, an integer in [2, 16]'),
    'pfacet_projectile': ('nodes', '', "model=yade_pfacet: what a sphere projectile meets: 'nodes' (the ribbons' grid nodes, "
                          "Ig2_Sphere_Sphere_ScGeom) or 'pfacets' (Ig2_Sphere_PFacet_ScGridCoGeom; its contact depth "
                          "jumps on these small tilted triangles, docs/yade_grid.md)"),
}


def engines(damping=0.0):
    """O.engines for a grid fabric (set before build(): gridConnection creates the bonds through the
    InteractionLoop's functors). NewtonIntegrator damping is YADE's numerical damping (0: none)."""
    return [
        ForceResetter(),
        InsertionSortCollider([Bo1_GridConnection_Aabb(), Bo1_Sphere_Aabb(), Bo1_Box_Aabb()],
                              avoidSelfInteractionMask=2 | 4 | 8, label='gridCollider'),
        InteractionLoop(
            [Ig2_GridNode_GridNode_GridNodeGeom6D(), Ig2_GridConnection_GridConnection_GridCoGridCoGeom(),
             Ig2_Sphere_GridConnection_ScGridCoGeom(), Ig2_Box_Sphere_ScGeom()],
            [Ip2_CohFrictMat_CohFrictMat_CohFrictPhys(setCohesionNow=True, setCohesionOnNewContacts=False),
             Ip2_FrictMat_FrictMat_FrictPhys()],
            [Law2_ScGeom6D_CohFrictPhys_CohesionMoment(), Law2_GridCoGridCoGeom_FrictPhys_CundallStrack(),
             Law2_ScGridCoGeom_FrictPhys_CundallStrack(), Law2_ScGeom_FrictPhys_CundallStrack()],
            label='gridLoop'),
        NewtonIntegrator(damping=damping, gravity=(0, 0, 0), label='gridNewton'),
    ]


def _segment_distance(p0, p1, q0, q1):
    """Smallest distance [m] between segments p0p1 and q0q1 (clamped closest points)."""
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e, f = d1 @ d1, d2 @ d2, d2 @ r
    c, b = d1 @ r, d1 @ d2
    den = a * e - b * b
    s = np.clip((b * f - c * e) / den, 0, 1) if den > 1e-30 * a * e else 0.0
    t = (b * s + f) / e
    if t < 0:
        t, s = 0.0, np.clip(-c / a, 0, 1)
    elif t > 1:
        t, s = 1.0, np.clip((b - c) / a, 0, 1)
    return float(np.linalg.norm(p0 + s * d1 - q0 - t * d2))


class GridFabric:
    """Grid version of woven yarns. nodes[y] / connections[y]: YADE body ids of yarn y (woven's yarn
    index order as given); radius [m]; K: bond stiffness of each connection [N/m] (E*A/L);
    length0: node distances at build [m]; material_length: woven yarn length each connection stands
    for [m]; kn: contact stiffness [N/m]; young_bond, young_contact [Pa]; crossing_fraction: where
    each crossing lies along its connections (0.5 = the middle)."""

    def node_ids(self):
        return [i for ids in self.nodes for i in ids]

    def connection_ids(self):
        return [i for ids in self.connections for i in ids]

    def total_mass(self):
        """Sum of the node masses [kg] (the connections carry none in YADE's dynamics)."""
        return sum(_O.bodies[i].state.mass for i in self.node_ids())

    def end_nodes(self, k):
        """([first node id], [last node id]) of yarn k: its clamp or grip (as PFacetFabric.end_nodes)."""
        return [self.nodes[k][0]], [self.nodes[k][-1]]

    def yarn_length(self, k):
        """Polyline length of yarn k through its nodes now [m]."""
        X = np.array([list(_O.bodies[i].state.pos) for i in self.nodes[k]])
        return float(np.linalg.norm(np.diff(X, axis=0), axis=1).sum())

    def fix_ends(self, which=None):
        """Holds the two end nodes of the yarns listed (indices into nodes; None: all)."""
        for k in (range(len(self.nodes)) if which is None else which):
            for i in (self.nodes[k][0], self.nodes[k][-1]):
                b = _O.bodies[i]
                b.state.blockedDOFs = 'xyzXYZ'
                b.state.vel = Vector3(0, 0, 0)

    def stable_dt(self, dt_factor=0.5, extra_contacts=4):
        """dt_factor * critical step [s]: Gershgorin's bound on the highest frequency of the free
        nodes, omega^2 <= 2*sum(k)/m, with every bond and `extra_contacts` contacts of stiffness kn
        at each node (a node's two connections meet about two crossings, more under a projectile);
        dt_crit = 2/omega. For a uniform chain with no contacts this is sqrt(m/K) = l0*sqrt(rho/E),
        woven's dt_crit."""
        ksum = {}
        for y, ids in enumerate(self.nodes):
            for j in range(len(ids) - 1):
                k = self.K[y][j]
                ksum[ids[j]] = ksum.get(ids[j], 0.0) + k
                ksum[ids[j + 1]] = ksum.get(ids[j + 1], 0.0) + k
        worst = float('inf')
        for i, ks in ksum.items():
            b = _O.bodies[i]
            if b.state.blockedDOFs == 'xyzXYZ':
                continue
            w2 = 2 * (ks + extra_contacts * self.kn) / b.state.mass
            worst = min(worst, 2 / math.sqrt(w2))
        return dt_factor * worst

    def remove_broken(self):
        """Erases the connections whose bond broke (their node pair has no interaction any more):
        a broken yarn no longer collides where it was cut. Returns how many were erased now."""
        n = 0
        for y, ids in enumerate(self.connections):
            for j, cid in enumerate(ids):
                if cid < 0:
                    continue
                a, b = self.nodes[y][j], self.nodes[y][j + 1]
                i = _O.interactions[a, b] if _O.interactions.has(a, b) else None
                if i is None or not i.isReal:
                    _O.bodies.erase(cid)
                    ids[j] = -1
                    self.broken.append((y, j, _O.time))
                    n += 1
        return n

    def max_overlap(self):
        """Largest penetrationDepth [m] among grid-grid contacts now (0 if none)."""
        m = 0.0
        for i in _O.interactions:
            if isinstance(i.geom, GridCoGridCoGeom):
                m = max(m, i.geom.penetrationDepth)
        return m


def _nodes_of_yarn(X, f=0.25):
    """Grid node positions of one woven yarn (its woven node positions X, shape (n, 3)).

    f = 0: the woven nodes themselves (a yarn with no crossings). f in (0, 0.5): on every woven
    element the points at f and 1-f of its length, and the yarn's two end nodes; the point at f of
    the first element and at 1-f of the last are left out (the end connections are (1-f) l0 long,
    not f l0, which would set the time step). Every inner woven node, so every crossing, is then the
    middle of the chord joining the points at f l0 either side of it. Returns (points, the woven
    material length each connection stands for [m])."""
    l0 = np.linalg.norm(np.diff(X, axis=0), axis=1)
    if f == 0:
        return X.copy(), l0
    n = len(l0)
    if n < 2:
        raise ValueError('a yarn of %d element(s) cannot be mapped with crossings mid-connection: need >= 2' % n)
    pts, mat = [X[0]], []
    pts.append(X[0] + (1 - f) * (X[1] - X[0]))
    mat.append((1 - f) * l0[0])
    for e in range(1, n):
        a = X[e] + f * (X[e + 1] - X[e])
        mat.append(f * (l0[e - 1] + l0[e]))  # the chord around woven node e
        pts.append(a)
        if e < n - 1:
            pts.append(X[e] + (1 - f) * (X[e + 1] - X[e]))
            mat.append((1 - 2 * f) * l0[e])
    pts.append(X[n])
    mat.append((1 - f) * l0[n - 1])
    return np.array(pts), np.array(mat)


def build(engine, yarns, kn=0.0, radius=0.0, bending=False, failure_strain=0.0, friction=0.0,
          crossings=None, offset=0.25):
    """Builds the yarns `yarns` of woven FabricEngine `engine` (at their current positions) as YADE
    grid nodes and connections and returns a GridFabric. Call after O.engines = engines().

    kn [N/m]: contact stiffness, > 0, or 0 for the yarn element's E*A/l0 (the first yarn's, at its
    mean l0). radius [m]: > 0, or 0 for half the smallest centre distance of the connections that
    cross (given `crossings`, a list of (yarn_a, yarn_b) index pairs into `yarns`, or all warp-weft
    pairs by family). failure_strain [-]: 0 (bonds never break) or in (0, 10]. friction [-]: Coulomb
    coefficient of the contacts, >= 0. offset [-]: where the grid nodes sit on each woven element
    (fraction of its length from either end, in (0, 0.5); 0: on woven's nodes, for yarns that cross
    nothing)."""
    if not (offset == 0 or 0 < offset < 0.5):
        raise ValueError('offset = %r is invalid: allowed 0 or (0, 0.5)' % offset)
    if not (math.isfinite(kn) and kn >= 0):
        raise ValueError('kn = %r is invalid: allowed [0, inf) N/m (0: E*A/l0 of the yarn element)' % kn)
    if not (math.isfinite(radius) and radius >= 0):
        raise ValueError('grid_radius = %r is invalid: allowed [0, inf) m (0: crossing connections just touch)' % radius)
    if not (math.isfinite(failure_strain) and 0 <= failure_strain <= 10):
        raise ValueError('failure_strain = %r is invalid: allowed 0 (no breakage) or (0, 10]' % failure_strain)
    if not (math.isfinite(friction) and friction >= 0):
        raise ValueError('friction = %r is invalid: allowed [0, inf)' % friction)
    from yade.gridpfacet import gridNode, gridConnection
    Xall = arrays.positions(engine)
    mall = arrays.masses(engine)
    infos = [engine.yarn(y) for y in yarns]
    chains = []
    for info in infos:
        a = info['first_node']
        chains.append(_nodes_of_yarn(Xall[a:a + info['n_nodes']], offset))
    # radius: the connections that cross just touch (segment distance of their chords)
    r_touch = float('inf')
    if crossings is None:
        fam = [info['family'] for info in infos]
        crossings = [(i, j) for i in range(len(yarns)) for j in range(len(yarns)) if fam[i] == 'warp' and fam[j] == 'weft']
    cross_frac = []
    for i, j in crossings:
        P, Q = chains[i][0], chains[j][0]
        # the connections of each yarn nearest the other's plan-view line: closest pair by midpoints
        mp, mq = 0.5 * (P[:-1] + P[1:]), 0.5 * (Q[:-1] + Q[1:])
        dxy = np.linalg.norm(mp[:, None, :2] - mq[None, :, :2], axis=2)
        a, b = np.unravel_index(np.argmin(dxy), dxy.shape)
        r_touch = min(r_touch, 0.5 * _segment_distance(P[a], P[a + 1], Q[b], Q[b + 1]))
        # where along connection a the crossing falls (plan-view intersection)
        r_, q_ = P[a + 1, :2] - P[a, :2], Q[b + 1, :2] - Q[b, :2]
        den = r_[0] * q_[1] - r_[1] * q_[0]
        if abs(den) > 1e-30:
            d0 = Q[b, :2] - P[a, :2]
            cross_frac.append((d0[0] * q_[1] - d0[1] * q_[0]) / den)
    r = radius if radius > 0 else r_touch
    if not (math.isfinite(r) and r > 0):
        raise ValueError('grid_radius = %r is invalid: no crossings to take it from; give grid_radius > 0 m' % radius)
    info0 = infos[0]
    l0_mean = float(np.mean(arrays.rest_lengths(engine)[info0['first_element']:info0['first_element'] + info0['n_elements']]))
    k_contact = kn if kn > 0 else info0['E'] * info0['area'] / l0_mean
    g = GridFabric()
    g.radius, g.kn, g.crossing_fraction = r, k_contact, np.array(cross_frac)
    g.young_contact = k_contact / r
    g.nodes, g.connections, g.K, g.length0, g.material_length, g.broken = [], [], [], [], [], []
    g.contact_material = _O.materials.append(FrictMat(young=g.young_contact, poisson=0.3, density=info0['rho'],
                                                      frictionAngle=math.atan(friction), label='gridContact'))
    g.bond_materials = []
    for info, (pts, lmat) in zip(infos, chains):
        EA = info['E'] * info['area']
        # kn of the bond = young*pi*r^2/L (gridpfacet.gridConnection): young = E*A/(pi r^2)
        big = 1e30  # no breakage: an adhesion no force reaches
        coh = EA * failure_strain / r ** 2 if failure_strain > 0 else big
        mid = _O.materials.append(CohFrictMat(young=EA / (math.pi * r * r), poisson=0.3, density=info['rho'],
                                              frictionAngle=math.atan(friction), normalCohesion=coh,
                                              shearCohesion=big, isCohesive=True, momentRotationLaw=bool(bending),
                                              fragile=True))
        g.bond_materials.append(mid)
        ids = [_O.bodies.append(gridNode(tuple(p), r, fixed=False, material=mid)) for p in pts]
        for i in ids:
            _O.bodies[i].mask = NODE_MASK
            _O.bodies[i].bounded = True  # a box projectile meets the nodes
        cids, ks = [], []
        mask = WEFT_MASK if info['family'] == 'weft' else WARP_MASK
        for j in range(len(ids) - 1):
            cids.append(_O.bodies.append(gridConnection(ids[j], ids[j + 1], r, material=g.contact_material,
                                                        mask=mask)))
            it = _O.interactions[ids[j], ids[j + 1]]
            ks.append(it.phys.kn)
            if not bending:
                it.phys.ks = it.phys.kr = it.phys.ktw = 0.0
        # masses: half of each connection's material length rho*A*l to each of its nodes
        rhoA = info['rho'] * info['area']
        m = np.zeros(len(ids))
        m[:-1] += 0.5 * rhoA * lmat
        m[1:] += 0.5 * rhoA * lmat
        for i, mi in zip(ids, m):
            b = _O.bodies[i]
            b.state.mass = float(mi)
            I = 0.4 * float(mi) * r * r  # a solid sphere of the node's radius: only for its own rotation
            b.state.inertia = Vector3(I, I, I)
        g.nodes.append(ids)
        g.connections.append(cids)
        g.K.append(ks)
        g.length0.append(np.linalg.norm(np.diff(pts, axis=0), axis=1))
        g.material_length.append(lmat)
    g.woven_mass = float(sum(mall[info['first_node']:info['first_node'] + info['n_nodes']].sum() for info in infos))
    return g


def projectile_material(g, shape, size):
    """A FrictMat for a projectile ('sphere' of diameter `size` [m] or 'box') whose contacts with the
    grid have normal stiffness g.kn [N/m] (YADE's harmonic mean 2ab/(a+b) of the two young*radius
    products solved for the projectile's). Returns the material id."""
    if shape == 'sphere':
        b = g.young_contact * g.radius          # the connection's young*r = kn
        a = g.kn * b / (2 * b - g.kn)           # = kn
        young = a / (0.5 * size)
    else:
        b = _O.materials[g.bond_materials[0]].young * g.radius  # the node's young*r (bond modulus)
        if not 2 * b > g.kn:
            raise ValueError('kn = %r is invalid for a box projectile: allowed (0, %g) N/m (twice the node stiffness '
                             'young*r)' % (g.kn, 2 * b))
        a = g.kn * b / (2 * b - g.kn)
        young = a / g.radius                    # Ig2_Box_Sphere_ScGeom: both radii are the node's
    return _O.materials.append(FrictMat(young=young, poisson=0.3, density=1000.0, frictionAngle=0.0,
                                        label='projectile'))
