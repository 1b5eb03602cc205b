# The native YADE plugin (docs/yade_native.md), built only with -DYADE_SOURCE_DIR=<YADE's source tree>.
# Included from CMakeLists.txt after Python3 and Boost are found. Defines:
#   woven_core_native  the core as a shared library (the default build's flags): the Python module _woven
#                      and the plugin share it, so a woven.FabricEngine made by a script is the very
#                      object the plugin's engine steps
#   woven_yade         libwoven_yade.so, the YADE classes (WovenFabricEngine, ...), loaded by yade
#   woven_newprobe     a tiny operator-new recorder for the ABI test (tests/yade/abi_sizes.py)
# and sets WOVEN_PY_CORE (what _woven links) and WOVEN_YADE_PLUGIN_DIR (where both libraries go).
if(NOT EXISTS "${YADE_SOURCE_DIR}/core/Scene.hpp" OR NOT EXISTS "${YADE_SOURCE_DIR}/lib/serialization/Serializable.hpp")
  message(FATAL_ERROR "YADE_SOURCE_DIR = ${YADE_SOURCE_DIR} is invalid: allowed YADE's source tree (core/Scene.hpp, "
                      "lib/serialization/Serializable.hpp), e.g. `apt-get source yade` or YADE's repository at tag 2023.02a")
endif()
if(NOT WOVEN_PYTHON)
  message(FATAL_ERROR "YADE_SOURCE_DIR needs WOVEN_PYTHON=ON (scripts build the fabric through the Python module)")
endif()

# --- the installed YADE's compile definitions, read from yade.config at configure time -----------
find_program(WOVEN_YADE_EXECUTABLE NAMES yade REQUIRED)
set(_cfg "${CMAKE_BINARY_DIR}/yade_config.cmake")
execute_process(COMMAND ${WOVEN_YADE_EXECUTABLE} -n -x "${CMAKE_CURRENT_SOURCE_DIR}/cmake/yade_config.py" "${_cfg}"
                RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _err TIMEOUT 600)
if(NOT _rc EQUAL 0 OR NOT EXISTS "${_cfg}")
  message(FATAL_ERROR "`${WOVEN_YADE_EXECUTABLE} -n -x cmake/yade_config.py` failed (${_rc}): ${_err}")
endif()
include("${_cfg}")
if(NOT WOVEN_YADE_REAL_BITS EQUAL 64)
  message(FATAL_ERROR "the installed YADE computes with ${WOVEN_YADE_REAL_BITS}-bit Real: woven needs yade-double (64)")
endif()
if(WOVEN_YADE_UNKNOWN_FEATURES)
  message(WARNING "YADE features woven does not know how to map to definitions: ${WOVEN_YADE_UNKNOWN_FEATURES}; the ABI test will tell")
endif()
message(STATUS "woven native: YADE ${WOVEN_YADE_VERSION} in ${WOVEN_YADE_LIBDIR}; definitions ${WOVEN_YADE_DEFINES}")
# The plugin's sources see YADE's classes only, compiled exactly as libyade (all of YADE's definitions,
# EIGEN_DONT_ALIGN and EIGEN_DONT_VECTORIZE included: they change Eigen's layout and rounding), and
# woven's engine only as an opaque type through pkg/engine/HostBridge.hpp. The core keeps the default
# build's flags (Eigen aligned and vectorized), so its code and its bits are the default build's.

# --- where yade finds the plugin ------------------------------------------------------------------
# yade loads every lib*.so under <prefix>/<libPATH>/yade<suffix>/ (recursively). Default: the `woven`
# subfolder of a prefix under the build tree's install prefix; a root install sets
# -DWOVEN_YADE_PLUGIN_DIR=/usr/lib/x86_64-linux-gnu/yade-double/woven (README).
set(WOVEN_YADE_PLUGIN_DIR "${CMAKE_INSTALL_PREFIX}/${WOVEN_YADE_LIBPATH}/yade${WOVEN_YADE_SUFFIX}/woven" CACHE PATH
    "Folder of libwoven_yade.so and libwoven_core.so (a subfolder of a yade-double folder yade searches)")

