# Ballistic impact of a rigid projectile on a single ply (paper Sec. 6.2) or a pack, run inside YADE's loop.
#   yade -n -x scripts/ballistic.py [V=200] [shape=box|sphere|rcc|fsp|mesh [mesh=FILE.stl]] [mass=1.1e-3] [size=5.59e-3] [side=0.0508]
#                                   [clamp=4] [plies=1] [ply_gap=-1] [ply_angles=0,45] [yaw=0] [obliquity=0]
#                                   [t_end=1e-4] [state=FILE] [vtk_every=N] [out=DIR] ...
# Packs and the standard projectiles (RCC, FSP as exact cylinder parts): docs/ballistic.md.
# The fabric (default KM2 style 706, a 50.8 x 50.8 mm single ply, clamped on its 4 edges) is built,
# its sections settled; the projectile is an ordinary YADE body (a cube of edge `size` face on, or a
# sphere of diameter `size`) coupled to the fabric (woven.coupling), `standoff` above its top surface,
# moving at V normal to it. YADE's NewtonIntegrator moves the projectile; the woven engine resolves its
# contacts with the yarns (impulses on both sides) and breaks elements past the failure strain.
# The run stops at t_end, or once the projectile has perforated (below the ply, and out of contact or
# no longer slowed for `clear_steps` steps: pieces of broken yarn may ride on it) or been arrested
# (moving back).
# Output (out/ballistic/): series.csv and yade.plot data (series.txt), ballistic.png, breaks.csv,
# vtk/frames.pvd with yarn tubes and the projectile every vtk_every steps, summary.json.
import math
import os
import subprocess
import sys
import time

import numpy as np
import woven
from woven.output import savetxt, atomic_open, atomic_path, savefig
from woven.params import check_steps, read_params
from woven.energy_guard import EnergyGuard
from woven.output import out_dir, write_summary
from woven.weave import WEAVE_KEYS
from woven.contact import CONTACT_KEYS
from yade import plot, utils
import woven.ballistic
import woven.contact
import woven.backface
import woven.render
import woven.pack
import woven.projectiles
import woven.mesh
from woven.overlap import OverlapMeter
import woven.overlap
import woven.yade_grid
import woven.yade_scenes

defaults = dict(WEAVE_KEYS)
defaults.update({
    'nx': (0, '', 'repeats along x (0: from side)'), 'ny': (0, '', 'repeats along y (0: from side)'),
    # 1 CP between crossings (0.75 mm): residual velocity within 2.7 % (200 m/s) and 12 % (120 m/s) of
    # 4 CPs, where 2 CPs were 6.9 % and 24 % off (docs/ballistic.md, resolution); 100 us in 22 s.
    'cp_per_span': (1, '', WEAVE_KEYS['cp_per_span'][2]),
    # Adaptive resolution (docs/ballistic.md): cp_per_span CPs per span within fine_radius of the
    # impact point, cp_coarse outside.
    'fine_radius': (-1.0, 'm', 'adaptive resolution: spans within this distance of the impact point get cp_per_span CPs, '
                    'the others cp_coarse; 0: the transverse wave\'s reach, U_E(V) t_end + the projectile\'s in-plane '
                    'half-diagonal (box) or radius (sphere); < 0: uniform cp_per_span'),
    'cp_coarse': (1, '', WEAVE_KEYS['cp_coarse'][2]),
    # Multiple time stepping (FabricEngine::setSubsteps, docs/ballistic.md): O.dt = substeps x safety x
    # dt_crit, the springs at O.dt / substeps, the contacts once per O.dt.
    'substeps': (1, '', 'spring substeps per contact step, [1, 64] (adaptive: cp_per_span / cp_coarse meets the '
                 'contacts at the coarse CPs\' rate); above 1 only with the gap model\'s impulses'),
    'multirate': (0, '', 'with substeps > 1, 1: the CPs stable at substeps x dt_crit (the coarse ones) step once per '
                  'O.dt and later substeps solve again only the rows near the others or the projectile; 0: every '
                  'CP steps substeps times, every row solved again (docs/design.md)'),
})
for k in ('fine_x', 'fine_y'):  # the fine region is centred on the impact point, the ply's middle
    del defaults[k]
