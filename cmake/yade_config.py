# Run by CMake at configure time (cmake/WovenYade.cmake) as `yade -n -x cmake/yade_config.py OUT`:
# writes OUT, a CMake file setting WOVEN_YADE_DEFINES (the compile definitions of the installed YADE,
# read from yade.config.features the way YADE's own CMakeLists.txt sets them) and the facts the plugin
# needs (version, libDir, precision). A plugin compiled with other definitions than libyade has other
# class layouts (Scene depends on YADE_MPI, State on the Eigen alignment...): tests/yade/abi_sizes.py
# checks the result against the installed binaries.
import sys
import yade.config as c
import yade.log

out = sys.argv[1]
feats = set(c.features)
# feature of yade.config.features -> definitions (YADE 2023.02a CMakeLists.txt)
table = {
    'LOGGER': ['YADE_BOOST_LOG', 'BOOST_LOG_DYN_LINK'],
    'COMPLEX_MP': ['YADE_COMPLEX_MP'],
    'VTK': ['YADE_VTK'],
    'OPENMP': ['YADE_OPENMP'],
    'GTS': ['YADE_GTS'],
    'QT5': ['YADE_OPENGL', 'YADE_QT5', 'QT_NO_KEYWORDS'],
    'CGAL': ['YADE_CGAL', 'CGAL_DISABLE_ROUNDING_MATH_CHECK'],
    'PFVFLOW': ['FLOW_ENGINE'],
    'LINSOLV': ['LINSOLV'],
    'MPI': ['YADE_MPI', 'OMPI_SKIP_MPICXX=1'],
    'TWOPHASEFLOW': ['TWOPHASEFLOW'],
    'LS_DEM': ['YADE_LS_DEM'],
    'FEMLIKE': ['YADE_FEM'],
    'GL2PS': ['YADE_GL2PS'],
    'LBMFLOW': ['LBM_ENGINE'],
    'THERMAL': ['THERMAL'],
    'PARTIALSAT': ['PARTIALSAT'],
    'POTENTIAL_PARTICLES': ['YADE_POTENTIAL_PARTICLES'],
    'POTENTIAL_BLOCKS': ['YADE_POTENTIAL_BLOCKS'],
    'SPH': ['YADE_SPH'],
    'DEFORM': ['YADE_DEFORM'],
    'LIQMIGRATION': ['YADE_LIQMIGRATION'],
    'MASK_ARBITRARY': ['YADE_MASK_ARBITRARY', 'YADE_MASK_ARBITRARY_SIZE=256'],
    'PROFILING': ['USE_TIMING_DELTAS', 'ISC_TIMING'],
    'MPFR': ['YADE_MPFR'],
}
ignored = {'USEFUL_ERRORS', 'ASAN', 'FAST_NATIVE', 'MPC', 'CHOLMOD_GPU', 'VECTORIZE'}
unknown = sorted(feats - set(table) - ignored)
defs = ['YADE_ODEINT']  # boost >= 1.53: always on
for f in sorted(feats):
    defs += table.get(f, [])
if 'VECTORIZE' not in feats:  # YADE built without vectorization: Eigen objects are not aligned
    defs += ['EIGEN_DONT_VECTORIZE', 'EIGEN_DONT_ALIGN', 'EIGEN_DISABLE_UNALIGNED_ARRAY_ASSERT']
defs += ['YADE_REAL_BIT=%d' % c.highPrecisionBits, 'YADE_REAL_DEC=%d' % c.highPrecisionDecimalPlaces]
try:
    import yade.math
    if len(yade.math.getRealHPCppDigits10()) <= 1:
        defs.append('YADE_DISABLE_REAL_MULTI_HP')
except Exception:
    pass
defs.append('MAX_LOG_LEVEL=%d' % yade.log.getMaxLevel())
with open(out, 'w') as f:
    f.write('set(WOVEN_YADE_DEFINES "%s")\n' % ';'.join(defs))
    f.write('set(WOVEN_YADE_FEATURES "%s")\n' % ';'.join(sorted(feats)))
    f.write('set(WOVEN_YADE_UNKNOWN_FEATURES "%s")\n' % ';'.join(unknown))
    f.write('set(WOVEN_YADE_VERSION "%s")\n' % c.version)
    f.write('set(WOVEN_YADE_LIBDIR "%s")\n' % c.libDir)
    f.write('set(WOVEN_YADE_LIBPATH "%s")\n' % c.libPATH)
    f.write('set(WOVEN_YADE_SUFFIX "%s")\n' % c.suffix)
    f.write('set(WOVEN_YADE_REAL_BITS "%d")\n' % c.highPrecisionBits)
