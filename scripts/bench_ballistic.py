# Benchmark of the default ballistic scene (scripts/ballistic.py's defaults: KM2 706 single ply 50.8 mm,
# clamped on 4 edges, cube 1.1 g at 200 m/s), all in one process on one core:
#   yade -n -x scripts/bench_ballistic.py [t_end=1e-4] [chain_steps=300] [threads=1] [repeats=1] [sweep_order=] [out=DIR]
#   yade -n -x scripts/bench_ballistic.py plies=8 V=400 shape=rcc t_end=2e-5     # the pack case (docs/ballistic.md)
# 1. baseline: the same ply's springs and integration alone (collisions and breakage off), chain_steps steps,
#    the fastest of five runs;
# 2. the coupled scene for t_end without stopping at perforation: wall time, CP-steps per second and
#    the time by phase (refit, broad, narrow, response and the position projection after the drift
#    from the collision stage's clocks; springs, integration, breakage and the YADE adapter as the rest).
# 3. threads = N >= 2 (run with yade -j N): the coupled scene once more on N threads in this process
#    (woven.set_threads), its speed-up over step 2 and whether both runs end in the same bits
#    (fabric positions and velocities, energy books, projectile); a difference fails the run. With
#    repeats = R the pair of runs is made R times, alternating, and the fastest of each count kept;
#    beside each pair an ideal loop (no serial part: woven.ideal_loop_seconds) on 1 and N threads
#    shows what the machine's cores give (on this shared machine well under N). Both
#    coupled runs then sweep the rows in `sweep_order` (default 'blocked': slabs of the ply at once on
#    the threads; 'coloured': colour by colour), not the scene's serial 'sequential'.
# Prints the figures (with the whole step's nanoseconds per contact row), the ratio to the baseline and to the speed goals (100 us in 3 s; a coupled
# CP-step rate of at least 1/30 of the springs-alone rate), and writes
# out/bench_ballistic/summary.json.
import json
import math
import os
import time

import woven
import woven.ballistic
import woven.pack
import woven.projectiles
from woven.params import read_params
from woven.output import out_dir, write_summary
from woven.contact import CONTACT_KEYS

p = read_params({'t_end': (1e-4, 's', 'simulated time of the coupled run'),
                 'chain_steps': (300, '', 'steps of the springs-only baseline'),
                 'side': (0.0508, 'm', 'ply side'), 'cp_per_span': (1, '', 'CPs between crossings (the scene\'s default: 1)'),
                 'goal_seconds': (3.0, 's', 'goal: wall time for 100 us of simulated time'),
                 'broad_phase': ('grid', '', "'grid' (the scene's default), 'tree' or 'sap'"),
                 'plies': (1, '', 'plies in the pack, [1, 40] (woven.pack; every ply clamped on 4 edges)'),
                 'ply_angles': ('0', 'deg', 'in-plane angle of each ply, comma-separated (one for all)'),
                 'V': (200.0, 'm/s', 'impact speed, (0, 5000]'),
                 'shape': ('box', '', "the scene's projectile: 'box' (1.1 g cube), 'sphere', 'rcc' or 'fsp' (woven.projectiles)"),
                 'threads': (1, '', 'threads of a second coupled run compared with one thread, in [1, 64] (1: one run only)'),
                 'repeats': (1, '', 'pairs of coupled runs (1 thread, then `threads`) in [1, 10]; the best of each is kept '
                             '(timings on a shared machine drift: the best-of ratio is the fairer one)'),
                 'sweep_order': ('', '', "row order of both coupled runs: 'sequential', 'coloured' or 'blocked' (default: the "
                                 "scene's 'sequential' with threads = 1, 'blocked' with threads >= 2)"),
                 'out': ('', '', 'output folder (default out/bench_ballistic)')})
if not (isinstance(p.threads, int) and 1 <= p.threads <= 64):
    raise ValueError('threads = %r is invalid: allowed an integer in [1, 64]' % (p.threads,))
