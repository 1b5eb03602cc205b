# Speed against accuracy: the same ballistic scene with woven's collision methods and with YADE's own
# grid elements, charted one against the other, and a stability map of where each method fails.
#   yade -n -x scripts/compare.py [quick=0] [map=1] [jobs=2] [out=DIR] ...
# Every case is one run of a scene script (scripts/ballistic.py, `model=yade` for the grid baseline;
# scripts/smith.py for the single-yarn error) in its own YADE process, with its own summary.json.
#
# Methods (docs/compare.md):
#   impulse          woven's default: gap functions with exact-gradient impulse rows and a position
#                    projection (contact_model=gap; docs/collisions.md), geometric flattening up to the MCD
#   impulse_adaptive the same method at adaptive resolution (scripts/ballistic.py fine_radius): the case's
#                    CPs per span within fine_radius of the impact point, 1 outside, one time step for all;
#                    fine_radius = each of `fine_radii` x the projectile's size; only at 2 CPs per span or more
# Both impulse methods also run with spring substeps (ballistic.py `substeps`, multiple time stepping):
# s = 2, 4 up to the case's CPs per span, the contacts then once per s spring steps (s = CPs per span:
# at the rate of a 1-CP ply). The adaptive cases with substeps run twice: every CP at the substep, and
# multi-rate (ballistic.py multirate=1: the coarse CPs once per step, docs/design.md).
#   chords           the default's gap functions and impulses with every crossing measured as the CP pairs
#                    of its chords (crossings=chords: four contacts a crossing, the default until the
#                    persistent crossings; docs/collisions.md)
#   paper            woven as the paper: SAT normal, depth on the sections, impulses (Eq. 5) (contact_model=paper)
#   penalty          the paper's OBB/SAT geometry, penalty forces k_p * overlap instead of impulses
#   no_flattening    the paper's method, sections never flatten
#   section_springs  the paper's method, flattening resisted by the section springs of Eq. 7, impulses past the MCD
#   yade_grid        YADE's GridNode/GridConnection yarns, FrictPhys contacts of stiffness kn
#   yade_pfacet      YADE's PFacet ribbons (woven.yade_pfacet) of pfacet_lines node lines, the same contacts;
#                    minutes a run, so only when `methods` names it
# Accuracy of a run: the projectile's velocity drop over the same simulated time against the
# reference run (impulse, finest resolution, half the time step): |dv - dv_ref| / dv_ref; the largest
# yarn-yarn and projectile-yarn interpenetration; the energy-balance error. Speed: wall seconds of
# the time loop per simulated microsecond, every timed run alone on the machine (one job at a time).
# Output (out/compare/): cases.csv, table.md, scenes.md, pareto.png, stability.csv, stability.png, summary.json
# with the speed ratio woven / YADE grid at matched accuracy.
import json
import math
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import woven  # noqa: F401  (checks the install)
from woven.params import read_params
from woven.output import out_dir, write_summary
from woven.output import atomic_open, csv_field, savefig, write_csv

p = read_params({
    'quick': (False, '', 'a reduced set of cases (a few minutes, for CI)'),
    'map': (True, '', 'also run the stability map'),
    'map_size': ('', '', "'quick' or 'full' stability map (default: 'quick' with quick=1, else 'full')"),
    'map_speeds': ('', 'm/s', "the stability map's impact speeds, comma-separated, each in (0, 2000] (default: the "
                   "map size's: quick 200,1000, full 100,300,1000)"),
    'jobs': (2, '', 'parallel runs for the stability map (timed runs always go one at a time)'),
    'V': (200.0, 'm/s', 'impact speed of the timed cases'),
    'side': (0.0, 'm', 'ply side (0: 25.4 mm, quick: 12.7 mm)'),
    't_end': (0.0, 's', 'simulated time of every timed case (0: 30 us, quick: 15 us)'),
    'shape': ('sphere', '', "projectile: 'sphere' or 'box' (both models have both)"),
    'size': (3.0e-3, 'm', 'sphere diameter or cube edge'),
    'mass': (0.25e-3, 'kg', 'projectile mass'),
    'methods': ('', '', 'comma-separated subset of impulse, impulse_adaptive, chords, paper, penalty, no_flattening, section_springs, '
                'yade_grid, yade_pfacet (default: all but yade_pfacet)'),
    'map_methods': ('', '', "the stability map's methods, comma-separated, among those run (default: every method "
                    "run but impulse_adaptive and chords, which share the impulse method's map)"),
    'fine_radii': ('1,2', '', "impulse_adaptive's fine_radius values, comma-separated multiples of the projectile's size, "
                   'each in (0, 100]'),
    'timeout': (900, 's', 'longest a single run may take'),
    'out': ('', '', 'output folder (default out/compare)'),
})


