# Collects the runs of a V50 sweep (scripts/batch/v50.table with scripts/ballistic.py) into one CSV and
# a PNG with the Lambert-Jonas fit and the ballistic limit it gives.
#   yade -n -x scripts/v50.py [runs=out/v50] [out=DIR]
# Reads RUNS/*/summary.json (impact velocity, residual velocity, outcome, seeds); writes (default
# RUNS) v50.csv, v50.png and summary.json with V50 = V_bl of the fit beside the reference V50 of a
# KM2 706 single ply (physics-reference.md).
import glob
import os
import sys

import numpy as np
import woven
import woven.campaign
from woven.output import dry_run_stop, savefig
from woven.params import read_params
from woven.output import write_summary

p = read_params({'runs': ('out/v50', '', 'folder holding one sub-folder per run with its summary.json'),
                 'out': ('', '', 'output folder (default: runs)')})
# A collector: its input is the folders it reads, which a dry run (WOVEN_DRY_RUN=1) does not need.
dry_run_stop('v50')
files = sorted(glob.glob(os.path.join(p.runs, '*', 'summary.json')))
if not files:
    raise ValueError('runs = %r is invalid: allowed a folder whose sub-folders hold summary.json files of '
                     'scripts/ballistic.py (yade-batch scripts/batch/v50.table scripts/ballistic.py)' % p.runs)
rows = woven.campaign.collect(files)  # (V, residual, perforated, seed, weibull_m, balance, broken, run, status)
d = p.out or p.runs
os.makedirs(d, exist_ok=True)
woven.campaign.write_csv(os.path.join(d, 'v50.csv'), rows)
V = np.array([r[0] for r in rows])
vr = np.array([r[1] for r in rows])
status, fit = 'ok', None
try:
    fit = woven.theory.fit_lambert_jonas(V, vr)
except ValueError as ex:
    status = 'failed'
    print('v50:', ex)

import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt
fig, ax = plt.subplots(figsize=(7, 5))
ax.plot(V, vr, 'ko', label='runs (%d)' % len(rows))
if fit:
    Vs = np.linspace(0, V.max() * 1.05, 300)
    ax.plot(Vs, woven.theory.lambert_jonas(Vs, fit['V_bl'], fit['a'], fit['p']), 'r-',
            label='Lambert-Jonas: V50 = %.1f m/s, a = %.3f, p = %.2f' % (fit['V_bl'], fit['a'], fit['p']))
ax.plot([0, V.max()], [0, V.max()], 'k:', lw=0.8, label='no fabric')
ax.axvspan(90, 100, color='g', alpha=0.15, label='reference V50 (0.22 RCC, KM2 706)')
ax.set_xlabel('impact velocity [m/s]')
ax.set_ylabel('residual velocity [m/s]')
ax.legend(fontsize=8)
fig.tight_layout()
savefig(fig, os.path.join(d, 'v50.png'), dpi=110)
measured = {'runs': len(rows), 'perforated': int(sum(r[2] for r in rows))}
measured.update(woven.campaign.bracket(rows))  # or the mixed zone, when seeds scatter
if fit:
    measured.update({'V50': fit['V_bl'], 'lambert_jonas_a': fit['a'], 'lambert_jonas_p': fit['p'], 'fit_rms': fit['rms']})
write_summary(d, 'v50', p, measured, {'V50_km2_706_single_ply_022_rcc': [90.0, 100.0]},
              {'V50': 'm/s', 'fit_rms': 'm/s', 'bracket': 'm/s', 'mixed_zone': 'm/s'}, status)
print('v50: %s; %d runs, V50 = %s m/s -> %s' % (status, len(rows), '%.1f' % fit['V_bl'] if fit else 'n/a', d))
if status != 'ok':
    sys.exit(1)
