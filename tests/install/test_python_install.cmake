# The Python module's install into a fresh virtual environment (docs/python.md): made with
# Debian's interpreter and its site packages (NumPy), `cmake --install BUILD --component python
# --prefix VENV`, then `import peelcd` from the venv's interpreter, run outside the build tree.
file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${PYTHON} -m venv --system-site-packages ${WORK} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "python -m venv failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --component python --prefix ${WORK} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install --component python failed (${rc})")
endif()
execute_process(COMMAND ${WORK}/bin/python -c "import peelcd, os; print(peelcd.__version__, os.path.dirname(peelcd.__file__))"
                WORKING_DIRECTORY ${WORK} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "${WORK}/lib/python3[.0-9]+/site-packages/peelcd")
  message(FATAL_ERROR "import peelcd from the venv failed (${rc}): ${out} ${err}")
endif()
message(STATUS "ok: ${out}")
