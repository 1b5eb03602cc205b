"""The commands the documentation shows work as written (once the README's main job failed
its own check with its defaults, and nothing ran it).

- The main job, `yade -n -x scripts/smith.py`, runs with no keys and passes its checks.
- Every other command the README shows runs, as written or, where it takes too long for CI, with the
  fewest keys changed that make it short (README_RUNS says which and why); so does the README's
  Python example.
- Every command in README.md and docs/*.md that runs a script of scripts/ (found in their code
  blocks and inline code, not listed by hand: a new or edited command is checked too) has its keys
  accepted by a dry run (WOVEN_DRY_RUN=1: the script reads and checks its keys, including its
  defaults' own checks, and stops before it builds anything); so does every line of every
  yade-batch table in scripts/batch. A renamed key, a script that no longer exists or a default that
  fails its own check fails here.
- The native plugin's commands point PYTHONPATH at the folder the build installs into.
"""
import glob
import json
import os
import re
import shlex
import subprocess

import pytest
from conftest import ROOT, check_scripts

DOCS = ['README.md'] + sorted(os.path.relpath(p, ROOT) for p in glob.glob(os.path.join(ROOT, 'docs', '*.md')))


# --- commands in the documentation ------------------------------------------------------------------
def snippets(path):
    """(line, text) of every piece of code in a markdown file: fenced blocks line by line (backslash
    continuations joined), and inline code spans, which may wrap onto the next line."""
    text = open(path).read()
    out = []
    fence = re.compile(r'^```[^\n]*\n(.*?)^```', re.S | re.M)
    for m in fence.finditer(text):
        line0 = text.count('\n', 0, m.start(1)) + 1
        buf, start = '', None
        for k, line in enumerate(m.group(1).split('\n')):
            start = line0 + k if start is None else start
            if line.rstrip().endswith('\\'):
                buf += line.rstrip()[:-1] + ' '
                continue
            out.append((start, buf + line))
            buf, start = '', None
    outside = fence.sub(lambda m: '\n' * m.group(0).count('\n'), text)
    for m in re.finditer(r'`([^`\n]+(?:\n[^`\n]+)?)`', outside):
        out.append((outside.count('\n', 0, m.start()) + 1, m.group(1).replace('\n', ' ')))
    return out


SCRIPT = re.compile(r'^(?:\S*/)?scripts/(\w+)\.py$')
TABLE = re.compile(r'^(?:\S*/)?scripts/batch/(\w+)\.table$')
KEY = re.compile(r'^(\w+)=(.*)$', re.S)
PLACEHOLDER = re.compile(r'\b[A-Z][A-Z_]+\b')  # NAME, KEYS, MU, MU_B, HOST: stand-ins in prose


def commands(doc):
    """[(doc, line, script, argv, table, runner)] of the commands in `doc` that run a script of
    scripts/ with yade (or yade-batch, then `table` is the table's name; runner: the yade command's
    name, yade-woven* for the native plugin's prefix). Placeholders are left out: a script named
    NAME, key=value, values such as MU or $S."""
    found = []
    for line, code in snippets(os.path.join(ROOT, doc)):
        try:
            toks = shlex.split(code, comments=True)
        except ValueError:
            toks = code.split()
        for i, t in enumerate(toks):
            m = SCRIPT.match(t)
            runner = [os.path.basename(x) for x in toks[:i] if re.search(r'(^|/)yade[-\w]*$', x)]
            if not m or not runner:
                continue
            if any(x.startswith('YADE_PREFIX=') for x in toks[:i]):  # yade of the native plugin's prefix
                runner = ['yade-woven']
            if PLACEHOLDER.fullmatch(m.group(1)):
                continue
            table = TABLE.match(toks[i - 1])
            argv = []
            for a in toks[i + 1:]:
                if a in ('&&', '||', '|', ';') or a.startswith(('>', '#')):
                    break
                km = KEY.match(a.strip('[]'))
                if not km or km.group(1) == 'key' or PLACEHOLDER.search(km.group(2)) or km.group(2).startswith('$'):
                    continue
                k, v = km.groups()
                argv.append('%s=%s' % (k, ' '.join(w for w in v.split() if not w.startswith('$'))))
            found.append((doc, line, m.group(1), argv, table.group(1) if table else None, runner[-1]))
    return found


