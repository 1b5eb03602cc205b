"""A short soak (scripts/soak.py; the 1e6-step figures are in docs/reliability.md): a pre-tensioned
weave under a cyclic load with collisions on keeps its energy bounded and its books balanced, and the
process's resident memory does not grow."""
import pytest

from conftest import run_scene


@pytest.mark.parametrize('mode', ['cyclic'])
def test_short_soak_energy_bounded_memory_flat(tmp_path, mode):
    # 6 x 6 yarns, 20 000 steps, four load cycles: about 10 s of stepping.
    rc, log, s = run_scene('soak.py', tmp_path, 'steps=20000', 'mode=%s' % mode, 'nx=3', 'ny=3', 'period=5000',
                           'samples=200', 'rss_tol=0.5', timeout=300)
    assert rc == 0 and s['status'] == 'ok', log[-3000:]
    m = s['measured']
    assert m['steps'] == 20000 and m['cycles'] == 4
    assert m['pretension_energy'] > 0 and m['rss_start'] > 50  # the yarns are taut; memory was read (MiB)
    # Tolerances (the script's checks, stated here again): the balance error moves by at most 1 % of
    # the pre-tension energy; kinetic + elastic never exceeds its start plus the work put in by more
    # than 5 % of it, nor does the last cycle's peak exceed the first's by more; and the resident
    # memory grows by at most 0.5 MiB over the last nine tenths (a leak of 30 bytes per step would not pass).
    assert abs(m['balance_drift_max']) <= 0.01
    assert m['bound_rise'] <= 0.05 and m['cycle_growth'] <= 0.05
    assert m['rss_growth'] <= 0.5
    assert all(c['passed'] for c in s['checks'].values()), s['checks']
