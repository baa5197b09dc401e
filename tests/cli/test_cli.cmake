# Command-line tests: exit codes, messages that name the input, and outputs.
# Run by ctest as: cmake -DPEELCD=<exe> -DFIXTURES=<dir> -DWORK=<dir> -P test_cli.cmake
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
set(failures 0)

# expect(<name> <exit code> <regex that stdout+stderr must match> <args...>)
function(expect name code regex)
  execute_process(COMMAND ${PEELCD} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  set(all "${out}${err}")
  if(NOT rc EQUAL code)
    message(SEND_ERROR "${name}: exit ${rc}, expected ${code}\n${all}")
  elseif(NOT all MATCHES "${regex}")
    message(SEND_ERROR "${name}: output does not match '${regex}'\n${all}")
  else()
    message(STATUS "ok: ${name}")
  endif()
endfunction()

set(scene ${FIXTURES}/scenes/bunny_dragon.json)
expect("help" 0 "detect" --help)
expect("detect help" 0 "--ids" detect --help)
expect("sweep help" 0 "--theta-step" sweep --help)
expect("no subcommand" 2 "subcommand" )
expect("default scene" 0 "bunny x dragon: .* colliding" detect ${scene})
expect("default scene, checked" 0 "exact reference: 228 pairs.*false contacts 0" detect ${scene} --check)
# --check can fail: --max-miss turns a miss ratio above it into exit 3 (the paper's configuration
# misses pairs on this scene; the default, conservative, misses none).
expect("max-miss exceeded" 3 "above --max-miss 1%" detect ${scene} --paper --check --max-miss 1)
expect("max-miss held" 0 "check: 228 exact pairs, 0 missed" detect ${scene} --check --max-miss 0)
expect("max-miss needs check" 2 "requires --check" detect ${scene} --max-miss 1)
expect("contradicting flags" 2 "contradict" detect ${scene} --conservative --no-conservative)
expect("conservative is the default" 0 "^[^\n]*\n?conservative  view theta=31 phi=51 roll=30" detect ${scene})

# The stage router: auto (default) sends this ROI to the exact CPU path on llvmpipe (its cost
# model predicts it cheaper); image and exact force one; both find all 228 pairs.
expect("stage auto is the default" 0 "stage auto: 1 of 1 ROIs by the exact CPU path" detect ${scene})
expect("stage image" 0 "stage image: 0 of 1 ROIs by the exact CPU path.*check: 228 exact pairs, 0 missed" detect ${scene} --stage image --check)
expect("stage exact" 0 "exact CPU path \\(predicted.*check: 228 exact pairs, 0 missed" detect ${scene} --stage exact --check)
expect("stage exact, paper config" 0 "check: 228 exact pairs, 0 missed" detect ${scene} --paper --stage exact --check)
expect("unknown stage" 2 "--stage: unknown stage \"fast\"" detect ${scene} --stage fast)

# JSON report
expect("json report" 0 "" detect ${scene} --res 128 --stage image --json ${WORK}/out.json --quiet)
file(READ ${WORK}/out.json report)
string(JSON npairs LENGTH "${report}" pairs)
string(JSON ncolliding LENGTH "${report}" pairs 0 colliding)
string(JSON total GET "${report}" timings_ms total)
string(JSON res GET "${report}" pairs 0 resolution)
if(NOT npairs EQUAL 1 OR ncolliding LESS 1 OR NOT res EQUAL 128 OR total STREQUAL "")
  message(SEND_ERROR "json report: pairs ${npairs}, colliding ${ncolliding}, resolution ${res}, total ${total}")
endif()
foreach(key aabb gpu readback cpu total)
  string(JSON v ERROR_VARIABLE e GET "${report}" timings_ms ${key})
  if(e)
    message(SEND_ERROR "json report: timings_ms.${key} missing")
  endif()
endforeach()

# Bad input: exit 2, a message naming the input and the problem, no output file left behind.
expect("missing scene" 2 "nowhere.json': no such file" detect ${WORK}/nowhere.json)
file(WRITE ${WORK}/malformed.json "{\"objects\": [")
expect("malformed scene" 2 "malformed.json': malformed JSON" detect ${WORK}/malformed.json)
file(WRITE ${WORK}/badids.json "{\"objects\":[{\"mesh\":\"${FIXTURES}/meshes/bunny_3k.obj\"}],\"ids\":\"fancy\"}")
expect("unknown ID mode in scene" 2 "badids.json': ids: unknown ID mode \"fancy\"" detect ${WORK}/badids.json)
expect("unknown ID mode option" 2 "unknown ID mode \"fancy\"" detect ${scene} --ids fancy)
expect("unknown culling option" 2 "--cull: unknown culling \"fancy\"" detect ${scene} --cull fancy)
expect("unknown resolve option" 2 "--resolve: unknown resolve \"fancy\"" detect ${scene} --resolve fancy)
file(WRITE ${WORK}/badcull.json "{\"objects\":[{\"mesh\":\"${FIXTURES}/meshes/bunny_3k.obj\"}],\"cull\":\"fancy\"}")
expect("unknown culling in scene" 2 "cull: unknown culling \"fancy\"" detect ${WORK}/badcull.json)
expect("box culling, host resolve" 0 "cull=box" detect ${scene} --res 64 --cull box --resolve host --check)
expect("two fused views" 0 "views=2 .*exact reference: 228 pairs" detect ${scene} --res 64 --views 2 --check)
expect("four fused views" 2 "--views" detect ${scene} --views 4)
expect("tile by the median edge" 0 "ROI 160x160.*exact reference: 228 pairs; found 228" detect ${scene} --stage image --check)
expect("tile from the budget" 0 "ROI 512x512" detect ${scene} --stage image --edge-texels 0)
expect("negative edge texels" 2 "--edge-texels: Value -2 is negative" detect ${scene} --edge-texels -2)
# A NaN or infinite option is refused, not read as "not given" (CLI11's own checks let NaN pass).
expect("NaN slope" 2 "--slope: Value nan is not a finite number" detect ${scene} --slope nan)
expect("NaN epsilon" 2 "--epsilon: Value nan is not a finite number" detect ${scene} --epsilon nan)
expect("infinite longitude" 2 "--theta: Value inf is not a finite number" detect ${scene} --theta inf)
expect("NaN latitude" 2 "--phi: Value nan is not a finite number" detect ${scene} --phi nan)
expect("huge edge texels" 2 "--edge-texels: Value 1e999 is not a finite number" detect ${scene} --edge-texels 1e999)
expect("slope not a number" 2 "--slope: Value fast is not a number" detect ${scene} --slope fast)
expect("sweep: NaN theta step" 2 "--theta-step: Value nan is not a finite number" sweep ${scene} --theta-step nan)
file(WRITE ${WORK}/nomesh.json "{\"objects\":[{\"mesh\":\"gone.obj\"},{\"mesh\":\"gone2.obj\"}]}")
expect("missing mesh" 2 "gone.obj': no such file" detect ${WORK}/nomesh.json)
expect("zero resolution" 2 "--res: Value 0 is not positive" detect ${scene} --res 0)
expect("resolution above the GL maximum" 2 "GL_MAX_TEXTURE_SIZE" detect ${scene} --res 1000000)
expect("negative epsilon" 2 "--epsilon" detect ${scene} --epsilon -1)
expect("latitude out of range" 2 "--phi" detect ${scene} --phi 120)
expect("unwritable json" 2 "cannot write" detect ${scene} --res 64 --json ${WORK}/no/such/dir/out.json)
if(EXISTS ${WORK}/no/such/dir/out.json OR EXISTS ${WORK}/no/such/dir/out.json.tmp)
  message(SEND_ERROR "unwritable json: a partial file was left")
endif()

# No overlapping boxes: no GL work.
file(WRITE ${WORK}/apart.json "{\"objects\":[{\"mesh\":\"${FIXTURES}/meshes/bunny_3k.obj\"},
  {\"mesh\":\"${FIXTURES}/meshes/bunny_3k.obj\",\"transform\":{\"translate\":[10,0,0]}}]}")
expect("no overlap" 0 "no overlapping bounding boxes: no GL work" detect ${WORK}/apart.json)

# A GL context that cannot be created (Mesa told to offer GL 3.3 only): exit 2, a clear message.
execute_process(COMMAND ${CMAKE_COMMAND} -E env MESA_GL_VERSION_OVERRIDE=3.3 ${PEELCD} detect ${scene} --res 64
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "cannot create an OpenGL 4.5 core context")
  message(SEND_ERROR "failed GL context: exit ${rc}\n${out}${err}")
else()
  message(STATUS "ok: failed GL context")
endif()

# Sweep: a tiny grid writes a CSV with one row per (configuration, view) and a summary.
expect("sweep" 0 "64 ring alternate slope=1 views=1" sweep ${scene} --res 64 --ids ring --mode alternate
       --theta-step 180 --phi-step 90 --csv ${WORK}/sweep.csv)
file(STRINGS ${WORK}/sweep.csv lines)
list(LENGTH lines nlines)
if(NOT nlines EQUAL 5)  # header + 4 views (two poles, theta 0 and 180 at phi 0)
  message(SEND_ERROR "sweep csv: ${nlines} lines, expected 5")
endif()
expect("sweep: bad mode" 2 "unknown mode \"fancy\"" sweep ${scene} --mode fancy)

# Layer dumps: every layer of every view as EXR and PNG, the PCS, meta.json, the viewer.
expect("dump help" 0 "--out" dump --help)
expect("golden help" 0 "compare" golden --help)
expect("dump" 0 "1 ROIs, 3 views" dump ${scene} --res 64 --views 3 --out ${WORK}/dump)
foreach(f meta.json index.html pair0_bunny_dragon/pcs.txt pair0_bunny_dragon/colliding.txt
        pair0_bunny_dragon/view0/layer00.exr pair0_bunny_dragon/view0/layer00.png pair0_bunny_dragon/view2/pcs.txt)
  if(NOT EXISTS ${WORK}/dump/${f})
    message(SEND_ERROR "dump: ${f} missing")
  endif()
endforeach()
expect("dump: output exists" 2 "exists and is not an empty folder" dump ${scene} --res 64 --out ${WORK}/dump)
expect("dump: bad resolution" 2 "resolution 100000 is outside" dump ${scene} --res 100000 --out ${WORK}/dump_bad)
if(EXISTS ${WORK}/dump_bad OR EXISTS ${WORK}/dump_bad.partial)
  message(SEND_ERROR "dump: a failed dump left ${WORK}/dump_bad behind")
endif()
expect("golden: unknown case" 2 "unknown case \"nonesuch\"" golden compare nonesuch)
expect("golden: bad tier" 2 "unknown tier" golden compare boxes_crossing --tier fuzzy)

# Dynamic scenes: a few frames of each; the exit status is non-zero on any false contact.
expect("simulate help" 0 "test1 or test2" simulate --help)
expect("simulate test1" 0 "summary \\(means per phase.*\\(d\\).*false contacts over all frames: 0"
       simulate test1 --frames 8 --res 64 --csv ${WORK}/sim1.csv)
file(STRINGS ${WORK}/sim1.csv lines)
list(LENGTH lines nlines)
if(NOT nlines EQUAL 9)
  message(SEND_ERROR "simulate csv: ${nlines} lines, expected 9")
endif()
expect("simulate test2" 0 "\\(h\\).*false contacts over all frames: 0" simulate test2 --frames 8 --res 64)
expect("simulate: unknown scene" 2 "test3" simulate test3)
# The benchmark runs every method on the same frames and prints the ratios.
expect("bench" 0 "CGAL box_intersection_d.*FCL 0.7.*floor" bench ${scene} --frames 1 --res 64)
expect("bench: bad peeler" 2 "unknown peeler" detect ${scene} --peeler magic)
