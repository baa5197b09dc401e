# Opens a dump's index.html in headless Chromium (no network: the page is self-contained) and
# checks the status the page's own script sets after loading: every layer image decoded, no
# script error. Saves a screenshot beside the dump.
# Run by ctest as: cmake -DPEELCD=<exe> -DCHROMIUM=<exe> -DCASE=<scene> -DWORK=<dir> -P test_viewer.cmake
if(NOT CHROMIUM OR NOT EXISTS "${CHROMIUM}")
  message(FATAL_ERROR "viewer: chromium not found (scripts/bootstrap.sh installs Debian's chromium)")
endif()
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
execute_process(COMMAND ${PEELCD} dump ${CASE} --out ${WORK}/dump RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "viewer: peelcd dump failed (${rc}): ${out}${err}")
endif()
file(GLOB_RECURSE pngs ${WORK}/dump/*.png)
list(LENGTH pngs npngs)

# Root in a container needs --no-sandbox; a private profile keeps runs independent.
set(flags --headless --no-sandbox --disable-gpu --no-first-run --user-data-dir=${WORK}/profile
          --virtual-time-budget=10000 --window-size=1400,1000 --hide-scrollbars)
execute_process(COMMAND ${CHROMIUM} ${flags} --dump-dom file://${WORK}/dump/index.html
                RESULT_VARIABLE rc OUTPUT_VARIABLE dom ERROR_VARIABLE log TIMEOUT 120)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "viewer: chromium --dump-dom failed (${rc}): ${log}")
endif()
string(REGEX MATCH "data-status=\"([a-z]+)\"[^>]*>([^<]*)" status "${dom}")
set(state "${CMAKE_MATCH_1}")
set(text "${CMAKE_MATCH_2}")
if(NOT state STREQUAL "ok")
  message(FATAL_ERROR "viewer: the page reports '${state}': ${text}")
endif()
if(NOT text MATCHES "${npngs} layer images loaded")
  message(FATAL_ERROR "viewer: '${text}', but the dump has ${npngs} layer previews")
endif()
# Chromium prints uncaught page errors as console messages on stderr.
if(log MATCHES "Uncaught|CONSOLE\\([0-9]+\\).*[Ee]rror")
  message(FATAL_ERROR "viewer: page errors in the console:\n${log}")
endif()
execute_process(COMMAND ${CHROMIUM} ${flags} --screenshot=${WORK}/screenshot.png file://${WORK}/dump/index.html
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE log TIMEOUT 120)
if(NOT rc EQUAL 0 OR NOT EXISTS ${WORK}/screenshot.png)
  message(FATAL_ERROR "viewer: no screenshot (${rc}): ${log}")
endif()
message(STATUS "viewer ok: ${text}; screenshot ${WORK}/screenshot.png")
