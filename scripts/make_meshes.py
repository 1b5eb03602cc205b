"""Writes closed STL meshes of two projectiles, for ballistic.py shape=mesh (mesh_scale=1, SI metres):
  bullet9mm.stl  a round-nose 9 mm bullet: a cylinder of the bore diameter with a tangent-ogive nose.
                 Tangent ogive of base radius R and nose length L: ogive radius rho = (R^2 + L^2)/(2R),
                 r(x) = sqrt(rho^2 - x^2) + R - rho for x in [0, L] from the shoulder (r(0) = R with
                 zero slope: the nose meets the cylinder without a kink; r(L) = 0 at the tip). Its 8.0 g is given as ballistic.py's mass=.
  rcc.stl        the RCC of woven.projectiles (diameter = length = RCC_DIAMETER), segments around.
Run: yade -n -x scripts/make_meshes.py out=DIR [segments=48] [nose_rings=20]
"""
import json
import os

import numpy as np

from woven import mesh, projectiles
from woven.output import dry_run_stop, write_text_atomic
from woven.params import read_params

BULLET = {'diameter': 9.02e-3, 'length': 15.6e-3, 'nose_length': 7.0e-3, 'mass': 8.0e-3}  # [m], [kg]

p = read_params({'out': ('out/meshes', '', 'output folder'),
                 'segments': (48, '', 'triangles around the axis per ring, [8, 1024]'),
                 'nose_rings': (20, '', 'rings along the ogive nose, [2, 1000]')})
if not 8 <= p.segments <= 1024:
    raise ValueError('segments = %r is invalid: allowed [8, 1024]' % p.segments)
if not 2 <= p.nose_rings <= 1000:
    raise ValueError('nose_rings = %r is invalid: allowed [2, 1000]' % p.nose_rings)
dry_run_stop('make_meshes')
os.makedirs(p.out, exist_ok=True)

R, L, Ln = BULLET['diameter'] / 2, BULLET['length'], BULLET['nose_length']
rho = (R * R + Ln * Ln) / (2 * R)
x = np.linspace(0, Ln, p.nose_rings + 1)[1:-1]  # the shoulder ring is (R, L - Ln); the tip (r = 0) the pole
nose = [(np.sqrt(rho * rho - xi * xi) + R - rho, L - Ln + xi) for xi in x]
profile = [(0.0, 0.0), (R, 0.0), (R, L - Ln)] + nose + [(0.0, L)]
v, t = mesh.revolve(profile, p.segments)
mesh.check_closed(t, 'bullet9mm')
m, cm, inertia = mesh.mass_properties(v, t, mass=BULLET['mass'])
mesh.write_stl(os.path.join(p.out, 'bullet9mm.stl'), v, t, 'bullet9mm')

rcc = projectiles.solid('rcc')
Rc, H = rcc['radius'], rcc['half_length']
vc, tc = mesh.revolve([(0.0, -H), (Rc, -H), (Rc, H), (0.0, H)], p.segments)
mesh.check_closed(tc, 'rcc')
mc, ccm, ic = mesh.mass_properties(vc, tc, density=projectiles.STEEL_DENSITY)
mesh.write_stl(os.path.join(p.out, 'rcc.stl'), vc, tc, 'rcc')

info = {'bullet9mm': {'triangles': len(t), 'mass': m, 'density': m / (mesh.mass_properties(v, t, density=1.0)[0]),
                      'centre_of_mass': cm.tolist(), 'inertia': np.diag(inertia).tolist()},
        'rcc': {'triangles': len(tc), 'mass': mc, 'exact_mass': rcc['mass'], 'centre_of_mass': ccm.tolist(),
                'inertia': np.diag(ic).tolist()}}
write_text_atomic(os.path.join(p.out, 'meshes.json'), json.dumps(info, indent=1))
print(json.dumps(info, indent=1))
