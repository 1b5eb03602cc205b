"""Output folders and summary.json: measured figures beside their reference figures, with units."""
import json
import math
import os


def out_dir(name, params):
    """out/NAME under the working directory, or the folder given by params['out'] if not empty."""
    d = params.get('out') or os.path.join('out', name)
    os.makedirs(d, exist_ok=True)
    return d


def _clean(x):
    if hasattr(x, 'item') and not isinstance(x, (list, tuple, dict)):  # numpy scalars
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    return x


def write_summary(directory, name, params, measured, reference, units, status, checks=None, extra=None):
    """Writes DIRECTORY/summary.json and returns its dict.

    measured/reference: {figure: value}; units: {figure: unit}; status: 'ok', 'failed' or 'unstable';
    checks: {check: {'value':…, 'limit':…, 'passed': bool}}.
    """
    s = {'scene': name, 'status': status,
         'parameters': {k: params[k] for k in params},
         'parameter_units': dict(getattr(params, 'units', {})),
         'measured': measured, 'reference': reference, 'units': units,
         'checks': checks or {}}
    if extra:
        s.update(extra)
    path = os.path.join(directory, 'summary.json')
    with open(path, 'w') as f:
        json.dump(_clean(s), f, indent=2, sort_keys=False)
    return s
