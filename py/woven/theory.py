"""Closed-form references the scenes are checked against (physics-reference.md). SI units.

Every argument is checked against a physical range (the same as the weave keys' where they overlap)
and refused naming it: NaN, infinities and zero spacings gave NaN, inf or ZeroDivisionError.
"""
import math

from ._args import finite as _finite


def _E(E):
    return _finite('E', E, 1e5, 1e13, 'Pa')


def _rho(rho):
    return _finite('rho', rho, 1, 1e5, 'kg/m^3')


def _array(name, x, lo, hi, unit):
    import numpy as np
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise ValueError('%s = %r is invalid: allowed numbers in [%g, %g] %s' % (name, x, lo, hi, unit)) from None
    if a.size == 0 or not np.all(np.isfinite(a)) or np.any(a < lo) or np.any(a > hi):
        raise ValueError('%s = %r is invalid: allowed finite numbers in [%g, %g] %s' % (name, x, lo, hi, unit))
    return a


def _strain_at(speed, V, name):
    """The strain e in (0, 1) at which the increasing `speed(e)` [m/s] equals V, by bisection."""
    lo, hi = 0.0, 1.0
    if speed(hi) < V:
        raise ValueError('%s: V = %g m/s exceeds the model range (strain > 100 %%)' % (name, V))
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if speed(mid) < V:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def smith(V, E, rho):
    """Smith's transverse impact of a yarn at speed V [m/s] (Smith, McCrackin & Schiefer 1958).

    Solves V = c*sqrt(2*eps*sqrt(eps*(1+eps)) - eps^2) for eps by bisection (monotonic), c = sqrt(E/rho).
    Returns dict: c [m/s], strain [-], w = c*eps [m/s] (material flow), U_L = c*sqrt(eps/(1+eps))
    [m/s] (material frame) and U_E = c*(sqrt(eps*(1+eps)) - eps) [m/s] (lab frame).
    """
    E, rho = _E(E), _rho(rho)
    V = _finite('V', V, 1e-6, 1e5, 'm/s')
    c = math.sqrt(E / rho)

    def speed(e):
        return c * math.sqrt(max(2 * e * math.sqrt(e * (1 + e)) - e * e, 0.0))

    e = _strain_at(speed, V, 'smith')
    return {'c': c, 'strain': e, 'w': c * e, 'U_L': c * math.sqrt(e / (1 + e)),
            'U_E': c * (math.sqrt(e * (1 + e)) - e)}


def smith_fabric(V, E, rho, mass_ratio=2.0):
    """Smith's impact for a yarn of a fabric whose transverse motion carries `mass_ratio` [1, 10]
    times the yarn's own mass (the crossing yarns it pushes out of plane: for a balanced plain weave
    the fabric's mass over the struck family's, about 2), while its longitudinal wave keeps the
    yarn's c = sqrt(E/rho) (frictionless crossings do not drag the crossing yarns along it).

    Smith's two conditions with the kink's material speed U = sqrt(T / (kappa m (1 + eps))) =
    c sqrt(eps / (kappa (1 + eps))) (momentum across a kink of a string of kappa m per unstretched
    length under T = E A eps) and the kinematics of the straight stretched segment behind it,
    (U (1 + eps))^2 = (U (1 + eps) - c eps)^2 + V^2, i.e. V^2 = 2 c eps U (1 + eps) - c^2 eps^2:
    solved for eps by bisection. mass_ratio = 1 is Smith's yarn (smith()). Returns the same dict as
    smith(): c, strain, w = c eps, U_L = U, U_E = U (1 + eps) - c eps (lab frame) [m/s]."""
    E, rho = _E(E), _rho(rho)
    V = _finite('V', V, 1e-6, 1e5, 'm/s')
    k = _finite('mass_ratio', mass_ratio, 1, 10, '')
    c = math.sqrt(E / rho)

    def kink(e):
        return c * math.sqrt(e / (k * (1 + e)))

    def speed(e):
        return math.sqrt(max(2 * c * e * kink(e) * (1 + e) - (c * e) ** 2, 0.0))

    e = _strain_at(speed, V, 'smith_fabric')
    return {'c': c, 'strain': e, 'w': c * e, 'U_L': kink(e), 'U_E': kink(e) * (1 + e) - c * e}


def smith_critical_velocity(failure_strain, E, rho):
    """Impact speed [m/s] at which the strain behind the front reaches failure_strain."""
    e = _finite('failure_strain', failure_strain, 1e-12, 10, '')
    c = math.sqrt(_E(E) / _rho(rho))
    return c * math.sqrt(2 * e * math.sqrt(e * (1 + e)) - e * e)


