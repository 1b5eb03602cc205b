"""V50 campaigns: scripts/ballistic.py over impact velocities x Weibull seeds, on this machine or on
a Dask cluster, resumable, with the Lambert-Jonas fit and a bootstrap confidence interval of V50.

    runs = woven.campaign.plan([80, 90, 100], [1, 2, 3], {'weibull_m': 10, 't_end': 3e-4}, 'out/campaign')
    woven.campaign.execute(runs, backend='local', jobs=2)        # or backend='dask', scheduler='tcp://host:8786'
    rows = woven.campaign.collect(run_dirs)                      # what scripts/v50.py reads, too
    fit = woven.campaign.v50(rows, boot=200, boot_seed=1)        # V50, a, p, rms, CI from the bootstrap

Every run is one process `yade -n -x scripts/ballistic.py key=value ... out=DIR`, whatever the backend:
a run's result depends only on its keys (one thread per run: YADE without -j sets OMP_NUM_THREADS=1,
and woven gives the same bits at any thread count anyway, docs/design.md), so the backends give the
same summaries bit for bit. A run is complete when DIR/summary.json parses, belongs to the
ballistic scene, holds a residual velocity and was made with the run's keys by this build of woven
(the summary's `build` fingerprint); complete runs are not done again (resume). The Weibull scatter
of the yarn strengths is ballistic.py's `weibull_m` (the modulus) and `seed` (the draw), so a seed
is a specimen. SI units.
"""
import json
import math
import os
import subprocess
import sys
import time

from .output import build_id

SCENE = 'ballistic'
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def run_name(V, seed):
    """Folder name of one run: V in m/s with 0.1 m/s resolution, then the seed (sorts by V)."""
    return 'V%06.1f-s%d' % (V, seed)


def plan(velocities, seeds, keys, out):
    """The campaign's runs: one per (velocity [m/s], seed), each a dict name, keys (ballistic.py's
    key=value pairs, V and seed included), out (its folder under `out`)."""
    runs = []
    for V in velocities:
        for s in seeds:
            k = dict(keys)
            k['V'], k['seed'] = float(V), int(s)
            name = run_name(V, s)
            runs.append({'name': name, 'keys': k, 'out': os.path.join(out, name)})
    names = [r['name'] for r in runs]
    if len(set(names)) != len(names):
        raise ValueError('velocities = %r is invalid: allowed distinct values (0.1 m/s apart at least)' % (list(velocities),))
    return runs


def _same(a, b):
    if isinstance(a, bool) or isinstance(b, bool):  # summary True against '1', 'true', 1 ...
        t = {'1': True, 'true': True, 'yes': True, 'on': True, '0': False, 'false': False, 'no': False, 'off': False}
        return t.get(str(a).lower()) == t.get(str(b).lower()) and str(a).lower() in t
    if isinstance(a, float) or isinstance(b, float):
        try:
            return float(a) == float(b)
        except (TypeError, ValueError):
            return False
    return str(a) == str(b)


def is_complete(run):
    """True when run['out']/summary.json is a finished ballistic run made with run['keys'] by this
    build of woven (output.build_id). A summary written halfway (a run killed while writing),
    another scene's, one made with other keys or by another build does not count."""
    path = os.path.join(run['out'], 'summary.json')
    try:
        with open(path) as f:
            s = json.load(f)
    except (OSError, ValueError):
        return False
    if s.get('scene') != SCENE or 'residual_velocity' not in s.get('measured', {}):
        return False
    if s.get('build') != build_id():
        return False
    q = s.get('parameters', {})
    return all(k == 'out' or (k in q and _same(q[k], v)) for k, v in run['keys'].items())


def command(run, script=None, yade='yade'):
    """The command line of one run (a list for subprocess)."""
    # The checkout's scripts/ballistic.py (the package may be installed elsewhere: pass `script`).
    script = script or os.path.join(ROOT, 'scripts', 'ballistic.py')
    if not os.path.exists(script):
        raise ValueError('script = %r is invalid: allowed the path of scripts/ballistic.py (the installed package does '
                         'not know the checkout: pass script=)' % script)
    args = ['%s=%r' % (k, v) if isinstance(v, float) else '%s=%s' % (k, v) for k, v in sorted(run['keys'].items())]
    return [yade, '-n', '-x', script] + args + ['out=%s' % run['out']]


def run_one(run, script=None, yade='yade', env=None):
    """Runs one impact in a child process, its output in run['out']/run.log. Returns a dict: name,
    returncode, wall [s], host. A module-level function, so Dask can ship it to its workers (which
    need woven importable and the same file system: the script and the out folder)."""
    import socket
    os.makedirs(run['out'], exist_ok=True)
    e = dict(os.environ)
    e.update(env or {})
    # One thread per run, as YADE without -j: the workers are the parallelism (and the bits do not
    # depend on it anyway).
    e['OMP_NUM_THREADS'] = '1'
    t0 = time.time()
    with open(os.path.join(run['out'], 'run.log'), 'w') as log:
        rc = subprocess.call(command(run, script, yade), stdout=log, stderr=subprocess.STDOUT,
                             cwd=run['out'], env=e)
    return {'name': run['name'], 'returncode': rc, 'wall': time.time() - t0, 'host': socket.gethostname()}


