# Cost of driving the woven engine from YADE's loop, measured in one process:
#   yade -n -x scripts/bench_pyrunner.py [nodes=1000] [iters=20000] [native=auto] [out=DIR]
# Prints microseconds per iteration for: an empty YADE loop, a PyRunner doing nothing, the woven
# adapter (PyRunner + C++ step), and the bare C++ step (FabricEngine.run); the adapter's overhead is
# adapter - bare step, independent of the fabric size. With the native YADE plugin loaded
# (docs/yade_native.md) it also times the plugin's WovenFabricEngine stepping the same chain
# (native_engine_us; its overhead native - bare step), and woven.attach's choice is the native one.
# It prints and records which woven it measured (package folder, build id, native plugin or why not):
# a PYTHONPATH that picks another build than meant silently measured the default build's PyRunner
# without a word. native=yes refuses to run without the native engine, naming why.
import os
import sys
import time

import woven
from woven.params import read_params
from woven.output import out_dir, write_summary

p = read_params({'nodes': (1000, '', 'nodes of the test chain'), 'iters': (20000, '', 'iterations per figure'),
                 'native': ('auto', '', "'yes': also time the native plugin's engine, refused without it; 'no': not; "
                            "'auto': when it is usable"),
                 'out': ('', '', 'output folder (default out/bench_pyrunner)')})
if p.nodes < 2 or p.iters < 100:
    raise ValueError('nodes >= 2 and iters >= 100 are allowed; got nodes=%r iters=%r' % (p.nodes, p.iters))
if p.native not in ('auto', 'yes', 'no'):
    raise ValueError("native = %r is invalid: allowed 'auto', 'yes' or 'no'" % p.native)
from woven import _native
from woven.output import build_id
why_not = _native.why_not()
if p.native == 'yes' and why_not:
    raise ValueError('native = yes is invalid here: the native engine cannot be used with woven from %s: %s'
                     % (os.path.dirname(woven.__file__), why_not))
d = out_dir('bench_pyrunner', p)
measured_build = {'woven_package': os.path.dirname(os.path.abspath(woven.__file__)), 'build': build_id(),
                  'native_plugin': 'usable' if not why_not else 'not usable: ' + why_not}
print('bench_pyrunner: measuring woven from %s (build %s); native engine: %s'
      % (measured_build['woven_package'], measured_build['build'], measured_build['native_plugin']))


def chain():
    f = woven.Fabric()
    f.add_yarn([Vector3(1e-4 * i, 0, 0) for i in range(p.nodes)], woven.YarnMaterial(), woven.YarnSection())
    e = woven.FabricEngine(f)
    e.fix(0)
    e.prescribe_velocity(p.nodes - 1, Vector3(1, 0.5, 0))
    return e


def per_iter(engines):
    O.reset()
    O.engines = engines
    O.dt = 1e-9
    t = time.perf_counter()
    O.run(p.iters, True)
    return (time.perf_counter() - t) / p.iters * 1e6


empty = per_iter([])
noop = per_iter([PyRunner(command='pass', iterPeriod=1)])
O.reset()
O.engines = []
e = chain()
# The PyRunner adapter, whichever build this is (WOVEN_NATIVE=0 makes attach take it).
os.environ['WOVEN_NATIVE'], saved = '0', os.environ.get('WOVEN_NATIVE')
woven.attach(e)
if saved is None:
    del os.environ['WOVEN_NATIVE']
else:
    os.environ['WOVEN_NATIVE'] = saved
t = time.perf_counter()
O.run(p.iters, True)
adapter = (time.perf_counter() - t) / p.iters * 1e6
native = None
if not why_not and p.native != 'no':
    O.reset()
    O.engines = []
    en = chain()
    O.engines = [_native.make(en, rewind=False)]
    O.dt = 0.7 * en.dt_crit
    t = time.perf_counter()
    O.run(p.iters, True)
    native = (time.perf_counter() - t) / p.iters * 1e6
e2 = chain()
t = time.perf_counter()
e2.run(0.9 * e2.dt_crit, p.iters)
bare = (time.perf_counter() - t) / p.iters * 1e6
res = {'empty_loop_us': empty, 'pyrunner_noop_us': noop, 'woven_adapter_us': adapter, 'bare_cpp_step_us': bare,
       'adapter_overhead_us': adapter - bare, 'bare_node_steps_per_s': p.nodes / (bare * 1e-6)}
if native is not None:  # the plugin's engine: its cost beyond the bare step and YADE's empty loop
    res.update({'native_engine_us': native, 'native_overhead_us': native - bare - empty})
for k, v in res.items():
    print('bench_pyrunner: %-24s %12.3f' % (k, v))
units = {k: ('us/iteration' if k.endswith('_us') else 'node-steps/s') for k in res}
res.update(measured_build)  # which woven these figures are of
write_summary(d, 'bench_pyrunner', p, res, {'pyrunner_cost_us_quoted': 30.0}, units, 'ok')
