"""pytest runs under Debian's /usr/bin/python3; `import woven` puts YADE's yade-double/py on
sys.path and imports yade, so O, Vector3 and PyRunner work here as inside `yade`."""
import json
import os
import select
import subprocess
import time

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


class ScriptServer:
    """One process that runs scene scripts in turn (tests/python/script_server.py): a command that
    must be refused is checked at the cost of its own checks, not of a YADE start each. Restarted
    after a crash or a timeout."""

    def __init__(self):
        self.p = None

    def _start(self):
        env = dict(os.environ, OMP_NUM_THREADS='1')
        self.p = subprocess.Popen(['/usr/bin/python3', '-u', os.path.join(ROOT, 'tests', 'python', 'script_server.py')],
                                  stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env,
                                  cwd=ROOT)
        self.buf = b''

    def run(self, script, folder, args, timeout=600):
        """(verdict, message, output) of `script` with `args` run in `folder`: verdict 'refused' (the
        message is the error it raised), 'completed', or 'exit N'."""
        if self.p is None or self.p.poll() is not None:
            self._start()
        path = script if os.path.isabs(script) else os.path.join(ROOT, 'scripts', script)
        os.makedirs(str(folder), exist_ok=True)
        job = {'script': path, 'argv': list(args), 'cwd': str(folder), 'dry': False}
        self.p.stdin.write((json.dumps(job) + '\n').encode())
        self.p.stdin.flush()
        out, deadline = [], time.time() + timeout
        fd = self.p.stdout.fileno()
        while True:
            while b'\n' in self.buf:
                line, self.buf = self.buf.split(b'\n', 1)
                text = line.decode(errors='replace')
                if text.startswith('{"verdict"'):
                    r = json.loads(text)
                    return r['verdict'], r['message'], '\n'.join(out)
                out.append(text)
            left = deadline - time.time()
            ready = select.select([fd], [], [], max(left, 0))[0] if left > 0 else []
            if not ready:
                self.close()
                raise TimeoutError('%s %s: no answer in %g s' % (script, ' '.join(args), timeout))
            chunk = os.read(fd, 65536)
            if not chunk:
                code = self.p.wait()
                self.p = None
                raise RuntimeError('%s %s: the script server died (exit %s):\n%s' % (script, ' '.join(args), code, '\n'.join(out)))
            self.buf += chunk

    def close(self):
        if self.p is not None:
            if self.p.poll() is None:
                self.p.kill()  # the server this fixture started, by its handle
            self.p.wait()
            self.p = None


@pytest.fixture(scope='session')
def script_server():
    s = ScriptServer()
    yield s
    s.close()


def run_refused(server, script, out, *args, timeout=600):
    """For a command that must be refused: (exit status as `yade -x` would give it, the error message
    and output, None), run in the session's script server. Exit status 1 for an error the script
    raised or a sys.exit with a message; the message then holds the error, as a log would."""
    args = list(args)
    if script == 'ballistic.py' and not any(a.startswith('pictures=') for a in args):
        args.append('pictures=0')
    verdict, message, output = server.run(script, out, ['out=%s' % out] + args, timeout=timeout)
    if verdict == 'refused':
        return 1, message + '\n' + output, None
    if verdict.startswith('exit '):
        code = verdict[5:]
        return (0 if code in ('0', 'None') else 1), code + '\n' + output, None
    return 0, output, None
