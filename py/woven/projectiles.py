"""Standard projectiles: the 0.22-calibre right circular cylinder (RCC) and the 17-grain 0.22-calibre
fragment-simulating projectile (FSP) with its chisel nose, as exact solids (woven's cylinder part,
pkg/shape/Cylinder.hpp), their mass, centre of mass and principal inertia. SI units.

    s = woven.projectiles.solid('fsp')           # dict: radius, half_length, chisel_angle, land_half_width,
                                                 # density, volume, mass, centroid_z, inertia
    s = woven.projectiles.solid('rcc', diameter=5.588e-3, density=7850)

Part frame: axis z, the enclosing cylinder's centre at the origin, the nose (chisel) at +z. The
solid is symmetric under x -> -x and y -> -y, so its principal axes are x (across the flats), y
(along the flat tip) and z; its centre of mass lies on the axis at centroid_z (< 0 for the FSP: the
chisel takes metal from the nose). Dimensions: docs/ballistic.md, "Packs and standard projectiles".
"""
import math

import numpy as np

STEEL_DENSITY = 7850.0  # [kg/m^3]
RCC_DIAMETER = 5.588e-3  # [m] 0.22 in; length = diameter
# FSP, 0.22 calibre, 17 grains (MIL-DTL-46593B; see docs/ballistic.md for what is taken from where)
FSP_DIAMETER = 5.588e-3  # [m] 0.220 in
FSP_LENGTH = 6.35e-3  # [m] 0.250 in
FSP_CHISEL_ANGLE = 35.0  # [deg] each flat to the axis
FSP_MASS = 17 * 64.79891e-6  # [kg] 17 grains = 1.1016 g
GRAIN = 64.79891e-6  # [kg]


def _strip_moments(R, h):
    """A disk of radius R cut to |x| <= h (0 <= h <= R): area, integral of x^2 and of y^2 [m^2, m^4]."""
    h = np.minimum(h, R)
    s = np.sqrt(np.maximum(R * R - h * h, 0.0))
    a = np.arcsin(h / R)
    area = 2 * (h * s + R * R * a)
    x2 = (h * (2 * h * h - R * R) * s + R ** 4 * a) / 2
    y2 = (h * (5 * R * R - 2 * h * h) * s + 3 * R ** 4 * a) / 6
    return area, x2, y2


def mass_properties(radius, half_length, chisel_angle=0.0, land_half_width=0.0, density=STEEL_DENSITY, order=64):
    """Volume [m^3], mass [kg], centre of mass on the axis [m] and principal inertia about it
    (x across the flats, y, z the axis) [kg m^2] of the cylinder part (chisel_angle [rad] > 0: the
    FSP's nose). Slices across the axis are a disk cut to a strip, integrated in closed form; along
    the axis the full disk in closed form and the chisel (smooth in z) by Gauss-Legendre of `order`
    points (exact to rounding at 64)."""
    R, H = float(radius), float(half_length)
    parts = []  # (z0, z1, strip half-width as a function of z or None: full disk)
    if chisel_angle > 0:
        t = math.tan(chisel_angle)
        zf = H - (R - land_half_width) / t  # where the flats meet the round surface
        parts = [(-H, zf, None), (zf, H, lambda z: land_half_width + (H - z) * t)]
    else:
        parts = [(-H, H, None)]
    V = Mz = Mzz = Sx = Sy = 0.0
    xg, wg = np.polynomial.legendre.leggauss(order)
    for z0, z1, half in parts:
        if half is None:  # full disk: area pi R^2, x^2 and y^2 moments pi R^4 / 4 each
            L = z1 - z0
            A, q = math.pi * R * R, math.pi * R ** 4 / 4
            V += A * L
            Mz += A * (z1 * z1 - z0 * z0) / 2
            Mzz += A * (z1 ** 3 - z0 ** 3) / 3
            Sx += q * L
            Sy += q * L
        else:
            z = 0.5 * (z1 - z0) * xg + 0.5 * (z1 + z0)
            w = 0.5 * (z1 - z0) * wg
            A, x2, y2 = _strip_moments(R, half(z))
            V += np.sum(w * A)
            Mz += np.sum(w * A * z)
            Mzz += np.sum(w * A * z * z)
            Sx += np.sum(w * x2)
            Sy += np.sum(w * y2)
    zc = Mz / V
    Izz_c = Mzz - V * zc * zc  # integral of (z - zc)^2 dV
    inertia = (density * (Sy + Izz_c), density * (Sx + Izz_c), density * (Sx + Sy))
    return {'volume': V, 'mass': density * V, 'centroid_z': zc, 'inertia': inertia}


def solid(shape, diameter=0.0, density=STEEL_DENSITY):
    """The 'rcc' (diameter = length = `diameter`, 0: 5.588 mm) or 'fsp' (the drawing's dimensions;
    `diameter` must be 0) solid of `density` [kg/m^3]: its part dimensions and mass properties."""
    if shape == 'rcc':
        D = diameter or RCC_DIAMETER
        out = {'radius': D / 2, 'half_length': D / 2, 'chisel_angle': 0.0, 'land_half_width': 0.0}
    elif shape == 'fsp':
        if diameter:
            raise ValueError('size = %r is invalid: allowed 0 for shape fsp (its drawing fixes its size)' % diameter)
        out = {'radius': FSP_DIAMETER / 2, 'half_length': FSP_LENGTH / 2,
               'chisel_angle': math.radians(FSP_CHISEL_ANGLE), 'land_half_width': fsp_land_half_width()}
    else:
        raise ValueError("shape = %r is invalid: allowed 'rcc' or 'fsp'" % (shape,))
    out['density'] = density
    out.update(mass_properties(out['radius'], out['half_length'], out['chisel_angle'], out['land_half_width'], density))
    return out


def fsp_land_half_width():
    """Half-width [m] of the FSP's flat tip that makes a 17-grain (1.1016 g) steel solid of the
    drawing's diameter, length and flat angle: the chisel's depth follows from the mass (bisection;
    the mass grows with the land)."""
    R, H, a = FSP_DIAMETER / 2, FSP_LENGTH / 2, math.radians(FSP_CHISEL_ANGLE)
    lo, hi = 0.0, R * (1 - 1e-12)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mass_properties(R, H, a, mid)['mass'] < FSP_MASS:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def parts(s):
    """woven's part list of the solid `s` in the body frame (origin at its centre of mass):
    [('cylinder', (radius, half_length, chisel_angle, land_half_width), offset, identity)]."""
    from yade._minieigenHP import Quaternion, Vector3
    return [('cylinder', (s['radius'], s['half_length'], s['chisel_angle'], s['land_half_width']),
             Vector3(0, 0, -s['centroid_z']), Quaternion.Identity)]
