# Builds a weave from parameters and writes its summary and a picture.
#   yade -n -x scripts/weave.py [preset=km2_706] [pattern=plain] [nx=3] [ny=3] [cp_per_span=4] [out=DIR] ...
# Output: out/weave/summary.json, out/weave/weave.png, out/weave/nodes.csv
import os
import sys

import woven
from woven.output import savetxt, savefig
from woven.params import read_params
from woven.output import out_dir, write_summary
from woven.weave import WEAVE_KEYS, SUMMARY_UNITS

defaults = dict(WEAVE_KEYS)
defaults.update({'nx': (3, '', WEAVE_KEYS['nx'][2]), 'ny': (3, '', WEAVE_KEYS['ny'][2]),
                 'out': ('', '', 'output folder (default out/weave)'),
                 'picture': (True, '', 'write weave.png')})
p = read_params(defaults)
d = out_dir('weave', p)
w = woven.weave(**{k: p[k] for k in WEAVE_KEYS})
s = w.summary

reference = {'required_gap': s['required_gap'], 'warp_crimp_peirce': s['warp_crimp_peirce'],
             'weft_crimp_peirce': s['weft_crimp_peirce']}
checks = {'crossing_clearance': {'value': s['min_vertical_gap'], 'limit': s['required_gap'] - 1e-9,
                                 'passed': s['min_vertical_gap'] >= s['required_gap'] - 1e-9,
                                 'what': 'centre-line gap at every crossing >= (t_warp + t_weft)/2 - 1e-9 m'}}
is_km2 = p.preset == 'km2_706' and p.pattern == 'plain' and all(
    p[k] is None for k in ('spacing', 'warp_spacing', 'weft_spacing', 'thickness', 'width', 'area', 'rho',
                           'linear_density', 'crimp', 'warp_crimp', 'weft_crimp'))
if is_km2:
    reference['areal_density'] = 0.180  # KM2 style 706, physics-reference.md
    err = abs(s['areal_density'] / 0.180 - 1)
    checks['areal_density'] = {'value': err, 'limit': 0.01, 'passed': err <= 0.01,
                               'what': 'relative difference from 180 g/m^2'}

import numpy as np
X = woven.positions(w.engine)
savetxt(os.path.join(d, 'nodes.csv'), X, delimiter=',', header='x_m,y_m,z_m', comments='')

if p.picture:
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from matplotlib.patches import Ellipse
    eng = w.engine
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 5.5), gridspec_kw={'width_ratios': [1, 1.4]})
    zmax = max(s['warp_crimp_height'], s['weft_crimp_height']) / 2
    for fam, ys, cmap in (('weft', w.weft_yarns, 'Blues'), ('warp', w.warp_yarns, 'Reds')):
        for y in ys:
            info = eng.yarn(y)
            P = X[info['first_node']:info['first_node'] + info['n_nodes']]
            a1.scatter(P[:, 0] * 1e3, P[:, 1] * 1e3, c=P[:, 2], cmap='coolwarm', vmin=-zmax, vmax=zmax, s=4)
            a1.plot(P[:, 0] * 1e3, P[:, 1] * 1e3, color='r' if fam == 'warp' else 'b', lw=0.5, alpha=0.6)
    a1.set_aspect('equal')
    a1.set_xlabel('x [mm]')
    a1.set_ylabel('y [mm]')
    a1.set_title('top view: warp (red lines) along x, weft (blue) along y;\nnodes coloured by height z')
    info = eng.yarn(w.warp_yarns[0])
    P = X[info['first_node']:info['first_node'] + info['n_nodes']]
    a2.plot(P[:, 0] * 1e3, P[:, 2] * 1e3, 'r.-', lw=1, label='warp 0 CP chain')
    t_w = info['thickness']
    for j, y in enumerate(w.weft_yarns):
        wi = eng.yarn(y)
        Q = X[wi['first_node']:wi['first_node'] + wi['n_nodes']]
        k = int(np.argmin(abs(Q[:, 1] - P[0, 1])))
        a2.add_patch(Ellipse((Q[k, 0] * 1e3, Q[k, 2] * 1e3), wi['width'] * 1e3, wi['thickness'] * 1e3,
                             fc='lightblue', ec='b'))
    a2.fill_between(P[:, 0] * 1e3, (P[:, 2] - t_w / 2) * 1e3, (P[:, 2] + t_w / 2) * 1e3, color='r', alpha=0.2,
                    label='warp thickness')
    a2.set_xlabel('x [mm]')
    a2.set_ylabel('z [mm]')
    a2.set_title('section along warp 0, z exaggerated (weft sections as ellipses)')
    a2.legend(loc='upper right', fontsize=8)
    fig.suptitle('%s, %d x %d yarns, %.1f g/m^2, crimp %.2f %% (Peirce %.2f %%), %d CPs/span' % (
        p.pattern, s['warp_yarns'], s['weft_yarns'], s['areal_density'] * 1e3, 100 * s['warp_crimp_built'],
        100 * s['warp_crimp_peirce'], s['cp_per_span']))
    fig.tight_layout()
    savefig(fig, os.path.join(d, 'weave.png'), dpi=110)

units = dict(SUMMARY_UNITS)
ok = all(c['passed'] for c in checks.values())
write_summary(d, 'weave', p, s, reference, units, 'ok' if ok else 'failed', checks)
print('woven weave: %d yarns, %d nodes, %d CPs, %.2f g/m^2, crimp %.3f %% (Peirce %.3f %%), gap %.4g m (required %.4g m) -> %s'
      % (s['warp_yarns'] + s['weft_yarns'], s['nodes'], s['elements'], s['areal_density'] * 1e3,
         100 * s['warp_crimp_built'], 100 * s['warp_crimp_peirce'], s['min_vertical_gap'], s['required_gap'], d))
if not ok:
    sys.exit(1)
