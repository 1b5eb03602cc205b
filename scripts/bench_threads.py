# Speed-up of woven's OpenMP threads on the tension scene (scripts/tension.py's scene: KM2 706, sections
# settled, warp ends held and pulled along +x at 1 m/s, collisions on), all in one process:
#   yade -j 2 -n -x scripts/bench_threads.py [nx=50] [ny=50] [steps=200] [threads=2] [repeats=2] [sweep_order=sequential] [out=DIR]
# Run it with yade -j N (N = threads): without -j YADE sets OMP_NUM_THREADS=1, and libgomp then lets its
# idle threads sleep between parallel regions instead of spinning, which costs the forced threads
# their gain (measured: 0.97x instead of 1.5x; OMP_WAIT_POLICY=active restores it).
# nx = ny = 50 repeats of the plain 2 x 2 pattern is 100 x 100 yarns (80 000 CPs). For each repeat the
# scene is built and run for `steps` steps on 1 thread, then on `threads` threads (woven.set_threads,
# which reaches the stepping thread whatever yade -j says); the wall time of the steps alone is
# measured. Both runs sweep the rows in `sweep_order` (default tension.py's 'sequential': here the
# sweeps are a few percent of a step, and 'blocked' gained nothing on two threads). Prints the times, the speed-up (best and each repeat) against the goal (1.8x on 2 cores),
# and checks that the runs end in the same bits (positions, velocities, sections, energy books).
# Beside each pair an ideal loop (no serial part: woven.ideal_loop_seconds) on 1 and N threads shows
# what the machine's cores give.
# Writes out/bench_threads/summary.json. Other processes on the machine make the speed-up smaller.
import time

import woven
from woven.params import read_params
from woven.output import out_dir, write_summary
from woven.contact import CONTACT_KEYS

p = read_params({'nx': (50, '', 'repeats along x (2 weft yarns each): 50 gives 100 x 100 yarns'),
                 'ny': (50, '', 'repeats along y (2 warp yarns each)'),
                 'steps': (200, '', 'steps of each timed run'),
                 'threads': (2, '', 'thread count compared with one thread'),
                 'repeats': (2, '', 'pairs of runs (1 thread, then `threads`)'),
                 'velocity': (1.0, 'm/s', 'grip speed'),
                 'goal': (1.8, '', 'goal for the speed-up on 2 cores'),
                 'sweep_order': ('sequential', '', "row order of the impulse and projection sweeps in both runs: "
                                 "'sequential' (serial; tension.py's), 'blocked' (slabs of the ply at once on the threads) "
                                 "or 'coloured'"),
                 'out': ('', '', 'output folder (default out/bench_threads)')})
for k, lo in (('nx', 1), ('ny', 1), ('steps', 1), ('threads', 1), ('repeats', 1)):
    if p[k] < lo:
        raise ValueError('%s = %r is invalid: allowed [%d, inf)' % (k, p[k], lo))
if not 0 < p.velocity <= 100:
    raise ValueError('velocity = %r is invalid: allowed (0, 100] m/s (tension.py\'s range)' % (p.velocity,))
if not 0 < p.goal <= 64:
    raise ValueError('goal = %r is invalid: allowed (0, 64] (a speed-up)' % (p.goal,))
d = out_dir('bench_threads', p)
if woven.openmp_threads() < p.threads:
    print('bench_threads: WARNING: OpenMP has %d thread(s) here (yade -j %d missing?): idle threads sleep between '
          'regions and the speed-up is understated' % (woven.openmp_threads(), p.threads))
if p.sweep_order not in ('sequential', 'coloured', 'blocked'):
    raise ValueError("sweep_order = %r is invalid: allowed 'sequential', 'coloured' or 'blocked'" % (p.sweep_order,))
contact_args = {k: v[0] for k, v in CONTACT_KEYS.items()}
contact_args['sweep_order'] = p.sweep_order


