# Yarn pull-out: one warp yarn pulled out of a plain-weave strip whose transverse (weft) yarns carry a
# pre-tension, run inside YADE's loop (docs/pullout.md).
#   yade -n -x scripts/pullout.py [pretension=2] [friction=0.3] [nx=5] [ny=2] [velocity=2] [pull=3e-3] [out=DIR] ...
# Protocol (SI units):
#  1. the strip (default KM2 706, 2 nx weft yarns crossing the pulled yarn, 2 ny warp yarns) is built and
#     its sections settled; the other warps are held at both ends; each weft is held at its y_min end
#     and its y_max end carries a dead load `pretension` [N] along +y, ramped up over 60 % of `settle`
#     and held for the rest (the yarns' axial dashpots, `damping`, calm the strip); the pulled yarn
#     (the middle warp) is held at its grip end (x_max) and its far end (x_min) carries a small dead
#     load `back_tension` along -x;
#  2. the grip moves along +x at `velocity` (reached over `ramp` of the pull) until it has moved `pull`;
#     the wefts keep their dead loads (`weft_ends=load`) or are clamped where they are (`weft_ends=clamp`).
# Why: the yarns have no bending stiffness. A free warp end folds, and a warp with no tension takes up
# whatever crimp the tensioned wefts give away (measured with free warps: crimped to ~8 %, ends pulled in
# by 1 mm), so the other warps are held. A pulled yarn with a slack free end whips: its tail ran inwards
# at 14 m/s behind a 2 m/s grip and buckled through the wefts; the back tension (0.05 N, 2.5 % of the
# default pre-tension) keeps it taut. Dead loads hold the wefts' tension at the set value; clamped
# wefts, axially rigid, are loaded further by the straightening pulled yarn (docs/pullout.md, "Protocol").
# Output (out/pullout/): curve.csv (grip displacement, grip force, contacts), pullout.png, summary.json
# (peak force, pull-out energy = area under the curve, energy books of the pull).
import math
import os
import sys
import time

import numpy as np
import woven
from woven.params import check_steps, read_params
from woven.output import out_dir, savefig, savetxt, write_summary
from woven.weave import WEAVE_KEYS
from woven.contact import CONTACT_KEYS

defaults = dict(WEAVE_KEYS)
defaults.update({
    # 10 wefts across the pulled yarn and 4 warps: the default run took 12-16 s (9 sweep runs: 12-42 s).
    'nx': (5, '', 'pattern repeats along x: weft yarns crossing the pulled yarn = 2 nx (plain)'),
    'ny': (2, '', 'pattern repeats along y: warp yarns = 2 ny (plain); the pulled one is the middle one'),
    # 2 CPs per span: a node between crossings lets the crimp move along the sliding yarn.
    'cp_per_span': (2, '', WEAVE_KEYS['cp_per_span'][2]),
    'damping': (0.1, '', WEAVE_KEYS['damping'][2]),
})
defaults.update(CONTACT_KEYS)
defaults.update({
    'friction': (0.3, '', 'Coulomb coefficient between yarns (the impulse law\'s), in [0, 2]'),
    # The positional correction puts energy into the books (docs/collisions.md): off, as in the ballistic scene.
    'position_correction': (0.0, '', CONTACT_KEYS['position_correction'][2]),
    # The paper's contact model: with the gap model the loose wefts of a 0 N pre-tension strip are
    # dragged along instead of slipping past, and the pull's books miss 7 % (measured; open, see
    # docs/pullout.md). The sweep's figures are this model's.
    'contact_model': ('paper', '', CONTACT_KEYS['contact_model'][2]),
    'broad_phase': ('grid', '', CONTACT_KEYS['broad_phase'][2]),
    'pretension': (2.0, 'N', 'dead load on the free end of every weft (transverse) yarn, in [0, 50]'),
    'velocity': (2.0, 'm/s', 'grip speed, in (0, 20]'),
    'pull': (3e-3, 'm', 'grip travel, in (0, 2 x the strip length]'),
    'ramp': (0.05, '', 'fraction of the pull over which the grip speed rises from 0, in [0, 0.5]'),
    'settle': (1.5e-4, 's', 'time to apply and hold the pre-tension (60 % ramp, 40 % hold), in (0, 0.01]'),
    # Dead loads keep the wefts' tension at the set value through the pull. Clamped wefts are rigid
    # axially: the straightening pulled yarn raises their tension (2 N -> 3.4-4.2 N measured), so
    # the pre-tension is no longer what the sweep varies (docs/pullout.md, Protocol).
    'weft_ends': ('load', '', "during the pull, the wefts' loaded ends keep their dead load ('load') or are clamped "
                  "where the pre-tension brought them ('clamp')"),
    # A free, slack far end whips: a tension-only chain with no bending stiffness sent its tail
    # inwards at 14 m/s behind a 2 m/s grip and buckled it through the wefts (docs/pullout.md).
    'back_tension': (0.05, 'N', 'dead load along -x on the pulled yarn\'s far end, from the start, in [0, 10]'),
    'safety': (0.7, '', 'O.dt = safety * dt_crit, in (0, 1]'),
    'samples': (400, '', 'rows of curve.csv, at least 20'),
    # The grip force is the support reaction of one step: impulses make it jump from step to step
    # (stick-slip), so its largest sample depends on when samples fall. The peak is taken from the
    # curve averaged over this much grip travel (a load cell's bandwidth); the raw one is reported too.
    'smooth': (1e-4, 'm', 'grip travel the force is averaged over before its peak is taken, in [0, pull / 4]'),
    'energy_limit': (0.02, '', 'allowed energy-balance error of the pull / the energy turnover, in (0, 1)'),
    'out': ('', '', 'output folder (default out/pullout)'),
})
p = read_params(defaults)


