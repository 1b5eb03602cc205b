"""The scenes' `model=yade` and `model=yade_pfacet` runs: the same fabric in YADE's grid elements
(woven.yade_grid) or PFacet ribbons (woven.yade_pfacet), driven by YADE's own engines, with the same
summary.json figures as the woven runs. SI units.

    yade -n -x scripts/ballistic.py model=yade side=0.0127 t_end=3e-5
    yade -n -x scripts/ballistic.py model=yade_pfacet side=0.0127 t_end=1.5e-5
"""
import math
import sys
import time

import numpy as np
import yade.wrapper
from yade import utils
from yade._minieigenHP import Vector3

from . import yade_grid as yg
from . import yade_pfacet as yp
from .output import savetxt
from .params import check_steps

_O = yade.wrapper.Omega()

MODELS = ('woven', 'yade', 'yade_pfacet')
#: what each YADE model is called in the scenes' progress lines
LABEL = {'yade': 'yade grid', 'yade_pfacet': 'yade pfacet'}


def check_model(p):
    """Raises ValueError naming the key when p['model'] is not 'woven', 'yade' or 'yade_pfacet', or a
    key of the YADE models is out of its range."""
    if p['model'] not in MODELS:
        raise ValueError("model = %r is invalid: allowed 'woven', 'yade' or 'yade_pfacet'" % p['model'])
    # above 1 on purpose: the stability maps (scripts/compare.py) look for the blow-up
    if p['model'] != 'woven' and not (0 < p['dt_factor'] <= 10):
        raise ValueError('dt_factor = %r is invalid: allowed (0, 10]' % p['dt_factor'])
    if 'pfacet_lines' in p:
        lo, hi = yp.LINES_RANGE
        n = p['pfacet_lines']
        if not (isinstance(n, int) and not isinstance(n, bool) and lo <= n <= hi):
            raise ValueError('pfacet_lines = %r is invalid: allowed an integer in [%d, %d] (node lines across a '
                             'ribbon, model=yade_pfacet)' % (n, lo, hi))
    if 'pfacet_projectile' in p and p['pfacet_projectile'] not in ('nodes', 'pfacets'):
        raise ValueError("pfacet_projectile = %r is invalid: allowed 'nodes' or 'pfacets'" % p['pfacet_projectile'])
    if p['model'] == 'yade_pfacet' and p.get('bending'):
        # the ribbon's bonds have no bending springs: its bending is the lines' geometry
        raise ValueError("bending = %r is invalid: allowed 0 with model = 'yade_pfacet' (its bonds have no bending "
                         "springs); 0 or 1 with model = 'yade'" % p['bending'])


def _build(p, e, yarns, failure_strain=0.0):
    """The YADE fabric of p.model (engines set, then built): a GridFabric or a PFacetFabric."""
    if p.model == 'yade_pfacet':
        return yp.build(e, yarns, lines=p.pfacet_lines, kn=p.kn, radius=p.grid_radius, failure_strain=failure_strain,
                        friction=p.friction)
    return yg.build(e, yarns, kn=p.kn, radius=p.grid_radius, bending=p.bending, failure_strain=failure_strain,
                    friction=p.friction)


def _engines(p, damping=0.0):
    return (yp if p.model == 'yade_pfacet' else yg).engines(damping=damping)


def _kinetic(ids):
    """Kinetic energy of bodies `ids` [J], translation and rotation."""
    s = 0.0
    for i in ids:
        st = _O.bodies[i].state
        s += 0.5 * st.mass * st.vel.squaredNorm()
        w, I = st.angVel, st.inertia
        s += 0.5 * (I[0] * w[0] ** 2 + I[1] * w[1] ** 2 + I[2] * w[2] ** 2)
    return s


def _elastic():
    """Elastic energy [J] stored in the bonds (normal) and in the contacts (normal + shear) now."""
    bonds, contacts = 0.0, 0.0
    for i in _O.interactions:
        ph = i.phys
        if isinstance(i.geom, yade.wrapper.GridNodeGeom6D):
            un = i.geom.penetrationDepth - ph.unp
            bonds += 0.5 * ph.kn * un * un
            if ph.ks > 0:
                bonds += 0.5 * ph.shearForce.squaredNorm() / ph.ks
        elif ph.kn > 0:
            contacts += 0.5 * ph.normalForce.squaredNorm() / ph.kn
            if ph.ks > 0:
                contacts += 0.5 * ph.shearForce.squaredNorm() / ph.ks
    return bonds, contacts


