# Soak: a long run of a pre-tensioned weave inside YADE's loop, at rest or under a cyclic load, with
# collisions on. It checks what only a long run shows: the energy stays bounded and its books keep
# balancing (no slow gain from slack/taut switching, contacts or the projection), and the resident
# memory of the process stays flat (nothing grows per step or per sample).
#   yade -n -x scripts/soak.py [steps=1000000] [mode=rest|cyclic] [nx=5] [ny=5] [cp_per_span=2] [out=DIR] ...
# Set-up: the weave (default KM2 706, 5 x 5 repeats = 10 x 10 yarns) with its sections settled; the
# first node of every yarn held, the last pulled outwards (warp along +x, weft along +y) at
# `pull_velocity` until the grips have taken out the built crimp plus `pretension`; then the grips
# stop. The soak proper, `steps` YADE iterations, follows: mode=rest holds the grips; mode=cyclic
# moves the warp grips by amplitude x L x sin(2 pi t / period) about the pre-tensioned position
# (velocity updated every `velocity_every` iterations), the weft grips held.
# Output (out/soak/ or out=DIR): soak.csv (one row per sample: step, time, energy books, RSS),
# soak.png (energy and memory against the step), summary.json (energy drift, bounds, RSS start /
# end / max, wall time; checks). Memory is read from /proc/self/status (VmRSS, VmHWM).
import math
import os
import sys
import time

import numpy as np
import woven
from woven.contact import CONTACT_KEYS
from woven.output import out_dir, savefig, savetxt, write_summary
from woven.params import check_steps, read_params
from woven.weave import WEAVE_KEYS

defaults = dict(WEAVE_KEYS)
defaults.update({
    'nx': (5, '', WEAVE_KEYS['nx'][2]), 'ny': (5, '', WEAVE_KEYS['ny'][2]),
    # Two CPs per span: the soak is about what a long run does, not about resolution; the default
    # 1e6 steps then take minutes rather than most of an hour.
    'cp_per_span': (2, '', WEAVE_KEYS['cp_per_span'][2]),
    'damping': (0.05, '', WEAVE_KEYS['damping'][2]),
})
defaults.update(CONTACT_KEYS)
defaults.update({
    'steps': (1000000, '', 'YADE iterations of the soak after the pre-tension, in [100, 1e8]'),
    'mode': ('rest', '', "'rest' (grips held) or 'cyclic' (warp grips moved sinusoidally)"),
    'pretension': (0.002, '', 'grip strain past the built crimp at the end of the pull, in (0, 0.02]'),
    'pull_velocity': (1.0, 'm/s', 'grip speed of the pull, in (0, 10]'),
    'amplitude': (0.001, '', "mode=cyclic: strain amplitude of the warp grips, in (0, pretension]"),
    'period': (100000, '', 'mode=cyclic: iterations per load cycle, in [100, steps]'),
    'velocity_every': (50, '', 'mode=cyclic: iterations between updates of the grip velocity, in [1, period/10]'),
    'safety': (0.7, '', 'O.dt = safety * dt_crit, in (0, 1]'),
    'samples': (1000, '', 'rows of soak.csv (energy and memory samples), in [10, 1e5]'),
    'energy_tol': (0.01, '', 'allowed drift of the balance error over the soak, as a fraction of the pre-tension energy'),
    'bound_tol': (0.05, '', 'allowed rise of kinetic + elastic above its bound (see summary), as a fraction of the pre-tension energy'),
    'rss_tol': (4.0, 'MiB', 'allowed growth of the resident memory from the first tenth of the soak to its end'),
    'out': ('', '', 'output folder (default out/soak)'),
})
p = read_params(defaults)
if p.mode not in ('rest', 'cyclic'):
    raise ValueError("mode = %r is invalid: allowed 'rest' or 'cyclic'" % p.mode)
for k, lo, hi in (('steps', 100, 1e8), ('samples', 10, 1e5)):
    if not (lo <= p[k] <= hi):
        raise ValueError('%s = %r is invalid: allowed [%g, %g]' % (k, p[k], lo, hi))
for k, lo, hi in (('pretension', 0, 0.02), ('pull_velocity', 0, 10), ('safety', 0, 1), ('energy_tol', 0, 1),
                  ('bound_tol', 0, 1), ('rss_tol', 0, 1e6)):
    if not (lo < p[k] <= hi):
        raise ValueError('%s = %r is invalid: allowed (%g, %g] %s' % (k, p[k], lo, hi, p.units[k]))
