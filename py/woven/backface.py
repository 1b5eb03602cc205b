"""Back-face deformation of a struck ply: the cone's apex depth and base radius, the
transverse front and the longitudinal strain front along the yarns through the impact point, against
time; their early speeds against Smith's theory. SI units.

    bf = woven.backface.BackFace(weave, X0, centre, direction=(0, 0, -1))
    row = bf.measure(time)       # dict: apex, base_radius, transverse_front, strain_front
    fit = woven.backface.front_speed(t, r, r_lo, r_hi)

The measures are plain functions of node positions and element strains (cone, front), so that they
can be checked on a constructed field (tests/python/test_backface.py):
- out-of-plane displacement w = (x - x0) . d of every node, d the impact direction (unit);
- apex depth: the largest w (the fabric under the projectile);
- base radius: the largest distance from the impact axis, in the plane normal to d, of a node whose
  w exceeds `w_threshold` (the transverse front of the whole ply);
- transverse front: along each arm of the yarns through the impact point (from the node nearest
  the axis outwards), the distance from the axis where w falls through `w_threshold`, interpolated
  linearly between the last node above it and the next one (a node spacing is 0.75 mm, as far as
  the front moves in 2 us: without it the early speed would rest on two or three steps);
- strain front: the same along those arms with the element strains at the elements' midpoints and
  `strain_threshold` (the longitudinal wave).
Distances are measured in the current (lab) frame, as Smith's U_E is.
"""
import math
import time as _time

import numpy as np

from . import arrays

UNITS = {'time': 's', 'apex': 'm', 'base_radius': 'm', 'transverse_front': 'm', 'strain_front': 'm'}


def _unit(direction):
    d = np.asarray(direction, dtype=float).reshape(3)
    n = float(np.linalg.norm(d))
    if not (math.isfinite(n) and n > 0):
        raise ValueError('direction = %r is invalid: allowed a finite non-zero vector' % (direction,))
    return d / n


def radial(X, centre, direction):
    """Distance [m] of each point of X (n, 3) from the line through `centre` along `direction`."""
    d = _unit(direction)
    r = np.asarray(X, dtype=float) - np.asarray(centre, dtype=float)
    return np.linalg.norm(r - np.outer(r @ d, d), axis=1)


def cone(X0, X, centre, direction, w_threshold, nodes=None):
    """(apex depth, base radius) [m] of the displacement field X - X0 (see the module doc); `nodes`
    limits both to these node indices. The radius is 0 while no node's w exceeds the threshold."""
    d = _unit(direction)
    if nodes is not None:
        X0, X = X0[nodes], X[nodes]
    w = (X - X0) @ d
    apex = float(w.max()) if len(w) else 0.0
    moved = w > w_threshold
    radius = float(radial(X[moved], centre, d).max()) if np.any(moved) else 0.0
    return apex, radius


def arm_front(r, value, threshold):
    """Front along one chain: r [m] the distances of its points from the impact axis and `value` at
    them, in chain order. On each arm from the point nearest the axis outwards, the distance where
    value falls through `threshold` after its last point above it, interpolated linearly to the next
    point (the arm's end when none follows); the larger over the two arms, 0 when no point is above."""
    r, value = np.asarray(r, dtype=float), np.asarray(value, dtype=float)
    if len(r) == 0:
        return 0.0
    k = int(np.argmin(r))
    best = 0.0
    for rr, vv in ((r[k:], value[k:]), (r[k::-1], value[k::-1])):
        above = np.nonzero(vv > threshold)[0]
        if len(above) == 0:
            continue
        j = int(above[-1])
        if j + 1 < len(rr):
            f = (vv[j] - threshold) / (vv[j] - vv[j + 1])
            best = max(best, float(rr[j] + f * (rr[j + 1] - rr[j])))
        else:
            best = max(best, float(rr[j]))
    return best