def bad(key, allowed):
    raise ValueError('%s = %r is invalid: allowed %s' % (key, p[key], allowed))


if p.map_size not in ('', 'quick', 'full'):
    bad('map_size', "'quick', 'full' or empty (follows quick)")
try:
    MAP_SPEEDS = [float(x) for x in str(p.map_speeds).split(',') if x.strip()]
except ValueError:
    MAP_SPEEDS = None
if MAP_SPEEDS is None or not all(math.isfinite(v) and 0 < v <= 2000 for v in MAP_SPEEDS):
    bad('map_speeds', 'comma-separated speeds in (0, 2000] m/s, or empty (the map size\'s)')
if not (1 <= p.jobs <= 64):
    bad('jobs', '[1, 64]')
if not (math.isfinite(p.V) and 0 < p.V <= 2000):
    bad('V', '(0, 2000] m/s')
if p.side < 0 or not math.isfinite(p.side):
    bad('side', '0 (default) or (0, inf) m')
if p.t_end < 0 or not math.isfinite(p.t_end):
    bad('t_end', '0 (default) or (0, inf) s')
if p.shape not in ('sphere', 'box'):
    bad('shape', "'sphere' or 'box'")
if not (p.size > 0 and p.mass > 0):
    bad('size' if not p.size > 0 else 'mass', '(0, inf)')
try:
    FINE_RADII = [float(x) for x in str(p.fine_radii).split(',') if x.strip()]
except ValueError:
    FINE_RADII = []
if not FINE_RADII or not all(math.isfinite(x) and 0 < x <= 100 for x in FINE_RADII):
    bad('fine_radii', 'comma-separated numbers in (0, 100] (multiples of the projectile size)')
d = out_dir('compare', p)
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0])))  # yade -x sets argv[0] to this script
side = p.side or (0.0127 if p.quick else 0.0254)
t_end = p.t_end or (15e-6 if p.quick else 30e-6)

# --- the cases ---------------------------------------------------------------------------------
# Each method: its keys, the stiffness key it sweeps (None: no contact stiffness) and the values.
METHODS = {
    'impulse': ({}, None, [None]),
    # The swept value is fine_radius [m] (the table's 'stiffness' column stays empty for it).
    'impulse_adaptive': ({'cp_coarse': 1}, 'fine_radius', [x * p.size for x in FINE_RADII]),
    'chords': ({'crossings': 'chords'}, None, [None]),
    'paper': ({'contact_model': 'paper'}, None, [None]),
    # The response and section variants stay on the paper's contact geometry they were charted with.
    'penalty': ({'contact_model': 'paper', 'response': 'penalty'}, 'penalty_stiffness', [1e5, 1e6, 1e7]),
    'no_flattening': ({'contact_model': 'paper', 'flattening': 'none'}, None, [None]),
    'section_springs': ({'contact_model': 'paper', 'flattening': 'springs'}, 'section_stiffness', [1e3, 1e4, 1e5]),
    'yade_grid': ({'model': 'yade'}, 'kn', [1e5, 1e6, 1e7]),
    'yade_pfacet': ({'model': 'yade_pfacet'}, 'kn', [1e5, 1e6, 1e7]),
}
# Opt-in methods: a PFacet run is minutes on the quick ply (YADE hands every warp-weft PFacet pair to
# its nodes and connections, ~8 candidate interactions a body, docs/yade_grid.md).
OPT_IN = ('yade_pfacet',)
if p.methods:
    chosen = [m.strip() for m in p.methods.split(',') if m.strip()]
    if not chosen or any(m not in METHODS for m in chosen) or 'impulse' not in chosen:
        bad('methods', 'a comma-separated subset of %s that includes impulse (the reference)' % ', '.join(METHODS))
    METHODS = {m: METHODS[m] for m in METHODS if m in chosen}
else:
    METHODS = {m: METHODS[m] for m in METHODS if m not in OPT_IN}
# The stability map's methods. The adaptive method is the impulse method at another resolution (the
# map's scene is at 1 CP); the chord contacts share the default's gap functions, rows and projection.
MAP_METHODS = [m for m in METHODS if m not in ('impulse_adaptive', 'chords')]
if p.map_methods:
    asked = [m.strip() for m in p.map_methods.split(',') if m.strip()]
    if not asked or any(m not in MAP_METHODS for m in asked):
        bad('map_methods', 'a comma-separated subset of %s' % ', '.join(MAP_METHODS))
    MAP_METHODS = [m for m in MAP_METHODS if m in asked]