defaults.update(CONTACT_KEYS)
defaults.update({
    'position_correction': (0.0, '', 'fraction of a locked overlap removed per step; 0 keeps the energy books closed'),
    # Measured on the default scene over 20 us (docs/ballistic.md): absorbed energy within 0.2 % of
    # the tension scene's contact settings (4 passes, 50 sweeps, 5 um skin), at 0.6x the wall time.
    'flatten_passes': (1, '', CONTACT_KEYS['flatten_passes'][2]),
    'max_iterations': (woven.pack.PLY_SWEEPS, '', CONTACT_KEYS['max_iterations'][2] + '; a pack takes 10 per ply (at least this many), a backing or a frame 200, unless given'),
    'skin': (4e-5, 'm', CONTACT_KEYS['skin'][2]),
    # Same pairs as the tree; 100 us of the default scene in 69 s against 84 s (bench_ballistic.py).
    'broad_phase': ('grid', '', CONTACT_KEYS['broad_phase'][2]),
    'side': (0.0508, 'm', 'side of the square ply (yarns = side / spacing, rounded to whole pattern repeats)'),
    'clamp': (4, '', 'edges held: 4 (every yarn end), 2 (warp ends only), 0 (free); every ply alike'),
    'backing': ('none', '', "'none', 'wall' (a fixed YADE Wall: a rigid plane) or 'facet' (a fixed plate of two YADE "
                "Facets, 1.5 side across) backing_standoff below the pack"),
    'backing_standoff': (5e-3, 'm', 'gap between the lowest yarn section and the backing wall, (0, 0.1] m'),
    'frame': ('none', '', "'none', or 'mesh': the edges held between two fixed jaws (closed square-ring meshes of YADE "
              "Facets, clumped) instead of fixed yarn ends; needs clamp=0"),
    'frame_width': (5e-3, 'm', 'frame mesh: how much of every edge the jaws cover, (0, side/4] m'),
    'frame_gap': (1e-6, 'm', 'frame mesh: clearance between each jaw and the nearest yarn sections, (0, 1e-3] m'),
    'frame_edge': (5e-4, 'm', 'frame mesh: radius of the jaws\' window edge on the ply\'s side, [0, min(1e-3, frame_width)] m (0: a right angle)'),
    'frame_force': (0.0, 'N', 'frame mesh: load the upper jaw presses the edges with, [0, 1e6] N (0: both jaws fixed; a pressed '
                    'jaw is not validated, docs/ballistic.md "Frames")'),
    'frame_friction': (0.3, '', "frame mesh: Coulomb coefficient between the jaws and the yarns, [0, 2] (the projectile's is body_friction)"),
    'plies': (1, '', 'plies in the pack, [1, 40] (woven.pack: copies of the ply stacked below the first)'),
    'ply_gap': (-1.0, 'm', 'clear gap between neighbouring plies, [0, 0.01] m; -1: one yarn thickness'),
    'ply_angles': ('0', 'deg', "in-plane angle of each ply about the ply's centre, comma-separated (one for all), "
                   'finite, [-360, 360]'),
    'state': ('', '', 'initial state file of the same weave (e.g. pretensioned.state of tension.py); empty: at rest'),
    'V': (200.0, 'm/s', 'impact speed, normal to the ply'),
    'shape': ('box', '', "'box' (a cube, face on, as the paper's OBB-bounded projectile), 'sphere', 'rcc' (0.22-calibre "
              "right circular cylinder), 'fsp' (17-grain 0.22-calibre fragment simulator, chisel nose): woven.projectiles, "
              "or 'mesh' (a closed STL solid: mesh=FILE)"),
    'mesh': ('', '', 'shape mesh: the STL file of a closed, outward-oriented solid (scripts/make_meshes.py writes a 9 mm bullet and the RCC)'),
    'mesh_scale': (1.0, '', 'shape mesh: factor from the file\'s units to metres, (0, 1e3] (1e-3 for a file in mm)'),
    'nose_axis': ('+z', '', "shape mesh: the file's axis that points along the flight: +x, -x, +y, -y, +z or -z"),
    'mass': (1.1e-3, 'kg', 'projectile mass, (0, 10] kg (default: a 0.22-calibre, 17-grain fragment simulator); rcc, '
             'fsp and mesh when not given: density x the exact solid\'s (the mesh\'s) volume'),
    'size': (5.59e-3, 'm', 'cube edge or sphere diameter, [1e-4, 0.1] m (default: 0.22 calibre); rcc: its diameter = '
             'length, 5.588e-3 when not given; fsp: fixed by its drawing (not to be given)'),
    'density': (7850.0, 'kg/m^3', 'rcc, fsp and mesh material density, [1000, 20000] (steel)'),
    'yaw': (0.0, 'deg', 'angle of the projectile\'s axis to its flight, in the plane of incidence, [-90, 90]'),
    'obliquity': (0.0, 'deg', 'angle of the flight to the ply\'s normal (towards +x), [0, 80]'),
    'standoff': (0.05e-3, 'm', 'gap between the projectile and the top of the ply at the start'),
    't_end': (1e-4, 's', 'simulated time at most'),
    'stop': (True, '', 'stop at perforation or arrest (else run to t_end)'),
    'clear_steps': (200, '', 'steps below the ply out of contact, or without a change of speed (> 1e-4 V), that count as perforated'),
    'break_strain': (0.0, '', 'failure strain in [1e-12, 10]; <= 0: the material failure strain (KM2: 5 %)'),
    'break_filter': (-4.0, 'm', 'strain filter: tau = L / c, L = break_filter [m] if > 0, |break_filter| element lengths if < 0, 0: raw strain'),
    'weibull_m': (0.0, '', 'Weibull modulus of yarn strength (0: none; else [1, 100])'),
    'seed': (1, '', 'seed of the Weibull draw'),
    'safety': (0.7, '', 'O.dt = safety * substeps * dt_crit'),
    'energy_guard': (0.005, '', 'energy-balance error past which O.dt drops to guard_safety * dt_crit for the rest of the run, in [0, energy_limit) (0: off; woven.energy_guard)'),
    'guard_safety': (0.0, '', 'O.dt = guard_safety * substeps * dt_crit once the guard acts, in (0, safety] (0: safety / 2, 0.35 by default)'),
    'samples': (400, '', 'rows of the time series at most'),
    'vtk_every': (0, '', 'write VTK frames every this many steps (0: first and last frame only; -1: none)'),
    'vtk_rings': (8, '', 'points per section ellipse in the VTK tubes'),
    'mirror_every': (0, '', 'copy the yarn nodes into YADE sphere bodies every this many steps (0: off)'),
    'progress': (5.0, 's', 'wall time between progress lines (0: none)'),
    'energy_limit': (0.01, '', 'allowed energy-balance error / initial kinetic energy'),
    'overlap_limit': (0.1, '', 'allowed largest overlap until the first break / yarn thickness (contact_model=gap)'),
    'out': ('', '', 'output folder (default out/ballistic)'),
    'model': ('woven', '', "'woven', 'yade': the same ply in YADE's grid elements (woven.yade_grid), or 'yade_pfacet': "
              "in YADE PFacet ribbons (woven.yade_pfacet; docs/yade_grid.md)"),
    # Back-face deformation (woven.backface, docs/ballistic.md): measured at every sample.
    'backface': (True, '', 'measure the back-face deformation (cone apex depth, base radius, fronts) at every sample'),
    # Twice the largest out-of-plane move of decrimping (KM2 706: crimp height 0.1 mm, nodes +-0.05 mm),
    # which the longitudinal wave brings ahead of the transverse front (measured: 10 um let it through).
    'backface_w': (1e-4, 'm', 'out-of-plane displacement that counts as moved (cone base radius, transverse front), in (0, 1e-3]'),
    'backface_strain': (0.0, '', 'strain that counts as reached by the longitudinal wave, in (0, 0.1]; 0: a tenth of Smith\'s yarn strain at V (4.7e-4 at 200 m/s)'),
    # Measured: 5.0 / 6.6 % (transverse / strain front) at 200 m/s, 0.9 / 1.8 % at 400 m/s; the bare
    # yarn's Smith is 25-27 % off, the membrane's c/sqrt(2) 13-17 % (docs/ballistic.md).
    'front_tolerance': (0.1, '', 'allowed |measured / theory - 1| of the early front speeds, in (0, 10]'),
    'front_check': (False, '', "1: the early front speeds' comparisons with Smith are checks of the run (fail it past front_tolerance); 0: reported in measured.backface.front_checks"),
    'pictures': (5, '', 'pictures of the deformed pack rendered with VTK: at t_end k / N (k < N) and at the end (for '
                 'the default run 20, 40, 60 us and the perforation), N in [0, 100]; 0: none'),
})
defaults.update(woven.yade_grid.GRID_KEYS)
p = read_params(defaults)
woven.yade_scenes.check_model(p)