def strain_front(X, strain, first_nodes, centre, direction, threshold):
    """Strain front [m] along one chain (arm_front): `strain` of its elements in chain order, their
    first nodes in `first_nodes`, taken at the elements' midpoints."""
    first_nodes = np.asarray(first_nodes)
    mid = 0.5 * (X[first_nodes] + X[first_nodes + 1])
    return arm_front(radial(mid, centre, direction), strain, threshold)


def front_speed(t, r, r_lo, r_hi, min_points=5, min_travel=1e-3):
    """Least-squares speed [m/s] of a front r(t) [m] over its first passage from r_lo to r_hi: the
    samples from the first with r >= r_lo up to the last before r first exceeds r_hi. Returns dict
    speed, intercept [m], t0, t1 [s] (the window), points; speed None with fewer than `min_points`
    samples or a front that moved less than `min_travel` [m] in the window (a ply too small, or a
    break too soon, to tell a speed: 1 mm is four samples' travel of the slowest front here)."""
    t, r = np.asarray(t, dtype=float), np.asarray(r, dtype=float)
    start = np.nonzero(r >= r_lo)[0]
    if len(start) == 0:
        return {'speed': None, 'intercept': None, 't0': None, 't1': None, 'points': 0}
    i0 = int(start[0])
    past = np.nonzero(r[i0:] > r_hi)[0]
    i1 = i0 + (int(past[0]) if len(past) else len(r) - i0)
    tt, rr = t[i0:i1], r[i0:i1]
    if len(tt) < min_points or tt[-1] <= tt[0] or rr.max() - rr.min() < min_travel:
        return {'speed': None, 'intercept': None, 't0': None, 't1': None, 'points': int(len(tt))}
    slope, icpt = np.polyfit(tt, rr, 1)
    return {'speed': float(slope), 'intercept': float(icpt), 't0': float(tt[0]), 't1': float(tt[-1]),
            'points': int(len(tt))}


def through_point(engine, yarns, X, centre, direction):
    """Of `yarns` (indices), the one whose chain passes closest to the impact axis."""
    best, dist = None, math.inf
    for y in yarns:
        info = engine.yarn(y)
        nodes = np.arange(info['first_node'], info['first_node'] + info['n_nodes'])
        r = float(radial(X[nodes], centre, direction).min())
        if r < dist:
            best, dist = y, r
    return best


class BackFace:
    """The back-face measures of a ply built by woven.weave (its engine, warp_yarns, weft_yarns),
    from the node positions X0 [m] at rest, about the impact axis through `centre` along
    `direction`. w_threshold [m]: the out-of-plane displacement that counts as moved; strain_threshold
    [-]: the strain that counts as reached by the longitudinal wave."""

    def __init__(self, weave, X0, centre, direction=(0.0, 0.0, -1.0), w_threshold=1e-4, strain_threshold=5e-4,
                 dense_radius=0.0):
        if not (math.isfinite(w_threshold) and w_threshold > 0):
            raise ValueError('w_threshold = %r is invalid: allowed (0, inf) m' % w_threshold)
        if not (math.isfinite(strain_threshold) and strain_threshold > 0):
            raise ValueError('strain_threshold = %r is invalid: allowed (0, inf)' % strain_threshold)
        self.engine, self.X0 = weave.engine, np.array(X0, dtype=float)
        self.centre, self.direction = np.asarray(centre, dtype=float), _unit(direction)
        self.w_threshold, self.strain_threshold = w_threshold, strain_threshold
        self.families = [fam for fam in (weave.warp_yarns, weave.weft_yarns) if fam]
        self.yarns = [through_point(self.engine, fam, self.X0, self.centre, self.direction) for fam in self.families]
        e0 = np.frombuffer(self.engine._element_first_nodes(), dtype=np.int32)
        self.chains = []  # per yarn through the impact point: its nodes, elements, elements' first nodes
        for y in self.yarns:
            info = self.engine.yarn(y)
            el = np.arange(info['first_element'], info['first_element'] + info['n_elements'])
            self.chains.append((np.arange(info['first_node'], info['first_node'] + info['n_nodes']), el, e0[el]))
        self.dense_radius = dense_radius
        self.rows = []
        self.seconds = 0.0  # wall time spent measuring [s]

    def dense(self):
        """True until the strain front has passed `dense_radius` [m]: the longitudinal wave crosses a
        50.8 mm ply in 3 us, so its front is measured every step until then (call measure from a
        per-step hook while this holds, and from the sampler after)."""
        return not self.rows or self.rows[-1]['strain_front'] < self.dense_radius

    def measure(self, time):
        """Appends and returns the measures now (dict with UNITS' keys); at a time already measured,
        returns that row."""
        if self.rows and self.rows[-1]['time'] == float(time):
            return self.rows[-1]
        t0 = _time.perf_counter()
        X = arrays.positions(self.engine)
        apex, radius = cone(self.X0, X, self.centre, self.direction, self.w_threshold)
        eps, live = arrays.strains(self.engine), arrays.alive(self.engine)
        front, sf = 0.0, 0.0
        for nodes, el, first in self.chains:
            w = (X[nodes] - self.X0[nodes]) @ self.direction
            front = max(front, arm_front(radial(X[nodes], self.centre, self.direction), w, self.w_threshold))
            sf = max(sf, strain_front(X, eps[el] * live[el], first, self.centre, self.direction, self.strain_threshold))
        row = {'time': float(time), 'apex': apex, 'base_radius': radius, 'transverse_front': front, 'strain_front': sf}
        self.rows.append(row)
        self.seconds += _time.perf_counter() - t0
        return row

    def series(self):
        """The rows as arrays: dict key -> np.ndarray."""
        return {k: np.array([r[k] for r in self.rows]) for k in UNITS}