if not (isinstance(p.repeats, int) and 1 <= p.repeats <= 10):
    raise ValueError('repeats = %r is invalid: allowed an integer in [1, 10]' % (p.repeats,))
if not (math.isfinite(p.t_end) and 0 < p.t_end <= 0.01):
    raise ValueError('t_end = %r is invalid: allowed (0, 0.01] s' % (p.t_end,))
if not (math.isfinite(p.side) and 1e-3 <= p.side <= 1):
    raise ValueError('side = %r is invalid: allowed [1e-3, 1] m (the scene\'s range)' % (p.side,))
if not (isinstance(p.chain_steps, int) and 1 <= p.chain_steps <= 10 ** 6):
    raise ValueError('chain_steps = %r is invalid: allowed an integer in [1, 1e6]' % (p.chain_steps,))
if not (math.isfinite(p.goal_seconds) and p.goal_seconds > 0):
    raise ValueError('goal_seconds = %r is invalid: allowed (0, inf) s' % (p.goal_seconds,))
if not 1 <= p.plies <= woven.pack.MAX_PLIES:
    raise ValueError('plies = %r is invalid: allowed [1, %d]' % (p.plies, woven.pack.MAX_PLIES))
if not (0 < p.V <= 5000):
    raise ValueError('V = %r is invalid: allowed (0, 5000] m/s' % p.V)
if p.sweep_order not in ('', 'sequential', 'coloured', 'blocked'):
    raise ValueError("sweep_order = %r is invalid: allowed 'sequential', 'coloured' or 'blocked'" % (p.sweep_order,))
if p.shape not in woven.ballistic.SHAPES:
    raise ValueError('shape = %r is invalid: allowed %s' % (p.shape, ', '.join(woven.ballistic.SHAPES)))
ply_angles = woven.pack.parse_angles(p.ply_angles, p.plies)
d = out_dir('bench_ballistic', p)
GOAL_RATE = 1 / 30  # speed goal: the coupled CP-step rate against the springs alone, same process
if p.threads > 1 and woven.openmp_threads() < p.threads:
    print('bench_ballistic: WARNING: OpenMP has %d thread(s) here (yade -j %d missing?): idle threads sleep between '
          'regions and the speed-up is understated' % (woven.openmp_threads(), p.threads))
weave_args = {'preset': 'km2_706', 'nx': 0, 'ny': 0, 'cp_per_span': p.cp_per_span}
# The scene's contact settings (scripts/ballistic.py)
contact_args = {k: v[0] for k, v in CONTACT_KEYS.items()}
contact_args.update(position_correction=0.0, flatten_passes=1, max_iterations=woven.pack.PLY_SWEEPS, skin=4e-5, broad_phase=p.broad_phase)
if p.sweep_order:
    contact_args['sweep_order'] = p.sweep_order
elif p.threads > 1:  # both coupled runs in an order whose sweeps use the threads (docs/design.md, Threads)
    contact_args['sweep_order'] = 'blocked'
if p.plies > 1:  # the scene's sweeps for a pack (scripts/ballistic.py)
    contact_args['max_iterations'] = woven.pack.sweeps_for(p.plies)

# 1. baseline: springs and integration of the same ply, collisions off
O.engines = []
O.bodies.clear()
base = woven.ballistic.build_ply(weave_args, contact_args, side=p.side, clamp=4, breakage=None)
be = base.engine
be.disable_collisions()
dt = 0.7 * be.dt_crit
woven.set_threads(1)  # one core, as the coupled run it is compared with
# The fastest of five runs: one run of 300 steps takes some 50 ms, whose time moved by 60 % from one
# process to the next (4.2e7 to 6.9e7 CP-steps/s), and the goal's ratio with it.
chain_runs = []
for _ in range(5):
    t0 = time.perf_counter()
    be.run(dt, p.chain_steps)
    chain_runs.append(time.perf_counter() - t0)
chain_seconds = min(chain_runs)
woven.set_threads(0)
chain_rate = be.n_elements * p.chain_steps / chain_seconds

