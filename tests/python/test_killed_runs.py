"""Killed runs: a write killed half-way leaves the previous file whole; a scene killed with
SIGKILL mid-run runs again into the same out= and completes; a yade-batch sweep killed mid-way
resumes without redoing its finished runs (woven.output.out_dir); every writer of the scripts and
the package goes through woven.output's atomic writers."""
import glob
import json
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np

from conftest import ROOT


def wait_for(cond, proc, timeout):
    """Polls cond() every 20 ms until it holds (True), the process ended or the time is up (False)."""
    t0 = time.time()
    while time.time() - t0 < timeout:
        if cond():
            return True
        if proc.poll() is not None:
            return False
        time.sleep(0.02)
    return False


def test_killed_write_keeps_the_previous_file(tmp_path):
    import woven.output  # noqa: F401  (the child imports it the same way)
    target = tmp_path / 'result.csv'
    target.write_text('old,complete\n')
    code = ('import sys, time\nsys.path[:0] = %r\nfrom woven.output import atomic_open\n'
            'with atomic_open(%r) as f:\n    f.write("new," * 100000)\n    f.flush()\n'
            '    print("writing", flush=True)\n    time.sleep(60)\n    f.write("end\\n")\n'
            % ([p for p in sys.path if p], str(target)))
    p = subprocess.Popen([sys.executable, '-c', code], stdout=subprocess.PIPE, text=True)
    for line in p.stdout:  # importing woven prints YADE's banner first
        if line.strip() == 'writing':
            break
    p.send_signal(signal.SIGKILL)
    p.wait(30)
    assert p.returncode == -signal.SIGKILL
    assert target.read_text() == 'old,complete\n'
    # What the kill leaves is a hidden temporary that no reader looks for (docs/reliability.md).
    assert [n for n in os.listdir(str(tmp_path)) if not n.startswith('.')] == ['result.csv']


def test_killed_scene_runs_again_into_the_same_folder(tmp_path):
    out = tmp_path / 'run'
    out.mkdir()
    # A small ply for long enough (about 7 s of stepping) to be killed while it writes VTK frames.
    args = ['side=0.01', 't_end=1e-4', 'stop=0', 'vtk_every=20', 'progress=0', 'out=%s' % out]
    cmd = ['yade', '-n', '-x', os.path.join(ROOT, 'scripts', 'ballistic.py')] + args
    p = subprocess.Popen(cmd, cwd=str(out), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    started = wait_for(lambda: len(glob.glob(str(out / 'vtk' / 'yarns_*.vtp'))) >= 4, p, 300)
    p.send_signal(signal.SIGKILL)
    p.wait(30)
    assert started and p.returncode == -signal.SIGKILL, 'the run ended before it could be killed mid-run'
    assert not (out / 'summary.json').exists()  # it is written last, and only whole
    r = subprocess.run(cmd, cwd=str(out), capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    s = json.load(open(str(out / 'summary.json')))
    assert s['scene'] == 'ballistic' and s['status'] == 'ok' and s['parameters']['t_end'] == 1e-4
    # Every file of the folder is whole: the CSVs load, the .pvd lists frames that exist.
    S = np.loadtxt(str(out / 'series.csv'), delimiter=',', skiprows=1)
    assert S.ndim == 2 and S.shape[0] > 10 and np.all(np.isfinite(S))
    pvd = (out / 'vtk' / 'frames.pvd').read_text()
    frames = re.findall(r'file="([^"]+)"', pvd)
    assert pvd.rstrip().endswith('</VTKFile>') and len(frames) > 8
    assert all((out / 'vtk' / f).stat().st_size > 0 for f in frames)


def test_killed_batch_sweep_resumes_without_redoing_finished_runs(tmp_path):
    table = tmp_path / 'sweep.table'
    names = ['a', 'b', 'c']
    rows = ['description nx ny out'] + ['%s %d 1 %s' % (n, k + 1, tmp_path / n) for k, n in enumerate(names)]
    table.write_text('\n'.join(rows) + '\n')
    cmd = ['yade-batch', '--job-threads=1', '-j', '1', '--log', str(tmp_path / '@.log'), str(table),
           os.path.join(ROOT, 'scripts', 'weave.py')]
    summary = [tmp_path / n / 'summary.json' for n in names]
    p = subprocess.Popen(cmd, cwd=str(tmp_path), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                         start_new_session=True)
    first = wait_for(lambda: summary[0].exists(), p, 300)
    os.killpg(p.pid, signal.SIGKILL)  # yade-batch and its running job
    p.wait(30)
    assert first and not summary[-1].exists(), 'the sweep was not killed mid-way'
    done = {s: (s.stat().st_mtime_ns, s.read_bytes()) for s in summary if s.exists()}
    r = subprocess.run(cmd, cwd=str(tmp_path), capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    for s in summary:
        d = json.load(open(str(s)))
        assert d['scene'] == 'weave' and d['status'] == 'ok'
    for s, (mtime, data) in done.items():
        # Not redone: the same file, and its job's log says why.
        assert (s.stat().st_mtime_ns, s.read_bytes()) == (mtime, data)
        assert 'not run again' in (tmp_path / (s.parent.name + '.log')).read_text()
    assert len(done) < len(names)
    redone = [s for s in summary if s not in done]
    assert all('not run again' not in (tmp_path / (s.parent.name + '.log')).read_text() for s in redone)


# Writers that bypass woven.output: numpy's and matplotlib's own, YADE's, and open() for writing.
_WRITERS = re.compile(r"np\.savetxt\(|\bfig\.savefig\(|plt\.savefig\(|saveDataTxt\(|\.tofile\(|"
                      r"\bopen\(.*,\s*['\"][wax]b?\+?['\"]\s*\)")
# Writes that are not results: a child's log stream, the fuzz test's own inputs, a file handed to
# the atomic writer by name (`tmp`).
_ALLOWED = [('py/woven/campaign.py', "'run.log'"), ('scripts/fuzz.py', 'open(v, '), ('scripts/fuzz.py', 'open(p, '),
            ('scripts/fuzz.py', 'worker.log'), ('py/woven/checkpoint.py', 'open(p, ')]


def test_every_writer_is_atomic():
    found = []
    for path in sorted(glob.glob(os.path.join(ROOT, 'scripts', '*.py')) + glob.glob(os.path.join(ROOT, 'py', 'woven', '*.py'))):
        rel = os.path.relpath(path, ROOT)
        if rel == 'py/woven/output.py':
            continue  # the atomic writers themselves
        for k, line in enumerate(open(path), 1):
            code = line.split('#')[0]
            if _WRITERS.search(code) and not any(rel == f and s in code for f, s in _ALLOWED) and '(tmp' not in code:
                found.append('%s:%d: %s' % (rel, k, line.strip()))
    assert not found, 'non-atomic writers (use woven.output):\n' + '\n'.join(found)