if p.mode == 'cyclic':
    if not (0 < p.amplitude <= p.pretension):
        raise ValueError('amplitude = %r is invalid: allowed (0, pretension = %g] (the yarns stay taut)' % (p.amplitude, p.pretension))
    if not (100 <= p.period <= p.steps):
        raise ValueError('period = %r is invalid: allowed [100, steps = %d]' % (p.period, p.steps))
    if not (1 <= p.velocity_every <= p.period // 10):
        raise ValueError('velocity_every = %r is invalid: allowed [1, period/10 = %d]' % (p.velocity_every, p.period // 10))
d = out_dir('soak', p)


def memory():
    """(VmRSS, VmHWM) of this process [MiB], from /proc/self/status."""
    got = {}
    with open('/proc/self/status') as f:
        for line in f:
            k, _, v = line.partition(':')
            if k in ('VmRSS', 'VmHWM'):
                got[k] = int(v.split()[0]) / 1024.0  # kB -> MiB
    return got['VmRSS'], got['VmHWM']


w = woven.weave(**{k: p[k] for k in WEAVE_KEYS})
eng = w.engine
woven.contact.enable(eng, **{k: p[k] for k in CONTACT_KEYS})
eng.settle_sections()
ends = {}
for fam, axis in ((w.warp_yarns, 0), (w.weft_yarns, 1)):
    for y in fam:
        info = eng.yarn(y)
        eng.fix(info['first_node'])
        ends.setdefault(axis, []).append(info['first_node'] + info['n_nodes'] - 1)
X0 = woven.positions(eng).copy()
first = {0: [eng.yarn(y)['first_node'] for y in w.warp_yarns], 1: [eng.yarn(y)['first_node'] for y in w.weft_yarns]}
L = {a: float(np.mean(X0[ends[a], a]) - np.mean(X0[first[a], a])) for a in (0, 1)}  # grip distances [m]
crimp = {0: w.summary['warp_crimp_built'], 1: w.summary['weft_crimp_built']}


def grips(v_warp, v_weft):
    for i in ends[0]:
        eng.prescribe_velocity(i, Vector3(v_warp, 0, 0))
    for i in ends[1]:
        eng.prescribe_velocity(i, Vector3(0, v_weft, 0))


O.engines = []
woven.attach(eng, set_dt=True, safety=p.safety)
for a in (0, 1):
    check_steps((crimp[a] + p.pretension) * L[a] / p.pull_velocity, O.dt, 'safety', p.safety, 'the pull to the pretension')
# The pull: both families to their built crimp + pretension at the same speed; the family with the
# shorter way stops first (its grips held from then on).
# The grips start over a tenth of the shorter pull (velocity_ramp), which costs them half the ramp's
# span of way: added to the pull.
base = {a: (crimp[a] + p.pretension) * L[a] / p.pull_velocity / O.dt for a in (0, 1)}
ramp = 0.1 * min(base.values())
pull_steps = {a: int(math.ceil(base[a] + 0.5 * ramp)) for a in (0, 1)}
eng.velocity_ramp = ramp * O.dt
grips(p.pull_velocity, p.pull_velocity)
status = 'ok'
t_wall0 = time.time()
try:
    done = 0
    for a in sorted((0, 1), key=lambda a: pull_steps[a]):
        if pull_steps[a] > done:  # O.run(0) would run without end
            O.run(pull_steps[a] - done, True)
        done = pull_steps[a]
        if a == 0:
            grips(0.0, p.pull_velocity if pull_steps[1] > done else 0.0)
        else:
            grips(p.pull_velocity if pull_steps[0] > done else 0.0, 0.0)
    grips(0.0, 0.0)
except RuntimeError as ex:
    status = 'unstable' if isinstance(woven.engine.last_error, woven.InstabilityError) else 'failed'
    print('soak: pre-tension stopped:', woven.engine.last_error or ex)
pull_wall = time.time() - t_wall0
X_pre = woven.positions(eng).copy()
strain_pre = {a: float(np.mean(X_pre[ends[a], a]) - np.mean(X_pre[first[a], a])) / L[a] - 1 for a in (0, 1)}

iter0 = eng.iter  # the soak's step 0 (the fabric's own counter: a PyRunner after the woven step
# sees O.iter before YADE counts the iteration, the fabric's counter after its step)
omega = 2 * math.pi / (p.period * O.dt) if p.mode == 'cyclic' else 0.0
every = max(1, p.steps // p.samples)
# The samples go into an array filled (so its pages are resident) before the soak: a growing list
# of tuples costs about 0.5 KiB per sample, which the memory check would see as a leak (1000 samples:
# 0.5 MiB, measured with samples=100 against 10000).
table = np.full((p.steps // every + 3, 13), np.nan)
filled = [0]  # rows of `table` filled (a counter: a list of row views would grow too)


def sample():
    e = eng.energy()
    rss, hwm = memory()
    s = eng.collision_stats()
    k = eng.iter - iter0
    if filled[0] and table[filled[0] - 1, 0] == k:
        return
    table[filled[0]] = (k, eng.time, e['kinetic'], e['elastic'], e['damped'], e['work'], e['contact'],
                 e['projection'], e['balance_error'], rss, hwm, s['contacts'], s['penetration'])
    filled[0] += 1


def cyclic():
    # Warp grips at u(t) = amplitude L sin(omega (t - t0)) about the pre-tensioned position: the
    # velocity is held constant over the next `velocity_every` iterations at its value at their middle, so
    # the grip follows the sine to O((omega update dt)^2) and comes back to it every cycle.
    t_mid = (eng.iter - iter0 + 0.5 * p.velocity_every) * O.dt
    v = p.amplitude * L[0] * omega * math.cos(omega * t_mid)
    grips(v, 0.0)


import __main__  # noqa: E402  (PyRunner commands run in __main__)
__main__._soak_sample = sample
__main__._soak_cyclic = cyclic
runners = []
if p.mode == 'cyclic':
    # Before the woven step (inserted first): the velocity of this iteration's step.
    runners.append(PyRunner(command='_soak_cyclic()', iterPeriod=p.velocity_every))
    O.engines = runners + list(O.engines)
runners.append(PyRunner(command='_soak_sample()', iterPeriod=every))
O.engines = list(O.engines) + runners[-1:]
for r in runners:
    # A PyRunner fires when O.iter - iterLast >= iterPeriod: make both fire at the soak's first
    # iteration and every period after it.
    r.iterLast = O.iter - r.iterPeriod
sample()  # the soak's start
t_wall1 = time.time()
if status == 'ok':
    try:
        O.run(p.steps, True)
        sample()
    except RuntimeError as ex:
        status = 'unstable' if isinstance(woven.engine.last_error, woven.InstabilityError) else 'failed'
        print('soak: run stopped at iteration %d:' % O.iter, woven.engine.last_error or ex)
soak_wall = time.time() - t_wall1

C = table[:filled[0]]
cols = 'step,time_s,kinetic_J,elastic_J,damped_J,work_J,contact_J,projection_J,balance_error_J,rss_MiB,hwm_MiB,contacts,penetration_m'
savetxt(os.path.join(d, 'soak.csv'), C, delimiter=',', comments='', header=cols)

step, K, U, D, Wk, Bal, rss = C[:, 0], C[:, 2], C[:, 3], C[:, 4], C[:, 5], C[:, 8], C[:, 9]
mech = K + U
E_ref = max(U[0], 1e-30)  # the pre-tension energy: the scale of every energy figure
# Balance error over the soak (its value at the soak's start includes the pull and the stop).
drift = (Bal[-1] - Bal[0]) / E_ref
drift_max = float(np.max(np.abs(Bal - Bal[0]))) / E_ref
# Bound: kinetic + elastic can never exceed what it had at the start plus the work put in since
# (the dashpots only take out); the margin is the scheme's O(dt^2) swing.
work_in = np.maximum.accumulate(np.maximum(Wk - Wk[0], 0.0))
rise = float(np.max(mech - (mech[0] + work_in))) / E_ref
tenth = int(np.searchsorted(step, 0.1 * step[-1]))
rss_growth = float(rss[-1] - rss[tenth])
measured = {
    'steps': int(step[-1]), 'dt': O.dt, 'simulated_time': float(C[-1, 1] - C[0, 1]), 'nodes': eng.n_nodes,
    'elements': eng.n_elements, 'pull_steps': int(max(pull_steps.values())),
    'strain_pretensioned_warp': strain_pre[0], 'strain_pretensioned_weft': strain_pre[1],
    'pretension_energy': float(U[0]), 'kinetic_start': float(K[0]), 'mechanical_start': float(mech[0]),
    'mechanical_end': float(mech[-1]), 'mechanical_max': float(mech.max()), 'work_soak': float(Wk[-1] - Wk[0]),
    'damped_soak': float(D[-1] - D[0]), 'balance_error_start': float(Bal[0]), 'balance_error_end': float(Bal[-1]),
    'balance_drift': float(drift), 'balance_drift_max': drift_max, 'bound_rise': rise,
    'rss_start': float(rss[0]), 'rss_tenth': float(rss[tenth]), 'rss_end': float(rss[-1]), 'rss_max': float(rss.max()),
    'rss_growth': rss_growth, 'hwm_end': float(C[-1, 10]), 'contacts_end': int(C[-1, 11]),
    'penetration_max_sampled': float(C[:, 12].max()), 'wall_pretension': pull_wall, 'wall_soak': soak_wall,
    'iterations_per_second': float(step[-1] / soak_wall) if soak_wall > 0 else float('nan'),
}
if p.mode == 'cyclic':
    # Energy cycle over cycle: the largest kinetic + elastic of the first and of the last full cycle.
    c0 = (step >= 0) & (step < p.period)
    n_cycles = int(step[-1] // p.period)
    c1 = (step >= (n_cycles - 1) * p.period) & (step < n_cycles * p.period)
    measured.update({'cycles': n_cycles, 'mechanical_max_first_cycle': float(mech[c0].max()),
                     'mechanical_max_last_cycle': float(mech[c1].max()),
                     'cycle_growth': float((mech[c1].max() - mech[c0].max()) / E_ref)})
checks = {
    'balance_drift': {'value': drift_max, 'limit': p.energy_tol, 'passed': bool(drift_max <= p.energy_tol),
                      'what': 'largest |balance error - its start value| over the soak / pre-tension energy'},
    'energy_bounded': {'value': rise, 'limit': p.bound_tol, 'passed': bool(rise <= p.bound_tol),
                       'what': 'largest (kinetic + elastic) - (its start value + work put in since), / pre-tension energy'},
    'memory_flat': {'value': rss_growth, 'limit': p.rss_tol, 'passed': bool(rss_growth <= p.rss_tol),
                    'what': 'resident memory growth from the first tenth of the soak to its end [MiB]'},
    'pretensioned': {'value': float(U[0]), 'limit': 0.0, 'passed': bool(U[0] > 0),
                     'what': 'the yarns carry elastic energy after the pull [J]'},
}
if p.mode == 'cyclic' and measured['cycles'] >= 2:
    checks['cycle_growth'] = {'value': measured['cycle_growth'], 'limit': p.bound_tol,
                              'passed': bool(measured['cycle_growth'] <= p.bound_tol),
                              'what': 'largest kinetic + elastic of the last cycle minus the first cycle\'s, / pre-tension energy'}
if status == 'ok' and not all(c['passed'] for c in checks.values()):
    status = 'failed'

import matplotlib  # noqa: E402
matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
fig, (a1, a2, a3) = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
a1.plot(step, U / E_ref, 'b-', lw=0.8, label='elastic')
a1.plot(step, K / E_ref, 'r-', lw=0.8, label='kinetic')
a1.plot(step, (D - D[0]) / E_ref, 'g-', lw=0.8, label='damped since start')
a1.plot(step, (Wk - Wk[0]) / E_ref, 'k--', lw=0.8, label='work since start')
a1.set_ylabel('energy / pre-tension energy')
a1.set_title('soak, %s: %d x %d yarns, %d nodes, %d steps (pre-tension energy %.3g J)'
             % (p.mode, len(w.warp_yarns), len(w.weft_yarns), eng.n_nodes, step[-1], E_ref))
a1.legend(fontsize=8, loc='best')
a2.plot(step, (Bal - Bal[0]) / E_ref, 'm-', lw=0.8)
a2.set_ylabel('balance error drift / pre-tension energy')
a2.axhline(p.energy_tol, color='0.6', ls=':')
a2.axhline(-p.energy_tol, color='0.6', ls=':')
a3.plot(step, rss, 'k-', lw=0.8, label='VmRSS')
a3.plot(step, C[:, 10], 'c--', lw=0.8, label='VmHWM')
a3.set_ylabel('resident memory [MiB]')
a3.set_xlabel('soak step')
a3.legend(fontsize=8)
fig.tight_layout()
savefig(fig, os.path.join(d, 'soak.png'), dpi=100)

reference = {'balance_drift_limit': p.energy_tol, 'bound_rise_limit': p.bound_tol, 'rss_growth_limit': p.rss_tol}
units = {'dt': 's', 'simulated_time': 's', 'pretension_energy': 'J', 'kinetic_start': 'J', 'mechanical_start': 'J',
         'mechanical_end': 'J', 'mechanical_max': 'J', 'work_soak': 'J', 'damped_soak': 'J', 'balance_error_start': 'J',
         'balance_error_end': 'J', 'balance_drift': '-', 'balance_drift_max': '-', 'bound_rise': '-',
         'rss_start': 'MiB', 'rss_tenth': 'MiB', 'rss_end': 'MiB', 'rss_max': 'MiB', 'rss_growth': 'MiB', 'hwm_end': 'MiB',
         'penetration_max_sampled': 'm', 'wall_pretension': 's', 'wall_soak': 's', 'iterations_per_second': '1/s',
         'mechanical_max_first_cycle': 'J', 'mechanical_max_last_cycle': 'J', 'cycle_growth': '-',
         'rss_growth_limit': 'MiB', 'balance_drift_limit': '-', 'bound_rise_limit': '-'}
write_summary(d, 'soak', p, measured, reference, units, status, checks)
print('soak %s: %s; %d steps in %.0f s, balance drift %.2e (max %.2e), bound rise %.2e, RSS %.1f -> %.1f MiB (max %.1f) -> %s'
      % (p.mode, status, step[-1], soak_wall, drift, drift_max, rise, rss[0], rss[-1], rss.max(), d))
if status != 'ok':
    sys.exit(1)