# --- input checks: every bad value names its key and the allowed range, before anything is built ---
def bad(key, allowed):
    raise ValueError('%s = %r is invalid: allowed %s' % (key, p[key], allowed))


if not (math.isfinite(p.V) and 0 < p.V <= 5000):
    bad('V', '(0, 5000] m/s, finite')
if p.shape not in woven.ballistic.SHAPES:
    bad('shape', ', '.join(woven.ballistic.SHAPES))
if not (math.isfinite(p.mass) and 0 < p.mass <= 10):
    bad('mass', '(0, 10] kg')
if p.shape == 'fsp' and 'size' in p.given:
    bad('size', 'not given for shape fsp (its drawing fixes its size)')
if not (math.isfinite(p.size) and 1e-4 <= p.size <= 0.1):
    bad('size', '[1e-4, 0.1] m')
if not (math.isfinite(p.density) and 1000 <= p.density <= 20000):
    bad('density', '[1000, 20000] kg/m^3')
if not (math.isfinite(p.yaw) and woven.ballistic.YAW_RANGE[0] <= p.yaw <= woven.ballistic.YAW_RANGE[1]):
    bad('yaw', '[%g, %g] deg' % woven.ballistic.YAW_RANGE)
if not (math.isfinite(p.obliquity) and woven.ballistic.OBLIQUITY_RANGE[0] <= p.obliquity <= woven.ballistic.OBLIQUITY_RANGE[1]):
    bad('obliquity', '[%g, %g] deg' % woven.ballistic.OBLIQUITY_RANGE)
if p.contact_model == 'paper' and p.shape in ('rcc', 'fsp', 'mesh'):
    bad('shape', "'box' or 'sphere' with contact_model paper (a cylinder and a mesh have the gap model's form only)")
if p.shape == 'mesh' and not p.mesh:
    bad('mesh', 'an STL file with shape mesh')
if p.mesh and p.shape != 'mesh':
    bad('mesh', "'' unless shape is mesh")
if p.shape == 'mesh' and 'size' in p.given:
    bad('size', 'not given for shape mesh (the mesh fixes its size)')
# The projectile: the standard solids' dimensions and mass (woven.projectiles), or a cube / sphere.
solid = None
if p.shape in ('rcc', 'fsp'):
    solid = woven.projectiles.solid(p.shape, p.size if 'size' in p.given else 0.0, p.density)
    size = 2 * solid['radius']
    mass = p.mass if 'mass' in p.given else solid['mass']
elif p.shape == 'mesh':  # the file is read once the keys have passed (below)
    woven.mesh.check_keys(p.mesh_scale, p.nose_axis)
    size, mass = p.size, p.mass
else:
    size, mass = p.size, p.mass
if not (math.isfinite(p.side) and 1e-3 <= p.side <= 1):
    bad('side', '[1e-3, 1] m (and at most %d nodes in the ply: woven.ballistic.build_ply)' % woven._woven.MAX_WEAVE_NODES)
if p.clamp not in (0, 2, 4):
    bad('clamp', '4, 2 or 0 edges')
if not 1 <= p.plies <= woven.pack.MAX_PLIES:
    bad('plies', '[1, %d] plies' % woven.pack.MAX_PLIES)
if not (math.isfinite(p.ply_gap) and (0 <= p.ply_gap <= 0.01 or p.ply_gap == -1)):
    bad('ply_gap', '[0, 0.01] m, or -1 (one yarn thickness)')
ply_angles = woven.pack.parse_angles(p.ply_angles, p.plies)  # names ply_angles and its range
if p.backing not in ('none', 'wall', 'facet'):
    bad('backing', "'none', 'wall' or 'facet'")
if not (math.isfinite(p.backing_standoff) and 0 < p.backing_standoff <= 0.1):
    bad('backing_standoff', '(0, 0.1] m')
if p.backing != 'none' and p.model != 'woven':
    bad('backing', "'none' with model %s" % p.model)
PINCH_SWEEPS = 200  # sweeps with a backing or a frame, unless max_iterations is given
if p.frame not in ('none', 'mesh'):
    bad('frame', "'none' or 'mesh'")
if p.frame == 'mesh' and p.clamp != 0:
    bad('clamp', '0 with frame mesh (the jaws hold the edges)')
if p.frame == 'mesh' and p.model != 'woven':
    bad('frame', "'none' with model %s" % p.model)
if p.frame == 'mesh':
    if not (math.isfinite(p.frame_width) and 0 < p.frame_width <= 0.25 * p.side):
        bad('frame_width', '(0, side/4 = %g] m' % (0.25 * p.side))
    if not (math.isfinite(p.frame_edge) and 0 <= p.frame_edge <= min(1e-3, p.frame_width)):
        bad('frame_edge', '[0, min(1e-3, frame_width) = %g] m' % min(1e-3, p.frame_width))
    if not (math.isfinite(p.frame_force) and 0 <= p.frame_force <= 1e6):
        bad('frame_force', '[0, 1e6] N (0: fixed jaws)')
    if not (math.isfinite(p.frame_gap) and 0 < p.frame_gap <= 1e-3):
        bad('frame_gap', '(0, 1e-3] m')
    if not (math.isfinite(p.frame_friction) and 0 <= p.frame_friction <= 2):
        bad('frame_friction', '[0, 2]')
    if p.response == 'penalty' and p.frame_friction > 0:
        bad('frame_friction', "0 with response penalty (Coulomb friction acts in the impulse rows only)")
if not (math.isfinite(p.standoff) and p.standoff > 0):
    bad('standoff', '(0, inf) m: the projectile starts clear of the ply')
if not (math.isfinite(p.t_end) and 0 < p.t_end <= 0.01):
    bad('t_end', '(0, 0.01] s')
if not (0 < p.safety <= 1):
    bad('safety', '(0, 1]')
if not (0 <= p.energy_guard < p.energy_limit):
    bad('energy_guard', '[0, energy_limit = %g) (0: off)' % p.energy_limit)
if not (0 <= p.guard_safety <= p.safety):
    bad('guard_safety', '(0, safety = %g], or 0: safety / 2' % p.safety)
if p.samples < 10:
    bad('samples', '[10, inf)')
if not (0 < p.energy_limit < 1):
    bad('energy_limit', '(0, 1)')
if not (0 < p.overlap_limit <= 100):
    bad('overlap_limit', '(0, 100] yarn thicknesses')
if p.vtk_every < -1:
    bad('vtk_every', '-1 (none), 0 (first and last) or a step count')
if p.mirror_every < 0:
    bad('mirror_every', '0 (off) or a step count')