# 2. the coupled scene (3.: again on p.threads threads)
def coupled(threads):
    """Builds and runs the coupled scene on `threads` threads; returns (ply, projectile, wall seconds,
    phase seconds, final state, the process's CPU seconds over the run: on a loaded machine the
    fairer figure on one thread)."""
    woven.set_threads(threads)
    O.engines = []
    O.bodies.clear()
    O.resetTime()
    ply = woven.ballistic.build_ply(weave_args, contact_args, side=p.side, clamp=4,
                                    breakage=dict(strain=0.0, filter_length=-4.0, weibull_m=0.0, seed=1),
                                    plies=p.plies, ply_angles=ply_angles)
    if p.shape in ('rcc', 'fsp'):
        solid = woven.projectiles.solid(p.shape)
        proj = woven.ballistic.add_projectile(ply, p.shape, solid['mass'], 2 * solid['radius'], p.V, solid=solid)
    else:
        proj = woven.ballistic.add_projectile(ply, p.shape, V=p.V)
    O.engines = [ForceResetter(), NewtonIntegrator(damping=0, gravity=(0, 0, 0))]
    woven.attach(ply.engine)
    t0, c0 = time.perf_counter(), time.process_time()
    O.run(int(round(p.t_end / O.dt)), True)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    s = ply.engine.collision_stats()
    phases = {'refit': s['seconds_refit'], 'broad': s['seconds_broad'], 'narrow': s['seconds_narrow'],
              'response': s['seconds_respond'], 'projection': s['seconds_project']}
    phases['springs_integration_breakage_adapter'] = wall - sum(phases.values())
    state = (ply.engine._positions(), ply.engine._velocities(), sorted(ply.engine.energy().items()),
             tuple(proj.state.vel), tuple(proj.state.pos))
    woven.set_threads(0)
    return ply, proj, wall, phases, state, cpu


# One thread, then (threads >= 2) N threads, `repeats` times; the fastest run of each count is kept.
# Beside each pair, the machine's own ceiling: an ideal loop (no serial part) on 1 and N threads
# (core/ThreadCeiling.hpp); on this shared machine it gives well under N.
runs1, runsN, ideal1, idealN = [], [], [], []
for _ in range(p.repeats):
    if p.threads > 1:
        ideal1.append(woven.ideal_loop_seconds(1)), idealN.append(woven.ideal_loop_seconds(p.threads))
    runs1.append(coupled(1))
    if p.threads > 1:
        runsN.append(coupled(p.threads))
ply, proj, wall, phases, state, cpu = min(runs1, key=lambda r: r[2])
solve = ply.engine.collision_stats()
steps = int(round(p.t_end / O.dt))
rate = ply.engine.n_elements * steps / wall
per_100us = wall * 1e-4 / (steps * O.dt)
measured = {'cps': ply.engine.n_elements, 'steps': steps, 'dt': O.dt, 'simulated_time': steps * O.dt,
            'wall_seconds': wall, 'cpu_seconds': cpu, 'cp_steps_per_second': rate, 'phase_seconds': phases,
            'phase_fraction': {k: v / wall for k, v in phases.items()},
            'wall_seconds_per_100us': per_100us, 'goal_ratio': per_100us / p.goal_seconds,
            'chain_only_cp_steps_per_second': chain_rate, 'coupled_over_chain': rate / chain_rate,
            'chain_only_seconds_each': chain_runs,
            'projectile_velocity_end': -proj.state.vel[2], 'broken_elements': ply.engine.broken_elements,
            # the impulse solve over the run (unresolved rows after the sweeps, goal < 1 %)
            'rows_per_step': solve['total_rows'] / max(solve['steps'], 1),
            # the whole step's wall time (every stage: refit, broad, narrow, rows, projection, springs,
            # the adapter) over the contacts' rows it solved: the contact cost in Box2D's measure
            'ns_per_contact_step': 1e9 * wall / max(solve['total_rows'], 1),
            'ns_per_contact_step_cpu': 1e9 * cpu / max(solve['total_rows'], 1),
            'sweeps_per_step': solve['total_sweeps'] / max(solve['steps'], 1),
            'unresolved_fraction': solve['total_unresolved'] / max(solve['total_rows'], 1),
            'largest_miss': solve['max_residual'], 'crossings': solve['crossings'],
            'sweep_order': contact_args['sweep_order']}
