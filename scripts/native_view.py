# YADE's 3D view of a woven fabric with the native plugin (docs/yade_native.md): a plain weave pulled
# along the warp, drawn by yade.wrapper.WovenGlDrawer as tubes of the yarns' elliptic sections, and a
# screenshot of it. Needs a display; on a machine without one, under Xvfb:
#   xvfb-run -a -s "-screen 0 1280x960x24" yade-woven -x scripts/native_view.py [nx=4] [steps=3000] [out=DIR]
# (yade-woven: the wrapper of scripts/yade_prefix.sh; not -n: the view needs YADE's GUI). Writes
# out/native_view/yarns.png and summary.json, then exits.
import os
import sys

import numpy as np

import woven
from woven import _native
from woven.params import read_params
from woven.output import out_dir, write_summary

p = read_params({'nx': (4, '', 'repeats of the plain weave along x and y'),
                 'steps': (3000, '', 'steps of the pull before the picture'),
                 'max_strain': (0.003, '', 'strain drawn in full red'),
                 'out': ('', '', 'output folder (default out/native_view)')})
d = out_dir('native_view', p)
w = woven.weave(nx=p.nx, ny=p.nx, cp_per_span=4)
e = w.engine
woven.contact.enable(e)
e.settle_sections()
for y in w.warp_yarns:
    info = e.yarn(y)
    e.fix(info['first_node'])
    e.prescribe_velocity(info['first_node'] + info['n_nodes'] - 1, Vector3(2.0, 0, 0))
O.engines = []
n = woven.attach(e)
if type(n).__name__ != 'WovenFabricEngine':
    print('native_view: the native plugin is not in use:', _native.why_not())
    sys.exit(2)
O.run(p.steps, True)
v = _native.view(segments=16, scale=1.0, max_strain=p.max_strain)
from yade import qt
X = woven.positions(e)
c = Vector3(*(0.5 * (X.min(axis=0) + X.max(axis=0))))
v.eyePosition = c + Vector3(-0.45, -0.75, 0.6) * (1.3 * float(np.ptp(X[:, 0])))
v.upVector = Vector3(0, 0, 1)
v.lookAt = c  # turns the camera towards the fabric from where it stands
import time
path = os.path.join(d, 'yarns.png')
v.saveSnapshot(path)
# The view draws (and writes the file) at its next frame, from Qt's event loop, which YADE only runs
# for its interactive shell: pump it here.
from PyQt5.QtWidgets import QApplication
for _ in range(300):
    QApplication.processEvents()
    if os.path.exists(path) and os.path.getsize(path) > 0:
        break
    time.sleep(0.05)
ok = os.path.exists(path) and os.path.getsize(path) > 0
if ok:  # QGLViewer writes JPEG whatever the name: store a real PNG
    from PIL import Image
    Image.open(path).convert('RGB').save(path, format='PNG')
write_summary(d, 'native_view', p, {'picture': path if ok else '', 'steps': p.steps, 'nodes': n.nodes}, {},
              {'picture': 'png', 'steps': '-', 'nodes': '-'}, 'ok' if ok else 'failed')
print('native_view: wrote', path if ok else 'nothing')
O.exitNoBacktrace(0 if ok else 1) if hasattr(O, 'exitNoBacktrace') else os._exit(0 if ok else 1)
