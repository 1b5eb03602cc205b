# How woven's step scales with the fabric (the scaling chart): wall time per step against the
# number of CPs, for KM2 706 plies of growing side at one CP per crossing, on one thread:
#   tension    the warp ends pulled apart at 1 m/s, the weft ends held: every crossing a resting,
#              persistent contact, nothing moving fast;
#   ballistic  the default cube (1.1 g, 200 m/s) striking the ply's centre, every yarn end clamped:
#              `warmup` steps after its first contact, then the timed ones: the impact region is
#              small and the rest of the ply at rest (what the broad phase by CP and the skin are for).
# Each case: the ply built and settled (not timed), `warmup` steps, then `steps` steps timed, each
# an O.step() (the YADE adapter included). The exponent b of t = a N^b is fitted by least squares on
# log t against log N, per scene.
#   yade -n -x scripts/bench_scaling.py [cps=1e3,3e3,1e4,3e4,1e5,3e5,1e6] [steps=20] [warmup=5]
#                                       [scenes=tension,ballistic] [out=DIR]
# Writes scaling.csv, scaling.png and summary.json to out/bench_scaling/ (or out=DIR).
import math
import time

import numpy as np
import woven
import woven.ballistic
import woven.pack
from woven.contact import CONTACT_KEYS
from woven.output import out_dir, savefig, write_csv, write_summary
from woven.params import read_params

p = read_params({'cps': ('1e3,3e3,1e4,3e4,1e5,3e5,1e6', '', 'target CP counts, comma-separated, each in [100, 2e6]'),
                 'steps': (20, '', 'timed steps per case, in [1, 10000]'),
                 'warmup': (20, '', 'steps before the timed ones (ballistic: after the first contact), in [0, 10000]'),
                 'scenes': ('tension,ballistic', '', "comma-separated, of 'tension' and 'ballistic'"),
                 'out': ('', '', 'output folder (default out/bench_scaling)')})
try:
    targets = [float(x) for x in str(p.cps).split(',') if x.strip()]
except ValueError:
    targets = []
if not targets or not all(math.isfinite(n) and 100 <= n <= 2e6 for n in targets):
    raise ValueError('cps = %r is invalid: allowed comma-separated counts in [100, 2e6]' % (p.cps,))
if not (isinstance(p.steps, int) and 1 <= p.steps <= 10000):
    raise ValueError('steps = %r is invalid: allowed an integer in [1, 10000]' % (p.steps,))
if not (isinstance(p.warmup, int) and 0 <= p.warmup <= 10000):
    raise ValueError('warmup = %r is invalid: allowed an integer in [0, 10000]' % (p.warmup,))
scenes = [s.strip() for s in str(p.scenes).split(',') if s.strip()]
if not scenes or any(s not in ('tension', 'ballistic') for s in scenes):
    raise ValueError("scenes = %r is invalid: allowed a comma-separated list of 'tension' and 'ballistic'" % (p.scenes,))
d = out_dir('bench_scaling', p)

weave_args = {'preset': 'km2_706', 'nx': 0, 'ny': 0, 'cp_per_span': 1}
contact_args = {k: v[0] for k, v in CONTACT_KEYS.items()}
# The ballistic scene's contact settings (scripts/ballistic.py), for both scenes.
contact_args.update(position_correction=0.0, flatten_passes=1, max_iterations=woven.pack.PLY_SWEEPS, skin=4e-5, broad_phase='grid')
DEFAULT_CPS, DEFAULT_SIDE = 9384, 0.0508  # the default ply: 50.8 mm at one CP per crossing
woven.set_threads(1)