checks, status = {}, 'ok'
if p.threads > 1:
    _, _, wall_n, phases_n, _, _ = min(runsN, key=lambda r: r[2])
    same = all(r[4] == state for r in runs1 + runsN)
    measured.update({'threads': p.threads, 'wall_seconds_n_threads': wall_n, 'phase_seconds_n_threads': phases_n,
                     'speedup': wall / wall_n, 'same_bits': bool(same),
                     'wall_seconds_each': [r[2] for r in runs1], 'wall_seconds_n_threads_each': [r[2] for r in runsN],
                     'speedup_each': [a[2] / b[2] for a, b in zip(runs1, runsN)],
                     'ideal_loop_speedup': min(ideal1) / min(idealN),
                     'ideal_loop_speedup_each': [a / b for a, b in zip(ideal1, idealN)]})
    checks['same_bits'] = {'value': bool(same), 'limit': True, 'passed': bool(same),
                           'what': 'positions, velocities, energy books and projectile equal bit for bit on 1 and N threads, '
                                   'in every repeat'}
    status = 'ok' if same else 'failed'
write_summary(d, 'bench_ballistic', p, measured, {'goal_wall_seconds_per_100us': p.goal_seconds, 'goal_coupled_over_chain': GOAL_RATE,
               'goal_speedup_2_cores': 1.8},
              {'wall_seconds': 's', 'cpu_seconds': 's', 'dt': 's', 'simulated_time': 's', 'cp_steps_per_second': '1/s',
               'phase_seconds': 's', 'wall_seconds_per_100us': 's', 'largest_miss': 'm/s', 'chain_only_cp_steps_per_second': '1/s',
               'chain_only_seconds_each': 's',
               'wall_seconds_n_threads': 's', 'phase_seconds_n_threads': 's'}, status, checks)
print('bench_ballistic: %d CPs, %d steps of %.3g s (%.1f us) in %.1f s (%.1f s CPU): %.3g CP-steps/s' %
      (ply.engine.n_elements, steps, O.dt, steps * O.dt * 1e6, wall, cpu, rate))
print('  by phase: ' + ', '.join('%s %.1f s (%.0f %%)' % (k, v, 100 * v / wall) for k, v in phases.items()))
print('  %.0f ns per contact (impulse row) per step, all stages included (%.0f ns of CPU, fairer on a loaded machine; '
      'goal 300)' % (measured['ns_per_contact_step'], measured['ns_per_contact_step_cpu']))
print('  impulse solve: %.0f rows and %.2f sweeps a step, %.2g %% of the rows unresolved after the sweeps (goal < 1 %%), '
      'largest miss %.3g m/s; %d crossings live' % (measured['rows_per_step'], measured['sweeps_per_step'],
                                                   100 * measured['unresolved_fraction'], solve['max_residual'],
                                                   solve['crossings']))
print('  springs + integration alone: %.3g CP-steps/s; coupled / alone = %.3g (goal %.3g)' %
      (chain_rate, rate / chain_rate, GOAL_RATE))
print('  100 us of this scene: %.1f s; goal %.0f s -> %.2fx the goal' % (per_100us, p.goal_seconds, per_100us / p.goal_seconds))
if p.threads > 1:
    print('  %d threads: %.1f s (%s): %.2fx one thread (best of %d each; per repeat %s); same bits: %s' %
          (p.threads, wall_n, ', '.join('%s %.1f s' % kv for kv in phases_n.items()), wall / wall_n, p.repeats,
           ', '.join('%.2fx' % x for x in measured['speedup_each']), same))
    print('  the machine: an ideal loop on %d threads %.2fx one thread (per repeat %s)' %
          (p.threads, measured['ideal_loop_speedup'], ', '.join('%.2fx' % x for x in measured['ideal_loop_speedup_each'])))
if status != 'ok':
    import sys
    sys.exit(1)