for k in ('nx', 'ny'):
    if not 0 <= p[k] <= 100000:
        bad(k, '[0, 100000] repeats (0: from side)')
if not 1 <= p.clear_steps <= 10 ** 7:
    bad('clear_steps', '[1, 1e7] steps')
if not 3 <= p.vtk_rings <= 256:
    bad('vtk_rings', '[3, 256] points per section')
if not (math.isfinite(p.progress) and p.progress >= 0):
    bad('progress', '[0, inf) s (0: none)')
woven.contact.check_friction(p)
if p.model != 'woven' and p.body_friction > 0:  # woven.yade_grid / yade_pfacet give the projectile a frictionless material
    bad('body_friction', "0 with model = %r (its projectile-yarn contacts are frictionless); [0, 2] with model = 'woven'" % p.model)
if not (math.isfinite(p.backface_w) and 0 < p.backface_w <= 1e-3):
    bad('backface_w', '(0, 1e-3] m')
if not (math.isfinite(p.backface_strain) and 0 <= p.backface_strain <= 0.1):
    bad('backface_strain', '(0, 0.1], or 0: a tenth of Smith\'s yarn strain at V')
if not (math.isfinite(p.front_tolerance) and 0 < p.front_tolerance <= 10):
    bad('front_tolerance', '(0, 10]')
if not (0 <= p.pictures <= 100):
    bad('pictures', '[0, 100] (0: none)')
if not (math.isfinite(p.fine_radius)):
    bad('fine_radius', '[0, inf) m (0: from the transverse wave), or < 0 for uniform cp_per_span')
if p.fine_radius >= 0 and not (1 <= p.cp_coarse <= p.cp_per_span):
    bad('cp_coarse', '[1, cp_per_span = %d] CPs between crossings outside fine_radius' % p.cp_per_span)
if not (isinstance(p.substeps, int) and 1 <= p.substeps <= 64):
    bad('substeps', 'an integer in [1, 64]')
if p.multirate not in (0, 1):
    bad('multirate', '0 or 1')
if p.substeps > 1 and (p.response == 'penalty' or p.flattening == 'springs' or p.model != 'woven' or p.contact_model == 'paper'):
    bad('substeps', "1 with response penalty, flattening springs, contact_model paper or models yade, yade_pfacet (only the "
                    "gap model's impulses substep)")
if p.model != 'woven' and (p.plies > 1 or any(ply_angles) or p.shape in ('rcc', 'fsp', 'mesh') or p.yaw or p.obliquity):
    bad('model', "'woven' for packs, rcc, fsp, mesh, yaw and obliquity (models yade, yade_pfacet: one ply, a cube or a "
                 "sphere, face on)")
d = out_dir('ballistic', p)
if p.shape == 'mesh':  # names the file when it is unreadable, open, non-manifold or wound inward
    solid = woven.mesh.solid(p.mesh, p.mesh_scale, density=p.density, nose_axis=p.nose_axis)
    size = 2 * solid['radius']
    mass = p.mass if 'mass' in p.given else solid['mass']
if p.model != 'woven':
    sys.exit(woven.yade_scenes.ballistic(p, d, [k for k in WEAVE_KEYS if k in p], CONTACT_KEYS))

# --- the ply and the projectile (an ordinary YADE body) ---
O.engines = []
O.bodies.clear()
weave_args = {k: p[k] for k in WEAVE_KEYS if k in p}
if p.fine_radius == 0:
    weave_args['fine_radius'] = woven.ballistic.fine_radius_from_waves(weave_args, p.V, p.t_end, p.shape, size)
contact_args = {k: p[k] for k in CONTACT_KEYS}
if p.plies > 1 and 'max_iterations' not in p.given:
    # Gauss-Seidel carries a push one contact layer per sweep, and a pack stacks 2 yarn layers per ply
    # between the projectile and the last ply: 10 sweeps per ply (docs/ballistic.md; 4 plies at 10
    # sweeps let the projectile 0.48 thickness into the yarns and the projection put in 6 % of KE0),
    # and never fewer than the single ply's.
    contact_args['max_iterations'] = woven.pack.sweeps_for(p.plies, at_least=p.max_iterations)
if (p.frame != 'none' or p.backing != 'none') and 'max_iterations' not in p.given:
    # Yarns pinched between two rigid bodies (the cube and a backing, a frame's jaws): Gauss-Seidel
    # carries the push through them slowly, and 20 sweeps left them crushed into each other (up to
    # 1.05 thickness against a wall, 0.35-0.48 in a frame); 200 held them to 0.02-0.07.
    contact_args['max_iterations'] = max(contact_args['max_iterations'], PINCH_SWEEPS)
ply = woven.ballistic.build_ply(weave_args, contact_args, side=p.side,
                                clamp=p.clamp, state=p.state,
                                breakage=dict(strain=p.break_strain, filter_length=p.break_filter,
                                              weibull_m=p.weibull_m, seed=p.seed),
                                plies=p.plies, ply_gap=None if p.ply_gap == -1 else p.ply_gap, ply_angles=ply_angles)
w, eng, settle_left = ply.weave, ply.engine, ply.settle_left
X0, thickness, z_mid = ply.X0, ply.thickness, ply.z_mid
proj = woven.ballistic.add_projectile(ply, p.shape, mass, size, p.V, p.standoff, p.yaw, p.obliquity, solid)
backing_id = None
if p.backing == 'wall':
    # A rigid backing: a fixed plane (YADE Wall, acting upwards) below the pack's lowest section; the
    # fabric meets it as the face of a box (woven.coupling._parts_of).
    z_wall = float(X0[:, 2].min()) - thickness - p.backing_standoff
    backing_id = O.bodies.append(utils.wall((ply.centre[0], ply.centre[1], z_wall), axis=2, sense=1))
    O.bodies[backing_id].dynamic = False
    woven.coupling.couple(eng, [backing_id])
elif p.backing == 'facet':
    # A rigid plate of two YADE Facets (lone facets: outside on both faces), 1.5 sides across, centred
    # under the ply: what a mesh backing (yade.ymport.stl of a plate) gives the fabric.
    z_wall = float(X0[:, 2].min()) - thickness - p.backing_standoff
    h = 0.75 * p.side
    cx, cy = ply.centre[0], ply.centre[1]
    c = [(cx - h, cy - h, z_wall), (cx + h, cy - h, z_wall), (cx + h, cy + h, z_wall), (cx - h, cy + h, z_wall)]
    plate = [O.bodies.append(utils.facet([c[0], c[1], c[2]], fixed=True)),
             O.bodies.append(utils.facet([c[0], c[2], c[3]], fixed=True))]
    for i in plate:
        O.bodies[i].dynamic = False
    woven.coupling.couple(eng, plate)
    backing_id = plate[0]
