"""woven: yarn-level mechanics of woven fabrics, a plugin for YADE.

Units are SI everywhere (m, kg, s, N, Pa, J). Typical use inside a YADE script::

    import woven
    weave = woven.weave(preset='km2_706', nx=5, ny=5)
    eng = woven.attach(weave.engine)          # puts a FabricEngine adapter into O.engines
    O.run(1000, True)

The yarn state lives in C++ (woven._woven); Python only sets up scenes and reads results.
"""
import glob as _glob
import sys as _sys


def _ensure_yade():
    """Make YADE's Python package importable (its Vector3 converters are what woven's C++ takes and
    returns). Under `yade` it is already loaded; under plain /usr/bin/python3 we add the
    yade-double/py folder that Debian's libyade installs."""
    if 'yade' in _sys.modules:
        return
    try:
        import yade  # noqa: F401
        return
    except ImportError:
        pass
    for d in sorted(_glob.glob('/usr/lib/*/yade-double/py')):
        if d not in _sys.path:
            _sys.path.insert(0, d)
    import yade  # noqa: F401


_ensure_yade()

from . import _woven  # noqa: E402
from . import _args  # noqa: E402
_args.install(_woven)  # argument errors name the argument (before anything is imported from _woven)
from ._woven import (FabricEngine, Fabric, Pattern, YarnMaterial, YarnSection, WeaveParams,  # noqa: E402,F401
                     InstabilityError, peirce_from_height, peirce_from_crimp, obb_contact, obb_first_contact,
                     set_threads, threads, openmp_threads, release_threads, ideal_loop_seconds)
from .weave import weave, pattern, WEAVE_KEYS  # noqa: E402,F401
from .engine import attach  # noqa: E402,F401
from . import checkpoint  # noqa: E402
checkpoint.hook()  # O.save / O.load carry the fabric of woven adapters (docs/reliability.md)
from .arrays import (positions, velocities, strains, tensions, masses, rest_lengths,  # noqa: E402,F401
                     section_flattening, section_semi_axes, contacts, candidate_pairs,
                     section_dirs, alive, filtered_strains, body_contacts)
from . import contact  # noqa: E402,F401
from . import coupling  # noqa: E402,F401
from . import theory  # noqa: E402,F401

__version__ = '0.1.0'
