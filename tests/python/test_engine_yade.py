"""The FabricEngine inside YADE's loop: O.dt and O.iter stay the clock, a too-large O.dt is refused
before anything moves, an instability stops the run naming step, node and cause, and the last good
state can be saved and loaded back bit for bit."""
import math

import numpy as np
import pytest


def chain(n=50, L=0.05, damping=0.0):
    import woven
    from yade import Vector3
    m = woven.YarnMaterial()
    m.damping = damping
    f = woven.Fabric()
    f.add_yarn([Vector3(L * i / n, 0, 0) for i in range(n + 1)], m, woven.YarnSection())
    return woven.FabricEngine(f)


def test_clock_and_dt(yade_ns):
    import woven
    O = yade_ns.O
    O.reset()
    O.engines = []
    e = chain()
    l0 = 0.05 / 50
    assert e.dt_crit == pytest.approx(l0 * math.sqrt(1440 / 90e9), rel=1e-12)
    woven.attach(e, set_dt=True, safety=0.9)
    assert O.dt == pytest.approx(0.9 * e.dt_crit, rel=1e-15)
    e.fix(0)
    e.prescribe_velocity(50, yade_ns.Vector3(1.0, 0, 0))
    O.run(25, True)
    assert O.iter == e.iter == 25 and e.time == pytest.approx(O.time, rel=1e-12)
    # the driven end moved exactly V * t
    assert e.pos(50)[0] == pytest.approx(0.05 + 1.0 * O.time, rel=1e-12)


def test_too_large_dt_refused_before_any_step(yade_ns):
    import woven
    O = yade_ns.O
    O.reset()
    O.engines = []
    e = chain()
    O.dt = 1.01 * e.dt_crit
    with pytest.raises(ValueError, match='dt'):
        woven.attach(e, set_dt=False)
    woven.attach(e, set_dt=True)
    O.dt = 1.01 * e.dt_crit  # changed behind the engine's back: refused at the next step
    X0 = woven.positions(e).copy()
    e.set_vel(10, yade_ns.Vector3(0, 1, 0))
    with pytest.raises(RuntimeError, match='dt_crit'):
        O.run(5, True)
    assert e.iter == 0 and np.array_equal(woven.positions(e), X0)
    assert isinstance(woven.engine.last_error, ValueError)


def test_default_time_stepper_is_refused(yade_ns):
    import woven
    O = yade_ns.O
    O.reset()  # `yade` starts a scene with default engines, GlobalStiffnessTimeStepper among them
    O.engines = [yade_ns.wrapper.ForceResetter(), yade_ns.wrapper.GlobalStiffnessTimeStepper()]
    with pytest.raises(ValueError, match='GlobalStiffnessTimeStepper'):
        woven.attach(chain())


def test_instability_stops_with_step_node_cause_and_keeps_last_good_state(yade_ns, tmp_path):
    """An energy budget of a quarter of (initial + work) is broken at the first step (the check's
    trigger, not the physics, is what is artificial here): the run must stop, name step, node and
    cause, and keep the last check point."""
    import struct
    import woven
    O = yade_ns.O
    O.reset()
    O.engines = []
    e = chain()
    e.checkpoint_interval = 3
    woven.attach(e)
    e.fix(0)
    e.fix(50)
    for i in range(1, 50):
        e.set_vel(i, yade_ns.Vector3(0.3 * math.sin(math.pi * i / 50), math.sin(math.pi * i / 50), 0))
    e.blowup_factor = 0.25
    with pytest.raises(RuntimeError, match='unstable at step'):
        O.run(500, True)
    err = woven.engine.last_error
    assert isinstance(err, woven.InstabilityError)
    assert 0 < err.step <= 500 and 0 <= err.node <= 50 and 'energy blow-up' in err.cause
    path = tmp_path / 'last_good.state'
    e.save_state(str(path), last_good=True)
    raw = path.read_bytes()
    # format 3, version 5 (pkg/fabric/StateIO.hpp): u32 version, u32 0, u64 fingerprint, int64 nodes, elements,
    # yarns, step, double time, double last dt, positions, ...
    assert raw[:8] == b'WOVENST3'
    version, _, _, n, ne, ny, step = struct.unpack('<IIQqqqq', raw[8:56])
    assert version == 5 and n == 51 and ne == 50 and ny == 1 and step % 3 == 0 and step < err.step
    X = np.frombuffer(raw[72:72 + 51 * 24], dtype='<f8')
    assert np.all(np.isfinite(X))
    e.restore_last_good()
    assert np.array_equal(woven.positions(e).ravel(), X)


def test_state_file_round_trip_is_bit_for_bit(yade_ns, tmp_path):
    import woven
    O = yade_ns.O
    O.reset()
    O.engines = []
    w = woven.weave(nx=2, ny=2)
    e = w.engine
    woven.attach(e)
    e.set_vel(5, yade_ns.Vector3(0, 0, 3.0))
    O.run(40, True)
    path = tmp_path / 's.state'
    e.save_state(str(path))
    w2 = woven.weave(nx=2, ny=2)
    w2.engine.load_state(str(path))
    assert woven.positions(w2.engine).tobytes() == woven.positions(e).tobytes()
    with pytest.raises(ValueError, match='state'):
        woven.weave(nx=1, ny=1).engine.load_state(str(path))


def test_determinism_same_inputs_same_bits(yade_ns):
    import woven
    O = yade_ns.O
    out = []
    for _ in range(2):
        O.reset()
        O.engines = []
        w = woven.weave(nx=2, ny=2)
        woven.attach(w.engine)
        for k, n in enumerate(w.warp_yarns):
            w.engine.fix(w.engine.yarn(n)['first_node'])
            w.engine.prescribe_velocity(w.engine.yarn(n)['first_node'] + w.engine.yarn(n)['n_nodes'] - 1,
                                        yade_ns.Vector3(2.0, 0, 0))
        O.run(200, True)
        out.append(woven.positions(w.engine).tobytes())
    assert out[0] == out[1]
