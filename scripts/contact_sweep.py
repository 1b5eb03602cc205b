# Contact sweep: how far yarns and projectiles overlap across the ballistic scenes the contact model
# must hold (docs/collisions.md, "Where the model stops being right"): cubes and spheres of 1.5, 3
# and 6 mm at 50 to 1000 m/s, 1, 2 and 4 CPs per crossing, 12.7 and 50.8 mm plies, breakage on.
#   yade -n -x scripts/contact_sweep.py [quick=0] [cp4_tail=0] [jobs=1] [contact_model=gap] [out=DIR]
# Each scene is one `scripts/ballistic.py` run (woven.campaign runs them: jobs at once, resumable, a
# complete run is not redone). Projectiles are steel (7850 kg/m^3) of the given size.
# Output (out/contact_sweep/): runs/*/, sweep.csv, summary.json with, per scene, the largest
# yarn-yarn and projectile-yarn overlaps over the whole run and until the first break (relative to
# the yarn thickness), the mean overlap, the energy-balance error, the projection's energy and the largest
# overlap the check met before its moves (docs/collisions.md), and
# checks against `overlap_limit` (0.1) and `energy_limit` (0.01).
import csv
import json
import math
import os
import sys
import time

import woven
import woven.campaign as campaign
import woven.contact
from woven.params import read_params
from woven.output import atomic_open, out_dir, write_summary

p = read_params({
    'quick': (False, '', '1: six scenes of the 12.7 mm ply (about a minute of runs); 0: the whole matrix (30 scenes)'),
    'cp4_tail': (False, '', '1: also 24 impacts at 4 CPs per span on the 12.7 mm ply (cube and sphere of 3, 4.5 and 6 mm at '
                 '100, 300, 600 and 900 m/s), where the overlaps after the breaks are largest (docs/collisions.md)'),
    'jobs': (1, '', 'runs at once, in [1, 64]'),
    'contact_model': ('gap', '', "'gap' (default) or 'paper': the contact model of every run"),
    'friction': (0.0, '', 'Coulomb coefficient between yarns of every run, in [0, 2]'),
    'body_friction': (0.0, '', 'Coulomb coefficient between the projectile and the yarns of every run, in [0, 2]'),
    'overlap_limit': (0.1, '', 'allowed largest overlap / yarn thickness, in (0, 100]'),
    'energy_limit': (0.01, '', 'allowed energy-balance error / initial kinetic energy, in (0, 1)'),
    # ballistic.py's own default: each run stops at perforation or arrest, or here
    't_end': (1e-4, 's', 'simulated time at most per run, in (0, 0.01]'),
    'yade': ('yade', '', 'the YADE command the runs start'),
    'out': ('', '', 'output folder (default out/contact_sweep); the runs go to OUT/runs'),
})


def bad(key, allowed):
    sys.exit('contact_sweep: %s = %r is invalid: allowed %s' % (key, p[key], allowed))


if not (isinstance(p.jobs, int) and 1 <= p.jobs <= 64):
    bad('jobs', 'an integer in [1, 64]')
if p.contact_model not in ('gap', 'paper'):
    bad('contact_model', "'gap' or 'paper'")
if not (math.isfinite(p.overlap_limit) and 0 < p.overlap_limit <= 100):
    bad('overlap_limit', '(0, 100] yarn thicknesses')
if not (math.isfinite(p.energy_limit) and 0 < p.energy_limit < 1):
    bad('energy_limit', '(0, 1)')
if not (math.isfinite(p.t_end) and 0 < p.t_end <= 0.01):
    bad('t_end', '(0, 0.01] s')
woven.contact.check_friction(p)
d = out_dir('contact_sweep', p)
STEEL = 7850.0  # kg/m^3


def scene(shape, size_mm, V, cp, side_mm):
    size = size_mm * 1e-3
    volume = size ** 3 if shape == 'box' else math.pi / 6 * size ** 3
    keys = {'shape': shape, 'size': size, 'mass': float('%.4g' % (STEEL * volume)), 'V': float(V),
            'cp_per_span': cp, 'side': side_mm * 1e-3, 'contact_model': p.contact_model, 'progress': 0.0,
            't_end': p.t_end,
            'friction': p.friction, 'body_friction': p.body_friction,
            'vtk_every': -1, 'overlap_limit': 100.0, 'energy_limit': 0.99, 'pictures': 0}
    name = '%s%.1f-V%04d-cp%d-ply%.1f' % (shape, size_mm, V, cp, side_mm)
    return {'name': name, 'keys': keys, 'out': os.path.join(d, 'runs', name)}


# The matrix: every shape and size at every speed on the 12.7 mm ply, the resolutions taking turns
# (a Latin square: each size meets each resolution), and the 50.8 mm ply at 1 CP (its 4-CP runs take
# an hour each on this machine: bench_adaptive's scenes cover that resolution).
speeds = (50, 200, 400, 1000)
runs = []
for k, (shape, size) in enumerate([(s, z) for s in ('box', 'sphere') for z in (1.5, 3.0, 6.0)]):
    for j, V in enumerate(speeds):
        runs.append(scene(shape, size, V, (1, 2, 4)[(j + k) % 3], 12.7))
for shape, size in (('box', 5.59), ('sphere', 6.0)):
    for V in (50, 200, 400):
        runs.append(scene(shape, size, V, 1, 50.8))
