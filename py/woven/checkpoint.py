"""Checkpoints in YADE's habit: O.save(path) / O.load(path) bring the fabric back with the scene.

YADE serialises its scene (bodies, engines, O.iter, O.time, O.tags) in C++; the fabric lives in
woven's C++ engine, which YADE does not know: the woven adapter in O.engines is a PyRunner whose
command '_woven_step(k)' names the engine only within the process. So woven keeps the fabric beside
the scene file:

    O.save('run.yade.gz')   ->  run.yade.gz        (YADE's scene, as always)
                                run.yade.gz.woven  (the fabric of every woven adapter in O.engines)
    O.load('run.yade.gz')   ->  the scene, then each adapter's engine loaded from run.yade.gz.woven

`import woven` installs this on YADE's Omega class (hook(); unhook() takes it away), so a user's
plain O.save / O.load / O.saveTmp / O.loadTmp / O.reload do it; woven.checkpoint.save / load are the
same calls by name. Which engine a loaded adapter drives (the fabric itself, its geometry, loads and
contact keys, is not in any file: it is built by the user's script, as before the save):
  - the engines attached in the scene that O.load replaces, in the order of their adapters (a fresh
    process: the script builds and woven.attach-es the fabric as it did before the save, then calls
    O.load instead of running from the start);
  - when none is attached there, the engines the saved adapters drove in this process (O.load in
    the process that saved, also after O.reset()).
The state file of each engine (format 3: positions, velocities, sections, clock, breakage and
energy books, its checksum and the weave's fingerprint) is loaded with FabricEngine.load_state, so
a fabric of another weave is refused. The continued run is the uninterrupted run bit for bit when
the save was made between O.run calls (tests/python/test_checkpoint.py).

The sidecar (format 1): b'WOVENCKP', u32 version, u32 0, u64 header length, the header (UTF-8 JSON:
token, O.iter, O.time, per adapter its key, position in O.engines, label, rewind flag, the engine's
step and its state file's length), the state files one after the other, and the SHA-256 of every
byte before it. A random token is written into the scene too (O.tags['woven_checkpoint']): a
sidecar from another save (an older one, another scene's, a save killed between the two files) is
refused. A missing, truncated, corrupted or foreign sidecar raises CheckpointError (a ValueError)
naming the file and what is wrong; the adapters of the loaded scene then refuse to step (a run would
otherwise go on with a fabric that does not belong to the scene).

Both files are written atomically (a temporary in the same folder, fsync, rename; the scene first),
so a run killed while saving keeps the previous checkpoint, or leaves a pair whose tokens differ,
which is refused. O.filename then names the scene's temporary (YADE has no setter for it): O.reload
uses the path given to O.save / O.load.
"""
import contextlib
import hashlib
import json
import os
import struct
import tempfile
import uuid

import yade.wrapper

from . import engine as _engine
from .output import atomic_open

MAGIC = b'WOVENCKP'
VERSION = 1
SUFFIX = '.woven'
TAG = 'woven_checkpoint'
_O = yade.wrapper.Omega()
_orig = {}      # Omega method name -> YADE's own method (while hooked)
_memory = {}    # O.saveTmp mark -> sidecar bytes
_last = [None]  # the path of the last save or load through this module (for O.reload)


class CheckpointError(ValueError):
    """A sidecar that cannot bring the fabric back (missing, truncated, corrupted, of another save or weave)."""


def sidecar(path):
    """The fabric's file beside the scene file `path`."""
    return os.fspath(path) + SUFFIX


def _check_path(path):
    if not isinstance(path, (str, os.PathLike)) or '\0' in os.fspath(path) or not os.fspath(path):
        raise ValueError('path = %r is invalid: allowed a file path without NUL characters' % (path,))
    return os.fspath(path)


def _call(name, *args):
    return (_orig.get(name) or getattr(yade.wrapper.Omega, name))(_O, *args)


def _state_bytes(eng):
    # The state file holds the collision stage's memory too (persistent crossings, pairs' measure
    # memory, last body contacts): saving changes nothing, and a loaded run continues as this one.
    with tempfile.TemporaryDirectory(prefix='woven-ckp-') as d:
        p = os.path.join(d, 'engine.state')
        eng.save_state(p)
        with open(p, 'rb') as f:
            return f.read()