def areal_density_plain(linear_density_warp, spacing_warp, crimp_warp, linear_density_weft, spacing_weft, crimp_weft):
    """Areal density [kg/m^2] of a woven fabric: sum over families of lambda*(1 + crimp)/spacing."""
    linear_density_warp = _finite('linear_density_warp', linear_density_warp, 0, 1e3, 'kg/m')
    linear_density_weft = _finite('linear_density_weft', linear_density_weft, 0, 1e3, 'kg/m')
    spacing_warp = _finite('spacing_warp', spacing_warp, 1e-8, 1, 'm')
    spacing_weft = _finite('spacing_weft', spacing_weft, 1e-8, 1, 'm')
    crimp_warp = _finite('crimp_warp', crimp_warp, 0, 0.999999, '')
    crimp_weft = _finite('crimp_weft', crimp_weft, 0, 0.999999, '')
    return (linear_density_warp * (1 + crimp_warp) / spacing_warp
            + linear_density_weft * (1 + crimp_weft) / spacing_weft)


def lambert_jonas(V, V_bl, a, p):
    """Lambert-Jonas residual velocity [m/s]: a (V^p - V_bl^p)^(1/p) above the ballistic limit V_bl
    [m/s], 0 below it (Lambert & Jonas, BRL R-1852, 1976)."""
    import numpy as np
    V = _array('V', V, 0, 1e5, 'm/s')
    V_bl = _finite('V_bl', V_bl, 0, 1e5, 'm/s')
    a = _finite('a', a, 0, 1, '')
    p = _finite('p', p, 0.1, 100, '')
    return np.where(V > V_bl, a * np.maximum(V ** p - V_bl ** p, 0.0) ** (1.0 / p), 0.0)


def fit_lambert_jonas(V, vr, p_range=(1.0, 4.0)):
    """Least-squares Lambert-Jonas fit of residual velocities vr [m/s] (0 where the projectile was
    stopped) against impact velocities V [m/s]: for each ballistic limit V_bl on a grid below the
    largest V and each exponent p in p_range, a follows in closed form (linear least squares, held
    within (0, 1]: a projectile never leaves faster than it came); the
    best pair is refined on a finer grid. Returns dict V_bl (the V50 the fit gives) [m/s], a [-], p
    [-], rms [m/s]. Raises ValueError with fewer than 3 points or no perforation at all."""
    import numpy as np
    V = _array('V', V, 1e-6, 1e5, 'm/s')
    vr = _array('vr', vr, 0, 1e5, 'm/s')
    p_range = (_finite('p_range[0]', p_range[0], 0.1, 100, ''), _finite('p_range[1]', p_range[1], 0.1, 100, ''))
    if p_range[1] < p_range[0]:
        raise ValueError('p_range = %r is invalid: allowed (low, high) with low <= high in [0.1, 100]' % (p_range,))
    if V.ndim != 1 or vr.ndim != 1 or len(V) < 3 or len(V) != len(vr):
        raise ValueError('runs = %d is invalid: allowed at least 3 (V, residual velocity) pairs of equal length' % V.size)
    if not np.any(vr > 0):
        raise ValueError('residual velocities are all 0: no run perforated, the V50 lies above %.1f m/s' % V.max())

    def best(vbl_grid, p_grid):  # the V_bl grid as one array operation per exponent (the bootstrap refits)
        out = None
        for p in p_grid:
            d = V[None, :] ** p - vbl_grid[:, None] ** p
            g = np.where(V[None, :] > vbl_grid[:, None], np.maximum(d, 0.0) ** (1.0 / p), 0.0)
            gg = np.einsum('ij,ij->i', g, g)
            a = np.clip(np.divide(g @ vr, gg, out=np.zeros_like(gg), where=gg > 0), 0.0, 1.0)
            sse = np.sum((a[:, None] * g - vr[None, :]) ** 2, axis=1)
            k = int(np.argmin(sse))
            if out is None or sse[k] < out[0]:
                out = (float(sse[k]), float(vbl_grid[k]), float(a[k]), float(p))
        return out
    top = V.max()
    sse, vbl, a, p = best(np.linspace(0, top, 401)[:-1], np.linspace(p_range[0], p_range[1], 31))
    step_v, step_p = top / 400, (p_range[1] - p_range[0]) / 30
    sse, vbl, a, p = best(np.linspace(max(0, vbl - step_v), min(top, vbl + step_v), 81),
                          np.linspace(max(p_range[0], p - step_p), min(p_range[1], p + step_p), 21))
    return {'V_bl': vbl, 'a': a, 'p': p, 'rms': math.sqrt(sse / len(V))}