ALL = [c for doc in DOCS for c in commands(doc)]


def table_lines(name):
    """The line numbers yade-batch gives the jobs of scripts/batch/NAME.table (YADE_BATCH=TABLE:LINE)."""
    lines = []
    for k, text in enumerate(open(os.path.join(ROOT, 'scripts', 'batch', name + '.table')), start=1):
        t = text.strip()
        if t and not t.startswith('#') and not t.startswith('description'):
            lines.append(k)
    return lines


def test_the_docs_show_the_commands_this_test_expects():
    # The extraction works: the README's main job, its ballistic commands, a yade-batch table, the
    # campaign's inline command that wraps onto a second line, and commands from several docs.
    readme = [(c[2], c[3], c[4]) for c in ALL if c[0] == 'README.md']
    assert ('smith', [], None) in readme
    assert ('ballistic', ['V=300', 'shape=sphere', 'mass=1e-3', 'size=5e-3', 'clamp=2', 'vtk_every=200',
                          'weibull_m=10', 'seed=3'], None) in readme
    assert ('smith', [], 'smith') in readme
    assert ('campaign', ['jobs=2', 'scene=pictures=0 backface=0'], None) in readme
    assert {c[0] for c in ALL} >= {'README.md', 'docs/README.md', 'docs/history.md', 'docs/pullout.md',
                                   'docs/campaign.md', 'docs/compare.md', 'docs/yade_native.md',
                                   'docs/yade_grid.md', 'docs/weave.md', 'docs/chain.md'}
    assert len(ALL) > 60


def test_every_documented_command_and_table_line_has_its_keys_accepted(tmp_path):
    jobs, where = [], []
    for doc, line, script, argv, table, runner in ALL:
        path = os.path.join(ROOT, 'scripts', script + '.py')
        assert os.path.exists(path), '%s:%d names scripts/%s.py, which does not exist' % (doc, line, script)
        if table:  # yade-batch: the table's lines are the commands (checked below, once per table)
            continue
        if runner.startswith('yade-woven'):  # the native build's command: this build has no plugin to demand
            argv = ['native=auto' if a == 'native=yes' else a for a in argv]
        jobs.append({'script': path, 'argv': argv, 'cwd': str(tmp_path)})
        where.append('%s:%d: %s %s' % (doc, line, script, ' '.join(argv)))
    for t in sorted(glob.glob(os.path.join(ROOT, 'scripts', 'batch', '*.table'))):
        name = os.path.splitext(os.path.basename(t))[0]
        head = open(t).read(400)
        m = re.search(r'scripts/(\w+)\.py', head)
        assert m, '%s: its first lines must name the script it is for' % t
        for k in table_lines(name):
            jobs.append({'script': os.path.join(ROOT, 'scripts', m.group(1) + '.py'), 'argv': [],
                         'batch': '%s:%d' % (t, k), 'cwd': str(tmp_path)})
            where.append('scripts/batch/%s.table line %d' % (name, k))
    results = check_scripts(jobs, tmp_path)
    refused = ['%s\n    -> %s' % (w, msg) for w, (verdict, msg) in zip(where, results) if verdict != 'accepted']
    assert not refused, 'documented commands whose keys are refused:\n' + '\n'.join(refused)
    # nothing was run: a dry run writes no output folder
    assert not os.path.exists(tmp_path / 'out')


def test_native_commands_use_the_folder_the_build_installs_into():
    # docs/yade_native.md's bench once read PYTHONPATH=$PWD/stage-native while the build installs into
    # $PWD/stage: woven then came silently from the default build.
    sites, paths = set(), []
    for doc in DOCS:
        text = open(os.path.join(ROOT, doc)).read()
        sites |= set(re.findall(r'-DWOVEN_PYTHON_SITE=\$PWD/([\w.-]+)', text))
        paths += [(doc, p) for p in re.findall(r'PYTHONPATH=\$PWD/([\w.-]+)', text)]
    assert sites == {'stage'}, sites
    wrong = [(doc, p) for doc, p in paths if p not in sites | {'build'}]
    assert paths and not wrong, wrong