def _pack():
    """(token, sidecar bytes) of the woven adapters in O.engines, or (None, None) when there is none."""
    found = _engine.runners()
    if not found:
        return None, None
    entries, blobs = [], []
    for pos, runner, key in found:
        if key not in _engine._registry:
            raise CheckpointError('O.engines[%d] = PyRunner %r has no woven engine in this process (%s): nothing to '
                                  'save for it' % (pos, runner.command, _engine._unbound.get(key, 'not attached')))
        eng, rewind = _engine._registry[key]
        blob = _state_bytes(eng)
        entries.append({'key': key, 'position': pos, 'label': runner.label, 'rewind': bool(rewind),
                        'engine_iter': eng.iter, 'nodes': eng.n_nodes, 'state_bytes': len(blob)})
        blobs.append(blob)
    token = uuid.uuid4().hex
    header = json.dumps({'format': 'woven checkpoint', 'version': VERSION, 'token': token, 'iter': _O.iter,
                         'time': _O.time, 'engines': entries}, sort_keys=True).encode()
    body = MAGIC + struct.pack('<IIQ', VERSION, 0, len(header)) + header + b''.join(blobs)
    return token, body + hashlib.sha256(body).digest()


def _unpack(data, where):
    """(header, [state bytes]) of sidecar bytes; CheckpointError naming `where` and what is wrong."""
    def bad(what):
        return CheckpointError('checkpoint %s is invalid: %s' % (where, what))
    if len(data) < len(MAGIC) + 16 + 32:
        raise bad('%d bytes, shorter than any woven checkpoint (truncated or empty)' % len(data))
    if data[:8] != MAGIC:
        raise bad('not a woven checkpoint (starts with %r, allowed %r)' % (data[:8], MAGIC))
    version, _, n = struct.unpack('<IIQ', data[8:24])
    if version != VERSION:
        raise bad('format version %d, allowed %d' % (version, VERSION))
    if hashlib.sha256(data[:-32]).digest() != data[-32:]:
        raise bad('checksum does not match its contents (corrupted or truncated)')
    if 24 + n > len(data) - 32:
        raise bad('header length %d past the end' % n)
    try:
        header = json.loads(data[24:24 + n].decode())
        sizes = [int(e['state_bytes']) for e in header['engines']]
        header['token'], header['iter']
    except (ValueError, KeyError, TypeError) as e:
        raise bad('unreadable header (%s)' % e) from None
    if 24 + n + sum(sizes) != len(data) - 32:
        raise bad('state files of %d bytes in %d bytes' % (sum(sizes), len(data) - 56 - n))
    blobs, at = [], 24 + n
    for s in sizes:
        blobs.append(data[at:at + s])
        at += s
    return header, blobs


def _restore(data, where, before):
    """After YADE loaded a scene: each woven adapter in it gets its engine and the engine its state
    from the sidecar `data` (None: missing). On failure, the adapters are left unable to step and
    CheckpointError is raised. before: keys of the engines attached in the scene O.load replaced."""
    found = _engine.runners()
    if not found:
        return
    import __main__
    __main__.__dict__['_woven_step'] = _engine._step  # a fresh process: YADE runs the commands in __main__
    try:
        if data is None:
            raise CheckpointError('checkpoint %s is missing: the scene holds %d woven engine(s) (%s) whose fabric was '
                                  'saved beside it by O.save with woven imported' %
                                  (where, len(found), ', '.join(r.command for _, r, _ in found)))
        header, blobs = _unpack(data, where)
        tags = _O.tags
        token = tags[TAG] if tags.has_key(TAG) else None
        if token != header['token']:
            raise CheckpointError('checkpoint %s is invalid: it belongs to another save than the scene (token %s, the '
                                  'scene\'s %s): an older or another scene\'s file, or a save killed between the '
                                  'two files' % (where, header['token'], token))
        saved = [e['key'] for e in header['engines']]
        if [k for _, _, k in found] != saved:
            raise CheckpointError('checkpoint %s is invalid: it holds engines %s, the scene adapters %s'
                                  % (where, saved, [k for _, _, k in found]))
        if before and len(before) == len(found):
            targets = before
        elif not before and all(k in _engine._registry for k in saved):
            targets = saved
        else:
            raise CheckpointError('checkpoint %s cannot be restored here: the scene holds %d woven engine(s), and %d '
                                  'is attached in this process before O.load: build and woven.attach the fabric as '
                                  'before the save (the same weave, loads and keys), then O.load' %
                                  (where, len(found), len(before)))
        for k, key in enumerate(targets):
            # Coupled bodies are named by id: the loaded scene must hold them (a fresh process's
            # set-up that appended other bodies first would couple the wrong ones).
            eng = _engine._registry[key][0]
            for b in range(eng.n_bodies):
                i = eng.body(b)['id']
                if not (0 <= i < len(_O.bodies)) or _O.bodies[i] is None:
                    raise CheckpointError('checkpoint %s cannot be restored here: engine %d is coupled to body id %d, '
                                          'which the loaded scene does not hold (%d bodies)' % (where, k, i, len(_O.bodies)))
        with tempfile.TemporaryDirectory(prefix='woven-ckp-') as d:
            for k, (key, blob, entry) in enumerate(zip(targets, blobs, header['engines'])):
                p = os.path.join(d, '%d.state' % k)
                with open(p, 'wb') as f:
                    f.write(blob)
                eng = _engine._registry[key][0]
                try:
                    eng.load_state(p)
                except ValueError as e:
                    raise CheckpointError('checkpoint %s is invalid for engine %d (PyRunner %r; another weave?): %s'
                                          % (where, k, found[k][1].command, e)) from None
                _engine._registry[key] = (eng, entry['rewind'])
        for (_, runner, _), key in zip(found, targets):
            runner.command = '_woven_step(%d)' % key
    except Exception as e:
        reason = 'woven: the fabric of this scene was not restored (%s); O.load again once that is fixed' % e
        for _, runner, _ in found:
            k = _engine.UNBOUND_KEYS + len(_engine._unbound)
            _engine._unbound[k] = reason
            runner.command = '_woven_step(%d)' % k
        raise



