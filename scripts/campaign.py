# V50 campaign: scripts/ballistic.py over impact velocities x Weibull seeds, on this machine or on a
# Dask cluster, resumable; then the Lambert-Jonas fit and V50 with a bootstrap confidence interval.
#   yade -n -x scripts/campaign.py [velocities=60,75,...] [seeds=1,2,3] [weibull_m=10] [jobs=2]
#                                  [backend=local|dask] [scheduler=tcp://host:8786] [scene='t_end=3e-4 side=0.0254'] [out=DIR]
# Every run is one process `yade -n -x scripts/ballistic.py key=value ... out=OUT/runs/NAME` (NAME =
# V<velocity>-s<seed>); `backend=local` keeps `jobs` of them going on this machine, `backend=dask`
# hands them to Dask workers: a LocalCluster of `jobs` workers, or the scheduler at `scheduler` (its
# workers need woven installed and the same file system). A run whose summary.json is complete is not
# run again, so a killed campaign resumes where it stopped (docs/campaign.md).
# The strengths' scatter is ballistic.py's Weibull draw: `weibull_m` (modulus) and `seed`.
# Output (out/campaign/): runs/*/ (each run's files and run.log), campaign.csv, v50.png, summary.json
# (V50, its bootstrap interval, the bracket or mixed zone, timings).
import glob
import math
import os
import shlex
import sys
import time

import numpy as np
import woven
import woven.campaign as campaign
import woven.contact
from woven.params import read_params
from woven.output import dry_run, out_dir, savefig, write_summary

p = read_params({
    'velocities': ('60,75,85,90,95,100,110,120,150,200', 'm/s', 'impact velocities, comma-separated, each in (0, 5000]'),
    'seeds': ('1,2,3', '', 'seeds of the Weibull draw of the yarn strengths, comma-separated integers >= 0'),
    'weibull_m': (10.0, '', 'Weibull modulus of the yarn strengths, in [1, 100] (0: no scatter, then one seed is enough)'),
    't_end': (3e-4, 's', 'simulated time at most per run (each stops at perforation or arrest), in (0, 0.01]'),
    'scene': ('', '', "more ballistic.py keys for every run, 'key=value key=value' (e.g. 'side=0.0254 mass=1e-3')"),
    'backend': ('local', '', "'local' (child processes on this machine) or 'dask' (dask.distributed workers)"),
    'jobs': (1, '', 'runs at once: local processes, or LocalCluster workers (backend=dask without scheduler), in [1, 256]'),
    'scheduler': ('', '', 'address of a running dask-scheduler, e.g. tcp://host:8786 (backend=dask); empty: a LocalCluster'),
    'boot': (200, '', 'bootstrap resamples of the runs for the V50 interval, in [0, 100000] (0: none)'),
    'boot_seed': (1, '', 'seed of the bootstrap resampling (the interval is repeatable)'),
    'level': (0.95, '', 'confidence level of the V50 interval, in (0, 1)'),
    'yade': ('yade', '', 'the YADE command the runs start'),
    'fit': (True, '', 'fit the V50 when the runs are done (0: only run them)'),
    'out': ('', '', 'output folder (default out/campaign); the runs go to OUT/runs'),
})


def bad(key, allowed):
    raise ValueError('%s = %r is invalid: allowed %s' % (key, p[key], allowed))


def numbers(key, cast):
    try:
        vals = [cast(v) for v in str(p[key]).replace(' ', '').split(',') if v != '']
    except ValueError:
        vals = None
    if not vals:
        bad(key, 'a comma-separated list of %s' % ('numbers' if cast is float else 'integers'))
    return vals


velocities = numbers('velocities', float)
if not all(math.isfinite(v) and 0 < v <= 5000 for v in velocities):
    bad('velocities', 'values in (0, 5000] m/s')
seeds = numbers('seeds', int)
if not all(s >= 0 for s in seeds) or len(set(seeds)) != len(seeds):
    bad('seeds', 'distinct integers >= 0')
if not (p.weibull_m == 0 or 1 <= p.weibull_m <= 100):
    bad('weibull_m', '0 or [1, 100]')
if not (math.isfinite(p.t_end) and 0 < p.t_end <= 0.01):
    bad('t_end', '(0, 0.01] s')
