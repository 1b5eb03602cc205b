"""Collision handling, Python face: the parameter table shared by scene scripts and yade-batch tables.

    woven.contact.enable(engine, mcd=0.6, restitution=0)   # same keys as CONTACT_KEYS, SI units
"""

import math

from . import _woven

# key: (default, unit, description); the keys of FabricEngine.enable_collisions.
CONTACT_KEYS = {
    'restitution': (0.0, '', 'coefficient of restitution e of Eq. 5, in [0, 1]'),
    'friction': (0.0, '', 'Coulomb coefficient between yarns, in [0, 2] (0 as in the paper; 0 with response=penalty); its work is the energy book friction'),
    'body_friction': (0.0, '', 'Coulomb coefficient between a rigid body (the projectile) and the yarns, in [0, 2] (0 with response=penalty); its work is the energy book friction'),
    'mcd': (0.6, '', 'maximum cross-sectional deformation eps = 1 - b/r0, in (0, 1)'),
    'section_rule': ('constant_area', '', "flattening: 'constant_area' (a*b = r0^2) or 'paper' (a = r0(1+eps))"),
    'margin': (1e-6, 'm', 'added to each side of a CP box: contacts start this close'),
    'tolerance': (1e-6, 'm/s', 'Eq. 4 resting band (and the impulse solve\'s least tolerance)'),
    'solver_tolerance': (1e-9, 'm', 'the impulse sweeps stop once no row errs the step\'s drift by more than this, in [0, 1e-3] '
                         '(0: tolerance alone; contact_model=gap only, the paper model stops at tolerance); the rows '
                         'over it are the unresolved ones'),
    'max_iterations': (50, '', 'impulse sweeps per step at most'),
    'flatten_passes': (4, '', 'flattening re-tests per step'),
    'position_correction': (0.2, '', 'contact_model=paper: fraction of a locked overlap removed per step before the drift, in [0, 1]'),
    'correction_slop': (0.5e-6, 'm', 'contact_model=paper: overlap the positional correction leaves alone'),
    'self_exclude': (1, '', 'CPs of one yarn this many elements apart never collide (raised to the section size)'),
    'broad_phase': ('tree', '', "'tree' (OBB tree per yarn), 'grid' (uniform grid of cells) or 'sap' (sweep and prune)"),
    'skin': (5e-6, 'm', 'Verlet skin: candidate pairs are kept while every CP box stays inside its box grown by this'),
    'threads': (0, '', 'threads of the collision stage in [0, 64]; 0: woven.threads() (OMP_NUM_THREADS, yade -j N); the same results, bit for bit, for any count'),
    'contact_cache': (1e-7, 'm', 'a contact is carried to the next step while its four nodes move together to within this (0: test every pair every step)'),
    'response': ('impulse', '', "'impulse' (Eq. 5 impulses, the paper) or 'penalty' (force k_p * overlap; docs/collisions.md)"),
    'penalty_stiffness': (1e5, 'N/m', 'penalty stiffness k_p > 0 (response=penalty), yarn-yarn and yarn-body'),
    'penalty_damping': (0.0, '', 'penalty damping ratio zeta in [0, 1): c = 2 zeta sqrt(k_p m_eff)'),
    'flattening': ('geometric', '', "'geometric' (free up to the MCD, the paper), 'none' (sections fixed) or 'springs' (Eq. 7 section springs)"),
    'section_stiffness': (1e4, 'N/m', 'section spring k_s > 0 (flattening=springs): a node flattened by r0*eps pushes back k_s*r0*eps'),
    'contact_model': ('gap', '', "'gap' (one gap function per contact kind, impulse rows its exact gradient, position projection "
                      "after the drift; the default) or 'paper' (the paper's SAT normal and depth, Sections 4-5; docs/collisions.md)"),
    'projection_sweeps': (-1, '', 'sweeps of the position projection after the drift (it stops once nothing moves), [0, 50]; -1: auto (8 with contact_model=gap '
                          'and response=impulse, else 0); >= 1 is refused with contact_model=paper or response=penalty'),
    'projection_slop': (0.5e-6, 'm', 'overlap the position projection leaves alone, in [0, 1e-3]'),
    'projection_max_move': (10e-6, 'm', 'most one contact moves a node in the position projection (3x this in all), in (0, 1e-3] (deep overlaps go out over a few steps)'),
    'projection_check': (2e-6, 'm', 'contacts still deeper than this after the flattening passes are projected out before the rows '
                         '(what the last projection left to a flattening that did not take it), in [0, 1e-3]; -1: no check'),
    'sweep_order': ('sequential', '', "row order of the impulse and projection sweeps: 'sequential' (contact order, serial; the default), "
                    "'coloured' (rows that share no node at once on the threads, colour by colour) or 'blocked' (slabs of the ply at once on the threads, "
                    "each in contact order, then the rows across the slabs); the same bits for any thread count in each"),
    'yarn_contacts': (True, '', 'contacts between yarns (False: only with rigid bodies; yarns pass through each other)'),
    'crossings': ('persistent', '', "contact_model=gap: 'persistent' (one contact per crossing of two yarns, carried from step to step on "
                  "their smooth centre lines; the default) or 'chords' (every CP pair measured afresh each step: four chord-pair contacts "
                  "per crossing, the model before persistent crossings; docs/collisions.md)"),
}