DT_KEY = {'yade_grid': 'dt_factor', 'yade_pfacet': 'dt_factor'}  # the others: 'safety' (fraction of the chain's dt_crit)
SCENE = {'side': side, 't_end': t_end, 'V': p.V, 'shape': p.shape, 'size': p.size, 'mass': p.mass,
         'stop': 0, 'vtk_every': -1, 'progress': 0, 'samples': 50, 'energy_limit': 0.99, 'overlap_limit': 100,
         'pictures': 0, 'backface': 0}  # the method's time, not the pictures' frames and back-face measures
SUBSTEPS = [1, 2, 4]  # of the impulse methods, each s <= the case's CPs per span
if p.quick:
    RES, DTS, REF_RES = [1, 2, 4], [0.7], 4
    STIFF_KEEP = {'penalty': [1e6], 'section_springs': [1e4], 'yade_grid': [1e6, 1e7], 'yade_pfacet': [1e7]}
else:
    RES, DTS, REF_RES = [1, 2, 4], [0.35, 0.7], 4
    STIFF_KEEP = {}
# The PFacet ribbons' resolutions: CPs per span (each doubling is ~4x the wall time: twice the bodies
# at half the step) and node lines across a ribbon.
RES_OF = {'yade_pfacet': [1, 2]}
PFACET_LINES = [2, 3]


def case_name(method, res, dt, k, sub=1, mr=0, lines=None):
    tail = ('' if sub == 1 else '_s%d' % sub) + ('_mr' if mr else '') + ('' if lines is None else '_l%d' % lines)
    if method == 'impulse_adaptive':
        return '%s_cp%d_dt%g_r%g%s' % (method, res, dt, k, tail)
    return '%s_cp%d_dt%g%s%s' % (method, res, dt, '' if k is None else '_k%g' % k, tail)


def keys_of(method, res, dt, k, sub=1, mr=0, lines=None):
    extra, kkey, _ = METHODS[method]
    q = dict(SCENE)
    q.update(extra)
    q['cp_per_span'] = res
    if lines is not None:
        q['pfacet_lines'] = lines
    if sub > 1:
        q['substeps'] = sub
    if mr:
        q['multirate'] = 1
    q[DT_KEY.get(method, 'safety')] = dt
    if kkey is not None:
        q[kkey] = k
    return q


def run(script, name, keys, folder):
    """One scene in its own YADE process; returns its summary (None if it wrote none) and output."""
    o = os.path.join(folder, name)
    os.makedirs(o, exist_ok=True)
    cmd = ['yade', '-n', '-x', os.path.join(ROOT, 'scripts', script), 'out=%s' % o] + \
          ['%s=%s' % (k, v) for k, v in keys.items()]
    t0 = time.time()
    try:
        r = subprocess.run(cmd, cwd=o, capture_output=True, text=True, timeout=p.timeout)
        text, code = r.stdout + r.stderr, r.returncode
    except subprocess.TimeoutExpired:
        text, code = 'timeout after %d s' % p.timeout, -1
    path = os.path.join(o, 'summary.json')
    s = json.load(open(path)) if os.path.exists(path) else None
    return {'summary': s, 'code': code, 'tail': text[-600:], 'process_seconds': time.time() - t0}


def ballistic_figures(r):
    """The figures compare.py uses from one ballistic run (None when the run wrote no summary)."""
    s = r['summary']
    if s is None:
        return None
    m = s['measured']
    return {'status': s['status'], 'v_end': m.get('projectile_velocity_end'),
            'yarn_pen': m.get('max_yarn_penetration'), 'body_pen': m.get('max_body_penetration'),
            'energy_err': m.get('energy_balance_error'), 'wall': m.get('wall_seconds'),
            'sim': m.get('simulated_time'), 'dt': m.get('dt'), 'cps': m.get('cps'),
            'broken': m.get('broken_elements'), 'thickness': m.get('yarn_thickness')}


# --- timed cases: one at a time ----------------------------------------------------------------
cases = []
for method, (extra, kkey, ks) in METHODS.items():
    for k in STIFF_KEEP.get(method, ks):
        for res in RES_OF.get(method, RES):
            if method == 'impulse_adaptive' and res < 2:  # 1 CP everywhere: the uniform case
                continue
            for sub in (SUBSTEPS if method in ('impulse', 'impulse_adaptive') else [1]):
                if sub > res:
                    continue
                for dt in DTS:
                    for lines in (PFACET_LINES if method == 'yade_pfacet' else [None]):
                        cases.append((method, res, dt, k, sub, 0, lines))
                    if method == 'impulse_adaptive' and sub > 1:  # its coarse CPs once per step (multirate)
                        cases.append((method, res, dt, k, sub, 1, None))
