"""Runs scene-script commands one after the other in one process (one YADE start for a whole test
session's refused commands, instead of one each, 2 s apiece):
    /usr/bin/python3 -u tests/python/script_server.py      (conftest.ScriptServer starts it)
Reads one JSON line per command on stdin, {"script": path, "argv": [...], "cwd": folder, "dry": false},
runs it through woven.params.dry_run_script and answers one JSON line {"verdict", "message"}. Lines
that are not JSON (YADE's banner, the scripts' prints) go to stdout too; the client skips them."""
import json
import os
import sys

import woven  # noqa: F401 (imports yade: the scripts' O, Vector3, PyRunner)
from woven.params import dry_run_script
import yade

here = os.getcwd()
for line in sys.stdin:
    job = json.loads(line)
    os.chdir(job.get('cwd') or here)
    verdict, message = dry_run_script(job['script'], job.get('argv', []), job.get('batch'), job.get('dry', False))
    yade.O.reset()  # a script refused halfway may have left bodies, engines or an adapter
    sys.stdout.write('\n' + json.dumps({'verdict': verdict, 'message': message}) + '\n')
    sys.stdout.flush()
