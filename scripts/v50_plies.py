# V50 against the number of plies, and against friction for one ply, from V50 campaigns of
# scripts/campaign.py; Cunniff's dimensionless chart (woven.cunniff).
#   yade -n -x scripts/v50_plies.py [campaigns=out/v50p/p1,out/v50p/p2,out/v50p/p4,out/v50p/p8]
#                                   [friction=out/v50p/p1_f02,out/v50p/p1_f04] [beside=OTHER/v50_plies.csv] [out=DIR]
# Each folder is a campaign's `out` (summary.json, campaign.csv, runs/*/summary.json). The ply
# campaigns must be one scene but for `plies`; the friction campaigns must be the 1-ply campaign's scene
# but for `friction` and `body_friction`. A campaign without a Lambert-Jonas fit is listed with its
# runs and bracket and no V50.
# `beside`: an earlier output's v50_plies.csv (another patch size, say), drawn beside on both charts.
# Output (out/v50_plies/): v50_plies.csv (one row per campaign: plies, friction, areal density, V50
# and its interval, bracket, Cunniff's axes, runs, CPU), v50_plies.png (V50 against plies and areal
# density; Cunniff's axes with a power law y = c x^b fitted through each family; V50 against
# friction), summary.json (U*, the rows, the fits, checks).
import csv
import json
import os
import sys

import numpy as np
import woven
import woven.cunniff as cunniff
from woven.output import dry_run_stop, csv_field as fmt, out_dir, savefig, write_csv, write_summary
from woven.params import read_params
from woven.weave import WEAVE_KEYS

p = read_params({
    'campaigns': ('out/v50p/p1,out/v50p/p2,out/v50p/p4,out/v50p/p8', '',
                  'campaign folders (scripts/campaign.py out=), one per ply count, comma-separated; one scene but for plies'),
    'friction': ('', '', "campaign folders of one ply at other friction / body_friction, comma-separated; the 1-ply "
                 "campaign's scene but for those keys (empty: none)"),
    'beside': ('', '', 'a v50_plies.csv of another family of ply campaigns (e.g. another patch size) drawn beside '
               'this one on the V50 and Cunniff charts, its Cunniff fit too (empty: none)'),
    'out': ('', '', 'output folder (default out/v50_plies)'),
})
# A collector: its input is the folders it reads, which a dry run (WOVEN_DRY_RUN=1) does not need.
dry_run_stop('v50_plies')

# Keys that may differ between campaigns of one family (V and seed are the runs' own; out is the folder).
RUN_KEYS = ('V', 'seed', 'out')


def load_beside(path):
    """The ply rows (family 'plies', with a V50) of an earlier v50_plies.csv, as floats."""
    try:
        with open(path) as f:
            rows = [r for r in csv.DictReader(f) if r.get('family') == 'plies' and r.get('V50_m_s')]
        out = [{k: float(r[k]) for k in ('plies', 'side_m', 'V50_m_s', 'cunniff_x', 'cunniff_y')} for r in rows]
        for k in ('fastest_stop_m_s', 'slowest_perforation_m_s'):
            for o, r in zip(out, rows):
                o[k] = float(r[k]) if r.get(k) else None
    except (OSError, ValueError, KeyError) as ex:
        raise ValueError('beside = %r is invalid: allowed a v50_plies.csv of this script (%s)' % (path, ex))
    if len(out) < 1:
        raise ValueError('beside = %r is invalid: allowed a v50_plies.csv with ply rows that have a V50' % path)
    return out


beside = load_beside(p.beside) if p.beside else []


def folders(key):
    return [f for f in str(p[key]).replace(' ', '').split(',') if f]


def load(key, folder):
    """The campaign in `folder`: its summary, its runs' rows (campaign.csv) and one run's summary."""
    path = os.path.join(folder, 'summary.json')
    try:
        s = json.load(open(path))
    except (OSError, ValueError) as ex:
        raise ValueError('%s = %r is invalid: allowed folders of scripts/campaign.py runs (%s: %s)'
                         % (key, p[key], path, ex))
    if s.get('scene') != 'campaign':
        raise ValueError('%s = %r is invalid: %s is a %r summary, not a campaign\'s' % (key, p[key], path, s.get('scene')))
    try:
        with open(os.path.join(folder, 'campaign.csv')) as f:
            rows = list(csv.DictReader(f))
    except OSError as ex:
        raise ValueError('%s = %r is invalid: %s has no campaign.csv (%s)' % (key, p[key], folder, ex))
    if not rows:
        raise ValueError('%s = %r is invalid: %s holds no runs' % (key, p[key], folder))
    runs = []
    for r in rows:
        try:
            runs.append(json.load(open(os.path.join(folder, 'runs', r['run'], 'summary.json'))))
        except (OSError, ValueError):
            raise ValueError('%s = %r is invalid: run %s of %s has no summary.json' % (key, p[key], r['run'], folder))
    return {'folder': folder, 'summary': s, 'rows': rows, 'runs': runs}