ref_case = ('impulse', REF_RES, min(DTS) / 2, None, 1, 0, None)
cases.insert(0, ref_case)
t_all = time.time()
results = {}
for c in cases:
    name = case_name(*c)
    r = run('ballistic.py', name, keys_of(*c), os.path.join(d, 'runs'))
    results[c] = r
    f = ballistic_figures(r)
    print('compare: %-40s %s' % (name, 'no summary (exit %d): %s' % (r['code'], r['tail'][-200:].replace('\n', ' '))
                                  if f is None else '%s v_end %.2f m/s, wall %.1f s' % (f['status'], f['v_end'], f['wall'])))
    sys.stdout.flush()

ref = ballistic_figures(results[ref_case])
if ref is None or ref['status'] != 'ok':
    raise RuntimeError('compare: the reference run %s failed: %s' % (case_name(*ref_case), results[ref_case]['tail']))
dv_ref = p.V - ref['v_end']

rows = []
for c in cases:
    f = ballistic_figures(results[c])
    method, res, dt, k, sub, mr, lines = c
    adaptive = method == 'impulse_adaptive'
    row = {'method': method, 'cp_per_span': res, 'dt_over_dt_crit': dt, 'substeps': sub, 'multirate': mr, 'pfacet_lines': lines,
           'stiffness': None if adaptive else k,
           'fine_radius': k if adaptive else None, 'reference': c == ref_case}
    if f is None:
        row.update({'status': 'crashed'})
    else:
        ok = f['status'] == 'ok' and f['v_end'] is not None and math.isfinite(f['v_end'])
        row.update({'status': f['status'], 'v_end': f['v_end'],
                    'velocity_error': abs((p.V - f['v_end']) - dv_ref) / dv_ref if ok else float('nan'),
                    'max_yarn_penetration': f['yarn_pen'], 'max_body_penetration': f['body_pen'],
                    'energy_error': abs(f['energy_err']) if f['energy_err'] is not None else float('nan'),
                    'wall_per_us': f['wall'] / (f['sim'] * 1e6) if f['sim'] else float('nan'),
                    'dt': f['dt'], 'cps': f['cps'], 'broken': f['broken']})
    rows.append(row)

COLS = ['method', 'cp_per_span', 'pfacet_lines', 'dt_over_dt_crit', 'substeps', 'multirate', 'stiffness', 'fine_radius', 'status', 'v_end', 'velocity_error',
        'max_yarn_penetration', 'max_body_penetration', 'energy_error', 'wall_per_us', 'dt', 'cps', 'broken', 'reference']


def fmt(v):
    return csv_field(v, 4)


write_csv(os.path.join(d, 'cases.csv'), COLS, rows, 4)
with atomic_open(os.path.join(d, 'table.md')) as f:
    f.write('| method | CPs/span | PFacet lines | dt/dt_crit | substeps | stiffness [N/m] | fine radius [mm] | CPs | status | '
            'v_end [m/s] | velocity-drop error | max yarn overlap [mm] | max projectile overlap [mm] | energy error | wall s / us |\n')
    f.write('|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n')
    for r in rows:
        mm = lambda v: '' if v is None or not isinstance(v, float) else '%.3f' % (1e3 * v)  # noqa: E731
        f.write('| %s%s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' % (
            r['method'], ' (reference)' if r['reference'] else '', r['cp_per_span'], fmt(r['pfacet_lines']) or '–',
            fmt(r['dt_over_dt_crit']),
            '%d%s' % (r['substeps'], ' multi-rate' if r['multirate'] else ''),
            fmt(r['stiffness']) or '–', mm(r['fine_radius']) or '–', fmt(r.get('cps')), r['status'], fmt(r.get('v_end')),
            '' if r.get('velocity_error') is None else '%.2f %%' % (100 * r['velocity_error']),
            mm(r.get('max_yarn_penetration')), mm(r.get('max_body_penetration')),
            '' if r.get('energy_error') is None else '%.2f %%' % (100 * r['energy_error']), fmt(r.get('wall_per_us'))))


# --- the other scenes: Smith's single yarn and the tension of a free weave ---------------------------------
# Smith: strain behind the front and the transverse wave speed against theory (physics-reference.md),
# woven's chain and YADE's grid chain at the same element counts. Tension: the toe strain (where the
# curve turns linear) against the built crimp and Kevlar's 0.25-0.65 %, with the final overlap.
scene_rows = []
SMITH_EL = [1000, 2000] if p.quick else [600, 1000, 2000, 4000]  # smith.py refuses < 518 at this speed
YADE_SCENE_MODELS = ['yade'] + (['yade_pfacet'] if 'yade_pfacet' in METHODS else [])
for model in ['woven'] + YADE_SCENE_MODELS:
    for n in SMITH_EL:
        keys = {'elements': n, 'levels': 1}
        if model != 'woven':
            keys['model'] = model
        r = run('smith.py', 'smith_%s_%d' % (model, n), keys, os.path.join(d, 'runs'))
        s = r['summary']
        row = {'scene': 'smith', 'model': model, 'elements': n, 'status': 'crashed' if s is None else s['status']}
        if s is not None:
            c = s['measured']['convergence'][0]
            row.update({'strain_error': abs(c['strain_error']), 'wave_speed_error': abs(c['U_E_error']),
                        'energy_error': abs(c.get('energy_balance_error') or float('nan')),
                        'process_seconds': r['process_seconds']})
        else:
            row['why'] = r['tail'][-200:].replace('\n', ' ')
        scene_rows.append(row)
