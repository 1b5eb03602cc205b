"""Weave builder, Python face: keys in SI, a preset, a pattern by name or as a 0/1 matrix.

    w = woven.weave(preset='km2_706', nx=5, ny=5, cp_per_span=4)
    w.engine       # woven.FabricEngine
    w.summary      # dict of measured figures (areal density, crimp, clearances, counts)
"""
import math

from . import _woven
from ._args import finite as _finite

# key: (default, unit, description). None = keep the preset's value.
WEAVE_KEYS = {
    'preset': ('km2_706', '', "'km2_706' or 'none' (then give every material and section key)"),
    'pattern': ('plain', '', "plain, twill, satin, basket, or a 0/1 matrix '1,0;0,1' (1 = warp over weft)"),
    'twill_over': (2, '', 'twill: wefts each warp passes over'),
    'twill_under': (1, '', 'twill: wefts each warp passes under'),
    'satin_n': (5, '', 'satin: harnesses'),
    'satin_step': (2, '', 'satin: move number'),
    'basket_n': (2, '', 'basket: yarns per group'),
    'nx': (1, '', 'repeats of the pattern along x (weft yarns = nx * pattern columns)'),
    'ny': (1, '', 'repeats of the pattern along y (warp yarns = ny * pattern rows)'),
    'spacing': (None, 'm', 'centre distance of neighbouring yarns, both families'),
    'warp_spacing': (None, 'm', 'centre distance of neighbouring warp yarns'),
    'weft_spacing': (None, 'm', 'centre distance of neighbouring weft yarns'),
    'width': (None, 'm', 'yarn width, both families'),
    'thickness': (None, 'm', 'yarn thickness, both families'),
    'E': (None, 'Pa', "Young's modulus of the fibre"),
    'rho': (None, 'kg/m^3', 'fibre density'),
    'area': (None, 'm^2', 'fibre cross-section area of a yarn'),
    'linear_density': (None, 'kg/m', 'yarn linear density (sets area = linear_density/rho)'),
    'damping': (None, '', 'damping ratio of the highest chain mode (c = xi*sqrt(K*m_e))'),
    'failure_strain': (None, '', 'strain at break'),
    'bending_stiffness': (None, 'N m^2', 'bending stiffness EI of a yarn, [0, 1] (0: none, the paper\'s chain; KM2 '
                          '600 den filaments alone: about 3e-8; docs/chain.md)'),
    'tension_only': (None, '', 'yarns carry no compression (1) or do (0)'),
    'crimp': (None, '', 'crimp of both families; < 0 = Peirce with touching yarns'),
    'warp_crimp': (None, '', 'warp crimp; < 0 = Peirce'),
    'weft_crimp': (None, '', 'weft crimp; < 0 = Peirce'),
    'cp_per_span': (None, '', 'CPs between neighbouring crossings (>= 1); inside fine_radius when adaptive'),
    'fine_radius': (None, 'm', 'adaptive resolution: spans within this distance of (fine_x, fine_y) get cp_per_span '
                    'CPs, the others cp_coarse; < 0: uniform cp_per_span'),
    'cp_coarse': (None, '', 'CPs between crossings outside fine_radius, [1, cp_per_span]'),
    'fine_x': (None, 'm', 'x of the fine centre (default: the middle of the fabric)'),
    'fine_y': (None, 'm', 'y of the fine centre (default: the middle of the fabric)'),
}