def scene_of(c):
    """The run keys every run of campaign c shares (its first run's parameters but V, seed, out)."""
    q = {k: v for k, v in c['runs'][0]['parameters'].items() if k not in RUN_KEYS}
    for r in c['runs'][1:]:
        other = {k: v for k, v in r['parameters'].items() if k not in RUN_KEYS}
        if other != q:
            diff = sorted(k for k in set(q) | set(other) if q.get(k) != other.get(k))
            raise ValueError('campaign %s mixes runs of different scenes (keys %s)' % (c['folder'], ', '.join(diff)))
    return q


def same_but(key, base, other, free, folder):
    diff = sorted(k for k in set(base) | set(other) if k not in free and base.get(k) != other.get(k))
    if diff:
        raise ValueError('%s = %r is invalid: allowed campaigns of one scene but for %s; %s differs in %s (%s)'
                         % (key, p[key], ', '.join(free), folder, ', '.join(diff),
                            ', '.join('%s: %r against %r' % (k, other.get(k), base.get(k)) for k in diff)))


ply_c = [load('campaigns', f) for f in folders('campaigns')]
if not ply_c:
    raise ValueError("campaigns = %r is invalid: allowed one or more campaign folders" % p.campaigns)
fric_c = [load('friction', f) for f in folders('friction')]
for c in ply_c + fric_c:
    c['scene'] = scene_of(c)
base = ply_c[0]['scene']
for c in ply_c[1:]:
    same_but('campaigns', base, c['scene'], ('plies', 'max_iterations'), c['folder'])
plies = [c['scene']['plies'] for c in ply_c]
if len(set(plies)) != len(plies):
    raise ValueError('campaigns = %r is invalid: allowed one campaign per ply count (plies %s)' % (p.campaigns, plies))
if fric_c:
    one = [c for c in ply_c if c['scene']['plies'] == 1]
    if not one:
        raise ValueError('friction = %r is invalid: allowed only with a 1-ply campaign among campaigns' % p.friction)
    for c in fric_c:
        same_but('friction', one[0]['scene'], c['scene'], ('friction', 'body_friction'), c['folder'])

# The yarn and the ply as the runs built them: the same weave keys, one repeat (the areal density is
# per unit area, the same for 1 and 17 repeats: 0.18040208723119316 kg/m^2 for KM2 706, measured).
weave_args = {k: base[k] for k in WEAVE_KEYS if k in base}
w = woven.weave(**dict(weave_args, nx=1, ny=1))
yarn = w.engine.yarn(w.warp_yarns[0])
E, rho, eps_f = yarn['E'], yarn['rho'], base['break_strain'] or yarn['failure_strain']
# The yarn is linear elastic to its failure strain (tension-only springs), so its strength is E eps_f;
# with a Weibull draw eps_f is the mean strength (pkg/dynamics/Breakage.cpp), used here.
sigma_f = E * eps_f
us = cunniff.u_star(sigma_f, eps_f, rho, E)
ply_areal = w.summary['areal_density']
proj = ply_c[0]['runs'][0]['measured']['projectile']
# A cylinder's presented area is its disk (diameter = 2 radius); a cube's or a sphere's from size.
diameter = 2 * proj['radius'] if 'radius' in proj else proj['size']
area = cunniff.presented_area(proj['shape'], diameter, proj['yaw'], base['obliquity'])
mass = proj['mass']