def mass_ratio(engine, family):
    """The ply's mass over the mass of the yarns of `family` (indices): what the transverse motion
    of a struck yarn carries per unit of its own mass (theory.smith_fabric's mass_ratio)."""
    m = arrays.masses(engine)
    own = 0.0
    for y in family:
        info = engine.yarn(y)
        own += float(m[info['first_node']:info['first_node'] + info['n_nodes']].sum())
    return float(m.sum()) / own


def compare(bf, t_proj, v_proj, reach, half_side, E, rho, t_max=None, tolerance=0.1, friction=0.0):
    """The early front speeds of BackFace `bf` against Smith's theory (theory.smith, smith_fabric).

    t_proj, v_proj: the projectile's speed [m/s] against time [s] (the theory is taken at the speed
    it had in the middle of the transverse window); reach [m]: the projectile's in-plane half size
    (the fronts start at its edge); half_side [m]: half the ply's side (fronts are fitted from
    reach + 1 mm to 0.8 half_side, where the clamps are not yet felt); t_max [s]: the fits stop
    there (the first break: the yarns through the impact point break first). Returns (measured,
    reference, checks) for summary.json; a check fails when a measured speed is off its theory by
    more than `tolerance` (relative). The strain front's theory is the yarn's c when the crossings are
    frictionless (friction = 0, the yarn-yarn coefficient); with friction they drag the crossing yarns
    part of the way, and it must lie between the membrane's c/sqrt(kappa) (all dragged) and c (none),
    each widened by the tolerance."""
    from . import theory
    s = bf.series()
    c = math.sqrt(E / rho)
    keep = s['time'] <= t_max if t_max is not None else np.ones(len(s['time']), bool)
    t = s['time'][keep]
    lo, hi = reach + 1e-3, 0.8 * half_side
    # Smith's fronts run at constant speed only until the longitudinal wave, reflected by the clamps,
    # meets the transverse front (then the strain behind it doubles): at r at t_c + (2 half_side -
    # reach - r) / c, t_c the first contact (the first sample with a cone).
    moved = np.nonzero(s['apex'] > 0)[0]
    t_c = float(s['time'][moved[0]]) if len(moved) else 0.0
    tf = s['transverse_front']
    early = keep & (s['time'] - t_c <= (2 * half_side - reach - tf) / c)
    fits = {'strain_front': front_speed(t, s['strain_front'][keep], lo, hi),
            'transverse_front': front_speed(s['time'][early], tf[early], reach + 0.25e-3, hi),
            'base_radius': front_speed(t, s['base_radius'][keep], lo, hi)}
    kappa = mass_ratio(bf.engine, bf.families[0])
    ft = fits['transverse_front']
    t_mid = 0.5 * (ft['t0'] + ft['t1']) if ft['speed'] is not None else float(t_proj[0])
    V = float(abs(np.interp(t_mid, t_proj, v_proj)))
    yarn = theory.smith(V, E, rho)
    fabric = theory.smith_fabric(V, E, rho, kappa)
    membrane = theory.smith(V, E / kappa, rho)  # the whole ply a membrane of wave speed c/sqrt(kappa)
    measured = {'apex_depth_end': float(s['apex'][-1]), 'base_radius_end': float(s['base_radius'][-1]),
                'apex_depth_max': float(s['apex'].max()), 'transverse_front_end': float(s['transverse_front'][-1]),
                'strain_front_end': float(s['strain_front'][-1]),
                'strain_front_speed': fits['strain_front']['speed'],
                'transverse_front_speed': ft['speed'], 'base_radius_speed': fits['base_radius']['speed'],
                'fits': fits, 'fit_window_radii': [lo, hi], 'first_contact_time': t_c, 'mass_ratio': kappa, 'V_at_transverse_window': V,
                'yarns_through_impact_point': [int(y) for y in bf.yarns],
                'w_threshold': bf.w_threshold, 'strain_threshold': bf.strain_threshold,
                'samples': len(s['time'])}
    reference = {'longitudinal_wave_speed_c': c, 'membrane_wave_speed_c_over_sqrt_kappa': c / math.sqrt(kappa),
                 'smith_fabric_U_E': fabric['U_E'], 'smith_fabric_strain': fabric['strain'],
                 'smith_yarn_U_E': yarn['U_E'], 'smith_yarn_strain': yarn['strain'],
                 'membrane_U_E': membrane['U_E'],
                 'relation': 'transverse front: Smith with the crossing yarns\' mass carried by the cone '
                             '(theory.smith_fabric, mass ratio kappa = ply mass / struck family mass); '
                             'strain front: the yarn\'s c = sqrt(E/rho) (frictionless crossings do not drag '
                             'the crossing yarns along; with friction between c/sqrt(kappa) and c); the yarn and '
                             'membrane (c/sqrt(kappa)) forms for comparison'}
    # A front that could not be fitted (a ply too small for the window, a break before it) is no
    # check: it is named in measured['not_fitted'] with the window it lacked.
    checks, measured['not_fitted'] = {}, []
    for name, fit, ref in (('strain_front_speed', fits['strain_front'], c),
                           ('transverse_front_speed', ft, fabric['U_E'])):
        if fit['speed'] is None:
            measured['not_fitted'].append('%s: %d samples in its window' % (name, fit['points']))
            continue
        if name == 'strain_front_speed' and friction > 0:
            lo_c, hi_c = (1 - tolerance) * c / math.sqrt(kappa), (1 + tolerance) * c
            checks[name] = {'value': fit['speed'], 'limit': [lo_c, hi_c], 'passed': bool(lo_c <= fit['speed'] <= hi_c),
                            'what': 'early strain front speed [m/s] between the membrane\'s c/sqrt(kappa) and the '
                                    'yarn\'s c (friction %g drags the crossing yarns part of the way), each widened by '
                                    'the tolerance %g' % (friction, tolerance)}
            continue
        err = abs(fit['speed'] / ref - 1)
        checks[name] = {'value': err, 'limit': tolerance, 'passed': bool(err <= tolerance),
                        'what': '|measured / theory - 1| of the early %s (%s)' % (
                            name.replace('_', ' '), 'c' if name.startswith('strain') else 'smith_fabric U_E')}
    return measured, reference, checks