# Allowed range of each numeric key, as the errors state it (the C++ side checks the same ranges).
WEAVE_RANGES = {
    'twill_over': (1, 1000, ''), 'twill_under': (1, 1000, ''), 'satin_n': (3, 1000, ''), 'satin_step': (1, 1000, ''),
    'basket_n': (1, 1000, ''), 'nx': (1, 100000, ''), 'ny': (1, 100000, ''),
    'spacing': (1e-8, 1, 'm'), 'warp_spacing': (1e-8, 1, 'm'), 'weft_spacing': (1e-8, 1, 'm'),
    'width': (1e-8, 1, 'm'), 'thickness': (1e-8, 1, 'm'), 'E': (1e5, 1e13, 'Pa'), 'rho': (1, 1e5, 'kg/m^3'),
    'area': (1e-16, 1e-2, 'm^2'), 'linear_density': (1e-16, 1e3, 'kg/m'), 'damping': (0, 9.999, ''),
    'failure_strain': (1e-12, 10, ''), 'bending_stiffness': (0, 1, 'N m^2'), 'tension_only': (0, 1, ''), 'crimp': (-1e300, 0.999999, ''),
    'warp_crimp': (-1e300, 0.999999, ''), 'weft_crimp': (-1e300, 0.999999, ''), 'cp_per_span': (1, 1000, ''),
    'fine_radius': (-1e300, 1e3, 'm'), 'cp_coarse': (1, 1000, ''), 'fine_x': (-1e3, 1e3, 'm'), 'fine_y': (-1e3, 1e3, 'm'),
}
_INTEGER_KEYS = ('twill_over', 'twill_under', 'satin_n', 'satin_step', 'basket_n', 'nx', 'ny', 'cp_per_span',
                 'cp_coarse', 'tension_only')


def _num(key, value):
    """A key's value as a number in its WEAVE_RANGES range; ValueError naming the key otherwise."""
    lo, hi, unit = WEAVE_RANGES[key]
    return _finite(key, value, lo, hi, unit, integer=key in _INTEGER_KEYS)


def pattern(name='plain', twill_over=2, twill_under=1, satin_n=5, satin_step=2, basket_n=2):
    """A woven.Pattern from a name or a matrix (list of lists, or text '1,0;0,1'). Entries must be
    exactly 0 or 1 (1.7 is refused, not truncated)."""
    if isinstance(name, (list, tuple)):
        try:
            rows = [list(r) for r in name]
        except TypeError:
            raise ValueError("pattern = %r is invalid: allowed a 0/1 matrix (list of rows)" % (name,)) from None
        return _woven.Pattern(rows)
    if isinstance(name, str) and (';' in name or ',' in name):
        rows = [r for r in name.replace(' ', '').split(';') if r]
        try:
            return _woven.Pattern([[float(v) for v in r.split(',')] for r in rows])
        except ValueError:
            raise ValueError("pattern = %r is invalid: allowed a 0/1 matrix written '1,0;0,1'" % name) from None
    if not isinstance(name, str):
        raise ValueError("pattern = %r is invalid: allowed plain, twill, satin, basket or a 0/1 matrix '1,0;0,1'" % (name,))
    twill_over, twill_under = _num('twill_over', twill_over), _num('twill_under', twill_under)
    satin_n, satin_step, basket_n = _num('satin_n', satin_n), _num('satin_step', satin_step), _num('basket_n', basket_n)
    if name == 'twill':
        return _woven.Pattern.twill(twill_over, twill_under)
    if name == 'satin':
        return _woven.Pattern.satin(satin_n, satin_step)
    if name == 'basket':
        return _woven.Pattern.basket(basket_n)
    return _woven.Pattern.by_name(name)


class Weave:
    """A built weave: .engine (FabricEngine), .summary (dict), .warp_yarns, .weft_yarns, .params."""

    def __init__(self, engine, summary, warp, weft, params, pattern):
        self.engine, self.summary, self.warp_yarns, self.weft_yarns = engine, summary, warp, weft
        self.params, self.pattern = params, pattern


def _summary_dict(s):
    return {
        'warp_yarns': s.warp_yarns, 'weft_yarns': s.weft_yarns, 'nodes': s.nodes, 'elements': s.elements,
        'spans': s.spans, 'fine_spans': s.fine_spans, 'min_element_length': s.min_element_length,
        'areal_density': s.areal_density,
        'warp_crimp_peirce': s.warp_peirce.crimp, 'weft_crimp_peirce': s.weft_peirce.crimp,
        'warp_crimp_built': s.warp_crimp_built, 'weft_crimp_built': s.weft_crimp_built,
        'warp_crimp_height': s.warp_peirce.h, 'weft_crimp_height': s.weft_peirce.h,
        'warp_weave_angle': s.warp_peirce.theta, 'weft_weave_angle': s.weft_peirce.theta,
        'required_gap': s.required_gap, 'min_vertical_gap': s.min_vertical_gap,
        'min_chain_clearance': s.min_chain_clearance, 'length_x': s.length_x, 'length_y': s.length_y,
    }


