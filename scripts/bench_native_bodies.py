# What it would cost to put woven's yarn nodes into YADE as bodies, measured in one process:
#   yade -n -x scripts/bench_native_bodies.py [n=20000] [iters=200] [out=DIR]
# Times per iteration, per node (docs/yade_native.md, "How much of the fabric is YADE bodies"):
#   yade_newton     n Sphere bodies, ForceResetter + NewtonIntegrator only (the least YADE does per body)
#   yade_collide    the same with InsertionSortCollider + InteractionLoop (no contacts: bodies apart)
#   woven_chain     n nodes of woven chains (yarns of 1000 nodes) through the engine woven.attach puts in
#   woven_contacts  a weave of about n nodes with collisions on (broad, narrow phase, impulses)
# and the bytes per body YADE allocates (Body, State, Sphere, Aabb and their shared pointers) against
# woven's per node.
import time

import numpy as np

import woven
from woven.params import read_params
from woven.output import out_dir, write_summary

p = read_params({'n': (20000, '', 'nodes / bodies'), 'iters': (200, '', 'iterations per figure'),
                 'out': ('', '', 'output folder (default out/bench_native_bodies)')})
d = out_dir('bench_native_bodies', p)


def timed(iters):
    t = time.perf_counter()
    O.run(iters, True)
    return (time.perf_counter() - t) / iters * 1e6


def yade_bodies(collide):
    O.reset()
    side = int(np.ceil(p.n ** (1 / 3)))
    r = 1e-4
    O.bodies.append([utils.sphere((3 * r * (i % side), 3 * r * ((i // side) % side), 3 * r * (i // side ** 2)), r,
                                  fixed=False) for i in range(p.n)])
    eng = [ForceResetter()]
    if collide:
        eng += [InsertionSortCollider([Bo1_Sphere_Aabb()]),
                InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_FrictPhys()],
                                [Law2_ScGeom_FrictPhys_CundallStrack()])]
    eng += [NewtonIntegrator(damping=0)]
    O.engines = eng
    O.dt = 1e-8
    O.run(2, True)  # first collider pass, allocations
    return timed(p.iters) / p.n


def woven_chains():
    O.reset()
    O.engines = []
    f = woven.Fabric()
    per = 1000
    for k in range(max(1, p.n // per)):
        f.add_yarn([Vector3(1e-4 * i, 1e-3 * k, 0) for i in range(per)], woven.YarnMaterial(), woven.YarnSection())
    e = woven.FabricEngine(f)
    for k in range(e.n_yarns):
        info = e.yarn(k)
        e.prescribe_velocity(info['first_node'] + info['n_nodes'] - 1, Vector3(1, 0.5, 0))
    kind = type(woven.attach(e)).__name__
    O.run(2, True)
    return timed(p.iters) / e.n_nodes, kind, e.n_nodes


def woven_weave():
    O.reset()
    O.engines = []
    side = max(2, int(round(np.sqrt(p.n / 8.0 / 2))))  # about n nodes with cp_per_span 4
    w = woven.weave(nx=side, ny=side, cp_per_span=4)
    e = w.engine
    woven.contact.enable(e)
    e.settle_sections()
    for y in w.warp_yarns:
        info = e.yarn(y)
        e.fix(info['first_node'])
        e.prescribe_velocity(info['first_node'] + info['n_nodes'] - 1, Vector3(1.0, 0, 0))
    woven.attach(e)
    O.run(2, True)
    return timed(p.iters) / e.n_nodes, e.n_nodes


newton = yade_bodies(False)
collide = yade_bodies(True)
chain, kind, nchain = woven_chains()
weave, nweave = woven_weave()
# Bytes YADE allocates per sphere body (tests/yade/abi_sizes.py measured these sizes in libyade):
# Body 176, State 320, Sphere 104, Aabb 144, and 4 shared_ptr control blocks (~24 each).
yade_bytes = 176 + 320 + 104 + 144 + 4 * 24
res = {'yade_newton_us_per_body': newton, 'yade_collide_us_per_body': collide,
       'woven_chain_us_per_node': chain, 'woven_contacts_us_per_node': weave,
       'yade_over_woven_chain': newton / chain, 'yade_bytes_per_body': yade_bytes,
       'woven_engine': kind, 'woven_chain_nodes': nchain, 'woven_weave_nodes': nweave}
for k, v in res.items():
    print('bench_native_bodies: %-28s %s' % (k, ('%.4f' % v) if isinstance(v, float) else v))
write_summary(d, 'bench_native_bodies', p, res, {}, {k: ('us' if '_us_' in k else '-') for k in res}, 'ok')