def row(c):
    s = c['summary']['measured']
    q = c['scene']
    n = q['plies']
    r = {'plies': n, 'friction': q['friction'], 'body_friction': q['body_friction'], 'side_m': q['side'],
         'areal_density_kg_m2': n * ply_areal, 'runs': len(c['rows']),
         'perforated': sum(int(x['perforated']) for x in c['rows']),
         # runs still moving in the pack at t_end: counted as stops (residual 0) by the fit
         'unfinished': sum(1 for x in c['runs'] if x['measured']['outcome'] not in ('perforated', 'arrested')),
         'V50_m_s': s.get('V50'), 'V50_lo_m_s': None, 'V50_hi_m_s': None,
         'fastest_stop_m_s': None, 'slowest_perforation_m_s': None,
         'lj_a': s.get('lambert_jonas_a'), 'lj_p': s.get('lambert_jonas_p'), 'fit_rms_m_s': s.get('fit_rms'),
         'cunniff_x': None, 'cunniff_y': None,
         'max_energy_balance_error': max(float(x['energy_balance_error']) for x in c['rows']),
         'cpu_seconds': sum(x['measured'].get('cpu_seconds') or 0.0 for x in c['runs']),
         'campaign': c['folder']}
    if s.get('V50_interval'):
        r['V50_lo_m_s'], r['V50_hi_m_s'] = s['V50_interval']
    stops = [float(x['V_m_s']) for x in c['rows'] if not int(x['perforated'])]
    through = [float(x['V_m_s']) for x in c['rows'] if int(x['perforated'])]
    r['fastest_stop_m_s'] = max(stops) if stops else None
    r['slowest_perforation_m_s'] = min(through) if through else None
    r['cunniff_x'], y = cunniff.axes(r['V50_m_s'] if r['V50_m_s'] is not None else 0.0,
                                     r['areal_density_kg_m2'], area, mass, us)
    r['cunniff_y'] = y if r['V50_m_s'] is not None else None
    return r


ply_rows = sorted((row(c) for c in ply_c), key=lambda r: r['plies'])
fric_rows = sorted((row(c) for c in fric_c + [c for c in ply_c if c['scene']['plies'] == 1 and fric_c]),
                   key=lambda r: (r['friction'], r['body_friction']))
d = out_dir('v50_plies', p)
cols = list(ply_rows[0].keys())


write_csv(os.path.join(d, 'v50_plies.csv'), ['family'] + cols,
          [dict(r, family=fam) for fam, rows in (('plies', ply_rows), ('friction', fric_rows)) for r in rows])

# Checks: every campaign fitted; V50 rises with the ply count (a thicker pack of the same fabric
# must not stop less); every run's energy balance within ballistic.py's 1 %.
checks = {}
nofit = [r['campaign'] for r in ply_rows + fric_rows if r['V50_m_s'] is None]
checks['fitted'] = {'value': nofit, 'limit': [], 'passed': not nofit, 'what': 'campaigns without a Lambert-Jonas V50'}
v = [r['V50_m_s'] for r in ply_rows if r['V50_m_s'] is not None]
rising = all(b > a for a, b in zip(v, v[1:]))
checks['v50_rises_with_plies'] = {'value': v, 'limit': 'increasing', 'passed': rising,
                                  'what': 'V50 of the ply campaigns, fewest plies first'}
worst = max(r['max_energy_balance_error'] for r in ply_rows + fric_rows)
limit = base['energy_limit']  # ballistic.py's own limit, one for every campaign (checked above)
checks['energy_balance'] = {'value': worst, 'limit': limit, 'passed': worst <= limit,
                            'what': 'largest energy-balance error of any run / its initial kinetic energy'}
status = 'ok' if all(c['passed'] for c in checks.values()) else 'failed'


def fit_of(rows):
    """Cunniff's power law y = c x^b through a family's points (woven.cunniff.power_fit), or None."""
    pts = [(r['cunniff_x'], r['cunniff_y']) for r in rows if r['cunniff_y']]
    if len({x for x, _ in pts}) < 2:
        return None
    c, b, rms = cunniff.power_fit([x for x, _ in pts], [y for _, y in pts])
    return {'c': c, 'b': b, 'rms_log': rms, 'points': len(pts)}


fit = fit_of(ply_rows)
fit_beside = fit_of(beside)

import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt
if fric_rows:
    fig, axs = plt.subplots(2, 2, figsize=(11, 9))
    axs = axs.ravel()
else:
    fig, axs = plt.subplots(1, 2, figsize=(11, 4.6))