def ballistic(p, d, weave_keys, contact_keys):
    """The ballistic scene of scripts/ballistic.py in grid elements or PFacet ribbons (p.model): the
    same ply (built by woven, then mapped), clamped edges as held end nodes, a YADE Sphere or Box of
    the same mass, size and speed. Writes d/summary.json and d/series.csv; returns the process exit
    status."""
    import woven.ballistic
    from .output import write_summary
    from . import theory
    O = _O
    O.engines = []
    O.bodies.clear()
    O.interactions.clear()
    ply = woven.ballistic.build_ply({k: p[k] for k in weave_keys}, {k: p[k] for k in contact_keys}, side=p.side, clamp=0)
    w, e = ply.weave, ply.engine
    info = e.yarn(w.warp_yarns[0])
    eps_f = p.break_strain or info['failure_strain']
    label = LABEL[p.model]
    O.engines = _engines(p)
    t0 = time.time()
    g = _build(p, e, w.warp_yarns + w.weft_yarns, failure_strain=eps_f)
    lines = getattr(g, 'lines_per_yarn', 1)  # a ribbon's line bond carries 1/lines of the yarn's force
    n_warp = len(w.warp_yarns)
    if p.clamp == 4:
        g.fix_ends()
    elif p.clamp == 2:
        g.fix_ends(range(n_warp))
    build_seconds = time.time() - t0
    X = np.array([list(O.bodies[i].state.pos) for i in g.node_ids()])
    centre = X.mean(axis=0)
    z_mid = float(np.median(X[:, 2]))
    z_top = float(X[:, 2].max()) + g.radius
    half = 0.5 * p.size
    start = Vector3(centre[0], centre[1], z_top + half + p.standoff)
    mat = (yp if p.model == 'yade_pfacet' else yg).projectile_material(g, p.shape, p.size)
    if p.shape == 'box':
        body = utils.box(start, (half, half, half), fixed=False, material=mat)
        body.mask = yg.BOX_MASK
        inertia = p.mass * p.size ** 2 / 6
    else:
        body = utils.sphere(start, half, fixed=False, material=mat)
        # a grid's sphere meets the connections; a ribbon's its nodes (pfacet_projectile=nodes, as a box
        # does) or its PFacets
        on_nodes = p.model == 'yade_pfacet' and p.pfacet_projectile == 'nodes'
        body.mask = yg.BOX_MASK if on_nodes else yg.CONNECTION_MASK
        inertia = 0.4 * p.mass * half ** 2
    pid = O.bodies.append(body)
    proj = O.bodies[pid]
    proj.state.mass = p.mass
    proj.state.inertia = Vector3(inertia, inertia, inertia)
    proj.state.vel = Vector3(0, 0, -p.V)
    O.dt = g.stable_dt(p.dt_factor)
    O.trackEnergy = True
    check_steps(p.t_end, O.dt, 'dt_factor', p.dt_factor, 't_end')
    steps_max = int(math.ceil(p.t_end / O.dt))
    every = max(1, steps_max // p.samples)
    node_ids = g.node_ids()
    KE0 = 0.5 * p.mass * p.V ** 2
    v_blow = 5 * p.V + 2 * math.sqrt(info['E'] / info['rho']) * eps_f  # (sample(): the blow-up check)
    st = {'contact_seen': False, 'clear': 0, 'steady': 0, 'vz_ref': -p.V, 'outcome': 'running',
          'min_nose': float('inf'), 'max_overlap': 0.0, 'max_body': 0.0, 'max_node_speed': 0.0, 'unstable': '', 'released': 0.0, 'last_progress': time.time(), 'wall0': time.time()}
    rows = []
    law = [f for f in O.engines if isinstance(f, yade.wrapper.InteractionLoop)][0]

    def projectile_contacts():
        """Number of real projectile contacts now; keeps the deepest one's penetrationDepth [m]."""
        n = 0
        for i in O.interactions.withBody(pid):
            if i.isReal:
                n += 1
                st['max_body'] = max(st['max_body'], i.geom.penetrationDepth)
        return n

    def blow_up(why):
        # the scene's 'unstable' status (woven's InstabilityError): stop at once
        if not st['unstable']:
            st['unstable'] = why
            print('ballistic (%s): unstable at t = %.3g us: %s' % (label, O.time * 1e6, why))
        O.pause()

    def check_breaks():
        # a bond that broke since the last check took its elastic energy with it: released, as
        # woven's books count it (its force was about E*A*eps_f, on a ribbon's line E*A*eps_f/lines,
        # when it went)
        n = g.remove_broken()
        if n:
            st['released'] += n * 0.5 * (info['E'] * info['area'] * eps_f / lines) ** 2 / float(np.mean(g.K[0]))

    def sample():
        ke_p = 0.5 * p.mass * proj.state.vel.squaredNorm()
        ke_f = _kinetic(node_ids)
        el_b, el_c = _elastic()
        ov = g.max_overlap()
        st['max_overlap'] = max(st['max_overlap'], ov)
        books = dict(O.energy.items())
        dissip = sum(v for k, v in books.items() if k in ('plastDissip', 'nonviscDamp', 'viscDamp'))
        # the balance from YADE's own books (O.trackEnergy: NewtonIntegrator's kinetic energy, the
        # contact laws' elastPotential and dissipation) plus what they do not book: the elastic
        # energy of the cohesive bonds and the energy the broken bonds took with them
        kin = books.get('kinetic', ke_p + ke_f)  # empty before the first step
        el_c_books = books.get('elastPotential', el_c)
        balance = (kin + el_c_books + el_b + dissip + st['released'] - KE0) / KE0
        # a blow-up: energy created, or (the fragile bonds break and cap the energy) a node faster
        # than the largest speed a stable impact gives: a few times the projectile's, plus twice the
        # speed c*eps_f at which a line's end snaps back when its bond breaks (the ribbons' cut ends
        # reached 5.6 V at 200 m/s with the energy books closed to 0.05 %)
        vmax = max(O.bodies[i].state.vel.norm() for i in node_ids)
        st['max_node_speed'] = max(st['max_node_speed'], vmax)
        if not (math.isfinite(balance) and math.isfinite(vmax)) or balance > 1:
            blow_up('energy %s times the projectile\'s initial kinetic energy' % (balance + 1))
        elif vmax > v_blow:
            blow_up('a node at %.3g m/s, %.3g times the impact speed (limit %.3g m/s)' % (vmax, vmax / p.V, v_blow))
        row = dict(t=O.time, vz=proj.state.vel[2], z=proj.state.pos[2], ke_projectile=ke_p, ke_fabric=ke_f,
                   elastic_bonds=el_b, elastic_contacts=el_c, dissipated=dissip, released=st['released'],
                   projectile_contacts=projectile_contacts(), broken=len(g.broken), overlap=ov,
                   balance_own=(ke_p + ke_f + el_b + el_c + dissip + st['released'] - KE0) / KE0, balance=balance)
        rows.append(row)

    def watch():
        st['step_end'] = time.time()  # the loop's wall time ends at the last step (see below)
        st['min_nose'] = min(st['min_nose'], proj.state.pos[2] - half)
        if O.iter % 10 == 0:
            check_breaks()
        nc = projectile_contacts()
        if nc > 0:
            st['contact_seen'], st['clear'] = True, 0
        else:
            st['clear'] += 1
        vz = proj.state.vel[2]
        if not (math.isfinite(vz) and abs(vz) < 10 * p.V):
            blow_up('projectile velocity %s m/s' % vz)
            return
        if abs(vz - st['vz_ref']) > 1e-4 * p.V:
            st['vz_ref'], st['steady'] = vz, 0
        else:
            st['steady'] += 1
        through = proj.state.pos[2] + half < z_mid - 2 * g.radius
        if st['contact_seen'] and through and (st['clear'] >= p.clear_steps or st['steady'] >= p.clear_steps):
            st['outcome'] = 'perforated'
        elif st['contact_seen'] and vz >= 0:
            st['outcome'] = 'arrested'
        if p.progress > 0 and time.time() - st['last_progress'] >= p.progress:
            st['last_progress'] = time.time()
            print('ballistic (%s): t = %.2f us of %.2f, vz = %.1f m/s, projectile contacts %d, broken %d, wall %.0f s'
                  % (label, O.time * 1e6, p.t_end * 1e6, vz, nc, len(g.broken), time.time() - st['wall0']))
            sys.stdout.flush()
        if p.stop and st['outcome'] != 'running':
            O.pause()

    import __main__
    __main__.grid_sample, __main__.grid_watch = sample, watch
    O.engines = O.engines + [yade.wrapper.PyRunner(command='grid_watch()', iterPeriod=1),
                             yade.wrapper.PyRunner(command='grid_sample()', iterPeriod=every)]
    sample()
    status = 'ok'
    wall0 = time.time()
    try:
        O.run(steps_max, True)
    except RuntimeError as ex:
        status = 'failed'
        print('ballistic (%s): run stopped:' % label, ex)
    # To the end of the last step, as woven's scene: O.run(n, True) returns on YADE's 40 ms poll.
    wall = st.get('step_end', time.time()) - wall0
    check_breaks()
    if st['outcome'] == 'running':
        st['outcome'] = 'no perforation by t_end'
    sample()
    if st['unstable']:
        status = 'unstable'
    import os
    keys = list(rows[0].keys())
    S = np.array([[r[k] for k in keys] for r in rows])
    savetxt(os.path.join(d, 'series.csv'), S, delimiter=',', comments='', header=','.join(keys))
    v_res = -proj.state.vel[2]
    ke_p = rows[-1]['ke_projectile']
    perforated = st['outcome'] == 'perforated'
    balance = rows[-1]['balance']
    n_conn = len(g.connection_ids())
    # a grid bond is a yarn gap; a ribbon's gap is cut where one of its lines broke (each listed)
    cut = set((b[0], b[-2]) for b in g.broken)
    measured = {
        'model': p.model, 'outcome': st['outcome'], 'perforated': perforated,
        'residual_velocity': v_res if perforated else 0.0, 'projectile_velocity_end': v_res,
        'absorbed_energy': KE0 - ke_p, 'energy_balance_error': balance,
        'max_penetration': z_mid - st['min_nose'], 'broken_elements': len(cut), 'broken_bonds': len(g.broken),
        'broken_yarns': len(set(b[0] for b in g.broken)),
        'first_break_time': min((b[-1] for b in g.broken), default=None),
        'simulated_time': O.time, 'steps': O.iter, 'dt': O.dt, 'yarns': len(g.nodes), 'grid_nodes': len(node_ids),
        'grid_connections': n_conn, 'pfacets': len(g.pfacet_ids()) if p.model == 'yade_pfacet' else None,
        'pfacet_lines': lines if p.model == 'yade_pfacet' else None, 'wall_seconds': wall, 'build_seconds': build_seconds,
        'wall_seconds_per_simulated_us': wall / max(O.time * 1e6, 1e-30),
        'max_yarn_penetration': st['max_overlap'], 'max_body_penetration': st['max_body'], 'cps': n_conn,
        'max_node_speed': st['max_node_speed'], 'node_speed_limit': v_blow,
        'yarn_thickness': info['thickness'], 'unstable_why': st['unstable'] or None, 'grid_radius': g.radius, 'kn': g.kn,
        'fabric_mass': g.total_mass(), 'woven_fabric_mass': g.woven_mass,
        'energy': {'projectile_initial': KE0, 'projectile_final': ke_p, 'fabric_kinetic': rows[-1]['ke_fabric'],
                   'elastic_bonds': rows[-1]['elastic_bonds'], 'elastic_contacts': rows[-1]['elastic_contacts'],
                   'dissipated': rows[-1]['dissipated'], 'released_breakage': st['released'],
                   'yade_O_energy': dict(O.energy.items())},
    }
    reference = {'v50_km2_706_single_ply_022_rcc': [90.0, 100.0],
                 'smith_strain_at_V': theory.smith(p.V, info['E'], info['rho'])['strain'],
                 'failure_strain': eps_f, 'woven_dt_crit': e.dt_crit}
    units = {'residual_velocity': 'm/s', 'projectile_velocity_end': 'm/s', 'absorbed_energy': 'J', 'max_penetration': 'm',
             'simulated_time': 's', 'dt': 's', 'wall_seconds': 's', 'build_seconds': 's', 'energy': 'J',
             'wall_seconds_per_simulated_us': 's/us', 'energy_balance_error': "fraction of the projectile's initial kinetic energy",
             'max_yarn_penetration': 'm', 'max_body_penetration': 'm', 'yarn_thickness': 'm', 'grid_radius': 'm', 'kn': 'N/m', 'fabric_mass': 'kg', 'woven_fabric_mass': 'kg',
             'first_break_time': 's', 'woven_dt_crit': 's', 'max_node_speed': 'm/s', 'node_speed_limit': 'm/s'}
    checks = {'energy_balance': {'value': balance, 'limit': p.energy_limit, 'passed': bool(abs(balance) <= p.energy_limit),
                                 'what': '(O.energy kinetic + elastPotential + dissipated, + bond elastic + released '
                                         '- initial) / initial kinetic energy'},
              'momentum_direction': {'value': v_res, 'limit': p.V, 'passed': bool(v_res <= p.V * (1 + 1e-9)),
                                     'what': 'the fabric only slows the projectile'},
              'mass': {'value': g.total_mass(), 'limit': g.woven_mass,
                       'passed': bool(abs(g.total_mass() / g.woven_mass - 1) < 1e-9), 'what': 'grid node masses sum to the woven fabric mass'}}
    if status == 'ok' and not all(c['passed'] for c in checks.values()):
        status = 'failed'
    write_summary(d, 'ballistic', p, measured, reference, units, status, checks)
    what = ('perforated, residual velocity %.1f m/s' % v_res) if perforated else \
        '%s (velocity %.1f m/s at t = %.1f us)' % (st['outcome'], v_res, O.time * 1e6)
    print('ballistic (%s): %s; %s; absorbed %.4g J, energy balance error %.2g %%, broken %d bonds; '
          'max yarn overlap %.3g m; %.1f us in %.1f s (%d steps, dt %.3g s) -> %s'
          % (label, status, what, KE0 - ke_p, 100 * balance, len(g.broken), st['max_overlap'], O.time * 1e6, wall, O.iter, O.dt, d))
    return 0 if status == 'ok' else 1


def tension(p, d, weave_args):
    """The tension scene of scripts/tension.py in grid elements or PFacet ribbons (p.model): warp end
    nodes at x_min held, those at x_max pulled along +x at p.velocity (ramped over p.ramp of the run);
    mode=biaxial pulls the weft too. NewtonIntegrator's non-viscous damping is p.damping (YADE's analogue of woven's damping
    ratio, not the same law). Writes curve.csv and summary.json; returns the exit status."""
    import os
    import woven
    from .output import write_summary
    O = _O
    O.engines = []
    O.bodies.clear()
    O.interactions.clear()
    w = woven.weave(**weave_args)
    e = w.engine
    O.engines = _engines(p, damping=p.damping)
    g = _build(p, e, w.warp_yarns + w.weft_yarns)
    nw = len(w.warp_yarns)
    strain_end = p.strain_end if p.strain_end > 0 else w.summary['warp_crimp_built'] + 0.003
    pulled = [(range(nw), 0)] + ([(range(nw, len(g.nodes)), 1)] if p.mode == 'biaxial' else [])
    first, last = [], []
    for yarns, axis in pulled:
        for k in yarns:
            a, b = g.end_nodes(k)  # a grid yarn's end node, or every line's of a ribbon
            for i in a + b:
                O.bodies[i].state.blockedDOFs = 'xyzXYZ'
                O.bodies[i].state.vel = Vector3(0, 0, 0)
            if axis == 0:
                first += a
                last += b
    grips = [(i, axis) for yarns, axis in pulled for k in yarns for i in g.end_nodes(k)[1]]

    def xs(ids):
        return float(np.mean([O.bodies[i].state.pos[0] for i in ids]))

    L = xs(last) - xs(first)
    t_run = strain_end * L / p.velocity * (1 + 0.5 * p.ramp)
    t_ramp = p.ramp * strain_end * L / p.velocity
    O.dt = g.stable_dt(p.dt_factor)
    check_steps(t_run, O.dt, 'dt_factor', p.dt_factor, 'the pull')
    steps = int(math.ceil(t_run / O.dt))
    every = max(1, steps // p.samples)
    rows, st = [], {'max_overlap': 0.0}

    def grip():
        v = p.velocity * min(1.0, O.time / t_ramp) if t_ramp > 0 else p.velocity
        for i, axis in grips:
            O.bodies[i].state.vel = Vector3(v, 0, 0) if axis == 0 else Vector3(0, v, 0)

    def sample():
        ov = g.max_overlap()
        st['max_overlap'] = max(st['max_overlap'], ov)
        force = -sum(O.forces.f(i)[0] for i in last)  # the grips' reaction, positive in tension
        rows.append((O.time, (xs(last) - xs(first)) / L - 1, force, ov))

    import __main__
    __main__.grid_grip, __main__.grid_tsample = grip, sample
    O.engines = [yade.wrapper.PyRunner(command='grid_grip()', iterPeriod=1, initRun=True)] + O.engines + \
        [yade.wrapper.PyRunner(command='grid_tsample()', iterPeriod=every)]
    wall0 = time.time()
    O.run(steps, True)
    wall = time.time() - wall0
    C = np.array(rows)
    savetxt(os.path.join(d, 'curve.csv'), C, delimiter=',', comments='', header='time_s,strain,force_N,overlap_m')
    info = e.yarn(w.warp_yarns[0])
    EA = info['E'] * info['area']
    eps, F = C[:, 1], C[:, 2]
    span = eps.max() - eps.min()
    fin = eps >= eps.max() - p.final_fit * span
    kf, bf = np.polyfit(eps[fin], F[fin], 1)
    toe = -bf / kf if kf > 0 else float('nan')
    thickness = info['thickness']
    measured = {'model': p.model, 'steps': O.iter, 'dt': O.dt, 'strain_end': strain_end, 'grip_distance': L,
                'strain_reached': float(eps.max()), 'force_end': float(F[-1]), 'toe_strain': toe, 'final_stiffness': kf,
                'final_stiffness_per_straight_yarns': kf / (nw * EA), 'max_transient_penetration': st['max_overlap'],
                'final_overlap': float(C[-1, 3]), 'grid_radius': g.radius, 'kn': g.kn, 'wall_seconds': wall,
                'fabric_mass': g.total_mass(), 'woven_fabric_mass': g.woven_mass}
    reference = {'warp_crimp_built': w.summary['warp_crimp_built'], 'straight_yarns_stiffness': nw * EA,
                 'yarn_thickness': thickness, 'grid_diameter': 2 * g.radius}
    units = {'grip_distance': 'm', 'force_end': 'N', 'final_stiffness': 'N', 'straight_yarns_stiffness': 'N',
             'max_transient_penetration': 'm', 'final_overlap': 'm', 'grid_radius': 'm', 'kn': 'N/m', 'dt': 's',
             'wall_seconds': 's', 'yarn_thickness': 'm', 'grid_diameter': 'm', 'fabric_mass': 'kg', 'woven_fabric_mass': 'kg'}
    checks = {'final_overlap': {'value': measured['final_overlap'] / (2 * g.radius), 'limit': p.penetration_limit,
                                'passed': bool(measured['final_overlap'] <= p.penetration_limit * 2 * g.radius),
                                'what': 'largest grid-grid overlap at the end / grid diameter'}}
    status = 'ok' if all(c['passed'] for c in checks.values()) else 'failed'
    write_summary(d, 'tension', p, measured, reference, units, status, checks)
    print('tension (%s): %s; toe %.3f %%, final / (n E A) %.3f, max overlap %.2g m (diameter %.2g m), '
          '%d steps in %.1f s -> %s' % (LABEL[p.model], status, 100 * toe, kf / (nw * EA), st['max_overlap'], 2 * g.radius, O.iter, wall, d))
    return 0 if status == 'ok' else 1
