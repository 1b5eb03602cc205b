"""Output folders and summary.json: measured figures beside their reference figures, with units.

Every file woven writes is written atomically (atomic_path, atomic_open, write_text_atomic,
savetxt, savefig): into a temporary in the same folder, flushed, fsync'ed and renamed over the
target, so a failed or killed run never leaves a half-written summary.json or CSV where the previous
complete one was (state files do the same in C++, pkg/fabric/StateIO.cpp).
"""
import contextlib
import hashlib
import json
import math
import os
import sys
import tempfile


@contextlib.contextmanager
def atomic_path(path):
    """Yields a temporary path beside `path` (same folder, same extension, so writers that pick the
    format from the name still work); on success its bytes are fsync'ed and it is renamed onto `path`,
    on an exception it is removed and `path` is untouched."""
    if not isinstance(path, (str, os.PathLike)) or '\0' in os.fspath(path):
        raise ValueError('path = %r is invalid: allowed a file path without NUL characters' % (path,))
    path = os.fspath(path)
    folder, name = os.path.split(os.path.abspath(path))
    stem, ext = os.path.splitext(name)
    fd, tmp = tempfile.mkstemp(prefix='.%s.' % stem, suffix='.tmp' + ext, dir=folder)
    os.close(fd)
    try:
        yield tmp
        with open(tmp, 'rb+') as f:
            os.fsync(f.fileno())
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.remove(tmp)
        raise


@contextlib.contextmanager
def atomic_open(path, mode='w'):
    """open() for writing, atomically (atomic_path): the file appears whole or not at all."""
    with atomic_path(path) as tmp:
        with open(tmp, mode) as f:
            yield f
            f.flush()


def csv_field(v, digits=6):
    """One CSV field: '' for None, a float to `digits` significant digits, anything else as str."""
    if v is None:
        return ''
    if isinstance(v, float):
        return '%.*g' % (digits, v)
    return str(v)


def write_csv(path, columns, rows, digits=6):
    """Writes dict rows under `columns` (a row's missing key: an empty field), atomically."""
    with atomic_open(path) as f:
        f.write(','.join(columns) + '\n')
        for r in rows:
            f.write(','.join(csv_field(r.get(k), digits) for k in columns) + '\n')


def write_text_atomic(path, text):
    with atomic_open(path) as f:
        f.write(text)


def savetxt(path, *args, **kw):
    """numpy.savetxt, atomically."""
    import numpy as np
    with atomic_path(path) as tmp:
        np.savetxt(tmp, *args, **kw)


def savefig(fig, path, **kw):
    """matplotlib's fig.savefig, atomically."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, **kw)


class DryRun(SystemExit):
    """Raised by dry_run_stop under WOVEN_DRY_RUN=1: a SystemExit with status 0, so `yade -x` exits
    cleanly, and a class of its own, so a driver running scripts in one process can tell "the keys
    were accepted" from a script's own sys.exit."""

    def __init__(self, name):
        SystemExit.__init__(self, 0)
        self.scene = name


def dry_run():
    """True under WOVEN_DRY_RUN=1 (or any value but '', '0'): a scene reads and checks its keys and
    stops before it builds, runs or writes anything (docs: a command checked without running it)."""
    return os.environ.get('WOVEN_DRY_RUN', '') not in ('', '0')


def dry_run_stop(name):
    """Under WOVEN_DRY_RUN, says that `name`'s keys were accepted and stops the script (exit 0)."""
    if dry_run():
        print('%s: dry run (WOVEN_DRY_RUN=1): the keys are accepted; nothing was run' % name)
        sys.stdout.flush()
        raise DryRun(name)


def out_dir(name, params):
    """out/NAME under the working directory, or the folder given by params['out'] if not empty.

    Every scene calls it once its keys have passed their checks and before it builds anything: under
    WOVEN_DRY_RUN=1 the script stops here (dry_run_stop), having made no folder.

    Under yade-batch (YADE_BATCH set) a run whose folder already holds a complete summary.json of
    this scene made with the same keys is not done again: the script stops here with the recorded
    outcome (exit 0 for status 'ok', else 1), so a sweep killed mid-way resumes where it was by
    running the same yade-batch command again. WOVEN_RESUME=0 in the environment runs it anyway.
    Outside yade-batch a scene always runs (a run killed mid-way and started again overwrites its
    folder's files, each of them atomically)."""
    dry_run_stop(name)
    d = params.get('out') or os.path.join('out', name)
    os.makedirs(d, exist_ok=True)
    if os.environ.get('YADE_BATCH') and os.environ.get('WOVEN_RESUME', '1') != '0':
        s = complete_summary(d, name, params)
        if s is not None:
            print('%s: %s holds a complete summary.json for these keys (status %s): not run again '
                  '(yade-batch resume; WOVEN_RESUME=0 runs it)' % (name, d, s['status']))
            sys.stdout.flush()
            sys.exit(0 if s['status'] == 'ok' else 1)
    return d


def complete_summary(d, name, params):
    """The summary.json in folder `d` as a dict when it is complete: it parses, belongs to scene
    `name`, has a final status, and was made with `params` (every key but 'out'); else None. A
    summary written halfway cannot exist (write_summary is atomic); one of another scene or of
    other keys does not count."""
    from .campaign import _same
    try:
        with open(os.path.join(d, 'summary.json')) as f:
            s = json.load(f)
    except (OSError, ValueError):
        return None
    if not isinstance(s, dict) or s.get('scene') != name or s.get('status') not in ('ok', 'failed', 'unstable'):
        return None
    q = s.get('parameters')
    if not isinstance(q, dict) or not isinstance(s.get('measured'), dict):
        return None
    if any(k != 'out' and (k not in q or not _same(q[k], v)) for k, v in params.items()):
        return None
    return s


def _clean(x):
    if hasattr(x, 'item') and not isinstance(x, (list, tuple, dict)):  # numpy scalars
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    return x


_BUILD = None


def build_id():
    """Fingerprint of the woven core this process runs: the first 16 hex digits of the sha256 of the
    _woven extension. Every summary.json carries it, so a resumed campaign redoes a run that another
    build made instead of charting its figures (after a rebuild, the same out= folder reported the
    old contact model's overlaps as the new one's)."""
    global _BUILD
    if _BUILD is None:
        from . import _woven
        h = hashlib.sha256()
        with open(_woven.__file__, 'rb') as f:
            for chunk in iter(lambda: f.read(1 << 20), b''):
                h.update(chunk)
        _BUILD = h.hexdigest()[:16]
    return _BUILD


def write_summary(directory, name, params, measured, reference, units, status, checks=None, extra=None):
    """Writes DIRECTORY/summary.json and returns its dict.

    measured/reference: {figure: value}; units: {figure: unit}; status: 'ok', 'failed' or 'unstable';
    checks: {check: {'value':…, 'limit':…, 'passed': bool}}.
    """
    s = {'scene': name, 'status': status, 'build': build_id(),
         'parameters': {k: params[k] for k in params},
         'parameter_units': dict(getattr(params, 'units', {})),
         'measured': measured, 'reference': reference, 'units': units,
         'checks': checks or {}}
    if extra:
        s.update(extra)
    path = os.path.join(directory, 'summary.json')
    with atomic_open(path) as f:
        json.dump(_clean(s), f, indent=2, sort_keys=False)
    return s