TENSION = {'nx': 3, 'ny': 3} if p.quick else {}
for model in ['woven'] + YADE_SCENE_MODELS:
    keys = dict(TENSION)
    if model != 'woven':
        keys['model'] = model
    r = run('tension.py', 'tension_%s' % model, keys, os.path.join(d, 'runs'))
    s = r['summary']
    row = {'scene': 'tension', 'model': model, 'status': 'crashed' if s is None else s['status']}
    if s is not None:
        m = s['measured']
        row.update({'toe_strain': m.get('toe_strain'), 'crimp': s['reference'].get('warp_crimp_built'),
                    'final_overlap': m.get('final_overlap'), 'crossing_order_flips': m.get('crossing_order_flips'),
                    'stiffness_per_straight_yarns': m.get('final_stiffness_per_straight_yarns'),
                    'process_seconds': r['process_seconds']})
    else:
        row['why'] = r['tail'][-200:].replace('\n', ' ')
    scene_rows.append(row)
for row in scene_rows:
    print('compare: %-8s %-6s %s' % (row['scene'], row['model'], {k: fmt(v) for k, v in row.items() if k not in ('scene', 'model')}))
with atomic_open(os.path.join(d, 'scenes.md')) as f:
    f.write('| scene | model | elements | status | strain error | wave-speed error | toe strain | built crimp | '
            'final overlap [mm] | order flips | process wall incl. YADE start [s] |\n|---|---|---|---|---|---|---|---|---|---|---|\n')
    pc = lambda v: '' if v is None or not isinstance(v, float) else '%.2f %%' % (100 * v)  # noqa: E731
    for r in scene_rows:
        f.write('| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' % (
            r['scene'], r['model'], fmt(r.get('elements')), r['status'], pc(r.get('strain_error')), pc(r.get('wave_speed_error')),
            pc(r.get('toe_strain')), pc(r.get('crimp')),
            '' if r.get('final_overlap') is None else '%.4f' % (1e3 * r['final_overlap']),
            fmt(r.get('crossing_order_flips')), fmt(r.get('process_seconds'))))

# --- speed at matched accuracy ---------------------------------------------------------------------
def good(r):
    return r['status'] == 'ok' and math.isfinite(r.get('velocity_error', float('nan')))


# woven's pool: the impulse method at uniform and at adaptive resolution, with and without spring
# substeps (the same contact method; fewer CPs away from the impact, fewer contact passes); the
# uniform cases without substeps alone give the second ratio (the measure before either).
impulse_runs = [r for r in rows if r['method'] in ('impulse', 'impulse_adaptive') and good(r) and not r['reference']]
uniform_runs = [r for r in impulse_runs if r['method'] == 'impulse' and r['substeps'] == 1]
grid_runs = [r for r in rows if r['method'] == 'yade_grid' and good(r)]


def name_of(r):
    return case_name(r['method'], r['cp_per_span'], r['dt_over_dt_crit'],
                     r['fine_radius'] if r['method'] == 'impulse_adaptive' else r['stiffness'], r['substeps'], r['multirate'],
                     r['pfacet_lines'])


def matched(grid, pool, strict):
    """Fastest run of `pool` at least as accurate as `grid` (velocity error; strict: also both
    overlaps and the energy error)."""
    ok = [w for w in pool if w['velocity_error'] <= grid['velocity_error'] and
          (not strict or (w['max_yarn_penetration'] <= grid['max_yarn_penetration'] and
                          w['max_body_penetration'] <= grid['max_body_penetration'] and
                          w['energy_error'] <= grid['energy_error']))]
    return min(ok, key=lambda w: w['wall_per_us']) if ok else None


ratios = []
for g in grid_runs:
    for strict in (False, True):
        w = matched(g, impulse_runs, strict)
        ratios.append({'grid_case': case_name('yade_grid', g['cp_per_span'], g['dt_over_dt_crit'], g['stiffness']),
                       'strict': strict, 'grid_velocity_error': g['velocity_error'], 'grid_wall_per_us': g['wall_per_us'],
                       'woven_case': None if w is None else name_of(w),
                       'woven_wall_per_us': None if w is None else w['wall_per_us'],
                       'speed_ratio': None if w is None else g['wall_per_us'] / w['wall_per_us']})
