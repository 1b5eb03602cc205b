"""Errors that name the argument for every call into woven's C++ module.

Boost.Python refuses an argument of the wrong type with its own ArgumentError ("Python argument
types in ... did not match C++ signature") or, for an integer past 2^31, an OverflowError saying only
"bad numeric conversion": neither names the argument nor says what is allowed. This module wraps every
function, method, constructor and property setter of woven._woven so that such a failure becomes a
ValueError "NAME = VALUE is invalid: allowed ...", found from the signature Boost.Python writes into
each docstring. Values of the right type are still checked by the C++ side (ParameterError, which
already names the parameter and its range); a successful call pays one Python frame.
"""
import functools
import math
import numbers
import re

_SIG = re.compile(r'^\s*(\w+)\((.*?)\) ->', re.M)
_ARG = re.compile(r'\((\w+)\)(\w+)(=[^,\]]*)?')
# Index arguments and the engine attribute that bounds them.
_INDEX_OF = {'node': 'n_nodes', 'element': 'n_elements', 'yarn': 'n_yarns', 'index': 'n_bodies'}
_INT32 = (-2 ** 31, 2 ** 31 - 1)


def _signature(fn):
    """[(type, name, optional)] of a Boost.Python function, from its docstring ([] if none)."""
    m = _SIG.search(getattr(fn, '__doc__', None) or '')
    if not m:
        return []
    return [(t, n, bool(d)) for t, n, d in _ARG.findall(m.group(2))]


def _is_real(v):
    return isinstance(v, numbers.Real)


def _is_vec(v, n):
    try:
        return len(v) == n and all(_is_real(v[k]) for k in range(n))
    except Exception:
        return False


def _allowed(kind, name, owner):
    if kind == 'int':
        attr = _INDEX_OF.get(name)
        if attr is not None and owner is not None and hasattr(owner, attr):
            count = getattr(owner, attr)
            return 'an integer index in [0, %d] (%s of this engine)' % (count - 1, name)
        return 'an integer in [%d, %d]' % _INT32
    return {'float': 'a real number (SI units)', 'str': 'a string', 'bool': 'True/False (or 0/1)',
            'Vector3': 'a Vector3 (3 real numbers, SI units)', 'Quaternion': 'a unit Quaternion',
            'Matrix3': 'a Matrix3 (3 x 3 real numbers)', 'object': 'a list'}.get(kind, 'a %s' % kind)


def _bad(kind, value):
    """True when `value` cannot be what a `kind` argument takes."""
    if kind == 'float':
        return not _is_real(value)
    if kind in ('int', 'bool'):
        if not isinstance(value, numbers.Integral):
            return True
        return kind == 'int' and not (_INT32[0] <= int(value) <= _INT32[1])
    if kind == 'str':
        return not isinstance(value, str)
    if kind == 'Vector3':
        return not _is_vec(value, 3)
    if kind == 'object':  # a list (nodes, points, parts): at least iterable
        try:
            iter(value)
        except TypeError:
            return True
        return isinstance(value, (str, bytes))
    if kind in ('Quaternion', 'Matrix3'):
        return type(value).__name__ != kind
    # a woven class (YarnMaterial, Pattern, WeaveParams, ...)
    return type(value).__name__ != kind


def _short(v):
    r = repr(v)
    return r if len(r) <= 60 else r[:57] + '...'


def _diagnose(fname, sig, args, kw, owner, error):
    names = [n for _, n, _ in sig]
    for k in kw:
        if k not in names:
            return 'unknown argument %r of %s: allowed %s' % (k, fname, ', '.join(names) or 'none')
    given = dict(zip(names, args))
    if len(args) > len(names):
        return '%s takes %d arguments (%s): %d given' % (fname, len(names), ', '.join(names), len(args))
    given.update(kw)
    for kind, name, optional in sig:
        if name not in given:
            if not optional:
                return 'argument %s of %s is missing: allowed %s' % (name, fname, _allowed(kind, name, owner))
            continue
        v = given[name]
        if _bad(kind, v):
            return '%s = %s is invalid: allowed %s' % (name, _short(v), _allowed(kind, name, owner))
    detail = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
    return '%s(%s) arguments are invalid (%s): allowed %s' % (
        fname, ', '.join(names), detail, ', '.join('%s: %s' % (n, _allowed(t, n, owner)) for t, n, _ in sig))


def _conversion_error(e):
    # Boost.Python's stl_input_iterator raises AttributeError ('... has no attribute __iter__') for a
    # list argument given something else.
    return (type(e).__name__ == 'ArgumentError' or isinstance(e, (OverflowError, TypeError)) or
            (isinstance(e, AttributeError) and '__iter__' in str(e)))


