"""Cunniff's dimensionless V50 (physics-reference.md, "Armour test conventions").

Cunniff (1999) collapses the V50 of fabric armours of different fibres, areal densities and fragments
onto one curve by plotting
    V50 / U*^(1/3)   against   A_d * A_p / m_p,
U* = (sigma_f * eps_f / (2 rho)) * sqrt(E / rho) being the fibre's specific toughness (sigma eps / 2 rho,
the elastic energy per unit mass at failure of a linear fibre) times its longitudinal wave speed
sqrt(E / rho); U*^(1/3) is a velocity. A_d is the pack's areal density, A_p the projectile's presented
area and m_p its mass, so A_d A_p / m_p is the mass of fabric the projectile's outline covers per unit
mass of projectile. SI units throughout.

    from woven import cunniff
    us = cunniff.u_star(4.5e9, 0.05, 1440.0, 90e9)          # 6.18e8 m^3/s^3 (KM2 as woven's preset)
    x, y = cunniff.axes(100.0, 0.1804, 2.4524e-5, 1.0758e-3, us)
    c, b, rms = cunniff.power_fit([x1, x2, x4], [y1, y2, y4])   # y = c x^b through a family of packs
"""
import math


def u_star(strength, failure_strain, density, modulus):
    """Cunniff's U* [m^3/s^3] = (strength * failure_strain / (2 density)) * sqrt(modulus / density)."""
    for name, v in (('strength', strength), ('failure_strain', failure_strain), ('density', density),
                    ('modulus', modulus)):
        if not (math.isfinite(v) and v > 0):
            raise ValueError('%s = %r is invalid: allowed a finite value > 0' % (name, v))
    return strength * failure_strain / (2.0 * density) * math.sqrt(modulus / density)


def presented_area(shape, size, yaw=0.0, obliquity=0.0):
    """The projectile's presented area [m^2] along its flight, nose on (yaw = obliquity = 0 only):
    a cylinder ('rcc', 'fsp') or a sphere of diameter `size`: pi size^2 / 4; a cube ('box') face on:
    size^2. A yawed projectile presents another outline, which is not computed here."""
    if yaw != 0.0:
        raise ValueError('yaw = %r is invalid: allowed 0 (the presented area is that of a projectile nose on)' % yaw)
    if obliquity != 0.0:
        # Obliquity turns the pack, not the projectile, but Cunniff's axes are for normal impact.
        raise ValueError('obliquity = %r is invalid: allowed 0 (Cunniff\'s axes are for normal impact)' % obliquity)
    if not (math.isfinite(size) and size > 0):
        raise ValueError('size = %r is invalid: allowed a finite value > 0' % size)
    if shape in ('rcc', 'fsp', 'sphere'):
        return math.pi * size * size / 4.0
    if shape == 'box':
        return size * size
    raise ValueError("shape = %r is invalid: allowed 'rcc', 'fsp', 'sphere' or 'box'" % shape)


def axes(v50, areal_density, area, mass, ustar):
    """Cunniff's axes of one pack: (A_d A_p / m_p, V50 / U*^(1/3)), both dimensionless."""
    for name, v in (('areal_density', areal_density), ('area', area), ('mass', mass), ('ustar', ustar)):
        if not (math.isfinite(v) and v > 0):
            raise ValueError('%s = %r is invalid: allowed a finite value > 0' % (name, v))
    return areal_density * area / mass, v50 / ustar ** (1.0 / 3.0)


def power_fit(xs, ys):
    """The power law y = c x^b through Cunniff's points of a family of packs (least squares on log y
    against log x): (c, b, rms), rms the root-mean-square of log(y / (c x^b)), about the relative misfit.
    Two points give the line through both (rms 0); needs at least two distinct x, every x and y > 0."""
    pts = [(float(x), float(y)) for x, y in zip(xs, ys)]
    if len(pts) != len(xs) or len(pts) != len(ys):
        raise ValueError('ys has %d values for %d xs: allowed one y per x' % (len(ys), len(xs)))
    for name, vals in (('xs', [x for x, _ in pts]), ('ys', [y for _, y in pts])):
        if not all(math.isfinite(v) and v > 0 for v in vals):
            raise ValueError('%s = %r is invalid: allowed finite values > 0' % (name, vals))
    lx = [math.log(x) for x, _ in pts]
    ly = [math.log(y) for _, y in pts]
    n = len(pts)
    mx, my = sum(lx) / max(n, 1), sum(ly) / max(n, 1)
    sxx = sum((a - mx) ** 2 for a in lx)
    if n < 2 or not sxx > 0:
        raise ValueError('xs = %r is invalid: allowed at least two distinct values' % [x for x, _ in pts])
    b = sum((a - mx) * (c - my) for a, c in zip(lx, ly)) / sxx
    c = math.exp(my - b * mx)
    rms = math.sqrt(sum((ly_k - (math.log(c) + b * lx_k)) ** 2 for lx_k, ly_k in zip(lx, ly)) / n)
    return c, b, rms