# --- the core, shared -----------------------------------------------------------------------------
add_library(woven_core_native SHARED ${WOVEN_CORE_SOURCES})
set_target_properties(woven_core_native PROPERTIES OUTPUT_NAME woven_core)
target_include_directories(woven_core_native PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/pkg)
target_link_libraries(woven_core_native PUBLIC Eigen3::Eigen OpenMP::OpenMP_CXX)
# One id for this build's core library and Python module (pkg/engine/HostBridge.hpp, coreBuildId):
# drawn once per build folder.
if(NOT WOVEN_BUILD_ID)
  string(RANDOM LENGTH 12 ALPHABET 0123456789abcdef _id)
  set(WOVEN_BUILD_ID "native-${_id}" CACHE INTERNAL "id of this native build (core and _woven)")
endif()
target_compile_definitions(woven_core_native PRIVATE WOVEN_BUILD_ID="${WOVEN_BUILD_ID}")
set(WOVEN_PY_CORE woven_core_native)

# --- the plugin -----------------------------------------------------------------------------------
find_path(WOVEN_MPI_INCLUDE_DIR mpi.h PATHS /usr/lib/x86_64-linux-gnu/openmpi/include /usr/include/x86_64-linux-gnu/openmpi)
if("YADE_MPI" IN_LIST WOVEN_YADE_DEFINES AND NOT WOVEN_MPI_INCLUDE_DIR)
  message(FATAL_ERROR "YADE was built with MPI (Scene's layout depends on it): mpi.h is needed: apt-get install libopenmpi-dev")
endif()
set(_yade_libs "")
foreach(_l yade pkg_common pkg_dem)
  set(_p "${WOVEN_YADE_LIBDIR}/lib${_l}.so")
  if(NOT EXISTS "${_p}")
    message(FATAL_ERROR "${_p} not found: the native plugin links YADE's libyade, libpkg_common and libpkg_dem")
  endif()
  list(APPEND _yade_libs "${_p}")
