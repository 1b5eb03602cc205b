"""The weave builder's Python face: counts, YADE Vector3 in and out, errors naming parameters."""
import numpy as np
import pytest


def test_counts_types_and_areal_density(yade_ns):
    import woven
    w = woven.weave(nx=2, ny=3, cp_per_span=4)
    s = w.summary
    assert (s['warp_yarns'], s['weft_yarns']) == (6, 4)  # plain repeat is 2 x 2
    e = w.engine
    assert e.n_yarns == 10 and e.n_nodes == s['nodes']
    # each warp crosses 4 wefts: (4-1)*4 CPs between outer crossings + 2*2 beyond them
    assert e.yarn(w.warp_yarns[0])['n_elements'] == 3 * 4 + 4
    assert type(e.pos(0)).__name__ == 'Vector3'
    # areal density equals the closed form lambda*(1 + crimp)/spacing summed over families
    lam = 1440 * (600 / 9000 * 1e-3) / 1440
    ref = woven.theory.areal_density_plain(lam, 25.4e-3 / 34, s['warp_crimp_built'], lam, 25.4e-3 / 34, s['weft_crimp_built'])
    assert s['areal_density'] == pytest.approx(ref, rel=1e-9)
    assert s['areal_density'] == pytest.approx(0.180, rel=0.01)
    # total node mass = rho*A*(sum of rest lengths)
    assert woven.masses(e).sum() == pytest.approx(lam * woven.rest_lengths(e).sum(), rel=1e-12)


def test_pattern_as_text_matrix(yade_ns):
    import woven
    w = woven.weave(pattern='1,1,0;0,1,1;1,0,1', nx=1, ny=1)
    assert w.pattern.matrix == [[1, 1, 0], [0, 1, 1], [1, 0, 1]]
    assert w.summary['min_vertical_gap'] >= w.summary['required_gap'] - 1e-9


@pytest.mark.parametrize('kw, name', [
    ({'E': -1.0}, 'E'), ({'rho': 0.0}, 'rho'), ({'thickness': -1e-4}, 'thickness'), ({'width': 0.0}, 'width'),
    ({'spacing': 0.5e-3}, 'spacing'), ({'pattern': 'herringbone'}, 'pattern'), ({'pattern': '1,1;1,0'}, 'pattern'),
    ({'cp_per_span': 0}, 'cp_per_span'), ({'nx': 0}, 'nx'), ({'colour': 'red'}, 'colour'),
    ({'crimp': 0.0001}, 'crimp'), ({'pattern': 'satin', 'satin_n': 6, 'satin_step': 2}, 'satin_step'),
    ({'bending_stiffness': 2.0}, 'bending_stiffness'), ({'bending_stiffness': -1e-9}, 'bending_stiffness'),
])
def test_bad_input_names_parameter_and_range(yade_ns, kw, name):
    import woven
    with pytest.raises(ValueError) as e:
        woven.weave(**kw)
    msg = str(e.value)
    assert name in msg and 'allowed' in msg


def test_arrays_are_views_of_the_state(yade_ns):
    import woven
    w = woven.weave()
    X = woven.positions(w.engine)
    i = w.engine.n_nodes // 2
    assert np.allclose(X[i], list(w.engine.pos(i)), rtol=0, atol=0)


def test_bending_weave_is_built_stress_free(yade_ns):
    """With bending_stiffness the crimped weave is its own rest shape: no bending energy and no motion
    as built; pressing one crossing node out of place stores energy, which the books carry as elastic
    and which, released, sets the yarns moving with the books closed."""
    import woven
    w = woven.weave(preset='km2_706', nx=2, ny=2, cp_per_span=2, bending_stiffness=3e-8)
    e = w.engine
    assert e.yarn(0)['bending'] == pytest.approx(3e-8)
    dt = 0.5 * e.dt_crit
    for _ in range(200):
        e.step(dt)
    E = e.energy()
    assert E['elastic'] == 0 and E['kinetic'] == 0
    w2 = woven.weave(preset='km2_706', nx=2, ny=2, cp_per_span=2)
    assert w2.engine.dt_crit > e.dt_crit  # the bending stiffness lowers the stable step
    X = woven.positions(e).copy()
    i = e.yarn(0)['first_node'] + 2
    from yade import Vector3
    e.set_pos(i, Vector3(X[i][0], X[i][1], X[i][2] + 20e-6))
    dt = 0.1 * e.dt_crit  # the leapfrog's books oscillate by O((omega dt)^2): small steps
    e.step(dt)
    E0 = e.energy()
    assert E0['elastic'] > 0
    for _ in range(2000):
        e.step(dt)
    E1 = e.energy()
    assert E1['kinetic'] > 0
    # the hand move is not in the books: their error from the first step on stays within 1 %
    assert abs(E1['balance_error'] - E0['balance_error']) < 1e-2 * (E0['elastic'] + E0['kinetic'])
