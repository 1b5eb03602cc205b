"""Threads under YADE: `yade -j N` reaches woven's loops (in the script and in YADE's loop thread),
and the thread benchmark's runs on 1 and 2 threads end in the same bits."""
import os
import subprocess

from conftest import ROOT, run_refused


def test_yade_j_sets_woven_threads_in_the_loop(tmp_path):
    script = tmp_path / 'probe.py'
    script.write_text('import woven\n'
                      'print("PROBE script", woven.threads())\n'
                      'O.engines = [PyRunner(command="import woven; print(\'PROBE loop\', woven.threads())", iterPeriod=1,'
                      ' initRun=True)]\n'
                      'O.run(1, True)\n')
    for j, expected in ((None, 1), (2, 2), (3, 3)):
        cmd = ['yade'] + (['-j', str(j)] if j else []) + ['-n', '-x', str(script)]
        r = subprocess.run(cmd, cwd=str(tmp_path), capture_output=True, text=True, timeout=120)
        lines = [l for l in r.stdout.splitlines() if l.startswith('PROBE')]
        # without -j YADE sets OMP_NUM_THREADS=1 itself
        assert lines == ['PROBE script %d' % expected, 'PROBE loop %d' % expected], r.stdout + r.stderr


def test_bench_threads_same_bits(tmp_path):
    cmd = ['yade', '-j', '2', '-n', '-x', os.path.join(ROOT, 'scripts', 'bench_threads.py'), 'out=%s' % tmp_path,
           'nx=9', 'ny=9', 'steps=60', 'repeats=1']
    r = subprocess.run(cmd, cwd=str(tmp_path), capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    import json
    s = json.load(open(os.path.join(str(tmp_path), 'summary.json')))
    assert s['measured']['same_bits'] is True
    assert s['measured']['openmp_threads_at_start'] == 2
    assert s['measured']['ideal_loop_speedup'] > 0  # the machine's ceiling, printed beside the speed-up
    assert s['measured']['cps'] > 2048  # more than one chunk of CPs
    assert s['measured']['sweep_order'] == 'sequential'


def test_bench_ballistic_same_bits_on_two_threads(script_server, tmp_path):
    # The struck ply (impulse rows on the projectile, blocked sweeps, position projection) on 1 and 2
    # threads in one process, twice each: the same bits in all four runs; a thread count, repeat count
    # or sweep order out of range is refused, naming the key.
    script = os.path.join(ROOT, 'scripts', 'bench_ballistic.py')
    cmd = ['yade', '-j', '2', '-n', '-x', script, 'out=%s' % tmp_path, 'side=0.0254', 't_end=5e-6', 'chain_steps=20',
           'threads=2', 'repeats=2']
    r = subprocess.run(cmd, cwd=str(tmp_path), capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    import json
    s = json.load(open(os.path.join(str(tmp_path), 'summary.json')))
    assert s['measured']['same_bits'] is True and s['status'] == 'ok'
    assert s['measured']['cps'] > 2048 and s['measured']['speedup'] > 0
    assert s['measured']['sweep_order'] == 'blocked'  # the default with threads >= 2
    assert len(s['measured']['speedup_each']) == 2 and len(s['measured']['wall_seconds_n_threads_each']) == 2
    assert s['measured']['wall_seconds_n_threads'] == min(s['measured']['wall_seconds_n_threads_each'])
    assert len(s['measured']['ideal_loop_speedup_each']) == 2
    for arg, text in (('threads=0', 'threads = 0 is invalid'), ('repeats=11', 'repeats = 11 is invalid'),
                      ('sweep_order=red-black', "sweep_order = 'red-black' is invalid")):
        rc, log, _ = run_refused(script_server, script, tmp_path, arg, timeout=120)
        assert rc != 0 and text in log, log
