"""pytest runs under Debian's /usr/bin/python3; `import woven` puts YADE's yade-double/py on
sys.path and imports yade, so O, Vector3 and PyRunner work here as inside `yade`."""
import json
import os
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.fixture(scope='session')
def yade_ns():
    import woven  # noqa: F401  (imports yade)
    import yade
    return yade


def run_scene(script, out, *args, timeout=600):
    """Runs `yade -n -x scripts/SCRIPT key=value...` with out=OUT; returns (exit code, output, summary)."""
    args = list(args)
    if script == 'ballistic.py' and not any(a.startswith('pictures=') for a in args):
        args.append('pictures=0')  # rendering (7 s a run) only where a test asks for it
    cmd = ['yade', '-n', '-x', os.path.join(ROOT, 'scripts', script), 'out=%s' % out] + args
    r = subprocess.run(cmd, cwd=str(out), capture_output=True, text=True, timeout=timeout)
    path = os.path.join(str(out), 'summary.json')
    summary = json.load(open(path)) if os.path.exists(path) else None
    return r.returncode, r.stdout + r.stderr, summary


def check_scripts(jobs, folder, timeout=600):
    """Runs scene-script commands in one YADE process (tests/python/script_driver.py): jobs are dicts
    {'script': NAME.py under scripts/ or a path, 'argv': [...], 'batch': 'TABLE:LINE' or None,
    'dry': True (check the keys, stop before running) / False (run: for commands that must be
    refused wherever the script refuses them), 'cwd': folder or None}. Returns [(verdict, message)]
    in order: 'accepted' / 'refused' (dry), 'completed' / 'exit N' / 'refused' (not dry)."""
    folder = str(folder)
    jobs = [dict(j, script=j['script'] if os.path.isabs(j['script']) else os.path.join(ROOT, 'scripts', j['script']))
            for j in jobs]
    jp, rp = os.path.join(folder, 'jobs.json'), os.path.join(folder, 'results.json')
    with open(jp, 'w') as f:
        json.dump(jobs, f)
    r = subprocess.run(['yade', '-n', '-x', os.path.join(ROOT, 'tests', 'python', 'script_driver.py'), jp, rp],
                       cwd=folder, capture_output=True, text=True, timeout=timeout)
    assert r.returncode == 0 and os.path.exists(rp), r.stdout[-3000:] + r.stderr[-3000:]
    return [(x['verdict'], x['message']) for x in json.load(open(rp))]