def bad(key, allowed):
    raise ValueError('%s = %r is invalid: allowed %s' % (key, p[key], allowed))


def finite_in(key, lo, hi, lo_open=False):
    v = p[key]
    if not (isinstance(v, (int, float)) and math.isfinite(v) and (v > lo if lo_open else v >= lo) and v <= hi):
        bad(key, '%s%g, %g] %s' % ('(' if lo_open else '[', lo, hi, p.units.get(key, '')))


finite_in('friction', 0, 2)
finite_in('pretension', 0, 50)
finite_in('velocity', 0, 20, lo_open=True)
finite_in('ramp', 0, 0.5)
finite_in('settle', 0, 0.01, lo_open=True)
finite_in('back_tension', 0, 10)
finite_in('safety', 0, 1, lo_open=True)
finite_in('energy_limit', 0, 1, lo_open=True)
if p.weft_ends not in ('load', 'clamp'):
    bad('weft_ends', "'load' or 'clamp'")
if p.samples < 20:
    bad('samples', '[20, inf)')
if p.nx < 1:
    bad('nx', '[1, inf): weft yarns crossing the pulled yarn = 2 nx')
if p.ny < 1:
    bad('ny', '[1, inf): warp yarns = 2 ny')
d = out_dir('pullout', p)

# --- the strip ---
weave_args = {k: p[k] for k in WEAVE_KEYS}
contact_args = {k: p[k] for k in CONTACT_KEYS}
w = woven.weave(**weave_args)
eng = w.engine
woven.contact.enable(eng, **contact_args)
settle_left = eng.settle_sections()
X0 = woven.positions(eng).copy()
length_x = float(w.summary['length_x'])
finite_in('pull', 0, 2 * length_x, lo_open=True)
finite_in('smooth', 0, p.pull / 4)

