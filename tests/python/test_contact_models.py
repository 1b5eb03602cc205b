"""The alternative collision responses and section models (docs/collisions.md, "Response and section
models"): penalty forces against the mass-spring theory, their stability limit shown not hidden,
sections that never flatten; bad values name the key. (No test yet of the section springs'
force: a head-on pair is stopped by the impulses before it flattens.)"""
import math

import numpy as np
import pytest

import woven
from yade import Vector3


def pair(v=1.0, **kw):
    """Two free one-element yarns crossing at right angles, 2 um apart, closing head-on at v [m/s]."""
    m, s = woven.YarnMaterial(), woven.YarnSection()
    f = woven.Fabric()
    L, h = 1e-3, math.sqrt(s.width * s.thickness) + 2e-6  # circular sections of radius r0 = sqrt(w t)/2
    f.add_yarn([Vector3(-L / 2, 0, 0), Vector3(L / 2, 0, 0)], m, s)
    f.add_yarn([Vector3(0, -L / 2, h), Vector3(0, L / 2, h)], m, s)
    e = woven.FabricEngine(f)
    woven.contact.enable(e, margin=0, **kw)
    for i, vz in ((0, v / 2), (1, v / 2), (2, -v / 2), (3, -v / 2)):
        e.set_vel(i, Vector3(0, 0, vz))
    return e


def test_penalty_head_on_conserves_energy_and_momentum_and_lasts_half_a_period():
    k, dt = 1e5, 1e-7
    e = pair(response='penalty', penalty_stiffness=k, flattening='none')
    M = woven.masses(e)
    m_eff = 1 / sum(0.25 / m for m in M)  # contact in the middle: weights 1/2 on each node
    ke0 = e.energy()['kinetic']
    steps, worst = 0, 0.0
    for _ in range(60):
        e.step(dt)
        steps += e.collision_stats()['force_rows'] > 0
        worst = max(worst, abs(e.energy()['balance_error']))
        assert np.allclose((M[:, None] * woven.velocities(e)).sum(0), 0, atol=1e-20)  # momentum, exactly
    # kinetic + 1/2 k delta^2 (spring book) constant to O((omega dt)^2) = 3 %: measured 0.3 %
    assert worst < 0.01 * ke0
    assert e.energy()['kinetic'] == pytest.approx(ke0, rel=0.01)
    assert steps * dt == pytest.approx(math.pi * math.sqrt(m_eff / k), abs=1.5 * dt)
    assert e.collision_stats()['max_penetration'] == pytest.approx(1.0 * math.sqrt(m_eff / k), rel=0.05)  # v/omega


def test_penalty_above_its_stability_limit_blows_up():
    k, dt = 1e8, 1e-7
    e = pair(response='penalty', penalty_stiffness=k, flattening='none')
    assert dt > 2.5 * woven.contact.penalty_dt_limit(woven.masses(e)[0], k)
    with pytest.raises(woven.InstabilityError if hasattr(woven, 'InstabilityError') else Exception, match='blow-up'):
        for _ in range(200):
            e.step(dt)


def test_penalty_dt_limit():
    assert woven.contact.penalty_dt_limit(4e-8, 1e4) == pytest.approx(2 * math.sqrt(4e-12), rel=1e-15)
    with pytest.raises(ValueError, match='k'):
        woven.contact.penalty_dt_limit(1e-8, 0)


def test_no_flattening_leaves_sections_alone():
    e = pair(v=5.0, flattening='none')
    before = woven.section_flattening(e).copy()
    for _ in range(60):
        e.step(1e-7)
    assert np.array_equal(woven.section_flattening(e), before)
    assert e.collision_stats()['max_penetration'] < 1e-6
    assert np.all(woven.velocities(e)[:2, 2] <= 1e-9)  # the impulses stopped the approach (e = 0)


def test_geometric_flattening_is_the_default_and_flattens():
    e = pair(v=5.0)
    for _ in range(60):
        e.step(1e-7)
    assert woven.section_flattening(e).max() > 0


@pytest.mark.parametrize('key, value, allowed', [('response', 'spring', "'penalty'"), ('flattening', 'soft', "'springs'"),
                                                 ('penalty_stiffness', 0.0, '(0, inf) N/m'),
                                                 ('penalty_damping', 1.0, '[0, 1)'),
                                                 ('section_stiffness', -1.0, '(0, inf) N/m')])
def test_bad_model_values_name_the_key(key, value, allowed):
    e = woven.weave(nx=2, ny=2).engine
    with pytest.raises(ValueError) as err:
        woven.contact.enable(e, **{key: value})
    assert key in str(err.value) and allowed in str(err.value)
    assert not e.collisions_enabled


def test_gap_model_keys_name_their_range_and_bad_combinations_are_refused():
    """The contact model's keys are validated before anything changes: the engine keeps running
    without collisions after each refusal."""
    e = pair()
    e.disable_collisions()
    for kw, key in (({'contact_model': 'sat'}, 'contact_model'),
                    ({'projection_sweeps': 51}, 'projection_sweeps'),
                    ({'projection_slop': -1e-6}, 'projection_slop'),
                    ({'projection_max_move': 0.0}, 'projection_max_move'),
                    ({'projection_check': -0.5}, 'projection_check'),
                    ({'projection_check': 2e-3}, 'projection_check'),
                    ({'sweep_order': 'red-black'}, 'sweep_order'),
                    # the projection belongs to the gap model's impulse response
                    ({'contact_model': 'paper', 'projection_sweeps': 2}, 'projection_sweeps'),
                    ({'response': 'penalty', 'projection_sweeps': 2}, 'projection_sweeps')):
        with pytest.raises(Exception) as ex:
            woven.contact.enable(e, **kw)
        assert key in str(ex.value) and ('allowed' in str(ex.value) or 'range' in str(ex.value)), str(ex.value)
        assert not e.collisions_enabled
    woven.contact.enable(e, contact_model='paper', projection_sweeps=0)  # a valid combination
    assert e.collisions_enabled


def test_gap_model_stops_a_head_on_pair_in_touch_and_books_the_projection():
    """Head-on at 10 m/s with sections that cannot flatten: the rows stop the pair within the gap,
    the books close, and whatever the projection moved is in its own book."""
    e = pair(v=10.0, flattening='none')
    dt = 1e-8
    for _ in range(100):
        e.step(dt)
    s, E = e.collision_stats(), e.energy()
    assert s['max_penetration'] < 0.01 * woven.YarnSection().thickness
    assert abs(E['balance_error']) < 1e-6 * 0.5 * woven.masses(e).sum() * 25
    assert 'projection' in E and s['projection_energy'] == pytest.approx(-E['projection'], abs=1e-18)