# --- the README's commands, run ----------------------------------------------------------------------
def yade(args, cwd, timeout=900, env=None):
    e = dict(os.environ, **(env or {}))
    r = subprocess.run(['yade'] + args, cwd=str(cwd), capture_output=True, text=True, timeout=timeout, env=e)
    return r.returncode, r.stdout + r.stderr


def summary(folder):
    return json.load(open(os.path.join(str(folder), 'summary.json')))


def test_main_job_runs_as_written(tmp_path):
    # `yade -n -x scripts/smith.py` in a fresh folder, no keys: exit 0, every check passed, and the
    # files the README names in out/smith.
    rc, log = yade(['-n', '-x', os.path.join(ROOT, 'scripts', 'smith.py')], tmp_path)
    assert rc == 0, log[-3000:]
    s = summary(tmp_path / 'out' / 'smith')
    assert s['status'] == 'ok' and s['checks'] and all(c['passed'] for c in s['checks'].values()), s['checks']
    for name in ('smith.png', 'convergence.csv'):
        assert os.path.getsize(tmp_path / 'out' / 'smith' / name) > 100


# The README's commands that run longer than CI allows, with the keys added to make them short; every
# other README command runs as written. Each addition changes how long the run goes on, not which
# scene or which checks it has.
README_RUNS = {
    # the default impact (50.8 mm ply, cube at 200 m/s): 30 s of CPU to perforation; its first 3 us
    # build the same ply and projectile and pass the same checks (pictures and all)
    ('ballistic', ()): ['t_end=3e-6'],
    ('ballistic', ('V=300', 'shape=sphere', 'mass=1e-3', 'size=5e-3', 'clamp=2', 'vtk_every=200', 'weibull_m=10',
                   'seed=3')): ['t_end=3e-6'],
    # a V50 campaign of 30 ballistic runs (10 min on 2 cores): one run of 2 us, no fit (one run has none)
    ('campaign', ('jobs=2', 'scene=pictures=0 backface=0')): ['velocities=200', 'seeds=1', 't_end=2e-6', 'fit=0'],
    # a million steps (15 min): 300
    ('soak', ('steps=1000000', 'mode=rest')): ['steps=300'],
}
# README commands not run here, and why (their keys are checked by the dry run above).
README_NOT_RUN = {
    # 30 ballistic runs of the default ply (10 min on 2 cores); the collector runs in test_ballistic.py
    ('ballistic', 'v50'): 'a V50 sweep of 30 full impacts',
}


def readme_commands():
    # the native plugin's commands (yade-woven) need its build (docs/yade_native.md): dry run only
    return [c for c in ALL if c[0] == 'README.md' and not c[5].startswith('yade-woven')]