if p.backend not in ('local', 'dask'):
    bad('backend', "'local' or 'dask'")
if not 1 <= p.jobs <= 256:
    bad('jobs', '[1, 256]')
if p.scheduler and p.backend != 'dask':
    bad('scheduler', "empty unless backend = 'dask'")
if not 0 <= p.boot <= 100000:
    bad('boot', '[0, 100000]')
if not 0 <= p.boot_seed < 2 ** 63:  # numpy's default_rng refused a negative one after every run had finished
    bad('boot_seed', 'an integer in [0, 2^63)')
if not 0 < p.level < 1:
    bad('level', '(0, 1)')
scene = {}
for tok in shlex.split(p.scene.replace(';', ' ')):
    if '=' not in tok:
        bad('scene', "'key=value key=value ...' of scripts/ballistic.py")
    k, v = tok.split('=', 1)
    if k in ('V', 'seed', 'weibull_m', 't_end', 'out'):
        bad('scene', "keys other than V, seed, weibull_m, t_end and out (the campaign's own keys set them)")
    scene[k] = v


def scene_value(v):
    """A scene value as ballistic.py will read it: a number when it parses as one (check_friction
    refuses strings for numbers, so scene='friction=0.2' was refused as 'not a number')."""
    try:
        return float(v)
    except ValueError:
        return v


# friction and body_friction refused before any run starts
woven.contact.check_friction({k: scene_value(v) for k, v in scene.items()})
if dry_run():
    # A dry run checks the runs' keys too: ballistic.py's own checks on the scene keys, in this process.
    from woven.params import dry_run_script
    run_keys = ['%s=%s' % kv for kv in scene.items()] + ['V=%r' % velocities[0], 'seed=%d' % seeds[0],
                                                          'weibull_m=%r' % p.weibull_m, 't_end=%r' % p.t_end]
    verdict, why = dry_run_script(os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), 'ballistic.py'), run_keys)
    if verdict != 'accepted':
        bad('scene', "keys scripts/ballistic.py accepts (it said: %s)" % why)
d = out_dir('campaign', p)
# What every run gets besides V and seed: no VTK and no progress lines (the campaign has its own bar).
# No pictures either (a render per run; the back-face figures are still in each summary.json).
keys = {'weibull_m': float(p.weibull_m), 't_end': float(p.t_end), 'vtk_every': -1, 'progress': 0.0, 'pictures': 0}
keys.update(scene)
runs = campaign.plan(velocities, seeds, keys, os.path.join(os.path.abspath(d), 'runs'))

print('campaign: %d runs (%d velocities x %d seeds), backend %s, %d jobs%s -> %s'
      % (len(runs), len(velocities), len(seeds), p.backend, p.jobs, (', scheduler ' + p.scheduler) if p.scheduler else '', d))
sys.stdout.flush()
t0 = time.time()
here = os.path.dirname(os.path.abspath(sys.argv[0]))  # under yade -x, __file__ is yade's own
res = campaign.execute(runs, backend=p.backend, jobs=p.jobs, scheduler=p.scheduler, yade=p.yade,
                       script=os.path.join(here, 'ballistic.py'))
wall = time.time() - t0
incomplete = [r['name'] for r in runs if not campaign.is_complete(r)]
failed = [x for x in res['done'] if x['returncode'] != 0]
for x in failed[:3]:
    log = os.path.join(d, 'runs', x['name'], 'run.log')
    tail = open(log).read().strip().splitlines()[-3:] if os.path.exists(log) else []
    print('campaign: run %s exited with %d: %s' % (x['name'], x['returncode'], ' | '.join(tail)))

rows = campaign.collect(sorted(glob.glob(os.path.join(d, 'runs', '*', 'summary.json'))))
names = {r['name'] for r in runs}
rows = [r for r in rows if r[7] in names]  # runs of this plan only (the folder may hold others)
campaign.write_csv(os.path.join(d, 'campaign.csv'), rows)
run_walls = [x['wall'] for x in res['done']]
measured = {'runs': len(runs), 'complete': len(runs) - len(incomplete), 'run_now': len(res['done']),
            'skipped_complete': len(res['skipped']), 'nonzero_exit': len(failed), 'incomplete': incomplete,
            'perforated': int(sum(r[2] for r in rows)), 'wall_seconds': wall, 'workers': res['workers'],
            'run_wall_mean': float(np.mean(run_walls)) if run_walls else None,
            'run_wall_max': float(np.max(run_walls)) if run_walls else None,
            'hosts': sorted({x['host'] for x in res['done']}),
            'statuses': {s: sum(1 for r in rows if r[8] == s) for s in sorted({r[8] for r in rows})}}