SUMMARY_UNITS = {
    'areal_density': 'kg/m^2', 'warp_crimp_height': 'm', 'weft_crimp_height': 'm', 'warp_weave_angle': 'rad',
    'weft_weave_angle': 'rad', 'required_gap': 'm', 'min_vertical_gap': 'm', 'min_chain_clearance': 'm',
    'length_x': 'm', 'length_y': 'm', 'min_element_length': 'm',
}


def weave(**kw):
    """Builds a weave from WEAVE_KEYS (SI units); unknown keys raise ValueError naming them."""
    for k in kw:
        if k not in WEAVE_KEYS:
            raise ValueError('unknown weave parameter %r: allowed keys are %s' % (k, ', '.join(sorted(WEAVE_KEYS))))
    a = {k: (kw[k] if kw.get(k) is not None else v[0]) for k, v in WEAVE_KEYS.items()}
    if a['preset'] == 'km2_706':
        P = _woven.km2_706()
    elif a['preset'] in ('none', '', None):
        P = _woven.WeaveParams()
        P.warp_spacing = P.weft_spacing = 1e-3
    else:
        raise ValueError("preset = %r is invalid: allowed 'km2_706' or 'none'" % a['preset'])
    pat = pattern(a['pattern'], a['twill_over'], a['twill_under'], a['satin_n'], a['satin_step'], a['basket_n'])
    # Every value read as a number of its key's range here, so that a string or an absurd value is
    # refused naming the key (float('abc') said only "could not convert string to float").
    num = {k: _num(k, a[k]) for k in WEAVE_RANGES if k in a and a[k] is not None and k not in (
        'twill_over', 'twill_under', 'satin_n', 'satin_step', 'basket_n')}
    P.pattern = pat
    P.nx, P.ny = num['nx'], num['ny']
    for fam in ('warp', 'weft'):
        sp = num.get(fam + '_spacing', num.get('spacing'))
        if sp is not None:
            setattr(P, fam + '_spacing', sp)
        sec, mat = getattr(P, fam + '_section'), getattr(P, fam + '_material')
        for key in ('width', 'thickness'):
            if key in num:
                setattr(sec, key, num[key])
        for key in ('E', 'rho', 'area', 'damping', 'failure_strain'):
            if key in num:
                setattr(mat, key, num[key])
        if 'bending_stiffness' in num:
            mat.bending = num['bending_stiffness']
        if 'linear_density' in num:
            area = num['linear_density'] / mat.rho
            if not (1e-16 <= area <= 1e-2):
                raise ValueError('linear_density = %r is invalid: allowed a value giving area = linear_density / rho '
                                 'in [1e-16, 1e-2] m^2 (here %g m^2)' % (a['linear_density'], area))
            mat.area = area
        if 'tension_only' in num:
            mat.tension_only = bool(num['tension_only'])
        setattr(P, fam + '_section', sec)
        setattr(P, fam + '_material', mat)
        cr = num.get(fam + '_crimp', num.get('crimp'))
        if cr is not None:
            setattr(P, fam + '_crimp', cr)
    if 'cp_per_span' in num:
        P.cp_per_span = num['cp_per_span']
    for key in ('fine_radius', 'cp_coarse', 'fine_x', 'fine_y'):
        if key in num:
            setattr(P, key, num[key])
    engine, s, warp, weft = _woven.build_weave(P)
    summary = _summary_dict(s)
    summary['cp_per_span'] = P.cp_per_span
    summary['fine_radius'], summary['cp_coarse'] = P.fine_radius, P.cp_coarse
    return Weave(engine, summary, list(warp), list(weft), a, pat)