@pytest.mark.parametrize('cmd', readme_commands(), ids=lambda c: 'README:%d-%s' % (c[1], c[2]))
def test_readme_command_runs(cmd, tmp_path):
    doc, line, script, argv, table, runner = cmd
    path = os.path.join(ROOT, 'scripts', script + '.py')
    if table:
        if (script, table) in README_NOT_RUN:
            pytest.skip(README_NOT_RUN[(script, table)])
        # as written, from a fresh folder: the table's out= folders are relative to it
        r = subprocess.run(['yade-batch', '--job-threads=1', os.path.join(ROOT, 'scripts', 'batch', table + '.table'), path],
                           cwd=str(tmp_path), capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
        # every line ran with its own keys (the table's V column) into its own out= folder
        rows = [l.split() for l in open(os.path.join(ROOT, 'scripts', 'batch', table + '.table'))
                if l.strip() and not l.startswith('#')]
        head, rows = rows[0], rows[1:]
        assert rows
        for r in rows:
            s = summary(tmp_path / r[head.index('out')])
            assert s['status'] == 'ok' and s['parameters']['V'] == float(r[head.index('V')]), s['parameters']
        return
    if script == 'smith' and not argv:
        return  # the main job: test_main_job_runs_as_written
    extra = README_RUNS.get((script, tuple(argv)), [])
    rc, log = yade(['-n', '-x', path] + argv + extra + ['out=%s' % tmp_path], tmp_path)
    assert rc == 0, log[-3000:]
    s = summary(tmp_path)
    assert s['status'] == 'ok', s.get('checks')


def test_readme_python_example_runs(tmp_path):
    # The "A YADE script" block, as it stands in the README.
    text = open(os.path.join(ROOT, 'README.md')).read()
    m = re.search(r'## A YADE script\s+```python\n(.*?)```', text, re.S)
    assert m, 'README: the "A YADE script" section lost its Python block'
    (tmp_path / 'my_scene.py').write_text(m.group(1))
    rc, log = yade(['-n', '-x', 'my_scene.py'], tmp_path)
    assert rc == 0, log[-3000:]
    assert os.path.getsize(tmp_path / 'pretensioned.state') > 1000


# Each script of the README's table with its defaults: run here (with the keys that make it short, and
# why), or run by the test file named (which the test checks holds a run of it). Benchmarks run
# shortened: their figures are timings, which no test asserts; what is run is that they work.
TABLE_RUNS = {
    'smith': ('here', []),
    'weave': ('here', []),
    'tension': ('here', []),  # README:279 too
    'ballistic': ('here', ['t_end=3e-6']),  # see README_RUNS
    'pullout': ('test_pullout.py', 'its sweep includes the defaults (pretension=2, friction=0.3) with pull=1e-3'),
    'soak': ('here', ['steps=300']),
    'bench_pyrunner': ('here', ['iters=200', 'nodes=100']),
    # six 12.7 mm impacts (quick) of 2 us each instead of the 30-run matrix
    'contact_sweep': ('here', ['quick=1', 't_end=2e-6', 'jobs=2']),
    'compare': ('test_compare.py', 'quick=1: every method on the 12.7 mm ply (the full set takes 53 min)'),
    'bench_adaptive': ('test_ballistic.py', 'quick=1'),
    'bench_ballistic': ('test_threads.py', 't_end shortened, threads=2'),
    'bench_scaling': ('test_bench_scaling.py', 'two sizes'),
    'bench_threads': ('test_threads.py', 'a small weave'),
    'fuzz': ('test_fuzz.py', '200 cases'),
    'v50': ('test_ballistic.py', 'a collector: run on a small sweep'),
    'campaign': ('test_campaign.py', 'campaigns of a tiny scene; README_RUNS runs the README one shortened'),
    'v50_plies': ('test_v50_plies.py', 'a collector: run on small campaigns'),
}


def table_scripts():
    text = open(os.path.join(ROOT, 'README.md')).read()
    return re.findall(r'^\| `scripts/(\w+)\.py` \|', text, re.M)


def test_every_script_of_the_readme_table_is_run_by_a_test():
    listed = table_scripts()
    assert 'smith' in listed and 'pullout' in listed and len(listed) > 15
    missing = [s for s in listed if s not in TABLE_RUNS]
    assert not missing, 'README table scripts with no run in TABLE_RUNS: %s' % missing
    for script, (where, why) in TABLE_RUNS.items():
        assert script in listed, script
        if where != 'here':
            text = open(os.path.join(ROOT, 'tests', 'python', where)).read()
            assert "'%s.py'" % script in text, '%s does not run scripts/%s.py' % (where, script)


@pytest.mark.parametrize('script', [s for s, (where, _) in TABLE_RUNS.items() if where == 'here'])
def test_readme_table_script_runs(script, tmp_path):
    if script in {c[2] for c in readme_commands() if not c[4]}:
        pytest.skip('run by test_main_job_runs_as_written / test_readme_command_runs')
    rc, log = yade(['-n', '-x', os.path.join(ROOT, 'scripts', script + '.py')] + TABLE_RUNS[script][1] +
                   ['out=%s' % tmp_path], tmp_path)
    assert rc == 0, log[-3000:]
    assert summary(tmp_path)['status'] == 'ok'
