"""Runs many scene-script commands in one YADE process (one YADE start instead of one per command):
    yade -n -x tests/python/script_driver.py JOBS.json RESULTS.json
JOBS.json: [{"script": path, "argv": ["key=value", ...], "batch": "TABLE:LINE" or null, "dry": true,
"cwd": folder or null}]. Each job runs through woven.params.dry_run_script (dry: the keys are read and
checked and the script stops before it builds anything; not dry: the script runs and its refusal is
caught). RESULTS.json: [{"verdict": ..., "message": ...}] in the jobs' order. conftest.check_scripts
drives it."""
import json
import os
import sys

from woven.params import dry_run_script

jobs_path, results_path = sys.argv[1], sys.argv[2]
results = []
here = os.getcwd()
for job in json.load(open(jobs_path)):
    os.chdir(job.get('cwd') or here)
    verdict, message = dry_run_script(job['script'], job.get('argv', []), job.get('batch'), job.get('dry', True))
    results.append({'verdict': verdict, 'message': message})
    # A script refused halfway may have left bodies, engines or a woven adapter: the next starts clean.
    O.reset()  # noqa: F821 (YADE's)
os.chdir(here)
with open(results_path, 'w') as f:
    json.dump(results, f)