best_grid = min(grid_runs, key=lambda g: g['velocity_error']) if grid_runs else None
pfacet_runs = [r for r in rows if r['method'] == 'yade_pfacet' and good(r)]
best_pfacet = min(pfacet_runs, key=lambda g: g['velocity_error']) if pfacet_runs else None
pfacet_ratio = pfacet_ratio_case = None
if best_pfacet is not None:
    w = matched(best_pfacet, impulse_runs, False)
    if w is not None:
        pfacet_ratio, pfacet_ratio_case = best_pfacet['wall_per_us'] / w['wall_per_us'], name_of(w)
headline = headline_uniform = headline_case = None
if best_grid is not None:
    w = matched(best_grid, impulse_runs, False)
    if w is not None:
        headline, headline_case = best_grid['wall_per_us'] / w['wall_per_us'], name_of(w)
    w = matched(best_grid, uniform_runs, False)
    if w is not None:
        headline_uniform = best_grid['wall_per_us'] / w['wall_per_us']

# --- Pareto chart ------------------------------------------------------------------------------------
import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt
MARK = {'impulse': ('o', 'C0'), 'impulse_adaptive': ('P', 'C9'), 'chords': ('<', 'C5'), 'paper': ('v', 'C4'), 'penalty': ('s', 'C1'), 'no_flattening': ('^', 'C2'),
        'section_springs': ('D', 'C3'), 'yade_grid': ('X', 'k'), 'yade_pfacet': ('*', 'C7')}
fig, ax = plt.subplots(1, 3, figsize=(17, 5.2))
panels = (('velocity_error', 'velocity-drop error vs reference', 1.0),
          ('max_yarn_penetration', 'largest yarn-yarn overlap [mm]', 1e3),
          ('energy_error', 'energy-balance error', 1.0))
for a, (key, label, scale) in zip(ax, panels):
    for method, (mk, colour) in MARK.items():
        pts = [r for r in rows if r['method'] == method and r['status'] not in ('crashed',) and not r['reference']
               and r.get(key) is not None and math.isfinite(r.get(key, float('nan'))) and math.isfinite(r.get('wall_per_us', float('nan')))]
        if not pts:
            continue
        x = [r['wall_per_us'] for r in pts]
        y = [max(scale * r[key], 1e-6) for r in pts]
        a.scatter(x, y, marker=mk, color=colour, s=[30 + 25 * r['cp_per_span'] for r in pts], label=method,
                  facecolors='none' if method in ('yade_grid', 'yade_pfacet') else colour, alpha=0.85)
        for r, xi, yi in zip(pts, x, y):
            a.annotate('%d%s%s%s' % (r['cp_per_span'], '' if r['stiffness'] is None else ' k%.0e' % r['stiffness'],
                                     '' if r['fine_radius'] is None else ' r%.1f mm' % (1e3 * r['fine_radius']),
                                     ('' if r['substeps'] == 1 else ' s%d' % r['substeps']) + (' mr' if r['multirate'] else '')
                                     + ('' if r['pfacet_lines'] is None else ' l%d' % r['pfacet_lines'])),
                       (xi, yi), fontsize=6, xytext=(3, 2), textcoords='offset points')
    a.set_xscale('log')
    a.set_yscale('log')
    a.set_xlabel('wall seconds per simulated microsecond')
    a.set_ylabel(label)
    a.grid(True, which='both', alpha=0.3)
ax[0].legend(fontsize=8, title='marker size: CPs per span')
thick = ref['thickness']
if thick:
    ax[1].axhline(1e3 * thick, color='r', ls=':', lw=0.8, label='yarn thickness')
    ax[1].legend(fontsize=8)
ax[2].axhline(0.05, color='r', ls=':', lw=0.8)
fig.suptitle('%s %.3g g at %.0f m/s on a %.1f mm ply, %.0f us; reference: impulse, %d CPs/span, dt = %.2f dt_crit '
             '(velocity drop %.2f m/s)' % (p.shape, p.mass * 1e3, p.V, side * 1e3, t_end * 1e6, REF_RES, ref_case[2], dv_ref))
fig.tight_layout()
savefig(fig, os.path.join(d, 'pareto.png'), dpi=110)
plt.close(fig)