def case(scene, target):
    """Builds the ply of about `target` CPs for `scene` and times its steps; returns a result row."""
    side = DEFAULT_SIDE * math.sqrt(target / DEFAULT_CPS)
    O.engines = []
    O.bodies.clear()
    O.resetTime()
    t0 = time.perf_counter()
    ply = woven.ballistic.build_ply(weave_args, contact_args, side=side, clamp=4 if scene == 'ballistic' else 0)
    eng = ply.engine
    if scene == 'ballistic':
        proj = woven.ballistic.add_projectile(ply, 'box', V=200.0)
    else:
        for y in ply.weave.warp_yarns:
            info = eng.yarn(y)
            eng.fix(info['first_node'])
            eng.prescribe_velocity(info['first_node'] + info['n_nodes'] - 1, Vector3(1.0, 0, 0))
        for y in ply.weave.weft_yarns:
            info = eng.yarn(y)
            eng.fix(info['first_node'])
            eng.fix(info['first_node'] + info['n_nodes'] - 1)
    O.engines = [ForceResetter(), NewtonIntegrator(damping=0, gravity=(0, 0, 0))]
    woven.attach(eng, set_dt=True, safety=0.7)
    build = time.perf_counter() - t0
    if scene == 'ballistic':  # to the first contact (the ply's top lies below its highest section)
        for _ in range(2000):
            O.step()
            if eng.collision_stats()['body_contacts'] > 0:
                break
        else:
            raise RuntimeError('bench_scaling: the cube did not reach the %d-CP ply in 2000 steps' % eng.n_elements)
    for _ in range(p.warmup):
        O.step()
    s0 = eng.collision_stats()
    t0 = time.perf_counter()
    for _ in range(p.steps):  # O.step, not O.run: O.run's wait polls, too coarse for a few steps
        O.step()
    wall = time.perf_counter() - t0
    s = eng.collision_stats()
    phases = {k: (s['seconds_' + k] - s0['seconds_' + k]) / p.steps for k in ('refit', 'broad', 'narrow', 'respond')}
    row = {'scene': scene, 'cps': eng.n_elements, 'side': side, 'build_seconds': build, 'steps': p.steps,
           'seconds_per_step': wall / p.steps, 'us_per_cp_step': wall / p.steps / eng.n_elements * 1e6,
           'contacts': s['contacts'], 'body_contacts': s['body_contacts'],
           'broad_phases_in_timed_steps': s['broad_phases'] - s0['broad_phases']}
    row.update({'seconds_per_step_' + k: v for k, v in phases.items()})
    if scene == 'ballistic':
        row['projectile_vz'] = proj.state.vel[2]
    print('bench_scaling: %-9s %8d CPs (side %.1f mm): %.4g s per step, %.2f us per CP-step; %d contacts '
          '(projectile %d); built in %.1f s' % (scene, row['cps'], side * 1e3, row['seconds_per_step'],
                                                  row['us_per_cp_step'], row['contacts'], row['body_contacts'], build))
    return row


rows = [case(scene, n) for scene in scenes for n in targets]

fits = {}
for scene in scenes:
    r = [x for x in rows if x['scene'] == scene]
    if len(r) >= 2:
        N = np.log([x['cps'] for x in r])
        T = np.log([x['seconds_per_step'] for x in r])
        b, a = np.polyfit(N, T, 1)
        fits[scene] = {'exponent': float(b), 'prefactor_seconds': float(math.exp(a)),
                       'from_cps': int(min(x['cps'] for x in r)), 'to_cps': int(max(x['cps'] for x in r))}
        print('bench_scaling: %s: t = %.3g s x N^%.3f (N from %d to %d CPs)' %
              (scene, math.exp(a), b, fits[scene]['from_cps'], fits[scene]['to_cps']))

write_csv('%s/scaling.csv' % d, list(dict.fromkeys(k for x in rows for k in x)), rows)

import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt
fig, ax = plt.subplots(1, 2, figsize=(11, 4.4))
for scene, marker in (('tension', 'o'), ('ballistic', 's')):
    r = [x for x in rows if x['scene'] == scene]
    if not r:
        continue
    N = np.array([x['cps'] for x in r], float)
    ax[0].loglog(N, [x['seconds_per_step'] for x in r], marker + '-', label=scene +
                 (' (N^%.2f)' % fits[scene]['exponent'] if scene in fits else ''))
    ax[1].semilogx(N, [x['us_per_cp_step'] for x in r], marker + '-', label=scene)
ax[0].set_xlabel('CPs')
ax[0].set_ylabel('wall time per step [s]')
ax[0].legend()
ax[0].grid(True, which='both', alpha=0.3)
ax[1].set_xlabel('CPs')
ax[1].set_ylabel('wall time per CP-step [us]')
ax[1].legend()
ax[1].grid(True, which='both', alpha=0.3)
fig.suptitle('woven, KM2 706 at 1 CP per crossing, one thread (%d steps timed per case)' % p.steps)
fig.tight_layout()
savefig(fig, '%s/scaling.png' % d)

write_summary(d, 'bench_scaling', p, {'cases': rows, 'fits': fits}, {}, {'seconds_per_step': 's', 'side': 'm',
              'build_seconds': 's', 'us_per_cp_step': 'us', 'prefactor_seconds': 's'}, 'ok', {})
