"""Closed-form references the scenes are checked against (physics-reference.md). SI units."""
import math


def smith(V, E, rho):
    """Smith's transverse impact of a yarn at speed V [m/s] (Smith, McCrackin & Schiefer 1958).

    Solves V = c*sqrt(2*eps*sqrt(eps*(1+eps)) - eps^2) for eps by bisection (monotonic), c = sqrt(E/rho).
    Returns dict: c [m/s], strain [-], w = c*eps [m/s] (material flow), U_L = c*sqrt(eps/(1+eps))
    [m/s] (material frame) and U_E = c*(sqrt(eps*(1+eps)) - eps) [m/s] (lab frame).
    """
    if not (E > 0 and rho > 0 and V > 0 and math.isfinite(V)):
        raise ValueError('smith: need E > 0 Pa, rho > 0 kg/m^3, V > 0 m/s; got %r, %r, %r' % (E, rho, V))
    c = math.sqrt(E / rho)

    def speed(e):
        return c * math.sqrt(max(2 * e * math.sqrt(e * (1 + e)) - e * e, 0.0))

    lo, hi = 0.0, 1.0
    if speed(hi) < V:
        raise ValueError('smith: V = %g m/s exceeds the model range (strain > 100 %%)' % V)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if speed(mid) < V:
            lo = mid
        else:
            hi = mid
    e = 0.5 * (lo + hi)
    return {'c': c, 'strain': e, 'w': c * e, 'U_L': c * math.sqrt(e / (1 + e)),
            'U_E': c * (math.sqrt(e * (1 + e)) - e)}


def smith_critical_velocity(failure_strain, E, rho):
    """Impact speed [m/s] at which the strain behind the front reaches failure_strain."""
    c = math.sqrt(E / rho)
    e = failure_strain
    return c * math.sqrt(2 * e * math.sqrt(e * (1 + e)) - e * e)


def areal_density_plain(linear_density_warp, spacing_warp, crimp_warp, linear_density_weft, spacing_weft, crimp_weft):
    """Areal density [kg/m^2] of a woven fabric: sum over families of lambda*(1 + crimp)/spacing."""
    return (linear_density_warp * (1 + crimp_warp) / spacing_warp
            + linear_density_weft * (1 + crimp_weft) / spacing_weft)