def errbars(ax, xs, rows, color, label):
    """V50 with a bar over the bracket (fastest stop, slowest perforation): with one seed per velocity
    the V50 lies there, while a bootstrap over 3-10 runs says little (it gave [0, 137] for 3 runs)."""
    pts = [(x, r) for x, r in zip(xs, rows) if r['V50_m_s'] is not None]
    if pts:
        ys = [r['V50_m_s'] for _, r in pts]
        lo = [max(0.0, r['V50_m_s'] - r['fastest_stop_m_s']) if r['fastest_stop_m_s'] is not None else 0 for _, r in pts]
        hi = [max(0.0, r['slowest_perforation_m_s'] - r['V50_m_s']) if r['slowest_perforation_m_s'] is not None else 0
              for _, r in pts]
        ax.errorbar([x for x, _ in pts], ys, yerr=[lo, hi], fmt='o-', color=color, capsize=4, label=label)
    for x, r in zip(xs, rows):  # the bracket of a campaign without a fit
        if r['V50_m_s'] is None and r['fastest_stop_m_s'] is not None:
            ax.plot([x, x], [r['fastest_stop_m_s'], r['slowest_perforation_m_s'] or r['fastest_stop_m_s']], 'k-', lw=3, alpha=0.4)


ax = axs[0]
errbars(ax, [r['plies'] for r in ply_rows], ply_rows, 'C0', 'V50, Lambert-Jonas (bar: fastest stop to slowest perforation)')
ax.axhspan(90, 100, xmin=0, xmax=0.08, color='g', alpha=0.25, label='1 ply, 50.8 mm, experiment: 90-100 m/s')
ax.set_xlabel('plies')
ax.set_ylabel('V50 [m/s]')
if beside:
    errbars(ax, [r['plies'] for r in beside], beside, 'C7',
            'beside: %.1f mm plies (%s)' % (1e3 * beside[0]['side_m'], os.path.basename(str(p.beside))))
ax.set_xticks(sorted({r['plies'] for r in ply_rows + beside}))
ax.set_title('KM2 706, %s, %.1f mm plies' % (proj['shape'].upper(), 1e3 * base['side']), fontsize=10)
top = ax.secondary_xaxis('top', functions=(lambda n: n * ply_areal, lambda a: a / ply_areal))
top.set_xlabel('areal density [kg/m$^2$]')
ax.legend(fontsize=7, loc='lower right')
ax.grid(alpha=0.3)

ax = axs[1]
pts = [r for r in ply_rows if r['cunniff_y'] is not None]
for rows, f, color, what in ((pts, fit, 'C0', '%.1f mm' % (1e3 * base['side'])),
                             (beside, fit_beside, 'C7', 'beside, %.1f mm' % (1e3 * beside[0]['side_m']) if beside else '')):
    if not rows:
        continue
    ax.plot([r['cunniff_x'] for r in rows], [r['cunniff_y'] for r in rows], 'o', color=color, label=what)
    for r in rows:
        ax.annotate('%d' % r['plies'], (r['cunniff_x'], r['cunniff_y']), textcoords='offset points', xytext=(4, -10), fontsize=8)
    if f:
        xs = np.linspace(0.5 * min(r['cunniff_x'] for r in rows), 1.1 * max(r['cunniff_x'] for r in rows), 60)
        ax.plot(xs, f['c'] * xs ** f['b'], '--', color=color, lw=1,
                label=r'fit $y = %.3f\,x^{%.3f}$ (rms %.1f %%)' % (f['c'], f['b'], 100 * f['rms_log']))
ax.set_xlabel(r'$A_d A_p / m_p$')
ax.set_ylabel(r'$V_{50} / U^{*1/3}$')
ax.set_title(r"Cunniff's axes: $U^{*1/3}$ = %.0f m/s" % us ** (1 / 3.), fontsize=10)
ax.set_xlim(left=0)
ax.set_ylim(bottom=0)
ax.grid(alpha=0.3)
ax.legend(fontsize=7, loc='upper left')

