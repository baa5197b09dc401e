# Dumps from any producer (docs/dump-format.md):
#  - a dump written by tests/oracle/independent_writer.cpp (its own EXR encoder and meta.json)
#    compares equal with `peelcd dump --backend cpu` of the same scene (exact tier), on a lossy
#    one-ROI scene and a conservative many-ROI scene;
#  - `peelcd golden compare-dumps` exits 0 for two dumps of one frame, 1 with a report for two
#    views of it, 2 for a truncated EXR, a missing layer and a malformed meta.json (naming the file);
#  - every meta.json (these dumps, every golden) validates against the JSON Schema, and a broken
#    one does not.
# Run by ctest: cmake -DPEELCD=.. -DWRITER=.. -DPYTHON=.. -DSOURCE=.. -DWORK=.. -P test_dumps.cmake
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

function(run expected_rc)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL expected_rc)
    message(FATAL_ERROR "expected exit ${expected_rc}, got ${rc}: ${ARGN}\n${out}\n${err}")
  endif()
  set(last_out "${out}" PARENT_SCOPE)
  set(last_err "${err}" PARENT_SCOPE)
endfunction()

function(expect text where)
  string(FIND "${where}" "${text}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "expected \"${text}\" in:\n${where}")
  endif()
endfunction()

set(metas "")
foreach(case bunny_dragon_front_paper crowded_conservative_16)
  set(scene ${SOURCE}/fixtures/golden/${case}/case.json)
  run(0 ${WRITER} ${scene} ${WORK}/${case}_independent)
  run(0 ${PEELCD} dump ${scene} --backend cpu --out ${WORK}/${case}_peelcd --quiet)
  run(0 ${PEELCD} golden compare-dumps ${WORK}/${case}_peelcd ${WORK}/${case}_independent --report ${WORK}/report_${case})
  expect("match" "${last_out}")
  list(APPEND metas ${WORK}/${case}_independent/meta.json ${WORK}/${case}_peelcd/meta.json)
endforeach()

# Two dumps of one frame: 0. Two views of it: 1, the report written.
set(scene ${SOURCE}/fixtures/golden/boxes_crossing/case.json)
run(0 ${PEELCD} dump ${scene} --out ${WORK}/first --quiet)
run(0 ${PEELCD} dump ${scene} --out ${WORK}/second --quiet)
run(0 ${PEELCD} dump ${scene} --theta 75 --out ${WORK}/turned --quiet)
run(0 ${PEELCD} golden compare-dumps ${WORK}/first ${WORK}/second)
run(1 ${PEELCD} golden compare-dumps ${WORK}/first ${WORK}/turned --report ${WORK}/report_turned)
expect("DIFFERENT" "${last_out}")
expect("first differing texels" "${last_out}")
if(NOT EXISTS ${WORK}/report_turned/report.txt OR NOT EXISTS ${WORK}/report_turned/pair0_box_bar_view0_layer00_error.png)
  message(FATAL_ERROR "compare-dumps wrote no report for two different views")
endif()
# The hardware tier accepts the same frame, not a turned one.
run(0 ${PEELCD} golden compare-dumps ${WORK}/first ${WORK}/second --tier hardware)
run(1 ${PEELCD} golden compare-dumps ${WORK}/first ${WORK}/turned --tier hardware --report ${WORK}/report_turned_hw)

# Malformed dumps: 2, naming the file.
file(COPY ${WORK}/second/ DESTINATION ${WORK}/truncated)
set(exr ${WORK}/truncated/pair0_box_bar/view0/layer01.exr)
# The first 2000 bytes of the layer only.
execute_process(COMMAND ${PYTHON} -c "import sys; src=open(sys.argv[1],'rb').read()[:2000]; open(sys.argv[2],'wb').write(src)"
                ${WORK}/second/pair0_box_bar/view0/layer01.exr ${exr})
run(2 ${PEELCD} golden compare-dumps ${WORK}/first ${WORK}/truncated)
expect("layer01.exr" "${last_err}")

file(COPY ${WORK}/second/ DESTINATION ${WORK}/missing)
file(REMOVE ${WORK}/missing/pair0_box_bar/view0/layer02.exr)
run(2 ${PEELCD} golden compare-dumps ${WORK}/first ${WORK}/missing)
expect("layer02.exr' is missing" "${last_err}")

file(COPY ${WORK}/second/ DESTINATION ${WORK}/badmeta)
file(WRITE ${WORK}/badmeta/meta.json "{\"renderer\": \"x\", \"pairs\": [")
run(2 ${PEELCD} golden compare-dumps ${WORK}/first ${WORK}/badmeta)
expect("meta.json' is not valid JSON" "${last_err}")
run(2 ${PEELCD} golden compare-dumps ${WORK}/first ${WORK}/nowhere)

# The schema: every meta.json valid; one without "pairs" and one with a layer count of -1 not.
file(GLOB golden_metas ${SOURCE}/fixtures/golden/*/expected/meta.json)
set(schema ${SOURCE}/docs/schema/dump-meta.schema.json)
run(0 ${PYTHON} ${SOURCE}/tests/oracle/validate_json.py ${schema} ${metas} ${WORK}/first/meta.json ${golden_metas})
file(READ ${WORK}/first/meta.json meta)
string(REPLACE "\"pairs\"" "\"pears\"" no_pairs "${meta}")
file(WRITE ${WORK}/no_pairs.json "${no_pairs}")
string(REGEX REPLACE "\"layers\": [0-9]+" "\"layers\": -1" bad_layers "${meta}")
file(WRITE ${WORK}/bad_layers.json "${bad_layers}")
run(1 ${PYTHON} ${SOURCE}/tests/oracle/validate_json.py ${schema} ${WORK}/no_pairs.json)
expect("'pairs' is a required property" "${last_out}")
run(1 ${PYTHON} ${SOURCE}/tests/oracle/validate_json.py ${schema} ${WORK}/bad_layers.json)
message(STATUS "dumps: independent writer = peelcd's, compare-dumps 0/1/2, schema valid")