endforeach()
file(GLOB WOVEN_YADE_SOURCES CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/pkg/yade/*.cpp)
add_library(woven_yade SHARED ${WOVEN_YADE_SOURCES})
# YADE's headers need GNU extensions (float128 literals) and its include root; woven's pkg/ comes first
# (its core/Types.hpp beside YADE's core/).
set_target_properties(woven_yade PROPERTIES CXX_EXTENSIONS ON)
target_include_directories(woven_yade PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/pkg ${YADE_SOURCE_DIR} ${Python3_INCLUDE_DIRS})
if(WOVEN_MPI_INCLUDE_DIR)
  target_include_directories(woven_yade SYSTEM PRIVATE ${WOVEN_MPI_INCLUDE_DIR})
endif()
target_compile_definitions(woven_yade PRIVATE ${WOVEN_YADE_DEFINES} BOOST_BIND_GLOBAL_PLACEHOLDERS BOOST_ALLOW_DEPRECATED_HEADERS)
if("YADE_CGAL" IN_LIST WOVEN_YADE_DEFINES)
  target_compile_options(woven_yade PRIVATE -frounding-math)
endif()
# Inline functions the plugin emits stay in it (never interpose on libyade's or the core's copies).
target_compile_options(woven_yade PRIVATE -fvisibility-inlines-hidden -Wno-unused-parameter -Wno-deprecated-declarations)
# Boost and Python symbols come from the running yade: no --no-undefined.
# OpenGL (the drawer, pkg/yade/WovenGlDrawer.cpp): libGL, as libpkg_common's OpenGLRenderer uses.
find_package(OpenGL REQUIRED COMPONENTS OpenGL)
target_link_libraries(woven_yade PRIVATE woven_core_native ${_yade_libs} OpenGL::GL)
set_target_properties(woven_yade PROPERTIES BUILD_RPATH "${WOVEN_YADE_LIBDIR};$<TARGET_FILE_DIR:woven_core_native>"
                                            INSTALL_RPATH "${WOVEN_YADE_LIBDIR};${WOVEN_YADE_PLUGIN_DIR}")
set_target_properties(woven_core_native PROPERTIES INSTALL_RPATH "${WOVEN_YADE_PLUGIN_DIR}")
install(TARGETS woven_yade woven_core_native LIBRARY DESTINATION ${WOVEN_YADE_PLUGIN_DIR})

# --- the ABI probe: records the sizes operator new is asked for (LD_PRELOAD'ed into a yade run) ----
add_library(woven_newprobe SHARED ${CMAKE_CURRENT_SOURCE_DIR}/tests/yade/newprobe.cpp)
set_target_properties(woven_newprobe PROPERTIES OUTPUT_NAME woven_newprobe)
# CTest of the native build: the plugin's class sizes against the installed libyade (run after
# `cmake --install` and scripts/yade_prefix.sh, with YADE_PREFIX pointing at the prefix).
enable_testing()
add_test(NAME yade_abi_sizes
         COMMAND ${CMAKE_COMMAND} -E env LD_PRELOAD=$<TARGET_FILE:woven_newprobe> YADE_PREFIX=${CMAKE_INSTALL_PREFIX}
                 ${WOVEN_YADE_EXECUTABLE} -n -x ${CMAKE_CURRENT_SOURCE_DIR}/tests/yade/abi_sizes.py)
# The native pytest file (tests/python/test_native.py) against the installed package and plugin.
add_test(NAME yade_native_pytest
         COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${WOVEN_PYTHON_SITE} YADE_PREFIX=${CMAKE_INSTALL_PREFIX}
                 OMP_WAIT_POLICY=passive ${Python3_EXECUTABLE} -m pytest -q ${CMAKE_CURRENT_SOURCE_DIR}/tests/python/test_native.py
         WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/tests/python)
# The ABI test must be able to fail: the same sizes compiled without the Eigen alignment definitions
# and YADE_MPI (State and Scene then differ) must be reported as a mismatch (exit 1).
add_library(woven_abi_mismatch SHARED ${CMAKE_CURRENT_SOURCE_DIR}/pkg/yade/AbiSizes.cpp)
set(_mismatch_defs ${WOVEN_YADE_DEFINES})
list(REMOVE_ITEM _mismatch_defs EIGEN_DONT_VECTORIZE EIGEN_DONT_ALIGN EIGEN_DISABLE_UNALIGNED_ARRAY_ASSERT YADE_MPI)
set_target_properties(woven_abi_mismatch PROPERTIES CXX_EXTENSIONS ON EXCLUDE_FROM_ALL ON)
target_include_directories(woven_abi_mismatch PRIVATE ${YADE_SOURCE_DIR} ${Python3_INCLUDE_DIRS})
target_compile_definitions(woven_abi_mismatch PRIVATE ${_mismatch_defs} BOOST_BIND_GLOBAL_PLACEHOLDERS BOOST_ALLOW_DEPRECATED_HEADERS)
target_compile_options(woven_abi_mismatch PRIVATE -frounding-math -Wno-deprecated-declarations)
target_link_libraries(woven_abi_mismatch PRIVATE Eigen3::Eigen)
if(WOVEN_MPI_INCLUDE_DIR)
  target_include_directories(woven_abi_mismatch SYSTEM PRIVATE ${WOVEN_MPI_INCLUDE_DIR})
endif()
add_test(NAME yade_abi_build_mismatch COMMAND ${CMAKE_COMMAND} --build ${CMAKE_BINARY_DIR} --target woven_abi_mismatch)
add_test(NAME yade_abi_detects_mismatch
         COMMAND ${CMAKE_COMMAND} -E env LD_PRELOAD=$<TARGET_FILE:woven_newprobe> YADE_PREFIX=${CMAKE_INSTALL_PREFIX}
                 ${WOVEN_YADE_EXECUTABLE} -n -x ${CMAKE_CURRENT_SOURCE_DIR}/tests/yade/abi_sizes.py $<TARGET_FILE:woven_abi_mismatch>)
set_tests_properties(yade_abi_detects_mismatch PROPERTIES DEPENDS yade_abi_build_mismatch
                     PASS_REGULAR_EXPRESSION "abi_sizes: FAILED: .*State.*differ")