measured.update(campaign.bracket(rows))
checks = {'complete': {'value': len(incomplete), 'limit': 0, 'passed': not incomplete,
                       'what': 'runs without a complete summary.json'}}
status = 'ok'
fit = None
if p.fit and rows:
    try:
        fit = campaign.v50(rows, boot=p.boot, boot_seed=p.boot_seed, level=p.level)
        measured.update({'V50': fit['V50'], 'lambert_jonas_a': fit['a'], 'lambert_jonas_p': fit['p'],
                         'fit_rms': fit['rms']})
        for k in ('V50_ci', 'V50_interval', 'ci_level', 'bootstrap_samples', 'bootstrap_without_fit', 'V50_bootstrap_std'):
            if k in fit:
                measured[k] = fit[k]
    except ValueError as ex:
        print('campaign:', ex)
        checks['fit'] = {'value': str(ex), 'limit': 'a Lambert-Jonas fit', 'passed': False,
                         'what': 'the runs give a fit (some perforated, at least 3 runs)'}
if not all(c['passed'] for c in checks.values()):
    status = 'failed'

if rows:
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    V = np.array([r[0] for r in rows])
    vr = np.array([r[1] for r in rows])
    fig, ax = plt.subplots(figsize=(7, 5))
    ax.plot(V, vr, 'ko', ms=4, label='runs (%d: %d velocities x %d seeds)' % (len(rows), len(velocities), len(seeds)))
    if fit:
        Vs = np.linspace(0, V.max() * 1.05, 300)
        ax.plot(Vs, woven.theory.lambert_jonas(Vs, fit['V50'], fit['a'], fit['p']), 'r-',
                label='Lambert-Jonas: V50 = %.1f m/s, a = %.3f, p = %.2f' % (fit['V50'], fit['a'], fit['p']))
        if 'V50_interval' in fit:
            lo, hi = fit['V50_interval']
            widened = fit['V50_interval'] != fit['V50_ci']
            ax.axvspan(lo, hi, color='r', alpha=0.15, label='%.0f %% bootstrap interval%s %.1f-%.1f m/s'
                       % (100 * p.level, ' widened to the bracket' if widened else '', lo, hi))
    ax.plot([0, V.max()], [0, V.max()], 'k:', lw=0.8, label='no fabric')
    ax.set_xlabel('impact velocity [m/s]')
    ax.set_ylabel('residual velocity [m/s]')
    ax.legend(fontsize=8)
    fig.tight_layout()
    savefig(fig, os.path.join(d, 'v50.png'), dpi=110)

units = {'V50': 'm/s', 'V50_ci': 'm/s', 'V50_interval': 'm/s', 'V50_bootstrap_std': 'm/s', 'fit_rms': 'm/s', 'bracket': 'm/s',
         'mixed_zone': 'm/s', 'wall_seconds': 's', 'run_wall_mean': 's', 'run_wall_max': 's'}
reference = {'V50_km2_706_single_ply_022_rcc': [90.0, 100.0],  # physics-reference.md, for the default scene only
             'interval': 'V50_ci: bootstrap over runs (percentiles of refitted V_bl, numpy default_rng(boot_seed)); '
                         'V50_interval: V50_ci widened to the bracket (fastest stop, slowest perforation) if any'}
write_summary(d, 'campaign', p, measured, reference, units, status, checks)
print('campaign: %s; %d of %d runs complete (%d run now, %d were done), V50 = %s m/s%s, %.0f s -> %s'
      % (status, measured['complete'], len(runs), len(res['done']), len(res['skipped']),
         '%.1f' % fit['V50'] if fit else 'n/a',
         ' (%.0f %%: %.1f-%.1f)' % (100 * p.level, fit['V50_ci'][0], fit['V50_ci'][1]) if fit and 'V50_ci' in fit else '',
         wall, d))
if status != 'ok':
    sys.exit(1)