def _wrap_method(cls_name, name, raw):
    sig = _signature(raw)
    if not sig:
        return None
    method = sig[0][1] == 'arg1'  # bound (or a constructor): the first argument is self
    asig = sig[1:] if method else sig

    fname = '%s.%s' % (cls_name, name) if cls_name else name
    # Boost.Python takes True for a real number (1.0): a bool given for a step size (dt) or any other
    # real argument ran with 1 (found by fuzzing). Refused, naming the argument: a check of the few
    # real arguments by identity, before the call.
    # The same for a vector given as a list with a bool in it (YADE's converter reads True as 1.0).
    reals = [(k, n, t) for k, (t, n, _) in enumerate(asig) if t in ('float', 'Vector3')]
    skip = 1 if method else 0

    def refuse_bools(args, kw):
        for k, n, t in reals:
            v = args[skip + k] if skip + k < len(args) else kw.get(n)
            if t == 'float':
                if v is True or v is False:
                    raise ValueError('%s = %r is invalid: allowed a real number (SI units), not a bool (argument of %s)'
                                     % (n, v, fname))
            elif type(v) in (list, tuple) and any(x is True or x is False for x in v):
                raise ValueError('%s = %s is invalid: allowed a Vector3 of 3 real numbers (SI units), not bools (argument '
                                 'of %s)' % (n, _short(v), fname))

    @functools.wraps(raw)
    def call(*args, **kw):
        if reals:
            refuse_bools(args, kw)
        try:
            return raw(*args, **kw)
        except Exception as e:
            if not _conversion_error(e):
                raise
            owner = args[0] if method and args else None
            rest = args[1:] if method else args
            raise ValueError(_diagnose(fname, asig, rest, kw, owner, e)) from None
    return call


def _wrap_setter(name, prop):
    def fset(self, value):
        if value is True or value is False:  # a bool for a real-valued property (a time, a factor): refused
            try:
                current = prop.fget(self) if prop.fget else None
            except Exception:
                current = None
            if isinstance(current, float):
                raise ValueError('%s = %r is invalid: allowed %s, not a bool' % (name, value, _allowed('float', name, None)))
        try:
            prop.fset(self, value)
        except Exception as e:
            if not _conversion_error(e):
                raise
            try:
                current = prop.fget(self) if prop.fget else None
            except Exception:
                current = None
            kind = ('bool' if isinstance(current, bool) else 'int' if isinstance(current, numbers.Integral)
                    else 'float' if _is_real(current) else type(current).__name__)
            raise ValueError('%s = %s is invalid: allowed %s' % (name, _short(value), _allowed(kind, name, None))) from None
    return property(prop.fget, fset, prop.fdel, prop.__doc__)


def install(module):
    """Wraps the functions and classes of the extension `module` in place (once)."""
    if getattr(module, '_args_installed', False):
        return
    for attr in list(vars(module)):
        obj = getattr(module, attr)
        if type(obj).__name__ == 'function' and type(obj).__module__ == 'Boost.Python':
            w = _wrap_method('', attr, obj)
            if w is not None:
                setattr(module, attr, w)
        elif isinstance(obj, type) and getattr(obj, '__module__', '') == module.__name__:
            for name, member in list(vars(obj).items()):
                if isinstance(member, property):
                    if member.fset is not None:
                        setattr(obj, name, _wrap_setter(name, member))
                elif isinstance(member, staticmethod):
                    w = _wrap_method(obj.__name__, name, member.__func__)
                    if w is not None:
                        setattr(obj, name, staticmethod(w))
                elif type(member).__name__ == 'function' and type(member).__module__ == 'Boost.Python':
                    w = _wrap_method(obj.__name__, name, member)
                    if w is not None:
                        setattr(obj, name, w)
    module._args_installed = True


def finite(name, value, lo=-math.inf, hi=math.inf, unit='', integer=False):
    """value as a float (int with integer=True) in [lo, hi]; else ValueError naming `name` and the range."""
    rng = '[%g, %g]%s' % (lo, hi, (' ' + unit) if unit else '')
    kind = 'an integer' if integer else 'a finite number'
    try:
        # a bool is no real quantity (True read as 1 s, 1 m...): refused unless a count was asked for
        if isinstance(value, (bytes, bytearray)) or (isinstance(value, bool) and not integer):
            raise TypeError
        v = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError('%s = %s is invalid: allowed %s in %s' % (name, _short(value), kind, rng)) from None
    if not (math.isfinite(v) and lo <= v <= hi) or (integer and v != int(v)):
        raise ValueError('%s = %s is invalid: allowed %s in %s' % (name, _short(value), kind, rng))
    return int(v) if integer else v
