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