class Progress:
    """A text progress bar on one line (\\r) on a terminal, one line per finished run otherwise."""

    def __init__(self, total, done=0, stream=None, width=30):
        self.total, self.done, self.skipped = total, done, done
        self.stream = stream or sys.stdout
        self.width, self.t0 = width, time.time()
        self.tty = hasattr(self.stream, 'isatty') and self.stream.isatty()

    def line(self, last=''):
        frac = self.done / self.total if self.total else 1.0
        bar = '#' * int(round(frac * self.width))
        run_now = self.done - self.skipped
        el = time.time() - self.t0
        eta = el / run_now * (self.total - self.done) if run_now else float('nan')
        return ('[%-*s] %d/%d runs (%d were done), %.0f s, ETA %s%s' %
                (self.width, bar, self.done, self.total, self.skipped, el,
                 '%.0f s' % eta if math.isfinite(eta) else '?', ('  ' + last) if last else ''))

    def step(self, last=''):
        self.done += 1
        self.show(last)

    def show(self, last=''):
        if self.tty:
            self.stream.write('\r' + self.line(last) + '   ')
            if self.done == self.total:
                self.stream.write('\n')
        else:
            self.stream.write(self.line(last) + '\n')
        self.stream.flush()


def connect(scheduler, jobs, timeout=3.0):
    """A dask.distributed Client: to the scheduler at `scheduler` (e.g. tcp://host:8786), or, when it is
    empty, to a LocalCluster of `jobs` single-threaded worker processes. An address where no scheduler
    answers within `timeout` seconds raises ValueError naming the key."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise ValueError("backend = 'dask' is invalid here: python3-distributed is not installed "
                         "(apt-get install python3-distributed); allowed 'local'") from None
    if scheduler:
        try:
            return Client(scheduler, timeout='%gs' % timeout)
        except (OSError, TimeoutError, ValueError) as ex:
            raise ValueError('scheduler = %r is invalid: no Dask scheduler answered within %g s (%s); allowed the '
                             'address of a running dask-scheduler (tcp://host:port), or empty for a LocalCluster '
                             'of `jobs` workers' % (scheduler, timeout, type(ex).__name__)) from None
    # Worker processes, one thread each: a run is a child process, the threads only wait for it.
    # The workers are spawned, and a spawned process first imports the parent's __main__ by its
    # file: under YADE that is YADE's launcher, which started a YADE session in every worker
    # (measured: banners, X warnings, seconds each). Without __file__ and __spec__ nothing is imported.
    main = sys.modules.get('__main__')
    saved = {k: main.__dict__.pop(k) for k in ('__file__', '__spec__') if main is not None and k in main.__dict__}
    try:
        if main is not None:
            main.__spec__ = None
        cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True, dashboard_address=None)
    finally:
        if main is not None:
            main.__dict__.pop('__spec__', None)
            main.__dict__.update(saved)
    return Client(cluster)


def execute(runs, backend='local', jobs=1, scheduler='', script=None, yade='yade', stream=None, env=None):
    """Runs what is not complete yet. Returns a dict: done (runs made now: name, returncode, wall,
    host), skipped (names of runs complete before), wall [s], backend, workers."""
    pending = [r for r in runs if not is_complete(r)]
    skipped = [r['name'] for r in runs if r not in pending]
    bar = Progress(len(runs), len(skipped), stream)
    bar.show()
    t0, done, workers = time.time(), [], jobs
    by_name = {r['name']: r for r in pending}

    def first_failure(res, cancel):
        # The first run to finish left no summary: most likely keys ballistic.py refuses, which every
        # run would repeat, so stop with that run's last words (they name the key).
        if len(done) == 1 and res['returncode'] != 0 and not is_complete(by_name[res['name']]):
            cancel()
            log = os.path.join(by_name[res['name']]['out'], 'run.log')
            tail = open(log).read().strip().splitlines()[-4:] if os.path.exists(log) else []
            raise ValueError('run %s failed (exit %d) and wrote no summary; stopped the campaign: %s'
                             % (res['name'], res['returncode'], ' | '.join(tail)))
    if backend == 'local':
        from concurrent.futures import ThreadPoolExecutor, as_completed
        with ThreadPoolExecutor(max_workers=jobs) as pool:
            futs = [pool.submit(run_one, r, script, yade, env) for r in pending]
            for f in as_completed(futs):
                res = f.result()
                done.append(res)
                bar.step('%s rc %d, %.1f s' % (res['name'], res['returncode'], res['wall']))
                first_failure(res, lambda: [g.cancel() for g in futs])
    elif backend == 'dask':
        from distributed import as_completed
        client = connect(scheduler, jobs)
        try:
            workers = len(client.scheduler_info().get('workers', {}))
            # pure=False: each run is one task even if two had the same keys; the paths are absolute
            # so a worker's working folder does not matter.
            futs = [client.submit(run_one, dict(r, out=os.path.abspath(r['out'])), script, yade, env, pure=False,
                                  key='woven-run-%s-%s' % (r['name'], os.urandom(4).hex())) for r in pending]
            for f in as_completed(futs):
                res = f.result()
                done.append(res)
                bar.step('%s rc %d, %.1f s on %s' % (res['name'], res['returncode'], res['wall'], res['host']))
                first_failure(res, lambda: client.cancel(futs))
        finally:
            cluster = getattr(client, 'cluster', None)
            client.close()
            if cluster is not None and not scheduler:
                cluster.close()
    else:
        raise ValueError("backend = %r is invalid: allowed 'local' or 'dask'" % backend)
    return {'done': done, 'skipped': skipped, 'wall': time.time() - t0, 'backend': backend, 'workers': workers}


# --- results: what scripts/v50.py and scripts/campaign.py read ---

def collect(summary_files):
    """Rows (V, residual velocity, perforated, seed, weibull_m, energy-balance error, broken elements,
    run name, status) of the ballistic summaries among `summary_files`, sorted by V then seed."""
    rows = []
    for f in summary_files:
        try:
            s = json.load(open(f))
        except (OSError, ValueError):
            continue
        if s.get('scene') != SCENE:
            continue
        m, q = s['measured'], s['parameters']
        rows.append((q['V'], m['residual_velocity'], int(m['perforated']), q.get('seed', 0), q.get('weibull_m', 0),
                     m['energy_balance_error'], m['broken_elements'], os.path.basename(os.path.dirname(f)),
                     s.get('status', '')))
    rows.sort()
    return rows


def write_csv(path, rows):
    from .output import atomic_open  # a killed collector never leaves half a CSV
    with atomic_open(path) as f:
        f.write('V_m_s,residual_m_s,perforated,seed,weibull_m,energy_balance_error,broken_elements,run,status\n')
        for r in rows:
            f.write('%.6g,%.6g,%d,%d,%.6g,%.4g,%d,%s,%s\n' % r)


def bracket(rows):
    """{'bracket': [fastest stop, slowest perforation]} when they do not overlap, else
    {'mixed_zone': [slowest perforation, fastest stop]} (seeds scatter), or {} without both kinds."""
    stopped = [r[0] for r in rows if not r[2]]
    through = [r[0] for r in rows if r[2]]
    if not (stopped and through):
        return {}
    if max(stopped) < min(through):
        return {'bracket': [max(stopped), min(through)]}
    return {'mixed_zone': [min(through), max(stopped)]}


def v50(rows, boot=200, boot_seed=1, level=0.95):
    """Lambert-Jonas fit of (V, residual velocity) of the rows (woven.theory.fit_lambert_jonas, as
    scripts/v50.py) and a bootstrap confidence interval of V50 = V_bl: the runs are resampled with
    replacement `boot` times (numpy's default_rng(boot_seed): the same interval every time), each
    sample refitted; the interval is the (1 -/+ level)/2 percentiles of those V_bl. Samples without a
    perforation have no fit and are counted, not used. Raises ValueError as the fit does."""
    import numpy as np
    from .theory import fit_lambert_jonas
    V = np.array([r[0] for r in rows], dtype=float)
    vr = np.array([r[1] for r in rows], dtype=float)
    fit = fit_lambert_jonas(V, vr)
    out = {'V50': fit['V_bl'], 'a': fit['a'], 'p': fit['p'], 'rms': fit['rms'], 'runs': len(rows)}
    if boot > 0:
        rng = np.random.default_rng(boot_seed)
        vals, failed = [], 0
        for _ in range(boot):
            i = rng.integers(0, len(V), len(V))
            try:
                vals.append(fit_lambert_jonas(V[i], vr[i])['V_bl'])
            except ValueError:
                failed += 1
        if vals:
            lo, hi = np.percentile(vals, [50 * (1 - level), 50 * (1 + level)])
            out.update({'V50_ci': [float(lo), float(hi)], 'ci_level': level, 'bootstrap_samples': len(vals),
                        'bootstrap_without_fit': failed, 'V50_bootstrap_std': float(np.std(vals))})
            # Resampling cannot see between the velocities that were shot: when every stop is slower
            # than every perforation, V_bl of nearly every resample sits on the fastest stop and the
            # interval shrinks to a point (measured: [95.0, 95.0] with stops up to 95 and perforations
            # from 110 m/s). The V50 can lie anywhere in that bracket, so V50_interval spans it too.
            b = bracket(rows).get('bracket')
            out['V50_interval'] = [min(float(lo), b[0]), max(float(hi), b[1])] if b else [float(lo), float(hi)]
    return out