# --- stability map -------------------------------------------------------------------------------------
# A small scene (6.35 mm ply, 1.5 mm sphere, 8 us) per method over dt/dt_crit x contact stiffness x
# impact speed; each cell is classified by the first failure found (docs/compare.md):
#   blow-up        non-finite state or energy blow-up (the scene's status 'unstable'), or no summary
#   crash          the process was killed by a signal (a segmentation fault)
#   refused        the time step was refused by a guard (woven: dt > dt_crit of the chain)
#   energy         energy-balance error > 5 % of the projectile's kinetic energy
#   overlap        a yarn-yarn or projectile-yarn overlap deeper than the yarn's thickness
#   tunnelling     the projectile ended below the ply with no yarn broken and < 1 % of its speed lost
#   stable         none of these
FAIL = ['stable', 'overlap', 'energy', 'tunnelling', 'refused', 'blow-up', 'crash']
map_rows = []
if p.map:
    if (p.map_size or ('quick' if p.quick else 'full')) == 'quick':
        M_DT, M_V = [0.5, 1.5], [200.0, 1000.0]
        M_K = {'penalty': [1e6, 1e8], 'section_springs': [1e5], 'yade_grid': [1e6, 1e8], 'yade_pfacet': [1e6, 1e8]}
    else:
        M_DT, M_V = [0.25, 0.5, 0.9, 1.5, 3.0], [100.0, 300.0, 1000.0]
        M_K = {'penalty': [1e5, 1e6, 1e7, 1e8, 1e9], 'section_springs': [1e3, 1e4, 1e5, 1e6, 1e8],
               'yade_grid': [1e5, 1e6, 1e7, 1e8, 1e9], 'yade_pfacet': [1e5, 1e6, 1e7, 1e8, 1e9]}
    if MAP_SPEEDS:
        M_V = MAP_SPEEDS
    MSCENE = {'side': 0.00635, 't_end': 8e-6, 'shape': 'sphere', 'size': 1.5e-3, 'mass': 0.05e-3,
              'stop': 0, 'vtk_every': -1, 'progress': 0, 'samples': 20, 'cp_per_span': 1, 'energy_limit': 0.99,
              'overlap_limit': 100, 'pictures': 0, 'backface': 0}
    jobs = []
    for method in MAP_METHODS:
        extra, kkey, _ = METHODS[method]
        for k in (M_K.get(method, [None]) if kkey else [None]):
            for dt in M_DT:
                for V in M_V:
                    q = dict(MSCENE)
                    q.update(extra)
                    q['V'] = V
                    q[DT_KEY.get(method, 'safety')] = dt
                    if kkey:
                        q[kkey] = k
                    jobs.append((method, dt, k, V, q))

    def classify(job, r):
        method, dt, k, V, q = job
        s = r['summary']
        if s is None:
            refused = 'is invalid' in r['tail'] and ('safety' in r['tail'] or 'dt' in r['tail'])
            if refused:
                return 'refused', r['tail'][-160:].replace('\n', ' ')
            if r['code'] < 0 or r['code'] > 128:  # killed by a signal (YADE's grid code segfaults at 1000 m/s)
                return 'crash', 'process ended by signal %d' % (-r['code'] if r['code'] < 0 else r['code'] - 128)
            return 'blow-up', r['tail'][-160:].replace('\n', ' ')
        if s['status'] == 'unstable':
            return 'blow-up', 'instability detected'
        m = s['measured']
        vals = [m.get('projectile_velocity_end'), m.get('energy_balance_error')]
        if any(v is None or not math.isfinite(v) for v in vals):
            return 'blow-up', 'non-finite result'
        # the model's own yarn: woven's section thickness, the grid cylinder's diameter
        thick = 2 * m['grid_radius'] if m.get('grid_radius') else (m.get('yarn_thickness') or 0.11e-3)
        if abs(m['energy_balance_error']) > 0.05:
            return 'energy', 'energy-balance error %.3g' % m['energy_balance_error']
        pen = max(m.get('max_yarn_penetration') or 0, m.get('max_body_penetration') or 0)
        if pen > thick:
            return 'overlap', 'overlap %.3g mm > thickness %.3g mm' % (pen * 1e3, thick * 1e3)
        # the nose deeper than the ply by more than the projectile: it is through
        through = (m.get('max_penetration') or 0) > q['size'] + thick
        if through and m.get('broken_elements', 0) == 0 and m['projectile_velocity_end'] > 0.99 * V:
            return 'tunnelling', 'through the ply unbroken'
        return 'stable', ''

    with ThreadPoolExecutor(max_workers=p.jobs) as ex:
        outs = list(ex.map(lambda j: run('ballistic.py', 'map_%s_dt%g_k%s_V%g' % (j[0], j[1], j[2], j[3]), j[4],
                                         os.path.join(d, 'map')), jobs))
    for j, r in zip(jobs, outs):
        kind, why = classify(j, r)
        map_rows.append({'method': j[0], 'dt_over_dt_crit': j[1], 'stiffness': j[2], 'V': j[3], 'result': kind, 'why': why})
    with atomic_open(os.path.join(d, 'stability.csv')) as f:
        f.write('method,dt_over_dt_crit,stiffness,V,result,why\n')
        for r in map_rows:
            f.write('%s,%g,%s,%g,%s,"%s"\n' % (r['method'], r['dt_over_dt_crit'], fmt(r['stiffness']), r['V'], r['result'],
                                                r['why'].replace('"', "'")))
    from matplotlib.colors import ListedColormap
    cmap = ListedColormap(['#4caf50', '#ffb300', '#fb8c00', '#8e24aa', '#9e9e9e', '#d32f2f', '#000000'])
    fig, axes = plt.subplots(len(MAP_METHODS), len(M_V), figsize=(4 * len(M_V), 2.3 * len(MAP_METHODS)), squeeze=False)
    for i, method in enumerate(MAP_METHODS):
        ks = M_K.get(method, [None]) if METHODS[method][1] else [None]
        for jv, V in enumerate(M_V):
            a = axes[i][jv]
            grid = np.zeros((len(ks), len(M_DT)))
            for r in map_rows:
                if r['method'] == method and r['V'] == V:
                    grid[ks.index(r['stiffness']), M_DT.index(r['dt_over_dt_crit'])] = FAIL.index(r['result'])
            a.imshow(grid, cmap=cmap, vmin=0, vmax=len(FAIL) - 1, aspect='auto', origin='lower')
            a.set_xticks(range(len(M_DT)))
            a.set_xticklabels(['%g' % x for x in M_DT], fontsize=7)
            a.set_yticks(range(len(ks)))
            a.set_yticklabels(['–' if k is None else '%.0e' % k for k in ks], fontsize=7)
            if i == len(MAP_METHODS) - 1:
                a.set_xlabel('dt / dt_crit')
            if jv == 0:
                a.set_ylabel('%s\nstiffness [N/m]' % method, fontsize=8)
            if i == 0:
                a.set_title('V = %.0f m/s' % V)
    from matplotlib.patches import Patch
    fig.legend(handles=[Patch(color=cmap(q), label=n) for q, n in enumerate(FAIL)], loc='lower center', ncol=len(FAIL))
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    savefig(fig, os.path.join(d, 'stability.png'), dpi=100)
    plt.close(fig)