frame_ids = []
if p.frame == 'mesh':
    # The jaws of a test rig's clamping frame: the yarn ends are free (clamp=0) and held only where
    # the jaws press them, so they pull in as far as the jaws' friction and the crimp let them.
    frame_ids = woven.ballistic.add_frame(ply, p.frame_width, p.frame_gap, p.frame_friction, p.frame_edge, p.frame_force)
    jaw0 = Vector3(O.bodies[frame_ids[0]].state.pos)
    ends = np.array(sorted({n for y in range(eng.n_yarns) for n in (eng.yarn(y)['first_node'],
                                                                    eng.yarn(y)['first_node'] + eng.yarn(y)['n_nodes'] - 1)}))
places0 = {}  # the crossings' places after the first step (they are made in it), for their slip (load_sharing)
# How far it reaches below and above its centre of mass at the start (the nose, and the rear that
# must pass the last ply): half the cube's edge or the sphere's radius in the scene as it was.
low, high = woven.ballistic.projectile_extent(p.shape, size, proj.state.ori, solid)
if p.shape in ('box', 'sphere') and p.yaw == 0 and p.obliquity == 0:
    low = high = 0.5 * size

O.engines = [ForceResetter(), NewtonIntegrator(damping=0, gravity=(0, 0, 0))]
eng.substeps = p.substeps
eng.multirate = bool(p.multirate)
woven.attach(eng, set_dt=True, safety=p.safety)
check_steps(p.t_end, O.dt, 'safety', p.safety, 't_end')
every = max(1, int(math.ceil(p.t_end / O.dt)) // p.samples)
guard = EnergyGuard(eng, p.energy_guard, p.guard_safety or 0.5 * p.safety)
check_steps(p.t_end, guard.smallest_dt(), 'guard_safety', p.guard_safety or 0.5 * p.safety, 't_end once the energy guard acts')
steps_max = int(math.ceil(p.t_end / guard.smallest_dt()))  # the run stops at t_end (watch)
KE0 = 0.5 * mass * p.V ** 2
E0 = eng.energy()
fabric_initial = E0['initial']

# --- mirror into YADE bodies (off by default): YADE's 3D view and VTKRecorder then show the yarns ---
mirror_ids = []
if p.mirror_every > 0:
    r0 = 0.5 * thickness
    for x in X0:
        b = utils.sphere(tuple(x), r0, fixed=True)
        b.mask = 0
        mirror_ids.append(O.bodies.append(b))


def mirror():
    X = woven.positions(eng)
    for i, bid in enumerate(mirror_ids):
        O.bodies[bid].state.pos = Vector3(*X[i])


def nose_z():
    return proj.state.pos[2] - low  # the cube's face, the sphere's pole, the cylinder's lowest point at the start


# min_nose: the deepest nose from the start (a run shorter than the watch's first call, t_end =
# 1e-300, read -inf as its penetration: scripts/fuzz.py seed=9001).
state = {'contact_seen': False, 'clear': 0, 'steady': 0, 'vz_ref': -p.V, 'outcome': 'running', 'min_nose': nose_z(),
         'wall0': time.time(), 'last_progress': time.time(), 'mirror_seconds': 0.0}
rows = []


def frame_work():
    """What a pressed jaw has put into the fabric [J]: its load's work over its drop less its kinetic
    energy (its permanent force is YADE's, outside woven's books; 0 for fixed jaws)."""
    if not (frame_ids and p.frame_force > 0):
        return 0.0
    st = O.bodies[frame_ids[0]].state
    return p.frame_force * (jaw0[2] - st.pos[2]) - 0.5 * st.mass * st.vel.squaredNorm()


def sample():
    E = eng.energy()
    s = eng.collision_stats()
    vz = proj.state.vel[2]
    ke_p = projectile_ke()
    dissipated = E['contact']
    row = dict(t=O.time, vz=vz, z=proj.state.pos[2], ke_projectile=ke_p, ke_fabric=E['kinetic'], elastic=E['elastic'],
               dissipated_impulses=dissipated, friction=E['friction'], damped=E['damped'], released=E['released'],
               contacts=s['contacts'], body_contacts=s['body_contacts'], broken=eng.broken_elements,
               projection=E['projection'], overlap=s['penetration'], body_overlap=s['body_penetration'],
               balance=(ke_p + E['kinetic'] + E['elastic'] + E['damped'] + dissipated + E['friction'] + E['released'] + E['spring']
                        + E['projection'] - KE0 - E['initial'] - (E['work'] - E['body_work']) - frame_work()) / KE0)
    if frame_ids and p.frame_force > 0:
        row['frame_work'] = frame_work()
    rows.append(row)
    plot.addData(**row)
    finer = guard.check(row['balance'])
    if finer > 1:  # as many rows per simulated time as before
        sampler.iterPeriod = max(1, int(round(sampler.iterPeriod * finer)))
    if bf is not None:
        bf.measure(O.time)


meter = OverlapMeter(eng, thickness)


def projectile_ke():
    """The projectile's kinetic energy [J]: translation, and rotation 1/2 w.I w (principal frame)."""
    ke = 0.5 * mass * proj.state.vel.squaredNorm()
    w = proj.state.ori.conjugate() * proj.state.angVel
    rot = 0.5 * sum(proj.state.inertia[k] * w[k] ** 2 for k in range(3))
    return ke + rot if rot != 0 else ke
pk = ply.pack
pack_start = None
if pk is not None:
    # Built without overlap, checked at step 0: the clear gap between neighbouring plies (their
    # sections' reach along z) and the largest CP overlap in the whole pack after settling.
    elems_per_ply = pk.elements[0][1]
    gaps = woven.pack.clear_gaps(eng, pk)
    pack_start = {'clear_gap_min': min(gaps), 'clear_gap_max': max(gaps), 'overlap': eng.overlap(),
                  'pitch': pk.pitch, 'angles': pk.angles}
    state['ply_touched'], state['touching'] = [False] * pk.plies, []


def watch():
    """Every step: deepest nose position, overlaps, perforation / arrest, progress line, mirror."""
    state['step_end'] = time.time()  # the loop's wall time ends at the last step (see below)
    if O.iter == 1:
        places0.update(woven.ballistic.crossing_places(eng))
    meter.sample()
    s = eng.collision_stats()
    state['min_nose'] = min(state['min_nose'], nose_z())
    if pk is not None and s['body_contacts'] > 0:  # which plies the projectile touches (the pack's books)
        plies_now = np.unique(woven.body_contacts(eng)['cp'] // elems_per_ply)
        state['touching'] = [int(k) for k in plies_now]
        for k in plies_now:
            state['ply_touched'][k] = True
    if s['body_contacts'] > 0:
        state['contact_seen'] = True
        state['clear'] = 0
    else:
        state['clear'] += 1
    # Steps since the projectile's speed last changed by more than 1e-4 V: pieces of broken yarn may
    # ride on it (contacts, but no more braking).
    vz = proj.state.vel[2]
    if abs(vz - state['vz_ref']) > 1e-4 * p.V:
        state['vz_ref'], state['steady'] = vz, 0
    else:
        state['steady'] += 1
    rear = proj.state.pos[2] + high
    through = rear < ply.z_exit - thickness
    if state['contact_seen'] and through and (state['clear'] >= p.clear_steps or state['steady'] >= p.clear_steps):
        state['outcome'] = 'perforated'
    elif state['contact_seen'] and proj.state.vel[2] >= 0:
        state['outcome'] = 'arrested'
    if p.mirror_every > 0 and O.iter % p.mirror_every == 0:
        t0 = time.time()
        mirror()
        state['mirror_seconds'] += time.time() - t0
    if p.progress > 0 and time.time() - state['last_progress'] >= p.progress:
        state['last_progress'] = time.time()
        print('ballistic: t = %.2f us of %.2f, vz = %.1f m/s, contacts %d (projectile %d), broken %d, wall %.0f s'
              % (O.time * 1e6, p.t_end * 1e6, proj.state.vel[2], s['contacts'], s['body_contacts'],
                 eng.broken_elements, time.time() - state['wall0']))
        sys.stdout.flush()
    if shots is not None:
        shots.due(O.time)
    if bf is not None and bf.dense():
        bf.measure(O.time)
    if (p.stop and state['outcome'] != 'running') or O.time + O.dt >= p.t_end * (1 - 1e-12):
        O.pause()


vtk_rec = None
if p.vtk_every >= 0:
    from woven.vtk_output import Recorder
    vtk_rec = Recorder(os.path.join(d, 'vtk'), eng, rings=p.vtk_rings)
    vtk_rec.write(0.0)


# The strain front's level: a fixed one lags where the impact strains the yarn little (at 50 m/s
# Smith's strain is 7e-4, and a 5e-4 front ran at half the wave speed while the strain built up).
_yarn = eng.yarn(w.warp_yarns[0])
backface_strain = p.backface_strain or 0.1 * woven.theory.smith(p.V, _yarn['E'], _yarn['rho'])['strain']
bf = woven.backface.BackFace(w, X0, ply.centre, (0, 0, -1), p.backface_w, backface_strain,
                             dense_radius=0.4 * min(np.ptp(X0[:, 0]), np.ptp(X0[:, 1]))) if p.backface else None
shots = woven.render.Pictures(eng, d, p.t_end, p.pictures, p.vtk_rings) if p.pictures > 0 else None


def vtk_frame():
    vtk_rec.write(O.time)


import __main__
__main__.sample, __main__.watch, __main__.vtk_frame = sample, watch, vtk_frame
sampler = PyRunner(command='sample()', iterPeriod=every)
O.engines = O.engines + [PyRunner(command='watch()', iterPeriod=1), sampler]
if vtk_rec is not None and p.vtk_every > 0:
    O.engines = O.engines + [PyRunner(command='vtk_frame()', iterPeriod=p.vtk_every)]

status = 'ok'
wall0, cpu0 = time.time(), time.process_time()
try:
    O.run(steps_max, True)
except RuntimeError as ex:
    status = 'unstable' if isinstance(woven.engine.last_error, woven.InstabilityError) else 'failed'
    print('ballistic: run stopped:', woven.engine.last_error or ex)
    eng.save_state(os.path.join(d, 'last_good.state'), last_good=True)
# The time loop's wall time, to the end of its last step: O.run(n, True) returns on YADE's 40 ms poll
# (measured: up to 39 ms late), up to 12 % of a 0.3 s run (compare.py's coarse cases).
wall = state.get('step_end', time.time()) - wall0
cpu = time.process_time() - cpu0  # this process's CPU time: less sensitive than wall to a shared machine
if state['outcome'] == 'running':
    state['outcome'] = 'no perforation by t_end'
sample()
if vtk_rec is not None:
    vtk_rec.write(O.time)

# --- results ---
E = eng.energy()
stats = eng.collision_stats()
v_res = -proj.state.vel[2]
ke_p = projectile_ke()
absorbed = KE0 - ke_p
balance = rows[-1]['balance']
perforated = state['outcome'] == 'perforated'
keys = list(rows[0].keys())
S = np.array([[r[k] for k in keys] for r in rows])
savetxt(os.path.join(d, 'series.csv'), S, delimiter=',', comments='', header=','.join(keys))
with atomic_path(os.path.join(d, 'series.txt')) as tmp:  # YADE's writer, atomically
    plot.saveDataTxt(tmp)
log = eng.break_log()
with atomic_open(os.path.join(d, 'breaks.csv')) as f:
    f.write('time_s,step,yarn,element,x_m,y_m,z_m,filtered_strain,raw_strain,energy_J\n')
    for b in log:
        f.write('%.9g,%d,%d,%d,%.9g,%.9g,%.9g,%.6g,%.6g,%.6g\n' % (b['time'], b['step'], b['yarn'], b['element'],
                b['position'][0], b['position'][1], b['position'][2], b['strain'], b['raw_strain'], b['energy']))

cp_steps = eng.n_elements * O.iter
phases = {k[8:]: stats[k] for k in stats if k.startswith('seconds_')}
if bf is not None:
    phases['backface'] = bf.seconds  # the back-face measures, inside the run's wall time
phases['integration_and_rest'] = max(0.0, wall - sum(phases.values()))
measured = {
    'outcome': state['outcome'], 'perforated': perforated,
    'residual_velocity': v_res if perforated else 0.0, 'projectile_velocity_end': v_res,
    'projectile_speed_end': proj.state.vel.norm(),  # |v| (the velocities above are along -z: oblique flights)
    'absorbed_energy': absorbed, 'energy_balance_error': balance,
    'max_penetration': z_mid - state['min_nose'],
    'broken_elements': eng.broken_elements, 'broken_yarns': eng.broken_yarns,
    'first_break_time': log[0]['time'] if log else None,
    'simulated_time': O.time, 'steps': O.iter, 'dt': O.dt, 'yarns': eng.n_yarns, 'cps': eng.n_elements,
    'dt_crit': eng.dt_crit, 'substeps': eng.substeps, 'multirate': int(eng.multirate), 'fabric_steps': eng.iter,
    'fine_radius': weave_args['fine_radius'], 'fine_spans': w.summary['fine_spans'], 'spans': w.summary['spans'],
    'wall_seconds': wall, 'cpu_seconds': cpu, 'cp_steps_per_second': cp_steps / wall if wall > 0 else None,
    'phase_seconds': phases, 'mirror_seconds': state['mirror_seconds'],
    'energy': {'projectile_initial': KE0, 'projectile_final': ke_p, 'fabric_kinetic': E['kinetic'],
               'fabric_elastic': E['elastic'], 'dissipated_impulses': E['contact'], 'friction': E['friction'], 'damped': E['damped'],
               'released_breakage': E['released'], 'fabric_initial': fabric_initial,
               'projection': E['projection']},
    'max_body_penetration': stats['max_body_penetration'], 'max_yarn_penetration': stats['max_penetration'],
    'settle_overlap': settle_left, 'yarn_thickness': thickness,
    # How far the projectile travels in one contact step (O.dt as the run ended) at its impact speed, in yarn
    # thicknesses: with substeps it grows with them (0.55 at 4 substeps, 900 m/s, 4 CPs per span, where
    # the projectile's overlap spikes after breaks reached 0.33 thickness; docs/ballistic.md).
    'contact_step_travel_rel': p.V * O.dt / thickness,
    'overlap': meter.summary(),
    'energy_guard': guard.summary(),
}
measured['max_iterations'] = contact_args['max_iterations']
# Which yarns hold the energy at the end (principal against secondary, by family), how many carry
# load, how far the crossings slipped (docs/ballistic.md, "Friction"; SI).
measured['load_sharing'] = woven.ballistic.load_sharing(eng, X0, ply.centre, 0.5 * size, places0)
if frame_ids:
    # How far the yarn ends were drawn in along the ply (in plane) by the end: the frame's hold
    pull = np.linalg.norm(woven.positions(eng)[ends, :2] - X0[ends, :2], axis=1)
    jaw = O.bodies[frame_ids[0]].state.pos - jaw0
    measured['frame'] = {'kind': p.frame, 'width': p.frame_width, 'gap': p.frame_gap, 'edge': p.frame_edge, 'friction': p.frame_friction,
                         'force': p.frame_force, 'jaw_drop': -float(jaw[2]), 'jaw_drift': float(math.hypot(jaw[0], jaw[1])),
                         'pull_in_max': float(pull.max()), 'pull_in_mean': float(pull.mean())}
else:
    measured['frame'] = {'kind': 'none'}
measured['backing'] = {'kind': p.backing, 'standoff': p.backing_standoff if backing_id is not None else None,
                       'z': float(O.bodies[backing_id].state.pos[2]) if backing_id is not None else None}
measured['projectile'] = {'shape': p.shape, 'mass': mass, 'size': size, 'yaw': p.yaw, 'obliquity': p.obliquity,
                          'inertia': list(proj.state.inertia), 'start_reach_below': low, 'start_reach_above': high}
if solid is not None and p.shape == 'mesh':
    measured['projectile'].update({'mesh': solid['file'], 'triangles': solid['count'], 'radius': solid['radius'],
                                   'half_length': solid['half_length'], 'volume': solid['volume'],
                                   'solid_mass': solid['mass'], 'mesh_scale': p.mesh_scale, 'nose_axis': p.nose_axis})
elif solid is not None:
    measured['projectile'].update({k: solid[k] for k in ('radius', 'half_length', 'chisel_angle', 'land_half_width',
                                                         'density', 'volume', 'centroid_z')})
    measured['projectile']['solid_mass'] = solid['mass']
if pk is not None:
    books = woven.pack.ply_books(eng, pk)
    # The ply that stopped the projectile: once it is arrested, the deepest ply it touches (the plies
    # above it are perforated or pushed aside; those below are pushed by the ply above, not by the
    # projectile); none when it perforated the pack or still moves on at t_end.
    deepest = max(state['touching']) if state['touching'] else None
    stopper = deepest if state['outcome'] == 'arrested' else None
    for k, b in enumerate(books):
        b['angle'] = pk.angles[k]
        b['touched_by_projectile'] = state['ply_touched'][k]
    measured['pack'] = {'plies': pk.plies, 'pitch': pk.pitch, 'start': pack_start, 'per_ply': books,
                        'stopped_by_ply': stopper, 'deepest_ply_in_contact_at_end': deepest,
                        'shared': {'dissipated_impulses': E['contact'], 'damped': E['damped'],
                                   'projection': E['projection'], 'work_of_loads': E['work'] - E['body_work']},
                        'sum_absorbed_per_ply': sum(b['absorbed'] for b in books),
                        'areal_density': w.summary['areal_density']}
info = eng.yarn(w.warp_yarns[0])
failure_strain = p.break_strain if p.break_strain > 0 else info['failure_strain']  # the engine's reading (<= 0: the material's)
reference = {'v50_km2_706_single_ply_022_rcc': [90.0, 100.0],  # physics-reference.md (Nilakantan et al.)
             'smith_strain_at_V': woven.theory.smith(p.V, info['E'], info['rho'])['strain'],
             'smith_critical_velocity': woven.theory.smith_critical_velocity(failure_strain,
                                                                            info['E'], info['rho']),
             'failure_strain': failure_strain}
units = {'projectile_speed_end': 'm/s', 'projectile': 'kg, m, deg, kg m^2, kg/m^3, m^3, rad (chisel_angle)',
         'pack': 'J, m, deg (per_ply: energies at the end of the run; shared: entries not split by ply)',
         'residual_velocity': 'm/s', 'projectile_velocity_end': 'm/s', 'absorbed_energy': 'J', 'max_penetration': 'm',
         'simulated_time': 's', 'dt': 's', 'dt_crit': 's', 'fine_radius': 'm', 'wall_seconds': 's', 'cpu_seconds': 's', 'cp_steps_per_second': '1/s', 'phase_seconds': 's',
         'energy': 'J', 'energy_balance_error': 'fraction of the projectile\'s initial kinetic energy',
         'max_body_penetration': 'm', 'max_yarn_penetration': 'm', 'overlap': woven.overlap.UNITS, 'yarn_thickness': 'm', 'contact_step_travel_rel': 'yarn thicknesses', 'first_break_time': 's', 'mirror_seconds': 's',
         'pictures_seconds': 's'}
if pk is not None:
    checks_pack = {'pack_built_apart': {
        'value': pack_start['clear_gap_min'], 'limit': 0.0, 'passed': bool(pack_start['clear_gap_min'] >= 0),
        'what': 'smallest clear gap between neighbouring plies at step 0 (sections\' reach along z) [m]'}}
checks = {'energy_balance': {'value': balance, 'limit': p.energy_limit, 'passed': bool(abs(balance) <= p.energy_limit),
                             'what': '(final kinetic + elastic + dissipated + released - initial) / initial kinetic energy'},
          'momentum_direction': {'value': v_res, 'limit': p.V, 'passed': bool(v_res <= p.V * (1 + 1e-9)),
                                 'what': 'the fabric only slows the projectile'}}
if pk is not None:
    checks.update(checks_pack)
if p.contact_model == 'gap':  # the paper's response lets yarns into each other: its overlap is reported, not checked
    # Checked up to the first broken element; after it, broken pieces whipping at 1000 m/s can read
    # a little more (contact_sweep.py checks whole runs: docs/collisions.md), reported as
    # yarn_max_rel / body_max_rel.
    ov = measured['overlap']
    worst = max(ov['yarn_max_before_break_rel'], ov['body_max_before_break_rel'])
    checks['overlap'] = {'value': worst, 'limit': p.overlap_limit, 'passed': bool(worst <= p.overlap_limit),
                         'what': 'largest yarn-yarn and projectile-yarn overlap after flattening, until the first '
                                 'broken element, / yarn thickness'}

if bf is not None:
    S_t, S_v = np.array([r['t'] for r in rows]), np.array([r['vz'] for r in rows])
    bf_m, bf_r, bf_c = woven.backface.compare(bf, S_t, S_v, 0.5 * size,
                                              0.5 * min(np.ptp(X0[:, 0]), np.ptp(X0[:, 1])), info['E'], info['rho'],
                                              t_max=log[0]['time'] if log else None, tolerance=p.front_tolerance,
                                              friction=p.friction)
    measured['backface'], reference['backface'] = bf_m, bf_r
    units['backface'] = dict(woven.backface.UNITS, apex_depth_end='m', base_radius_end='m', strain_front_speed='m/s',
                             transverse_front_speed='m/s', base_radius_speed='m/s')
    # The fronts are fitted over the windows the ply leaves them: on a 12.7 mm ply or at 1000 m/s a
    # few samples, and the comparison is then 10-70 % off (contact_sweep.py's scenes). A run's
    # status rests on them only when asked.
    if p.front_check:
        checks.update(bf_c)
    else:
        bf_m['front_checks'] = bf_c
    woven.backface.write_series(bf, os.path.join(d, 'backface.csv'))
    woven.backface.chart(bf, os.path.join(d, 'backface.png'), bf_m, bf_r,
                         '%s %.3g g at %.0f m/s' % (p.shape, p.mass * 1e3, p.V))
if shots is not None:
    # Pictures are an extra: one that cannot be rendered (no X server, xvfb-run failing to start one:
    # seen in a test run here, beside a stale Xvfb) is reported, and the run's figures and status stand.
    try:
        t_pic = time.time()
        measured['pictures'] = shots.finish(O.time, failure_strain)
        measured['pictures_seconds'] = time.time() - t_pic
    except (RuntimeError, OSError, subprocess.TimeoutExpired) as ex:
        print('ballistic: WARNING: pictures failed (the run stands):', ex)
        measured['pictures'], measured['pictures_error'] = [], str(ex)

import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt
col = {k: i for i, k in enumerate(keys)}
t_us = S[:, col['t']] * 1e6
fig, ax = plt.subplots(2, 2, figsize=(12, 8))
ax[0, 0].plot(t_us, -S[:, col['vz']], 'k-')
ax[0, 0].set_ylabel('projectile velocity [m/s]')
ax[0, 0].set_title('%s %.3g g at %.0f m/s: %s' % (p.shape, mass * 1e3, p.V, state['outcome']))
for k, lab in (('ke_projectile', 'projectile kinetic'), ('ke_fabric', 'fabric kinetic'), ('elastic', 'fabric elastic'),
               ('dissipated_impulses', 'dissipated by impulses'), ('friction', 'work of friction'),
               ('released', 'released by breakage')):
    ax[0, 1].plot(t_us, S[:, col[k]], label=lab)
ax[0, 1].set_ylabel('energy [J]')
ax[0, 1].legend(fontsize=8)
ax[1, 0].plot(t_us, 100 * S[:, col['overlap']] / thickness, label='yarn-yarn overlap')
ax[1, 0].plot(t_us, 100 * S[:, col['body_overlap']] / thickness, label='projectile-yarn overlap')
ax[1, 0].set_ylabel('largest overlap [% of yarn thickness]')
ax[1, 0].legend(fontsize=8, loc='upper left')
ax10 = ax[1, 0].twinx()  # counts on their own axis (18 000 yarn contacts flatten the others)
ax10.plot(t_us, S[:, col['body_contacts']], 'g:', label='projectile contacts')
ax10.plot(t_us, S[:, col['broken']], 'k:', label='broken elements')
ax10.set_ylabel('count')
ax10.legend(fontsize=8, loc='upper right')
ax[1, 0].set_xlabel('time [us]')
ax[1, 1].plot(t_us, 100 * S[:, col['balance']], 'r-')
ax[1, 1].set_ylabel('energy balance error [% of initial kinetic]')
ax[1, 1].set_xlabel('time [us]')
fig.tight_layout()
savefig(fig, os.path.join(d, 'ballistic.png'), dpi=100)

if status == 'ok' and not all(c['passed'] for c in checks.values()):
    status = 'failed'
write_summary(d, 'ballistic', p, measured, reference, units, status, checks)
if perforated:
    what = 'perforated, residual velocity %.1f m/s' % v_res
else:
    what = '%s: the projectile did not perforate (velocity %.1f m/s at t = %.1f us, deepest %.2f mm)' % (
        state['outcome'], v_res, O.time * 1e6, 1e3 * measured['max_penetration'])
print('ballistic: %s; %s; absorbed %.4g J, energy balance error %.2g %%, broken %d elements in %d yarns; '
      '%.1f us in %.1f s (%.3g CP-steps/s) -> %s' % (status, what, absorbed, 100 * balance, eng.broken_elements,
                                                   eng.broken_yarns, O.time * 1e6, wall, cp_steps / max(wall, 1e-9), d))
if status != 'ok':
    sys.exit(1)