if fric_rows:
    ax = axs[2]
    # Two series from the frictionless ply: yarn-yarn friction alone, and the same coefficient on both pairs.
    for rows, color, label in (([r for r in fric_rows if r['body_friction'] == 0], 'C1', 'yarn-yarn only'),
                               ([r for r in fric_rows if r['body_friction'] == r['friction']], 'C2',
                                'yarn-yarn = projectile-yarn')):
        if any(r['friction'] > 0 for r in rows):
            errbars(ax, [r['friction'] for r in rows], rows, color, label)
    ax.set_xlabel('friction coefficient')
    ax.set_ylabel('V50 [m/s]')
    ax.set_title('one ply: V50 against friction', fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    # The V50 moves by less than the velocity step; the residual velocities show the effect at every
    # velocity: the friction campaign's minus the frictionless ply's, at the velocities both shot.
    ax = axs[3]
    by_folder = {c['folder']: c for c in fric_c + ply_c}
    ref = {float(x['V_m_s']): float(x['residual_m_s']) for x in by_folder[one[0]['folder']]['rows']}
    for k, r in enumerate(x for x in fric_rows if x['friction'] > 0 or x['body_friction'] > 0):
        pts = sorted((float(x['V_m_s']), float(x['residual_m_s']) - ref[float(x['V_m_s'])])
                     for x in by_folder[r['campaign']]['rows'] if float(x['V_m_s']) in ref)
        ax.plot([a for a, _ in pts], [b for _, b in pts], 'o-', color='C%d' % (k + 3), ms=4,
                label='friction %g, projectile %g' % (r['friction'], r['body_friction']))
    ax.axhline(0, color='k', lw=0.8)
    ax.set_xlabel('impact velocity [m/s]')
    ax.set_ylabel('residual velocity - frictionless [m/s]')
    ax.set_title('one ply: friction against the residual velocity', fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
fig.tight_layout()
savefig(fig, os.path.join(d, 'v50_plies.png'), dpi=110)

measured = {'plies': ply_rows, 'friction': fric_rows, 'U_star': us, 'U_star_cbrt': us ** (1 / 3.),
            'yarn': {'E': E, 'rho': rho, 'failure_strain': eps_f, 'strength': sigma_f},
            'ply_areal_density': ply_areal, 'presented_area': area, 'projectile_mass': mass,
            'cunniff_x_per_ply': ply_areal * area / mass,
            'cunniff_fit': fit, 'cunniff_fit_beside': fit_beside,
            'cpu_seconds': sum(r['cpu_seconds'] for r in ply_rows) +
                           sum(r['cpu_seconds'] for r in fric_rows if r['campaign'] not in [q['campaign'] for q in ply_rows])}
reference = {'V50_km2_706_single_ply_022_rcc': [90.0, 100.0],  # physics-reference.md (Nilakantan et al.; 50.8 mm)
             'cunniff_x_per_ply_km2_706_1.1g': 0.0040,          # physics-reference.md
             'friction_raises_V50_by': 0.10}                     # Rao et al. 2009, yarn-level FE
units = {'cunniff_fit': 'y = c x^b on Cunniff\'s axes (both dimensionless); rms_log: rms of log(y / fit)',
         'cunniff_fit_beside': 'the same for the beside CSV\'s rows',
         'U_star': 'm^3/s^3', 'U_star_cbrt': 'm/s', 'yarn': 'Pa, kg/m^3, -, Pa', 'ply_areal_density': 'kg/m^2',
         'presented_area': 'm^2', 'projectile_mass': 'kg', 'cpu_seconds': 's',
         'plies': 'rows of v50_plies.csv (units in the column names)', 'friction': 'rows of v50_plies.csv'}
write_summary(d, 'v50_plies', p, measured, reference, units, status, checks)
for r in ply_rows + fric_rows:
    print('v50_plies: plies %d, friction %g / %g: V50 %s m/s (%s), bracket %s-%s, x = %.5f, y = %s'
          % (r['plies'], r['friction'], r['body_friction'], fmt(r['V50_m_s']),
             '%s-%s' % (fmt(r['V50_lo_m_s']), fmt(r['V50_hi_m_s'])), fmt(r['fastest_stop_m_s']),
             fmt(r['slowest_perforation_m_s']), r['cunniff_x'], fmt(r['cunniff_y'])))
for name, f in (('', fit), (' beside', fit_beside)):
    if f:
        print('v50_plies: Cunniff fit%s: V50 / U*^(1/3) = %.4f (A_d A_p / m_p)^%.4f over %d packs, rms %.1f %%'
              % (name, f['c'], f['b'], f['points'], 100 * f['rms_log']))
print('v50_plies: %s; U*^(1/3) = %.1f m/s -> %s' % (status, us ** (1 / 3.), d))
if status != 'ok':
    sys.exit(1)
