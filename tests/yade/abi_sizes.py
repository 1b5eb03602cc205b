# ABI test of the native plugin (docs/yade_native.md): the sizes of YADE's classes as the plugin was
# compiled (YADE's source + the definitions cmake/yade_config.py read) must equal the sizes the
# installed libyade allocates. A plugin compiled against another YADE version or other definitions
# lays out State, Scene, Body... differently and corrupts memory at the first access: this test says
# so instead.
#
#   LD_PRELOAD=<build>/libwoven_newprobe.so YADE_PREFIX=<prefix> yade -n -x tests/yade/abi_sizes.py
#
# How Debian's sizes are observed: libwoven_newprobe.so (tests/yade/newprobe.cpp) replaces operator
# new and records the sizes asked while armed; YADE's Python constructors do `new T` first
# (Serializable_ctor_kwAttrs), and O.addScene() does `new Scene` first. The plugin's sizes come from
# its extern "C" woven_yade_sizeof (pkg/yade/AbiSizes.cpp). Exit status 0: all equal; 1: a mismatch
# (listed); 2: the test could not run (probe or plugin missing).
import ctypes
import sys

import yade.wrapper


def loaded_plugin():
    for line in open('/proc/self/maps'):
        if line.rstrip().endswith('/libwoven_yade.so'):
            return line.split()[-1]
    return None


# argv[1] (optional): a library with woven_yade_sizeof to check instead of the loaded plugin (the
# CTest yade_abi_detects_mismatch gives one compiled without YADE's definitions: it must fail).
path = sys.argv[1] if len(sys.argv) > 1 else loaded_plugin()
if path is None:
    print('abi_sizes: FAILED TO RUN: libwoven_yade.so is not loaded (set YADE_PREFIX to the prefix the plugin is installed in)')
    sys.exit(2)
plugin = ctypes.CDLL(path)  # the same handle yade loaded (dlopen counts references)
plugin.woven_yade_sizeof.restype = ctypes.c_long
plugin.woven_yade_sizeof.argtypes = [ctypes.c_char_p]
plugin.woven_yade_abi_classes.restype = ctypes.c_char_p
me = ctypes.CDLL(None)
try:
    arm, disarm, count, size = (me.woven_probe_arm, me.woven_probe_disarm, me.woven_probe_count, me.woven_probe_size)
except AttributeError:
    print('abi_sizes: FAILED TO RUN: the operator-new probe is not preloaded (LD_PRELOAD=<build>/libwoven_newprobe.so)')
    sys.exit(2)
size.restype = ctypes.c_long


def allocated(make):
    """Size of the first operator new during make()."""
    arm()
    obj = make()
    disarm()
    n = count()
    return (size(0) if n > 0 else -1), obj


O = yade.wrapper.Omega()
rows, bad = [], []
for name in plugin.woven_yade_abi_classes().decode().split():
    ours = plugin.woven_yade_sizeof(name.encode())
    if name == 'Scene':
        debian, _ = allocated(lambda: O.addScene())
    else:
        debian, _ = allocated(getattr(yade.wrapper, name))
    rows.append((name, ours, debian))
    if ours != debian:
        bad.append(name)
for name, ours, debian in rows:
    print('abi_sizes: %-22s plugin %5d  installed libyade %5d  %s' % (name, ours, debian, 'ok' if ours == debian else 'MISMATCH'))
if bad:
    print('abi_sizes: FAILED: %s differ between the plugin and the installed YADE. The YADE source the plugin was built '
          'against (YADE_SOURCE_DIR) is not the installed version, or its definitions differ (cmake/yade_config.py); '
          'use the exact source (`apt-get source yade` or tag %s) and reconfigure.'
          % (', '.join(bad), yade.config.version if hasattr(yade, 'config') else 'of the installed yade'))
    sys.exit(1)
print('abi_sizes: ok, %d classes' % len(rows))
sys.exit(0)
