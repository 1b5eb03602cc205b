# Collects a pull-out sweep (scripts/batch/pullout.table with scripts/pullout.py) into one CSV and a
# chart: peak force and pull-out energy against the wefts' pre-tension, one line per friction.
#   yade -n -x scripts/pullout_chart.py [runs=out/pullout-sweep] [out=DIR]
# Reads RUNS/*/summary.json of the pullout scene; writes (default RUNS) pullout_sweep.csv,
# pullout_sweep.png and summary.json with the trends checked (physics-reference.md: the peak force
# and the pull-out energy rise with pre-tension and with friction).
import glob
import os
import sys

import numpy as np
from woven.params import read_params
from woven.output import dry_run_stop, atomic_open, savefig, write_summary

p = read_params({'runs': ('out/pullout-sweep', '', 'folder holding one sub-folder per run with its summary.json'),
                 'out': ('', '', 'output folder (default: runs)')})
# A collector: its input is the folders it reads, which a dry run (WOVEN_DRY_RUN=1) does not need.
dry_run_stop('pullout_chart')
import json
rows = []
for f in sorted(glob.glob(os.path.join(p.runs, '*', 'summary.json'))):
    try:
        s = json.load(open(f))
    except ValueError:
        continue
    if s.get('scene') != 'pullout' or 'peak_force' not in s.get('measured', {}):
        continue
    q, m = s['parameters'], s['measured']
    rows.append((q['pretension'], q['friction'], m['peak_force'], m['peak_force_raw'], m['pullout_energy'],
                 m['energy_balance_error'], m['max_transient_penetration'], m['wall_seconds'],
                 os.path.basename(os.path.dirname(f)), s['status']))
if not rows:
    raise ValueError('runs = %r is invalid: allowed a folder whose sub-folders hold summary.json files of '
                     'scripts/pullout.py (yade-batch scripts/batch/pullout.table scripts/pullout.py)' % p.runs)
rows.sort()
d = p.out or p.runs
os.makedirs(d, exist_ok=True)
with atomic_open(os.path.join(d, 'pullout_sweep.csv')) as f:
    f.write('pretension_N,friction,peak_force_N,peak_force_raw_N,pullout_energy_J,energy_balance_error,'
            'max_transient_penetration_m,wall_s,run,status\n')
    for r in rows:
        f.write('%.6g,%.6g,%.6g,%.6g,%.6g,%.3g,%.3g,%.1f,%s,%s\n' % r)

T = sorted({r[0] for r in rows})
mu = sorted({r[1] for r in rows})
peak = {(r[0], r[1]): r[2] for r in rows}
energy = {(r[0], r[1]): r[4] for r in rows}
import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt
fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
for m_ in mu:
    ts = [t for t in T if (t, m_) in peak]
    a1.plot(ts, [peak[(t, m_)] for t in ts], 'o-', label='friction %.2g' % m_)
    a2.plot(ts, [1e3 * energy[(t, m_)] for t in ts], 'o-', label='friction %.2g' % m_)
a1.set_xlabel('weft pre-tension [N per yarn]')
a1.set_ylabel('peak pull-out force [N]')
a1.set_title('peak force (averaged over 0.1 mm of travel)')
a2.set_xlabel('weft pre-tension [N per yarn]')
a2.set_ylabel('pull-out energy over the pull [mJ]')
a2.set_title('energy: area under the force-displacement curve')
for a in (a1, a2):
    a.legend(fontsize=8)
    a.grid(alpha=0.3)
fig.tight_layout()
savefig(fig, os.path.join(d, 'pullout_sweep.png'), dpi=110)

# Trends: along each friction line with pre-tension > 0 ... and along each pre-tension > 0 line with
# friction. At zero pre-tension nothing presses the crossings, so friction has nothing to act on.
checks = {}
for name, table in (('peak_force', peak), ('pullout_energy', energy)):
    up_T = all(table[(T[i + 1], m_)] > table[(T[i], m_)] for m_ in mu if m_ > 0 for i in range(len(T) - 1)
               if (T[i], m_) in table and (T[i + 1], m_) in table)
    up_mu = all(table[(t, mu[i + 1])] > table[(t, mu[i])] for t in T if t > 0 for i in range(len(mu) - 1)
                if (t, mu[i]) in table and (t, mu[i + 1]) in table)
    checks[name + '_rises_with_pretension'] = {'value': up_T, 'limit': True, 'passed': bool(up_T),
                                               'what': 'at every friction > 0, larger pre-tension gives more'}
    checks[name + '_rises_with_friction'] = {'value': up_mu, 'limit': True, 'passed': bool(up_mu),
                                             'what': 'at every pre-tension > 0, larger friction gives more'}
measured = {'runs': len(rows), 'pretensions': T, 'frictions': mu,
            'peak_force': {'%g N, mu %g' % k: v for k, v in sorted(peak.items())},
            'pullout_energy': {'%g N, mu %g' % k: v for k, v in sorted(energy.items())},
            'max_energy_balance_error': max(abs(r[5]) for r in rows)}
status = 'ok' if all(c['passed'] for c in checks.values()) and all(r[9] == 'ok' for r in rows) else 'failed'
write_summary(d, 'pullout_chart', p, measured,
              {'trend': 'peak force and pull-out energy rise with pre-tension and friction (Roark et al. 2023; '
                        'Kirkwood et al. 2004)'},
              {'peak_force': 'N', 'pullout_energy': 'J', 'pretensions': 'N'}, status, checks)
print('pullout_chart: %s; %d runs -> %s' % (status, len(rows), os.path.join(d, 'pullout_sweep.png')))
for m_ in mu:
    print('  friction %.2g: peak %s N' % (m_, ', '.join('%.3f' % peak[(t, m_)] for t in T if (t, m_) in peak)))
if status != 'ok':
    sys.exit(1)
