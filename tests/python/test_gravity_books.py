"""A YADE body resting on a fabric under YADE's gravity: the energy books count the body's
kinetic energy at its synchronised velocity, from the kick YADE's NewtonIntegrator gave it between
two woven steps (RigidBody::hostKick). The oracle is YADE's side of the body: gravity's work along
its path less its kinetic energy gain is what it did on the fabric. tests/cpp/test_gravity_books.cpp
has a fabric resting on a box under gravity, and the same body with the host played by the test."""
import pytest


def test_cube_resting_on_a_fabric_under_yade_gravity(yade_ns):
    import woven
    from yade import utils, Vector3, NewtonIntegrator, ForceResetter
    O = yade_ns.O
    O.reset()
    g = Vector3(0, 0, -9.81)
    # a taut layer: four straight round yarns (r = 0.1 mm, 12 CPs of 0.25 mm, 0.4 mm apart), their
    # ends pulled out by 0.1 % (4.2 N) and clamped; no gravity on it (it waits for the cube)
    f = woven.Fabric()
    m, sec = woven.YarnMaterial(), woven.YarnSection()
    m.damping = 0.1
    sec.width = sec.thickness = 2e-4
    for y in range(4):
        f.add_yarn([Vector3(i * 0.25e-3, y * 0.4e-3, 0) for i in range(13)], m, sec)
    e = woven.FabricEngine(f)
    for y in range(4):
        a, b = 13 * y, 13 * y + 12
        e.set_pos(a, e.pos(a) - Vector3(1.5e-6, 0, 0))
        e.set_pos(b, e.pos(b) + Vector3(1.5e-6, 0, 0))
        e.fix(a)
        e.fix(b)
    woven.contact.enable(e)
    # a 1 g, 1 mm cube 20 nm above the middle two yarns, under YADE's gravity
    M = 1e-3
    cube = utils.box(center=(1.5e-3, 0.6e-3, 1e-4 + 2e-8 + 0.5e-3), extents=(0.5e-3, 0.5e-3, 0.5e-3))
    cube.state.mass = M
    cube.state.inertia = Vector3(1, 1, 1) * (M * 1e-6 / 6)
    cid = O.bodies.append(cube)
    woven.coupling.couple(e, [cid])
    O.engines = [ForceResetter(), NewtonIntegrator(gravity=g, damping=0.0)]
    woven.attach(e)
    dt = O.dt
    s = O.bodies[cid].state
    # YADE's leapfrog: the synchronised velocity is the half-step one plus half the next kick
    ke0 = 0.5 * M * (s.vel + 0.5 * dt * g).squaredNorm()
    z0 = s.pos[2]
    O.run(10000, True)
    books = e.energy()
    w = s.angVel
    ke1 = 0.5 * M * (s.vel + 0.5 * dt * g).squaredNorm() + 0.5 * sum(s.inertia[k] * w[k] ** 2 for k in range(3))
    gravity_work = M * 9.81 * (z0 - s.pos[2])
    lost = gravity_work - (ke1 - ke0)
    assert gravity_work > 0 and books['body_work'] > 0.1 * gravity_work, 'the cube came down onto the yarns'
    # to 1e-6 of the potential energy the cube turned over (counted at its half-step velocities: 9e-6)
    assert books['body_work'] == pytest.approx(lost, abs=1e-6 * gravity_work), (books['body_work'], lost, gravity_work)