FRICTION_KEYS = ('friction', 'body_friction')


def check_friction(keys):
    """Refuses, before anything is built, a friction key of `keys` (a dict or a scene's params) outside
    [0, 2] or above 0 with response=penalty (Coulomb friction acts in the impulse rows only): ValueError
    naming the key and its range. Keys absent from `keys` take their defaults."""
    response = keys['response'] if 'response' in keys else CONTACT_KEYS['response'][0]
    for k in FRICTION_KEYS:
        if k not in keys:
            continue
        v = _convert(k, keys[k])
        if not (math.isfinite(v) and 0 <= v <= 2):
            raise ValueError('%s = %r is invalid: allowed [0, 2] (%s)' % (k, keys[k], CONTACT_KEYS[k][2]))
        if v > 0 and response == 'penalty':
            raise ValueError("%s = %r is invalid: allowed 0 with response = 'penalty' (Coulomb friction acts in the "
                             "impulse rows only); [0, 2] with response = 'impulse'" % (k, keys[k]))


def penalty_dt_limit(m, k):
    """Largest stable time step [s] of a penalty contact of effective mass m [kg] and stiffness k [N/m]:
    2 sqrt(m / k) (central differences on an undamped spring; docs/collisions.md)."""
    from ._args import finite
    return _woven.penalty_dt_limit(finite('m', m, 0, 1e6, 'kg'), finite('k', k, 0, 1e15, 'N/m'))


def _convert(key, value):
    """A contact key's value as the type of its default; ValueError naming the key and what it allows
    (a string given for a number raised Boost.Python's ArgumentError, 2.5 iterations became 2)."""
    default, unit, doc = CONTACT_KEYS[key]
    allowed = '%s%s' % (doc, (' [%s]' % unit) if unit else '')
    if isinstance(default, bool):
        if isinstance(value, bool) or (isinstance(value, (int, float)) and value in (0, 1)):
            return bool(value)
        if isinstance(value, str) and value.strip().lower() in ('0', '1', 'true', 'false'):
            return value.strip().lower() in ('1', 'true')
        raise ValueError('%s = %r is invalid: allowed 0/1 or True/False (%s)' % (key, value, allowed))
    if isinstance(default, str):
        if not isinstance(value, str):
            raise ValueError('%s = %r is invalid: allowed %s' % (key, value, allowed))
        return value
    try:
        # a bool for a real-valued key (True read as 1) is refused; integer keys take 0/1 as counts
        if isinstance(value, (str, bytes)) or value is None or (isinstance(value, bool) and isinstance(default, float)):
            raise TypeError
        f = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError('%s = %r is invalid: allowed a number: %s' % (key, value, allowed)) from None
    if isinstance(default, int):
        if not (math.isfinite(f) and f == int(f) and abs(f) < 2 ** 31):
            raise ValueError('%s = %r is invalid: allowed an integer: %s' % (key, value, allowed))
        return int(f)
    if math.isnan(f):
        raise ValueError('%s = %r is invalid: allowed a number: %s' % (key, value, allowed))
    return f


def enable(engine, **kw):
    """Turns collision handling on for `engine` with CONTACT_KEYS (others are refused)."""
    bad = sorted(set(kw) - set(CONTACT_KEYS))
    if bad:
        raise ValueError('unknown contact key(s) %s: allowed %s' % (', '.join(bad), ', '.join(sorted(CONTACT_KEYS))))
    args = {k: _convert(k, kw[k]) if k in kw else v[0] for k, v in CONTACT_KEYS.items()}
    engine.enable_collisions(**args)
    return engine
