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
# The per-texel readout: the page reads its first layer's first texel back through it.
if(NOT text MATCHES "readout ok")
  message(FATAL_ERROR "viewer: no per-texel readout: '${text}'")
endif()
# The search: a triangle of the first colliding pair (the dump's colliding.txt), run on load
# through the address (#search=a:T), must find its colliding pairs.
file(GLOB colliding_files ${WORK}/dump/*/colliding.txt)
list(GET colliding_files 0 colliding_file)
file(STRINGS ${colliding_file} first_pair LIMIT_COUNT 1)
string(REGEX MATCH "^([0-9]+)" tri "${first_pair}")
execute_process(COMMAND ${CHROMIUM} ${flags} --dump-dom "file://${WORK}/dump/index.html#search=a:${tri}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE dom2 ERROR_VARIABLE log2 TIMEOUT 120)
string(REGEX MATCH "data-status=\"([a-z]+)\"[^>]*>([^<]*)" status2 "${dom2}")
if(NOT CMAKE_MATCH_1 STREQUAL "ok" OR NOT CMAKE_MATCH_2 MATCHES "search \"a:${tri}\": [1-9][0-9]* colliding pairs hold it")
  message(FATAL_ERROR "viewer: the search of A's triangle ${tri} found nothing: '${CMAKE_MATCH_2}'")
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