def _attached_now():
    return [k for _, _, k in _engine.runners() if k in _engine._registry]


@contextlib.contextmanager
def _scene_tmp(path):
    """A temporary beside `path` whose name ends with the whole file name (YADE picks the format
    from the suffixes: .xml, .xml.gz, .yade.gz ...), renamed onto `path` after it was fsync'ed."""
    folder, name = os.path.split(os.path.abspath(path))
    tmp = os.path.join(folder, '.woven-tmp-%s-%s' % (uuid.uuid4().hex[:12], name))
    try:
        yield tmp
        with open(tmp, 'rb+') as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.remove(tmp)
        raise


def save(path, quiet=False):
    """O.save(path) with the fabric of every woven adapter in O.engines in path + '.woven' (atomic,
    both files). A scene without woven adapters removes an old sidecar of that name."""
    path = _check_path(path)
    token, data = _pack()
    side = sidecar(path)
    if token is not None:
        _O.tags[TAG] = token
    with _scene_tmp(path) as tmp:
        _call('save', tmp, quiet)
    if data is None:
        with contextlib.suppress(FileNotFoundError):
            os.remove(side)
    else:
        with atomic_open(side, 'wb') as f:
            f.write(data)
    _last[0] = path


def load(path, quiet=False):
    """O.load(path), then the fabric of each woven adapter of the loaded scene from path + '.woven'
    (module docstring: which engine; CheckpointError when the sidecar is missing, corrupted or foreign)."""
    path = _check_path(path)
    before = _attached_now()
    _call('load', path, quiet)
    _last[0] = path
    side = sidecar(path)
    try:
        with open(side, 'rb') as f:
            data = f.read()
    except FileNotFoundError:
        data = None
    _restore(data, side, before)


def save_tmp(mark='', quiet=False):
    """O.saveTmp(mark) with the fabric kept in memory under the same mark."""
    token, data = _pack()
    if token is not None:
        _O.tags[TAG] = token
    _call('saveTmp', mark, quiet)
    if data is None:
        _memory.pop(mark, None)
    else:
        _memory[mark] = data


def load_tmp(mark='', quiet=False):
    """O.loadTmp(mark), then the fabric saved by save_tmp(mark)."""
    before = _attached_now()
    _call('loadTmp', mark, quiet)
    _restore(_memory.get(mark), 'O.saveTmp(%r) in memory' % (mark,), before)


def reload(quiet=False):
    """O.reload(): load() of the last file saved or loaded."""
    load(_last[0] or _O.filename, quiet)


def _method(fn, name):
    def m(self, *args, **kw):
        if 'file' in kw:  # YADE's keyword for the path
            args = (kw.pop('file'),) + args
        return fn(*args, **kw)
    m.__name__ = name
    m.__doc__ = ((_orig.get(name) or getattr(yade.wrapper.Omega, name)).__doc__ or '') + \
        '\n(woven: the fabric of woven adapters too, woven.checkpoint.%s)' % fn.__name__
    m._woven = True
    return m


_METHODS = {'save': save, 'load': load, 'saveTmp': save_tmp, 'loadTmp': load_tmp, 'reload': reload}


def hook():
    """Make YADE's O.save, O.load, O.saveTmp, O.loadTmp and O.reload carry the fabric (idempotent)."""
    for name, fn in _METHODS.items():
        cur = getattr(yade.wrapper.Omega, name)
        if getattr(cur, '_woven', False):
            continue
        _orig[name] = cur
        setattr(yade.wrapper.Omega, name, _method(fn, name))


def unhook():
    """YADE's own methods back (the fabric is then neither saved nor restored)."""
    for name, cur in list(_orig.items()):
        setattr(yade.wrapper.Omega, name, cur)
        del _orig[name]


def hooked():
    return all(getattr(getattr(yade.wrapper.Omega, n), '_woven', False) for n in _METHODS)