if p.quick:
    runs = [r for r in runs if r['name'] in (
        'box1.5-V1000-cp1-ply12.7', 'box3.0-V0400-cp4-ply12.7', 'box6.0-V0200-cp4-ply12.7',
        'sphere1.5-V0400-cp4-ply12.7', 'sphere3.0-V0050-cp2-ply12.7', 'sphere6.0-V1000-cp2-ply12.7')]
if p.cp4_tail:
    for shape in ('box', 'sphere'):
        for size in (3.0, 4.5, 6.0):
            runs += [scene(shape, size, V, 4, 12.7) for V in (100, 300, 600, 900)]

t0 = time.time()
script = os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), 'ballistic.py')  # under yade -x, __file__ is yade's
report = campaign.execute(runs, backend='local', jobs=p.jobs, script=script, yade=p.yade)
rows = []
for r in runs:
    s = json.load(open(os.path.join(r['out'], 'summary.json'))) if campaign.is_complete(r) else None
    if s is None:
        rows.append({'scene': r['name'], 'status': 'no summary'})
        continue
    m, o = s['measured'], s['measured'].get('overlap', {})
    rows.append({
        'scene': r['name'], 'status': s.get('status', ''), 'outcome': m.get('outcome', ''),
        'residual_velocity': m['residual_velocity'], 'broken_elements': m['broken_elements'],
        'yarn_max_rel': o.get('yarn_max_rel', float('nan')), 'body_max_rel': o.get('body_max_rel', float('nan')),
        'yarn_max_before_break_rel': o.get('yarn_max_before_break_rel', float('nan')),
        'body_max_before_break_rel': o.get('body_max_before_break_rel', float('nan')),
        'yarn_mean_rel': o.get('yarn_mean_rel', float('nan')),
        'energy_balance_error': m['energy_balance_error'],
        'projection_energy_in': o.get('projection_energy_in', float('nan')),
        'checked_max_rel': o.get('checked_max_rel', float('nan')), 'check_steps': o.get('check_steps', 0),
        'initial_kinetic_energy': m['energy']['projectile_initial'], 'wall_seconds': m['wall_seconds']})
fields = ['scene', 'status', 'outcome', 'residual_velocity', 'broken_elements', 'yarn_max_rel', 'body_max_rel',
          'yarn_max_before_break_rel', 'body_max_before_break_rel', 'yarn_mean_rel', 'energy_balance_error',
          'projection_energy_in', 'checked_max_rel', 'check_steps', 'initial_kinetic_energy', 'wall_seconds']
with atomic_open(os.path.join(d, 'sweep.csv'), 'w') as f:
    w = csv.DictWriter(f, fieldnames=fields, restval='')
    w.writeheader()
    w.writerows(rows)


def worst(key):
    vals = [r[key] for r in rows if key in r and math.isfinite(r[key])]
    return max(vals) if vals else float('nan')


complete = all('yarn_max_rel' in r for r in rows)
checks = {
    'all_runs_complete': {'value': sum('yarn_max_rel' in r for r in rows), 'limit': len(rows), 'passed': complete,
                          'what': 'scenes with a summary'},
    'yarn_overlap': {'value': worst('yarn_max_rel'), 'limit': p.overlap_limit,
                     'passed': worst('yarn_max_rel') <= p.overlap_limit,
                     'what': 'largest yarn-yarn overlap over every run / yarn thickness'},
    'projectile_overlap': {'value': worst('body_max_rel'), 'limit': p.overlap_limit,
                           'passed': worst('body_max_rel') <= p.overlap_limit,
                           'what': 'largest projectile-yarn overlap over every run / yarn thickness'},
    'energy_balance': {'value': worst('energy_balance_error'), 'limit': p.energy_limit,
                       'passed': worst('energy_balance_error') <= p.energy_limit,
                       'what': 'largest energy-balance error / initial kinetic energy'},
}
ok = all(c['passed'] for c in checks.values())
measured = {'scenes': rows, 'worst': {k: worst(k) for k in fields[5:13]}, 'wall_seconds': time.time() - t0,
            'runs_made_now': len(report['done']), 'runs_skipped': len(report['skipped'])}
write_summary(d, 'contact_sweep', p, measured, {'overlap_limit': p.overlap_limit, 'energy_limit': p.energy_limit},
              {'yarn_max_rel': 'yarn thicknesses', 'body_max_rel': 'yarn thicknesses', 'energy_balance_error': '-',
               'checked_max_rel': 'yarn thicknesses (largest overlap the check met, before its moves)',
               'projection_energy_in': 'J', 'residual_velocity': 'm/s', 'wall_seconds': 's'},
              'ok' if ok else 'failed', checks)
for r in rows:
    if 'yarn_max_rel' in r:
        print('%-30s %-7s yarn %.3f (%.3f before break)  projectile %.3f (%.3f)  balance %.2f %%  projection %.3g J'
              % (r['scene'], r['status'], r['yarn_max_rel'], r['yarn_max_before_break_rel'], r['body_max_rel'],
                 r['body_max_before_break_rel'], 100 * r['energy_balance_error'], r['projection_energy_in']))
    else:
        print('%-30s no summary' % r['scene'])
print('contact_sweep: %s; worst yarn %.3f, projectile %.3f thicknesses, balance %.2f %% -> %s'
      % ('ok' if ok else 'failed', worst('yarn_max_rel'), worst('body_max_rel'), 100 * worst('energy_balance_error'), d))
sys.exit(0 if ok else 1)
