"""The fuzz test's quick subset (scripts/fuzz.py): 200 generated cases of the public Python API (and
four scene runs with a mutated key), each in a worker process that is restarted after a crash. No
case may crash, hang or leave a non-finite state without an error; the errors must be ValueError /
RuntimeError naming what was wrong (the full run, 2000 cases, is in the README).
The classes an earlier outside fuzz found accepted (a bool for a step size, absurd steps in the
single-pair contact helpers, a body inside the fabric, /dev/zero as a state) are among the cases,
each knowing it must be refused: none may be accepted."""
import json
import os
import subprocess

from conftest import ROOT


def test_quick_fuzz_has_no_crash_hang_or_silent_nonfinite_state(tmp_path):
    cmd = ['yade', '-n', '-x', os.path.join(ROOT, 'scripts', 'fuzz.py'), 'cases=200', 'seed=7', 'scene_every=50',
           'timeout=30', 'out=%s' % tmp_path]
    r = subprocess.run(cmd, cwd=str(tmp_path), capture_output=True, text=True, timeout=300)
    s = json.load(open(os.path.join(str(tmp_path), 'summary.json')))
    m = s['measured']
    detail = json.dumps(s.get('failures', [])[:5], indent=1)
    assert m['cases'] == 200 and m['scene_cases'] == 4
    assert m['crashes'] == 0, detail
    assert m['hangs'] == 0, detail
    assert m['silent_nonfinite'] == 0, detail
    assert m['unclean_errors'] == 0, detail
    assert m['wrongly_accepted'] == 0, detail
    assert m['must_refuse_cases'] >= 10
    # the cases do probe: most are refused, cleanly, and nearly all refusals name the argument
    assert m['clean_errors'] > 100 and m['accepted'] > 10
    assert m['errors_naming_key'] >= 0.9 * m['clean_errors']
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]


def _scene_bases():
    """fuzz.py's SCENES (read from the script without running it): {script: (base keys, mutated keys)}."""
    import ast
    tree = ast.parse(open(os.path.join(ROOT, 'scripts', 'fuzz.py')).read())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, 'id', '') == 'SCENES' for t in node.targets):
            return ast.literal_eval(node.value)
    raise AssertionError('fuzz.py has no SCENES')


def test_each_scene_base_of_the_fuzzer_runs_on_its_own(script_server, tmp_path):
    # a base that is refused by itself makes every mutated case of its script a refusal of the base,
    # naming another key: smith.py's duration 0.2 did (every smith case "failed" to name its key)
    from conftest import run_refused
    for script, (base, _) in _scene_bases().items():
        args = ['%s=%r' % (k, v) for k, v in base.items()]
        rc, log, s = run_refused(script_server, script, tmp_path / script, *args)
        # runs (tension's base is too short a pull for its checks, which then fail: exit 1, no error)
        assert 'is invalid' not in log and 'Error' not in log, (script, log[-1500:])
        assert os.path.exists(tmp_path / script / 'summary.json'), (script, log[-1500:])
