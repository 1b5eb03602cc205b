"""Scene parameters: `key=value` on the command line and the same keys from yade-batch tables.

    p = read_params({'V': (200.0, 'm/s', 'impact speed'), ...})

Each default is (value, unit, description); the value's type (float, int, bool, str) is the type
the key is read as. Precedence: defaults < yade-batch table line (YADE_BATCH) < command line.
Unknown keys and unparsable values raise ValueError naming the key and what is allowed.
"""
import math
import os
import sys


# The most steps a scene may be asked to run: a billion steps of the smallest scenes (~10 us each) is
# months of CPU, and a count past 2^63 overflowed YADE's C long (safety = 1e-300: an OverflowError
# instead of an error naming the key).
MAX_STEPS = 10 ** 9


def check_steps(duration, dt, key, value, what='the run'):
    """Refuses a run of `duration` s at time step `dt` that would take more than MAX_STEPS steps:
    ValueError naming `key` (the key that set dt, in proportion: safety, guard_safety) with the least
    value this run allows. Returns duration / dt."""
    n = duration / dt if dt > 0 else math.inf
    if not n <= MAX_STEPS:
        least = value * n / MAX_STEPS if math.isfinite(n) else math.inf
        raise ValueError('%s = %r is invalid: %s (%.6g s) would take %.3g steps of %.3g s, more than %d; allowed %s >= '
                         '%.3g here (within its own range)' % (key, value, what, duration, n, dt, MAX_STEPS, key, least))
    return n


class Params(dict):
    """dict with attribute access; .units and .docs hold each key's unit and description."""

    def __getattr__(self, k):
        try:
            return self[k]
        except KeyError:
            raise AttributeError(k)


def _convert(key, text, default):
    t = text.strip()
    if len(t) >= 2 and t[0] == t[-1] and t[0] in '"\'':
        t = t[1:-1]
    try:
        if isinstance(default, bool):
            low = t.lower()
            if low in ('1', 'true', 'yes', 'on'):
                return True
            if low in ('0', 'false', 'no', 'off'):
                return False
            raise ValueError
        if isinstance(default, int):
            f = float(t)
            # Past 2^53 a float no longer holds every integer (and 1e300 is no count of anything).
            if not (math.isfinite(f) and abs(f) <= 2 ** 53) or f != int(f):
                raise ValueError
            return int(f)
        if isinstance(default, float):
            return float(t)
        if default is None:  # no default: a number if it reads as one, else text
            for cast in (int, float):
                try:
                    return cast(t)
                except ValueError:
                    pass
        return t
    except ValueError:
        kind = {bool: '0/1/true/false', int: 'an integer in [-2^53, 2^53]', float: 'a number'}.get(type(default), 'text')
        raise ValueError('%s = %r is invalid: allowed %s' % (key, text, kind)) from None


def _batch_line():
    """The parameters of this yade-batch job (column -> text), or {} outside yade-batch."""
    spec = os.environ.get('YADE_BATCH', '')
    if not spec:
        return {}
    from yade.utils import TableParamReader
    table, line = spec.rsplit(':', 1)
    row = TableParamReader(table).paramDict()[int(line)]
    return {k: v for k, v in row.items() if k != 'description' and not k.startswith('!')}


def read_params(defaults, argv=None):
    """defaults: {key: (value, unit, description)}; argv: list of 'key=value' (default sys.argv[1:])."""
    if argv is None:
        argv = sys.argv[1:]
    p = Params({k: v[0] for k, v in defaults.items()})
    p.units = {k: v[1] for k, v in defaults.items()}
    p.docs = {k: v[2] for k, v in defaults.items()}
    given = dict(_batch_line())
    for a in argv:
        if '=' not in a:
            raise ValueError('argument %r is invalid: allowed key=value with key one of %s' % (a, ', '.join(sorted(defaults))))
        k, v = a.split('=', 1)
        given[k.strip()] = v
    p.given = set(given)  # the keys set by the table line or the command line (the rest are defaults)
    for k, v in given.items():
        if k not in defaults:
            raise ValueError('unknown parameter %r: allowed keys are %s' % (k, ', '.join(sorted(defaults))))
        p[k] = _convert(k, v, defaults[k][0]) if isinstance(v, str) else v
    return p


def dry_run_script(path, argv=(), batch=None, dry=True):
    """Runs the scene script `path` with `argv` (['key=value', ...]) in this process under
    WOVEN_DRY_RUN=1: the script reads and checks its keys and stops where it would start building
    (woven.output.dry_run_stop). `batch`: 'TABLE:LINE' of a yade-batch table, as YADE_BATCH gives it.
    Returns ('accepted', '') or ('refused', message), the message of the error the script raised
    (or 'exit N' for a script that exited before its dry-run point). Needs YADE's namespace (run
    it under `yade -x`, or with yade imported): the scripts use O, Vector3, PyRunner as YADE gives them.
    One process checks many commands at the cost of one YADE start (tests/python/test_doc_commands.py).
    dry=False runs the script for real (a command expected to be refused, wherever the script
    refuses it): then ('completed', '') when it ran to its end, ('exit N', '') for sys.exit(N)."""
    import runpy
    from .output import DryRun
    main = sys.modules.get('__main__')
    names = vars(main) if main is not None and 'O' in vars(main) else None
    if names is None:
        import yade
        names = vars(yade)
    init = {k: v for k, v in names.items() if not k.startswith('_')}
    saved_argv, saved_env = sys.argv, {k: os.environ.get(k) for k in ('WOVEN_DRY_RUN', 'YADE_BATCH')}
    sys.argv = [path] + list(argv)
    if dry:
        os.environ['WOVEN_DRY_RUN'] = '1'
    else:
        os.environ.pop('WOVEN_DRY_RUN', None)
    if batch:
        os.environ['YADE_BATCH'] = batch
    else:
        os.environ.pop('YADE_BATCH', None)
    try:
        runpy.run_path(path, init_globals=init, run_name='__main__')
        return ('refused', 'the script ran to its end without reaching its dry-run point') if dry else ('completed', '')
    except DryRun:
        return 'accepted', ''
    except SystemExit as e:
        return ('refused', 'exit %s' % (e.code,)) if dry else ('exit %s' % (e.code,), '')
    except Exception as e:  # noqa: BLE001 - the script's own refusal, reported
        return 'refused', '%s: %s' % (type(e).__name__, e)
    finally:
        sys.argv = saved_argv
        for k, v in saved_env.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