# --- summary ---------------------------------------------------------------------------------------------
measured = {'cases': len(rows), 'reference_case': case_name(*ref_case), 'reference_velocity_drop': dv_ref,
            'speed_ratio_at_matched_accuracy': headline,
            'speed_ratio_basis': 'YADE grid run with the smallest velocity-drop error against the fastest woven '
                                 'impulse run, uniform or adaptive, with or without spring substeps, at least as accurate '
                                 '(wall seconds per simulated us)',
            'speed_ratio_woven_case': headline_case,
            'speed_ratio_uniform_only': headline_uniform,
            'matched_pairs': ratios,
            'best_grid_case': None if best_grid is None else case_name('yade_grid', best_grid['cp_per_span'], best_grid['dt_over_dt_crit'], best_grid['stiffness']),
            'best_pfacet_case': None if best_pfacet is None else name_of(best_pfacet),
            'pfacet_speed_ratio_at_matched_accuracy': pfacet_ratio, 'pfacet_speed_ratio_woven_case': pfacet_ratio_case,
            'rows': rows, 'scenes': scene_rows, 'stability': map_rows, 'wall_seconds': time.time() - t_all}
checks = {}
if headline is not None:
    checks['speed_ratio'] = {'value': headline, 'limit': 10.0, 'passed': bool(headline >= 10.0),
                             'what': 'woven impulse faster than YADE grid at equal or better velocity error (goal)'}
status = 'ok' if all(r['status'] != 'crashed' for r in rows if r['method'] not in ('yade_grid', 'yade_pfacet')) else 'failed'
write_summary(d, 'compare', p, measured, {'speed_ratio_goal': 10.0, 'stability_energy_limit': 0.05},
              {'reference_velocity_drop': 'm/s', 'wall_per_us': 's/us', 'max_yarn_penetration': 'm',
               'max_body_penetration': 'm', 'velocity_error': 'fraction of the reference velocity drop',
               'energy_error': "fraction of the projectile's initial kinetic energy"}, status, checks)
print('compare: %s; %d cases, reference velocity drop %.3f m/s; speed ratio woven/YADE grid at matched accuracy: %s (%s; '
      'uniform resolution only: %s); %.0f s -> %s' % (status, len(rows), dv_ref, 'n/a' if headline is None else '%.1f' % headline,
                                                     headline_case, 'n/a' if headline_uniform is None else '%.1f' % headline_uniform,
                                                     time.time() - t_all, d))
if status != 'ok':
    sys.exit(1)