def chart(bf, path, measured, reference, title=''):
    """backface.png: apex depth, base radius and the two fronts against time, with the fitted and
    the theory's front lines."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from .output import savefig
    s = bf.series()
    t_us = 1e6 * s['time']
    fig, (a1, a2, a3) = plt.subplots(1, 3, figsize=(16, 4.5))
    a1.plot(t_us, 1e3 * s['apex'], 'k-')
    a1.set_xlabel('time [us]')
    a1.set_ylabel('apex depth of the cone [mm]')
    a1.set_title(title)
    for k, style, lab in (('base_radius', 'b-', 'cone base radius (w > %.3g mm)' % (1e3 * bf.w_threshold)),
                          ('transverse_front', 'g-', 'transverse front, yarns through the impact point'),
                          ('strain_front', 'r-', 'strain front (strain > %.2g)' % bf.strain_threshold)):
        a2.plot(t_us, 1e3 * s[k], style, label=lab)
    for k, ref, style in (('transverse_front', reference['smith_fabric_U_E'], 'g:'),
                          ('strain_front', reference['longitudinal_wave_speed_c'], 'r:')):
        f = measured['fits'][k]
        if f['speed'] is None:
            continue
        tt = np.array([f['t0'], f['t1']])
        a2.plot(1e6 * tt, 1e3 * (f['intercept'] + f['speed'] * tt), style, lw=3, alpha=0.5)
        r0 = f['intercept'] + f['speed'] * f['t0']
        a2.plot(1e6 * tt, 1e3 * (r0 + ref * (tt - f['t0'])), 'k--', lw=0.8)
    a2.plot([], [], 'k--', lw=0.8, label='theory: c (strain), Smith fabric U_E (transverse)')
    a2.set_xlabel('time [us]')
    a2.set_ylabel('distance from the impact axis [mm]')
    a2.set_ylim(0, 1e3 * max(float(s['base_radius'].max()), float(s['strain_front'].max()), 1e-6) * 1.05)
    a2.legend(fontsize=8, loc='lower right')
    # The transverse front in its fit window (until the clamps' reflection meets it), with Smith's lines.
    f = measured['fits']['transverse_front']
    if f['speed'] is not None:
        end = f['t1'] + 0.5 * (f['t1'] - f['t0'])
        m = s['time'] <= end
        a3.plot(t_us[m], 1e3 * s['transverse_front'][m], 'g.-', label='transverse front (measured)')
        tt = np.array([f['t0'], f['t1']])
        r0 = f['intercept'] + f['speed'] * f['t0']
        a3.plot(1e6 * tt, 1e3 * (f['intercept'] + f['speed'] * tt), 'g-', lw=3, alpha=0.4,
                label='fit: %.0f m/s' % f['speed'])
        for key, style, lab in (('smith_fabric_U_E', 'k--', 'Smith, fabric (kappa = %.2f)' % measured['mass_ratio']),
                                ('membrane_U_E', 'b:', 'Smith, membrane c/sqrt(kappa)'),
                                ('smith_yarn_U_E', 'r:', 'Smith, bare yarn')):
            a3.plot(1e6 * tt, 1e3 * (r0 + reference[key] * (tt - f['t0'])), style,
                    label='%s: %.0f m/s' % (lab, reference[key]))
        a3.set_title('early transverse front (V = %.0f m/s)' % measured['V_at_transverse_window'], fontsize=10)
        a3.legend(fontsize=8, loc='upper left')
    a3.set_xlabel('time [us]')
    a3.set_ylabel('distance from the impact axis [mm]')
    fig.tight_layout()
    savefig(fig, path, dpi=100)
    plt.close(fig)


def write_series(bf, path):
    """backface.csv: the rows of `bf` (UNITS' columns, SI)."""
    from .output import savetxt
    s = bf.series()
    keys = list(UNITS)
    savetxt(path, np.column_stack([s[k] for k in keys]), delimiter=',', comments='',
            header=','.join('%s_%s' % (k, UNITS[k]) for k in keys))
