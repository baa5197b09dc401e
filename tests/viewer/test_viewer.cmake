# Opens a dump's index.html in headless Chromium (no network: the page is self-contained) and
# checks the status the page's own script sets after loading: every layer image decoded, no
# script error. Then a two-dump comparison's page and the --paper dump's missed pairs. Saves
# screenshots in WORK (screenshot*.png: docs/images/viewer_*.png are copies).
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

include(${CMAKE_CURRENT_LIST_DIR}/page_status.cmake)
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
# Two dumps texel by texel: a copy of the dump with its first view's layer 00 replaced by its layer
# 01 (EXR files), compared on the exact tier; the report's page must mark as many texels beyond
# the tolerance as the comparison counts, and none within (tests/oracle checks the marks texel
# by texel on synthetic layers).
file(GLOB first_views LIST_DIRECTORIES true ${WORK}/dump/*/view0)
list(GET first_views 0 first_view)
file(RELATIVE_PATH first_view_rel ${WORK}/dump ${first_view})
file(COPY ${WORK}/dump/ DESTINATION ${WORK}/perturbed)
file(COPY_FILE ${WORK}/dump/${first_view_rel}/layer01.exr ${WORK}/perturbed/${first_view_rel}/layer00.exr)
execute_process(COMMAND ${PEELCD} golden compare-dumps ${WORK}/dump ${WORK}/perturbed --tier exact --report ${WORK}/diff
                RESULT_VARIABLE rc OUTPUT_VARIABLE diff_out ERROR_VARIABLE diff_err)
string(REGEX MATCH "differing texels: ([0-9]+)" counted "${diff_out}")
set(counted "${CMAKE_MATCH_1}")
if(NOT rc EQUAL 1 OR NOT counted OR NOT EXISTS ${WORK}/diff/index.html)
  message(FATAL_ERROR "viewer: compare-dumps of a perturbed copy (${rc}) wrote no page:\n${diff_out}${diff_err}")
endif()
page_status(file://${WORK}/diff/index.html state4 text4)
if(NOT state4 STREQUAL "ok" OR NOT text4 MATCHES "diff ok: 1 layers, ${counted} texels beyond the tolerance, 0 within")
  message(FATAL_ERROR "viewer: the two-dump page marks other texels than the ${counted} compared: '${text4}'")
endif()
message(STATUS "viewer: two dumps: ${text4}")
execute_process(COMMAND ${CHROMIUM} ${flags} --screenshot=${WORK}/screenshot_two_dumps.png file://${WORK}/diff/index.html
                OUTPUT_QUIET ERROR_QUIET TIMEOUT 120)
# A real backend difference: this machine's dump of the torus and fish case against the NVIDIA
# H100's (docs/backends/nvidia-h100-2026-11-27/dump_torus_fish_genus1): the hardware tier passes,
# and the report's page marks its differing texels, all within the tolerance.
set(h100_dump ${SOURCE}/docs/backends/nvidia-h100-2026-11-27/dump_torus_fish_genus1)
if(SOURCE AND EXISTS ${h100_dump}/meta.json)
  execute_process(COMMAND ${PEELCD} dump ${SOURCE}/fixtures/golden/torus_fish_genus1/case.json --out ${WORK}/torus
                  RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
  execute_process(COMMAND ${PEELCD} golden compare-dumps ${WORK}/torus ${h100_dump} --tier hardware --report ${WORK}/h100
                  RESULT_VARIABLE rc OUTPUT_VARIABLE h100_out ERROR_VARIABLE err)
  string(REGEX MATCH "plus ([0-9]+) within tolerance" within "${h100_out}")
  if(NOT rc EQUAL 0 OR NOT within OR NOT EXISTS ${WORK}/h100/index.html)
    message(FATAL_ERROR "viewer: the H100 dump against this machine's (${rc}):\n${h100_out}${err}")
  endif()
  page_status(file://${WORK}/h100/index.html state5 text5)
  if(NOT state5 STREQUAL "ok" OR NOT text5 MATCHES "diff ok: [1-9][0-9]* layers, 0 texels beyond the tolerance, [1-9][0-9]* within")
    message(FATAL_ERROR "viewer: the H100 difference page: '${text5}'")
  endif()
  message(STATUS "viewer: H100 against this machine: ${text5}")
endif()
# Missed pairs: the README's walkthrough dump (--paper, 512^2) lists every reference pair the
# frame missed (reference.txt less colliding.txt), and the search of a missed pair (351,1283 of
# the default scene) shows why, from peelcd explain's verdict stored in missed.txt.
if(SCENE)
  execute_process(COMMAND ${PEELCD} dump ${SCENE} --paper --out ${WORK}/paper RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "viewer: peelcd dump --paper failed (${rc}): ${out}${err}")
  endif()
  file(GLOB reference_file ${WORK}/paper/*/reference.txt)
  file(GLOB paper_colliding ${WORK}/paper/*/colliding.txt)
  file(STRINGS ${reference_file} reference_lines)
  file(STRINGS ${paper_colliding} colliding_lines)
  set(missed_count 0)
  foreach(line IN LISTS reference_lines)
    string(REGEX MATCH "^[0-9]+ [0-9]+" key "${line}")
    string(REGEX MATCH "(^|;)${key} " found "${colliding_lines}")
    if(NOT found)
      math(EXPR missed_count "${missed_count} + 1")
    endif()
  endforeach()
  page_status("file://${WORK}/paper/index.html#search=351,1283" state3 text3)
  set(dom3 "${page_dom}")
  if(NOT state3 STREQUAL "ok" OR NOT text3 MATCHES "search \"351,1283\": 0 colliding pairs hold it; missed: [a-z_]+: ")
    message(FATAL_ERROR "viewer: the missed pair 351,1283 of the --paper dump shows no verdict: '${text3}'")
  endif()
  # The pair's two triangles found in the layers by the IDs they write, and where they meet.
  if(NOT text3 MATCHES "in the layers: A's triangle .ID [0-9]+. in [1-9][0-9]* texels, B's .ID [0-9]+. in [1-9][0-9]*, meeting in depth at [0-9]+")
    message(FATAL_ERROR "viewer: the missed pair 351,1283 is not drawn in the layers: '${text3}'")
  endif()
  # Its texel words (29 MB) are one file a layer, loaded on demand: the readout works all the same.
  file(GLOB layer_scripts ${WORK}/paper/*/view0/layer*.js)
  if(NOT layer_scripts OR NOT text3 MATCHES "readout ok")
    message(FATAL_ERROR "viewer: the 512^2 --paper dump reads no texel back: '${text3}'")
  endif()
  string(REGEX MATCHALL "<tr class=\"pair missed\"" missed_rows "${dom3}")
  list(LENGTH missed_rows missed_listed)
  if(missed_count EQUAL 0 OR NOT missed_listed EQUAL missed_count)
    message(FATAL_ERROR "viewer: the --paper page lists ${missed_listed} missed pairs; reference.txt less colliding.txt has ${missed_count}")
  endif()
  message(STATUS "viewer: --paper dump, ${missed_listed} missed pairs listed; ${text3}")
  execute_process(COMMAND ${CHROMIUM} ${flags} --screenshot=${WORK}/screenshot_missed.png
                          "file://${WORK}/paper/index.html#search=351,1283" OUTPUT_QUIET ERROR_QUIET TIMEOUT 120)
endif()
message(STATUS "viewer ok: ${text}; screenshot ${WORK}/screenshot.png")
