# A dump at 2048^2 in headless Chromium: the page loads its layers' words on demand (one script a
# layer) and reads its first texel back; prints how long that took (not asserted: timings are
# for benchmarks). Run as: cmake -DPEELCD=<exe> -DCHROMIUM=<exe> -DCASE=<scene> -DWORK=<dir> -P ...
if(NOT CHROMIUM OR NOT EXISTS "${CHROMIUM}")
  message(FATAL_ERROR "viewer: chromium not found (scripts/bootstrap.sh installs Debian's chromium)")
endif()
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
execute_process(COMMAND ${PEELCD} dump ${CASE} --res 2048 --out ${WORK}/dump RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "viewer: peelcd dump --res 2048 failed (${rc}): ${out}${err}")
endif()
file(GLOB layer_scripts ${WORK}/dump/*/view0/layer*.js)
if(NOT layer_scripts)
  message(FATAL_ERROR "viewer: a 2048^2 dump wrote no layer scripts")
endif()
include(${CMAKE_CURRENT_LIST_DIR}/page_status.cmake)
set(flags --headless --no-sandbox --disable-gpu --no-first-run --user-data-dir=${WORK}/profile --virtual-time-budget=30000
          --window-size=1400,1000)
string(TIMESTAMP t0 "%s")
page_status(file://${WORK}/dump/index.html state text)
string(TIMESTAMP t1 "%s")
math(EXPR seconds "${t1} - ${t0}")
if(NOT state STREQUAL "ok" OR NOT text MATCHES "readout ok")
  message(FATAL_ERROR "viewer: the 2048^2 dump does not read out: '${text}'")
endif()
message(STATUS "viewer: 2048^2 dump: ${text}; headless Chromium from start to the status: ${seconds} s")
# The dump is large: removed once checked.
file(REMOVE_RECURSE ${WORK})
