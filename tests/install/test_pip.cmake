# pip knows peelcd (pyproject.toml, setup.py; docs/python.md): in a fresh virtual environment
# (Debian's interpreter and its site packages: NumPy), `pip install --no-build-isolation
# --no-index SOURCE` with the module taken from this build (PEELCD_BUILD_DIR), `pip show`,
# `import peelcd` outside the source tree, a frame; `pip wheel` makes a wheel; `pip uninstall`
# removes it.
#   -DPYTHON=<interpreter> -DBUILD=<peelcd build dir> -DSOURCE=<peelcd source dir> -DWORK=<scratch dir>
file(REMOVE_RECURSE ${WORK})
function(run)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY ${WORK} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()
file(MAKE_DIRECTORY ${WORK})
run(${PYTHON} -m venv --system-site-packages ${WORK}/venv)
set(pip ${CMAKE_COMMAND} -E env PEELCD_BUILD_DIR=${BUILD} ${WORK}/venv/bin/python -m pip)
run(${pip} install --no-build-isolation --no-index ${SOURCE})
run(${WORK}/venv/bin/python -m pip show peelcd)
if(NOT last_output MATCHES "Name: peelcd" OR NOT last_output MATCHES "Location: ${WORK}/venv/lib/python3[.0-9]+/site-packages")
  message(FATAL_ERROR "pip show peelcd: ${last_output}")
endif()
run(${WORK}/venv/bin/python -c "import numpy as np, peelcd
V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, -0.5], [0.2, 0.2, 0.5], [0.6, 0.2, 0]], float)
a = peelcd.Mesh(V[:3], np.array([[0, 1, 2]]))
b = peelcd.Mesh(V[3:], np.array([[0, 1, 2]]))
r = peelcd.collide(a, b)
assert r and len(r['triangles']) == 1, r
print(peelcd.__file__)")
if(NOT last_output MATCHES "${WORK}/venv/lib/python3[.0-9]+/site-packages/peelcd/__init__.py")
  message(FATAL_ERROR "import peelcd did not load the installed package: ${last_output}")
endif()
run(${pip} wheel --no-build-isolation --no-index --no-deps -w ${WORK}/dist ${SOURCE})
file(GLOB wheels ${WORK}/dist/peelcd-*.whl)
if(NOT wheels)
  message(FATAL_ERROR "pip wheel made no peelcd wheel in ${WORK}/dist")
endif()
run(${WORK}/venv/bin/python -m pip uninstall -y peelcd)
# Gone from the venv (a peelcd installed for Debian's interpreter may still import, from there).
execute_process(COMMAND ${WORK}/venv/bin/python -m pip show peelcd WORKING_DIRECTORY ${WORK} RESULT_VARIABLE rc
                OUTPUT_QUIET ERROR_QUIET)
file(GLOB left ${WORK}/venv/lib/python3*/site-packages/peelcd*)
if(rc EQUAL 0 OR left)
  message(FATAL_ERROR "pip uninstall peelcd left it in the venv: ${left}")
endif()
message(STATUS "ok: installed, imported, wheel ${wheels}, uninstalled")