def run(threads):
    """Builds the scene on `threads` threads, runs it; returns (wall seconds of the steps, final state)."""
    woven.set_threads(threads)
    w = woven.weave(preset='km2_706', nx=p.nx, ny=p.ny, damping=0.1)
    e = w.engine
    woven.contact.enable(e, **contact_args)
    e.settle_sections()
    for y in w.warp_yarns:
        info = e.yarn(y)
        e.fix(info['first_node'])
        e.prescribe_velocity(info['first_node'] + info['n_nodes'] - 1, Vector3(p.velocity, 0, 0))
    e.velocity_ramp = 1e-5  # [s] about a tenth of scripts/tension.py's run at 100 x 100 yarns
    dt = 0.7 * e.dt_crit
    e.run(dt, 2)  # warm-up: trees, buffers
    t0 = time.perf_counter()
    e.run(dt, p.steps)
    wall = time.perf_counter() - t0
    s = e.collision_stats()
    state = (e._positions(), e._velocities(), e._section_flattening(), e._section_dirs(), sorted(e.energy().items()))
    phases = {k[8:]: s[k] for k in s if k.startswith('seconds_')}
    woven.set_threads(0)
    return wall, state, phases, e.n_elements, s['contacts']


times1, timesN, ideal1, idealN, same = [], [], [], [], True
for r in range(p.repeats):
    # the machine's own ceiling beside each pair: an ideal loop (no serial part) on 1 and N threads
    ideal1.append(woven.ideal_loop_seconds(1)), idealN.append(woven.ideal_loop_seconds(p.threads))
    w1, s1, ph1, cps, contacts = run(1)
    wN, sN, phN, _, _ = run(p.threads)
    times1.append(w1), timesN.append(wN)
    same = same and s1 == sN
    print('bench_threads: repeat %d: 1 thread %.2f s, %d threads %.2f s: %.2fx (phases 1 thread %s; %d threads %s)'
          % (r + 1, w1, p.threads, wN, w1 / wN, {k: round(v, 2) for k, v in ph1.items()}, p.threads,
             {k: round(v, 2) for k, v in phN.items()}))
ratios = [a / b for a, b in zip(times1, timesN)]
best = min(times1) / min(timesN)
measured = {'cps': cps, 'contacts_end': contacts, 'steps': p.steps, 'seconds_1_thread': times1,
            'seconds_n_threads': timesN, 'speedup_per_repeat': ratios, 'speedup_best': best,
            'same_bits': bool(same), 'openmp_threads_at_start': woven.openmp_threads(), 'sweep_order': p.sweep_order,
            'ideal_loop_speedup': min(ideal1) / min(idealN), 'ideal_loop_speedup_per_repeat': [a / b for a, b in zip(ideal1, idealN)]}
checks = {'same_bits': {'value': bool(same), 'limit': True, 'passed': bool(same),
                        'what': 'positions, velocities, sections and energy books equal bit for bit on 1 and N threads'}}
status = 'ok' if same else 'failed'
write_summary(d, 'bench_threads', p, measured, {'goal_speedup_2_cores': p.goal},
              {'seconds_1_thread': 's', 'seconds_n_threads': 's'}, status, checks)
print('bench_threads: %d CPs (%d x %d repeats), %d steps: 1 thread %s s, %d threads %s s; speed-up best %.2fx '
      '(each: %s), goal %.1fx on 2 cores; same bits: %s'
      % (cps, p.nx, p.ny, p.steps, ', '.join('%.2f' % t for t in times1), p.threads,
         ', '.join('%.2f' % t for t in timesN), best, ', '.join('%.2f' % r for r in ratios), p.goal, same))
print('bench_threads: the machine: an ideal loop on %d threads %.2fx one thread (each: %s)'
      % (p.threads, measured['ideal_loop_speedup'], ', '.join('%.2f' % x for x in measured['ideal_loop_speedup_per_repeat'])))
if status != 'ok':
    import sys
    sys.exit(1)