pulled = w.warp_yarns[len(w.warp_yarns) // 2]
pinfo = eng.yarn(pulled)
far = pinfo['first_node']                          # x_min end: carries the back tension
grip = pinfo['first_node'] + pinfo['n_nodes'] - 1  # x_max end: the grip (held until the pull)
for y in w.warp_yarns:
    i = eng.yarn(y)
    if y != pulled:
        eng.fix(i['first_node'])
    eng.fix(i['first_node'] + i['n_nodes'] - 1)
anchors, loaded = [], []
for y in w.weft_yarns:
    i = eng.yarn(y)
    anchors.append(i['first_node'])
    loaded.append(i['first_node'] + i['n_nodes'] - 1)
    eng.fix(anchors[-1])
crossings = len(w.weft_yarns)  # wefts the pulled yarn passes under or over
back = Vector3(-p.back_tension, 0, 0)  # on the far end (x_min), pulling away from the grip
if p.back_tension > 0:
    eng.set_point_force(far, back)

O.engines = []
woven.attach(eng, set_dt=True, safety=p.safety)
dt = O.dt
check_steps(p.settle + p.pull / p.velocity * (1 + 0.5 * p.ramp), dt, 'safety', p.safety, 'the settling and the pull')
n_settle = max(1, int(math.ceil(p.settle / dt)))
n_pull = max(1, int(math.ceil(p.pull / p.velocity / dt + 0.5 * p.ramp * p.pull / p.velocity / dt)))
n_ramp = int(p.ramp * n_pull)
every = max(1, n_pull // p.samples)

# Phases driven by one PyRunner before the woven step (it sets this iteration's loads). The
# pre-tension ramps in 50 increments: a change of point force costs a force refresh.
phase = {'name': 'settle', 'k': 0, 'x_grip0': None, 'E_pull0': None, 'x_far0': None, 'F_sum': 0.0, 'F_n': 0}
rows = []


def set_pretension(f):
    for i in loaded:
        eng.set_point_force(i, Vector3(0, f, 0))


def sample():
    # The force of a row is the mean of the grip reactions since the last row (every step): the
    # reaction jumps from step to step (impulses, stick-slip), and one step's value every `every`
    # steps missed the grip work by 5 % at friction 0 (measured); the mean keeps the curve's area
    # on the books'.
    X = woven.positions(eng)
    s = eng.collision_stats() if O.iter > 0 else {'contacts': 0, 'penetration': 0.0}
    F = phase['F_sum'] / phase['F_n'] if phase['F_n'] else eng.reaction([grip])[0]
    phase['F_sum'], phase['F_n'] = 0.0, 0
    rows.append((O.time, X[grip][0] - phase['x_grip0'], F, X[far][0] - X0[far][0],
                 s['contacts'], s['penetration']))
    census.append(crossing_census())


pe0 = pinfo['first_element']
pe1 = pe0 + pinfo['n_elements']
weft_elems = [(i['first_element'], i['first_element'] + i['n_elements'], i['first_node'])
              for i in (eng.yarn(y) for y in w.weft_yarns)]


def _angle(u, v):
    return math.acos(max(-1.0, min(1.0, float(np.dot(u, v) / (np.linalg.norm(u) * np.linalg.norm(v))))))


def crossing_census():
    """The wefts that press on the pulled yarn now: (sum of their normal forces from each weft's
    tension and its turning there, 2 T sin(psi / 2) [N]; the pulled yarn's own turning at them [rad];
    wefts counted; their mean tension [N]). A weft presses where one of its CPs touches the pulled
    yarn (the contact list, or the persistent crossings of the gap model); psi is the angle between
    its CPs one before and one after that CP, T the mean tension of the three."""
    X = woven.positions(eng)
    Tn = woven.arrays.tensions(eng)
    pairs = [(int(r[0]), int(r[1])) for r in woven.arrays.contacts(eng)]
    pairs += [(int(r[0]), int(r[2])) for r in woven.arrays.crossings(eng)]
    touched = {}  # weft CP -> a pulled-yarn CP it touches
    for a, b in pairs:
        if pe0 <= a < pe1 and not pe0 <= b < pe1:
            touched.setdefault(b, a)
        elif pe0 <= b < pe1 and not pe0 <= a < pe1:
            touched.setdefault(a, b)
    N_geo, turn, n, T_sum, seen = 0.0, 0.0, 0, 0.0, set()
    for other, mine in sorted(touched.items()):
        for e0, e1, n0 in weft_elems:
            if e0 < other < e1 - 1 and (e0, other - 1) not in seen and (e0, other + 1) not in seen:
                seen.add((e0, other))
                i = n0 + (other - e0)  # element k joins nodes n0 + (k - e0) and the next one
                psi = _angle(X[i] - X[i - 1], X[i + 2] - X[i + 1])
                T = float(np.mean(Tn[other - 1:other + 2]))
                N_geo += 2 * T * math.sin(0.5 * psi)
                T_sum += T
                n += 1
                j = pinfo['first_node'] + (mine - pe0)
                if pinfo['first_node'] < j and j + 2 < pinfo['first_node'] + pinfo['n_nodes']:
                    turn += _angle(X[j] - X[j - 1], X[j + 2] - X[j + 1])
    return N_geo, turn, n, T_sum / n if n else 0.0


census = []  # (grip displacement [m], census) at each curve row


def drive():
    k = phase['k']
    phase['k'] += 1
    if phase['name'] == 'settle':
        n_up = max(1, int(0.6 * n_settle))
        step = max(1, n_up // 50)
        if k % step == 0 and k <= n_up:
            set_pretension(p.pretension * min(1.0, (k + step) / n_up))
        if k + 1 >= n_settle:
            if p.weft_ends == 'clamp':
                # Locked where the pre-tension brought them, as a rig's side grips are tightened and
                # then locked; from here the wefts' tension follows the pulled yarn (docs/pullout.md).
                set_pretension(0.0)
                for i in loaded:
                    eng.fix(i)
            else:
                set_pretension(p.pretension)
            phase['name'] = 'start'
        return
    if phase['name'] == 'start':  # start of the pull: the books and positions it is measured from
        X = woven.positions(eng)
        phase['x_grip0'] = X[grip][0]
        phase['x_far0'] = X[far][0]
        phase['Y_loaded0'] = X[loaded, 1].copy()
        phase['E_pull0'] = eng.energy()
        phase['name'], phase['k'], k = 'pull', 1, 0
        sample()
    if phase['name'] == 'pull':
        if k > 0:  # the reaction of the step just made (the grip's support force)
            phase['F_sum'] += eng.reaction([grip])[0]
            phase['F_n'] += 1
        if k <= n_ramp:
            eng.prescribe_velocity(grip, Vector3(p.velocity * (min(1.0, k / n_ramp) if n_ramp else 1.0), 0, 0))
        if k > 0 and k % every == 0:
            sample()


import __main__
__main__.drive = drive
# The driver runs before the adapter so that this iteration's step sees this iteration's loads.
driver = PyRunner(command='drive()', iterPeriod=1)
driver.initRun = True  # also at O.iter 0 (a constructor keyword is ignored, py/woven/engine.py)
O.engines = [driver] + list(O.engines)

status = 'ok'
wall0 = time.time()
total = n_settle + 1 + n_pull
try:
    O.run(total, True)
except RuntimeError as ex:
    status = 'unstable' if isinstance(woven.engine.last_error, woven.InstabilityError) else 'failed'
    print('pullout: run stopped:', woven.engine.last_error or ex)
wall = time.time() - wall0
if phase['name'] == 'pull':
    sample()

C = np.array(rows) if rows else np.zeros((0, 6))
savetxt(os.path.join(d, 'curve.csv'), C, delimiter=',', comments='',
           header='time_s,grip_displacement_m,grip_force_N,far_end_displacement_m,contacts,penetration_m')

# --- results ---
measured = {'steps': O.iter, 'dt': dt, 'wall_seconds': wall, 'crossings': crossings, 'settle_overlap': settle_left,
            'strip_length': length_x, 'yarns': eng.n_yarns, 'cps': eng.n_elements}
checks = {}


def crossing_summary(ipk):
    """The wefts' normal forces on the pulled yarn at the row of the peak, and the closed forms."""
    if ipk >= len(census):
        return None
    N_geo, turn, n, T_mean = census[ipk]
    return {'wefts_pressing': n, 'weft_tension_mean': T_mean, 'normal_force_sum': N_geo,
            'pulled_yarn_turning': turn,
            # Coulomb at each crossing: the grip pulls the back tension plus mu times the normal forces.
            'coulomb_estimate': p.back_tension + p.friction * N_geo,
            # Capstan on the pulled yarn's own turning: its tension grows by exp(mu psi) at each crossing.
            'capstan_estimate': p.back_tension * math.exp(p.friction * turn)}


thickness = min(eng.yarn(w.warp_yarns[0])['thickness'], eng.yarn(w.weft_yarns[0])['thickness'])
if phase['E_pull0'] is not None and len(C) > 5:
    disp, F = C[:, 1], C[:, 2]
    n_avg = max(1, int(round(p.smooth / (disp[-1] / (len(disp) - 1))))) if disp[-1] > 0 else 1
    F_avg = np.convolve(F, np.ones(n_avg) / n_avg, mode='valid')  # centred window of n_avg samples
    ipk = int(np.argmax(F_avg)) + (n_avg - 1) // 2
    E0, E1 = phase['E_pull0'], eng.energy()
    X1 = woven.positions(eng)
    # The dead loads (back tension, and the pre-tension unless clamped) are constant during the pull:
    # their work is exact from the travel of the ends they act on. Clamps do no work.
    W_back = -p.back_tension * float(X1[far][0] - phase['x_far0'])
    W_pre = p.pretension * float(np.sum(X1[loaded, 1] - phase['Y_loaded0'])) if p.weft_ends == 'load' else 0.0
    W_dead = W_back + W_pre
    W_engine = E1['work'] - E0['work']
    W_grip = W_engine - W_dead
    d_books = {k: E1[k] - E0[k] for k in ('kinetic', 'elastic', 'damped', 'contact', 'friction', 'projection', 'spring', 'released')}
    residual = sum(d_books.values()) - W_engine  # = change of the engine's balance error over the pull
    turnover = abs(W_grip) + abs(W_back) + abs(W_pre) + sum(abs(v) for v in d_books.values())
    balance = residual / turnover if turnover > 0 else 0.0
    energy_curve = float(np.sum(F[1:] * np.diff(disp)))  # each row holds the mean force over its interval
    far_moved = float(X1[far][0] - X0[far][0])
    measured.update({
        'peak_force': float(F_avg.max()), 'peak_displacement': float(disp[ipk]), 'peak_force_raw': float(F.max()),
        'crossing_normal_forces': crossing_summary(ipk),
        'smoothing_samples': n_avg,
        'mean_force': energy_curve / float(disp[-1]) if disp[-1] > 0 else 0.0,
        'pullout_energy': energy_curve, 'grip_work_books': W_grip, 'back_tension_work': W_back,
        'pretension_work': W_pre,
        'grip_travel': float(disp[-1]), 'far_end_displacement_x': far_moved,
        'energy': {'grip_work': W_grip, 'back_tension_work': W_back, 'pretension_work': W_pre, 'kinetic_change': d_books['kinetic'],
                   'elastic_change': d_books['elastic'], 'damped': d_books['damped'],
                   'dissipated_contacts': d_books['contact'], 'friction': d_books['friction']},
        'energy_balance_error': balance, 'final_overlap': eng.overlap(),
        'max_transient_penetration': eng.collision_stats()['max_penetration'],
        'max_unresolved_impulse_rows': eng.collision_stats()['max_unresolved'],
    })
    checks['energy_balance'] = {
        'value': balance, 'limit': p.energy_limit, 'passed': bool(abs(balance) <= p.energy_limit),
        'what': 'over the pull: (change of kinetic + elastic + damped + dissipated by contacts - grip work - '
                'work of the dead loads) / the sum of their magnitudes'}
    # The curve (sampled every `every` steps) and the books (every step) must tell the same grip work.
    if abs(W_grip) > 1e-6:
        rel = (energy_curve - W_grip) / abs(W_grip)
        checks['curve_vs_books'] = {'value': rel, 'limit': 0.05, 'passed': bool(abs(rel) <= 0.05),
                                    'what': '(area under the sampled curve - grip work in the books) / grip work'}
    checks['pulled'] = {'value': float(disp[-1]), 'limit': 0.95 * p.pull, 'passed': bool(disp[-1] >= 0.95 * p.pull),
                        'what': 'grip travel reached (m)'}
else:
    status = status if status != 'ok' else 'failed'

if 'peak_force' in measured:
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.5))
    a1.plot(C[:, 1] * 1e3, C[:, 2], '-', color='0.6', lw=0.8, label='grip force')
    a1.plot(disp[(n_avg - 1) // 2:(n_avg - 1) // 2 + len(F_avg)] * 1e3, F_avg, 'k-', lw=1.2,
            label='averaged over %.2g mm' % (1e3 * p.smooth))
    a1.plot([measured['peak_displacement'] * 1e3], [measured['peak_force']], 'ro',
            label='peak %.3g N at %.2f mm' % (measured['peak_force'], 1e3 * measured['peak_displacement']))
    a1.set_xlabel('grip displacement [mm]')
    a1.set_ylabel('grip force [N]')
    a1.set_title('pull-out: pre-tension %.3g N, friction %.3g; energy %.3g mJ'
                 % (p.pretension, p.friction, 1e3 * measured['pullout_energy']))
    a1.legend(fontsize=8)
    a2.plot(C[:, 1] * 1e3, C[:, 3] * 1e3, 'b-', lw=1, label='far end x')
    a2.plot(C[:, 1] * 1e3, C[:, 5] / thickness * 100, 'm-', lw=1, label='largest overlap [% thickness]')
    a2.set_xlabel('grip displacement [mm]')
    a2.set_ylabel('far end displacement [mm] / overlap [%]')
    a2.legend(fontsize=8)
    fig.tight_layout()
    savefig(fig, os.path.join(d, 'pullout.png'), dpi=110)

if status == 'ok' and not all(c['passed'] for c in checks.values()):
    status = 'failed'
n_cross = crossings
reference = {
    # physics-reference.md: the peak force and the pull-out energy rise with transverse pre-tension and
    # yarn-yarn friction (KM2+ swatches, Roark et al., Fibers 2023; Kirkwood et al., Text. Res. J. 2004).
    'trend': 'peak force and pull-out energy rise with pre-tension and with friction',
    # Coulomb bound with the built weave angle: each weft wraps the pulled yarn by about 2 theta, so
    # its pre-tension presses with N ~ 2 T sin(theta) per crossing; the sliding force of all crossings
    # is about mu N n (no capstan, no crimp interchange): an order of magnitude, not a prediction.
    'coulomb_estimate_peak_force': p.friction * 2 * p.pretension * math.sin(w.summary['weft_weave_angle']) * n_cross,
    'weave_angle': w.summary['weft_weave_angle'],
}
units = {'peak_force': 'N', 'peak_force_raw': 'N', 'peak_displacement': 'm', 'mean_force': 'N', 'pullout_energy': 'J', 'grip_work_books': 'J',
         'back_tension_work': 'J', 'pretension_work': 'J', 'grip_travel': 'm', 'far_end_displacement_x': 'm',
         'energy': 'J', 'energy_balance_error': 'fraction of the energy turnover of the pull', 'final_overlap': 'm',
         'max_transient_penetration': 'm', 'coulomb_estimate_peak_force': 'N', 'weave_angle': 'rad', 'dt': 's',
         'wall_seconds': 's', 'settle_overlap': 'm', 'strip_length': 'm'}
units['crossing_normal_forces'] = 'N (sums and closed-form forces), rad (turning)'
write_summary(d, 'pullout', p, measured, reference, units, status, checks)
cn = measured.get('crossing_normal_forces')
if cn:
    print('pullout: at the peak %d wefts (mean tension %.3g N) press with %.4g N in all: back tension + mu N = %.4g N; '
          'capstan on the pulled yarn\'s turning %.3g rad: %.4g N' % (cn['wefts_pressing'], cn['weft_tension_mean'],
                                                                   cn['normal_force_sum'], cn['coulomb_estimate'],
                                                                   cn['pulled_yarn_turning'], cn['capstan_estimate']))
print('pullout: %s; pre-tension %.3g N, friction %.3g: peak %.4g N at %.3g mm, energy %.4g mJ, balance %.2g %%, '
      '%d steps in %.1f s -> %s' % (status, p.pretension, p.friction, measured.get('peak_force', float('nan')),
                                     1e3 * measured.get('peak_displacement', float('nan')),
                                     1e3 * measured.get('pullout_energy', float('nan')),
                                     100 * measured.get('energy_balance_error', float('nan')), O.iter, wall, d))
if status != 'ok':
    sys.exit(1)
