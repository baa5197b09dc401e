# Command-line tests: exit codes, messages that name the input, and outputs.
# Run by ctest as: cmake -DPEELCD=<exe> -DFIXTURES=<dir> -DWORK=<dir> -P test_cli.cmake
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
set(failures 0)

# validate(<what> <schema file under docs/schema> <json files...>): every file valid against it.
function(validate what schema)
  execute_process(COMMAND ${PYTHON} ${SOURCE}/tests/oracle/validate_json.py ${SOURCE}/docs/schema/${schema} ${ARGN}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(SEND_ERROR "${what}: not valid against docs/schema/${schema}\n${out}${err}")
  else()
    message(STATUS "ok: ${out}")
  endif()
endfunction()

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
expect("version" 0 "peelcd [0-9]" --version)
expect("detect help" 0 "--ids" detect --help)
expect("sweep help" 0 "--theta-step" sweep --help)
expect("no subcommand" 2 "subcommand" )
expect("default scene" 0 "bunny x dragon: .* colliding" detect ${scene})
# Containment: a ball inside a ball is a collision without contact (docs/design.md).
set(nested ${FIXTURES}/scenes/ball_in_ball.json)
expect("containment: inside" 0 "inside: 'inner' is inside 'outer'.*collision: 0 colliding triangle pairs in 1 of 1" detect ${nested})
expect("containment: --status" 0 "" detect ${nested} --status --quiet)
expect("containment: JSON" 0 "\"relation\": \"b_inside_a\"" detect ${nested} --json - --quiet)
expect("containment: volume checked" 0 "volume 0.05[0-9]+ .*exact volume \\(CGAL corefinement\\): 0.05[0-9]+; .*within the estimate" detect ${nested} --volume --check)
expect("containment: explain" 0 "'inner' is inside 'outer'" explain ${nested} --pair outer:0,inner:0)
expect("volume: an open mesh" 0 "volume unknown: B is open"
       detect ${FIXTURES}/meshes/generated/ball_16x32.obj ${FIXTURES}/meshes/generated/grid_tilted_12x12.obj --volume)
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
expect("unknown resolve option" 2 "--resolve: unknown value \"fancy\" .expected auto/gpu/host." detect ${scene} --resolve fancy)
file(WRITE ${WORK}/badcull.json "{\"objects\":[{\"mesh\":\"${FIXTURES}/meshes/bunny_3k.obj\"}],\"cull\":\"fancy\"}")
expect("unknown culling in scene" 2 "cull: unknown culling \"fancy\"" detect ${WORK}/badcull.json)
expect("box culling, host resolve" 0 "cull=box" detect ${scene} --res 64 --cull box --resolve host --check)
expect("two fused views" 0 "views=2 .*exact reference: 228 pairs" detect ${scene} --res 64 --views 2 --check)
expect("four fused views" 2 "--views" detect ${scene} --views 4)
expect("tile by the median edge" 0 "ROI 32x32.*exact reference: 228 pairs; found 228" detect ${scene} --stage image --check)
expect("tile by the median edge, 12 texels" 0 "ROI 160x160.*exact reference: 228 pairs; found 228" detect ${scene} --stage image --check --edge-texels 12)
expect("point sampling: 12 texels per edge" 0 "ROI 160x160" detect ${scene} --stage image --no-conservative)
expect("threads: the same pairs" 0 "exact reference: 228 pairs; found 228, missed 0" detect ${scene} --threads 2 --check)
expect("threads: out of range" 2 "--threads: must be within 0..64" detect ${scene} --threads 99)
expect("tile from the budget" 0 "ROI 512x512" detect ${scene} --stage image --edge-texels 0)
expect("negative edge texels" 2 "--edge-texels: must be >= 0 \\(0 = the budget's share\\)" detect ${scene} --edge-texels -2)
# A NaN or infinite option is refused, not read as "not given" (CLI11's own checks let NaN pass).
expect("NaN slope" 2 "--slope: \"nan\" is not a finite number" detect ${scene} --slope nan)
expect("NaN epsilon" 2 "--epsilon: \"nan\" is not a finite number" detect ${scene} --epsilon nan)
expect("infinite longitude" 2 "--theta: \"inf\" is not a finite number" detect ${scene} --theta inf)
expect("NaN latitude" 2 "--phi: \"nan\" is not a finite number" detect ${scene} --phi nan)
expect("huge edge texels" 2 "--edge-texels: \"1e999\" is not a finite number" detect ${scene} --edge-texels 1e999)
expect("slope not a number" 2 "--slope: \"fast\" is not a number" detect ${scene} --slope fast)
expect("sweep: NaN theta step" 2 "--theta-step: Value nan is not a finite number" sweep ${scene} --theta-step nan)
file(WRITE ${WORK}/nomesh.json "{\"objects\":[{\"mesh\":\"gone.obj\"},{\"mesh\":\"gone2.obj\"}]}")
expect("missing mesh" 2 "gone.obj': no such file" detect ${WORK}/nomesh.json)
# --res 0 and --epsilon 0 mean what a scene's 0 means (the option table: tiles from the budget, one texel).
expect("zero resolution: from the budget" 0 "ROI 32x32" detect ${scene} --res 0 --stage image)
expect("negative resolution" 2 "--res: must be within 0..32768 \\(0 = from the budget.*got -4" detect ${scene} --res -4)
expect("fractional views" 2 "--views: \"2.5\" is not an integer" detect ${scene} --views 2.5)
expect("unknown flag value for a choice" 2 "--peel: unknown peel mode \"sideways\" \\(expected full or alternate\\)" detect ${scene} --peel sideways)
expect("budget flag" 0 "ROI 256x256" detect ${scene} --budget 256 --edge-texels 0 --stage image)
expect("resolution above the GL maximum" 2 "GL_MAX_TEXTURE_SIZE" detect ${scene} --res 20000)
expect("negative epsilon" 2 "--epsilon" detect ${scene} --epsilon -1)
expect("latitude out of range" 2 "--phi" detect ${scene} --phi 120)
expect("unwritable json" 2 "the folder '.*/no/such/dir' does not exist" detect ${scene} --res 64 --json ${WORK}/no/such/dir/out.json)
if(EXISTS ${WORK}/no/such/dir)
  message(SEND_ERROR "unwritable json: something was created")
endif()
# Outputs that never destroy: a directory refused; a symlink followed (the link stays);
# no temporary file left behind.
file(MAKE_DIRECTORY ${WORK}/outdir)
expect("json into a directory" 2 "outdir': is a directory" detect ${scene} --json ${WORK}/outdir)
file(WRITE ${WORK}/outdir/target.json "old")
file(CREATE_LINK target.json ${WORK}/outdir/link.json SYMBOLIC)
expect("json through a symlink" 0 "" detect ${scene} --json ${WORK}/outdir/link.json --quiet)
file(READ ${WORK}/outdir/target.json via_link)
if(NOT IS_SYMLINK ${WORK}/outdir/link.json OR NOT via_link MATCHES "peelcd.result/2")
  message(SEND_ERROR "json through a symlink: the link was replaced or its target not written")
endif()
# A FIFO is written in place as a stream (a reader gets the JSON); a character device too, and it
# stays a device (as root, a rename would replace /dev/null-like nodes with a file).
execute_process(COMMAND sh -c "rm -f '${WORK}/outdir/fifo' && mkfifo '${WORK}/outdir/fifo' && (cat '${WORK}/outdir/fifo' > '${WORK}/fifo_read.json' &) && '${PEELCD}' detect '${scene}' --json '${WORK}/outdir/fifo' --quiet; rc=$?; sleep 0.3; rm -f '${WORK}/outdir/fifo'; exit $rc"
                RESULT_VARIABLE rc)
file(READ ${WORK}/fifo_read.json fifo_json)
if(NOT rc EQUAL 0 OR NOT fifo_json MATCHES "peelcd.result/2")
  message(SEND_ERROR "json into a FIFO: exit ${rc}, the reader got:\n${fifo_json}")
else()
  message(STATUS "ok: json into a FIFO")
endif()
expect("json into a character device" 0 "" detect ${scene} --json /dev/null --quiet)
execute_process(COMMAND test -c /dev/null RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "json into a character device: /dev/null is no longer a character device")
endif()
expect("json into /dev/full" 2 "/dev/full': cannot write it" detect ${scene} --json /dev/full --quiet)
# An unwritable file: refused before any work (not testable as root, who may write anything).
execute_process(COMMAND id -u OUTPUT_VARIABLE uid OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT uid STREQUAL "0")
  file(WRITE ${WORK}/outdir/readonly.json "keep")
  file(CHMOD ${WORK}/outdir/readonly.json PERMISSIONS OWNER_READ)
  expect("json onto an unwritable file" 2 "the file is not writable" detect ${scene} --json ${WORK}/outdir/readonly.json)
  file(REMOVE ${WORK}/outdir/readonly.json)
else()
  message(STATUS "skipped: json onto an unwritable file (running as root)")
endif()
file(GLOB leftovers ${WORK}/outdir/.*)
if(leftovers)
  message(SEND_ERROR "json: temporary files left behind: ${leftovers}")
endif()
# JSON on stdout: the human summary goes to stderr, stdout is one JSON document.
execute_process(COMMAND ${PEELCD} detect ${scene} --check --json - RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(JSON schema ERROR_VARIABLE json_error GET "${out}" schema)
string(JSON exact ERROR_VARIABLE json_error2 GET "${out}" check exact)
string(JSON tri_a ERROR_VARIABLE json_error3 GET "${out}" pairs 0 colliding 0 tri_a)
if(NOT rc EQUAL 0 OR json_error OR NOT schema STREQUAL "peelcd.result/2" OR NOT exact EQUAL 228 OR json_error3
   OR NOT err MATCHES "check: 228 exact pairs")
  message(SEND_ERROR "json on stdout: rc ${rc}, schema '${schema}', check.exact '${exact}' ${json_error} ${json_error3}\n${err}")
else()
  message(STATUS "ok: json on stdout, human text on stderr, --check in the JSON")
endif()
file(WRITE ${WORK}/stdout.json "${out}")
# Every JSON output validates against docs/schema/result.schema.json.
expect("json: two meshes" 0 "" detect ${FIXTURES}/meshes/bunny_3k.obj ${FIXTURES}/meshes/kitten_1k5.obj --json ${WORK}/meshes.json --quiet)
expect("json: many ROIs" 0 "" detect ${FIXTURES}/golden/crowded_conservative_16/case.json --check --stage image --json ${WORK}/crowd.json --quiet)
expect("json: depth, margin and volume" 0 "within 0.001: [0-9]+ triangle pairs; least distance 0.*depth [0-9.]+ .* along"
       detect ${FIXTURES}/scenes/bunny_dragon.json --depth --margin 0.001 --volume --json ${WORK}/queries.json)
expect("--margin must be finite" 2 "--margin: \"inf\" is not a finite number" detect ${FIXTURES}/scenes/bunny_dragon.json --margin inf)
# The image stage's clocks: its host work, and with --gpu-timers its GPU passes by timer queries.
expect("gpu timers" 0 "host work [0-9.]+ .total - GL waits [0-9.]+.*GPU passes .timer queries.: raster [0-9.]+  compute"
       detect ${FIXTURES}/scenes/bunny_dragon.json --stage image --gpu-timers --json ${WORK}/timers.json)
file(READ ${WORK}/timers.json timers_json)
string(JSON raster ERROR_VARIABLE raster_error GET "${timers_json}" timings_ms gpu_raster)
if(raster_error OR NOT raster GREATER 0)
  message(SEND_ERROR "gpu timers: timings_ms.gpu_raster '${raster}' ${raster_error}")
endif()
validate("json" result.schema.json ${WORK}/stdout.json ${WORK}/meshes.json ${WORK}/crowd.json ${WORK}/out.json
         ${WORK}/outdir/target.json ${WORK}/queries.json ${WORK}/timers.json)
# Inputs: mesh files without a scene; scene validation.
expect("detect A.obj B.obj" 0 "bunny_3k x dragon_3k" detect ${FIXTURES}/meshes/bunny_3k.obj ${FIXTURES}/meshes/dragon_3k.obj)
# A glTF scene: one object per node, the node transforms applied ("far" is moved 10 away: no pair).
expect("detect a glTF scene" 0 "3 objects.*left x right: .* 24 colliding" detect ${FIXTURES}/meshes/three_box_nodes.gltf)
execute_process(COMMAND ${PEELCD} detect ${FIXTURES}/meshes/three_box_nodes.gltf OUTPUT_VARIABLE gltf_out)
if(gltf_out MATCHES "far")
  message(SEND_ERROR "detect a glTF scene: the node \"far\" overlaps: its transform was not applied\n${gltf_out}")
endif()
file(WRITE ${WORK}/gltf_scene.json "{\"objects\":[{\"name\":\"boxes\",\"mesh\":\"${FIXTURES}/meshes/three_box_nodes.gltf\"},{\"name\":\"bunny\",\"mesh\":\"${FIXTURES}/meshes/bunny_3k.obj\"}]}")
expect("glTF nodes in a scene file" 0 "boxes/left x boxes/right" detect ${WORK}/gltf_scene.json)
expect("detect one mesh" 2 "is one mesh: give a scene file" detect ${FIXTURES}/meshes/bunny_3k.obj)
expect("detect the same mesh twice" 0 "bunny_3k x bunny_3k_2" detect ${FIXTURES}/meshes/bunny_3k.obj ${FIXTURES}/meshes/bunny_3k.obj)
file(WRITE ${WORK}/dupnames.json "{\"objects\":[{\"name\":\"a\",\"mesh\":\"${FIXTURES}/meshes/bunny_3k.obj\"},{\"name\":\"a\",\"mesh\":\"${FIXTURES}/meshes/bunny_3k.obj\"}]}")
expect("duplicate names" 2 "objects\\[1\\].name: duplicate name \"a\" \\(also objects\\[0\\]\\)" detect ${WORK}/dupnames.json)
file(WRITE ${WORK}/huge.json "{\"objects\":[{\"name\":\"a\",\"mesh\":\"${FIXTURES}/meshes/bunny_3k.obj\",\"transform\":{\"scale\":1e39}},{\"name\":\"b\",\"mesh\":\"${FIXTURES}/meshes/dragon_3k.obj\"}]}")
expect("scale beyond float" 2 "objects\\[0\\] \\(\"a\"\\): the transform gives the vertex .*outside the float range" detect ${WORK}/huge.json)

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

# Outputs that would destroy an input, or name nothing, are refused before any work (exit 2).
# (through sh: CMake drops an empty argument)
foreach(cmdline "detect '${scene}' --json ''" "simulate test1 --frames 1 --csv ''" "sweep '${scene}' --plot ''")
  execute_process(COMMAND sh -c "'${PEELCD}' ${cmdline}" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 2 OR NOT err MATCHES "an empty path")
    message(SEND_ERROR "empty output path: ${cmdline}: exit ${rc}\n${out}${err}")
  else()
    message(STATUS "ok: empty output path refused: ${cmdline}")
  endif()
endforeach()
configure_file(${FIXTURES}/meshes/kitten_1k5.obj ${WORK}/kitten_copy.obj COPYONLY)
file(SHA256 ${WORK}/kitten_copy.obj kitten_before)
expect("json onto an input mesh" 2 "kitten_copy.obj': it is the input" detect ${FIXTURES}/meshes/bunny_3k.obj ${WORK}/kitten_copy.obj --json ${WORK}/kitten_copy.obj)
file(SHA256 ${WORK}/kitten_copy.obj kitten_after)
if(NOT kitten_before STREQUAL kitten_after)
  message(SEND_ERROR "json onto an input mesh: the mesh was changed")
endif()
configure_file(${scene} ${WORK}/scene_copy.json COPYONLY)
file(READ ${scene} scene_text)
string(REPLACE "../meshes/" "${FIXTURES}/meshes/" scene_text "${scene_text}")
file(WRITE ${WORK}/scene_copy.json "${scene_text}")
expect("json onto the scene file" 2 "scene_copy.json': it is the input" detect ${WORK}/scene_copy.json --json ${WORK}/scene_copy.json)
expect("json onto a scene's mesh" 2 "it is the input" detect ${WORK}/scene_copy.json --json ${FIXTURES}/meshes/bunny_3k.obj)
# sweep --plot onto a file or a device: refused before the sweep runs.
file(WRITE ${WORK}/plot_is_a_file "x")
expect("sweep --plot onto a file" 2 "--plot '.*plot_is_a_file': exists and is not a folder" sweep ${scene} --res 16 --theta-step 180 --phi-step 90 --plot ${WORK}/plot_is_a_file)
expect("sweep --plot onto /dev/full" 2 "--plot '/dev/full': exists and is not a folder" sweep ${scene} --res 16 --theta-step 180 --phi-step 90 --plot /dev/full)
expect("sweep --plot under a missing folder" 2 "does not exist" sweep ${scene} --res 16 --plot ${WORK}/no/such/plots)
expect("sweep merge --plot onto a file" 2 "exists and is not a folder" sweep merge ${WORK}/sweep.csv --plot ${WORK}/plot_is_a_file)
# The summary first, the list on request, an exit status for scripts.
expect("detect: a one-line total" 0 "collision: 228 colliding triangle pairs in 1 of 1 overlapping object pairs" detect ${scene})
execute_process(COMMAND ${PEELCD} detect ${scene} OUTPUT_VARIABLE out)
if(out MATCHES "\\([0-9]+,[0-9]+\\)")
  message(SEND_ERROR "detect without --list printed triangle pairs:\n${out}")
endif()
expect("detect --list" 0 "triangle pairs \\(bunny, dragon\\)\n  \\([0-9]+,[0-9]+\\)" detect ${scene} --list)
expect("detect --status, colliding" 0 "collision: 228" detect ${scene} --status)
file(WRITE ${WORK}/apart.json "{\"objects\":[{\"name\":\"b\",\"mesh\":\"${FIXTURES}/meshes/bunny_3k.obj\"},{\"name\":\"k\",\"mesh\":\"${FIXTURES}/meshes/kitten_1k5.obj\",\"transform\":{\"translate\":[50,0,0]}}]}")
expect("detect --status, nothing collides" 1 "no collision: 0 colliding triangle pairs in 0 of 0" detect ${WORK}/apart.json --status)
# A fallback is never hidden: a view too large for any k-buffer says so, in the text and the JSON.
expect("detect: the exhaustive fallback is said" 0 "views fell back to the exhaustive exact test.*path exhaustive: --stage image; 1 of 1 views too deep or too large"
       detect ${scene} --stage image --res 4096 --json ${WORK}/fallback.json)
file(READ ${WORK}/fallback.json fallback)
string(JSON path GET "${fallback}" pairs 0 path)
string(JSON nviews GET "${fallback}" views_exhaustive)
if(NOT path STREQUAL "exhaustive" OR NOT nviews EQUAL 1)
  message(SEND_ERROR "fallback JSON: path '${path}', views_exhaustive ${nviews}")
endif()
validate("fallback json" result.schema.json ${WORK}/fallback.json)
# Help that reads: no "INT:INT in [...]".
execute_process(COMMAND ${PEELCD} detect --help OUTPUT_VARIABLE help)
if(help MATCHES "INT:INT|FLOAT:FINITE|:POSITIVE|:NONNEGATIVE" OR NOT help MATCHES "--threads INT in \\[0, 64\\]")
  message(SEND_ERROR "detect --help: garbled option types\n${help}")
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
expect("sweep: the default modes include the default, conservative" 0 "conservative" sweep ${scene} --res 16 --ids unique
       --theta-step 180 --phi-step 90)

# Layer dumps: every layer of every view as EXR and PNG, the PCS, meta.json, the viewer.
expect("dump help" 0 "--out" dump --help)
expect("golden help" 0 "compare" golden --help)
expect("dump" 0 "1 ROIs, 3 views" dump ${scene} --res 64 --views 3 --out ${WORK}/dump)
# dump takes what detect takes: a glTF scene, two mesh files.
expect("dump a glTF scene" 0 "1 ROIs" dump ${FIXTURES}/meshes/three_box_nodes.gltf --out ${WORK}/dump_gltf)
expect("dump two meshes" 0 "1 ROIs" dump ${FIXTURES}/meshes/bunny_3k.obj ${FIXTURES}/meshes/dragon_3k.obj --res 32 --out ${WORK}/dump_meshes)
expect("dump one mesh" 2 "peelcd dump: .* is one mesh" dump ${FIXTURES}/meshes/bunny_3k.obj --out ${WORK}/dump_one)
# The viewer marks the texels the default (conservative) stage used: some PCS texels, not 0 everywhere.
file(READ ${WORK}/dump/index.html viewer_html)
if(NOT viewer_html MATCHES "[1-9][0-9]* PCS texels")
  message(SEND_ERROR "dump: the viewer marks no PCS texel in conservative mode")
endif()
foreach(f meta.json index.html pair0_bunny_dragon/pcs.txt pair0_bunny_dragon/colliding.txt
        pair0_bunny_dragon/view0/layer00.exr pair0_bunny_dragon/view0/layer00.png pair0_bunny_dragon/view2/pcs.txt)
  if(NOT EXISTS ${WORK}/dump/${f})
    message(SEND_ERROR "dump: ${f} missing")
  endif()
endforeach()
expect("dump: output exists" 2 "exists and is not an empty folder" dump ${scene} --res 64 --out ${WORK}/dump)
# With --volume, each view shows the inside intervals: inside.png and their volume in meta.json.
expect("dump --volume" 0 "1 ROIs" dump ${scene} --res 64 --volume --cull box --out ${WORK}/dump_inside)
file(READ ${WORK}/dump_inside/meta.json inside_meta)
if(NOT EXISTS ${WORK}/dump_inside/pair0_bunny_dragon/view0/inside.png OR
   NOT inside_meta MATCHES "\"inside\": {[^}]*\"volume\": 0\\.4[0-9]")
  message(SEND_ERROR "dump --volume: no inside.png, or meta.json's inside volume is not about 0.45")
endif()
expect("dump: missing parent folder" 2 "the folder '.*/no/such' does not exist" dump ${scene} --out ${WORK}/no/such/dump)
expect("dump: bad resolution" 2 "resolution 20000 is outside" dump ${scene} --res 20000 --out ${WORK}/dump_bad)
if(EXISTS ${WORK}/dump_bad OR EXISTS ${WORK}/dump_bad.partial)
  message(SEND_ERROR "dump: a failed dump left ${WORK}/dump_bad behind")
endif()
# Sharded sweeps: three shards merged give the full sweep's rows (accuracy columns; times differ).
set(sweep_args ${FIXTURES}/golden/boxes_crossing/case.json --res 32 --ids unique --mode full,paper --theta-step 90 --phi-step 45)
expect("sweep: full" 0 "" sweep ${sweep_args} --csv ${WORK}/sweep_full.csv)
foreach(k 1 2 3)
  expect("sweep: shard ${k}/3" 0 "" sweep ${sweep_args} --shard ${k}/3 --csv ${WORK}/sweep_s${k}.csv)
endforeach()
foreach(k 1 2)
  expect("sweep: shard ${k}/2" 0 "" sweep ${sweep_args} --shard ${k}/2 --csv ${WORK}/sweep_h${k}.csv)
endforeach()
# Two halves merged, with the plots (python3-matplotlib, installed by the bootstrap).
expect("sweep merge: halves, plotted" 0 "28 rows from 2 files" sweep merge ${WORK}/sweep_h1.csv ${WORK}/sweep_h2.csv
       --csv ${WORK}/sweep_halves.csv --plot ${WORK}/sweep_plots)
if(NOT EXISTS ${WORK}/sweep_plots/time_vs_miss.png)
  message(SEND_ERROR "sweep merge --plot: no time_vs_miss.png")
endif()
expect("sweep merge" 0 "28 rows from 3 files, 2 configurations" sweep merge ${WORK}/sweep_s1.csv ${WORK}/sweep_s2.csv
       ${WORK}/sweep_s3.csv --csv ${WORK}/sweep_merged.csv)
execute_process(COMMAND ${PYTHON} -c "
import csv, sys
keep = ['config', 'theta', 'phi', 'exact', 'found', 'missed', 'false_contacts', 'pcs', 'candidates', 'layers']
rows = lambda p: sorted(tuple(r[k] for k in keep) for r in csv.DictReader(open(p)))
sys.exit(0 if rows(sys.argv[1]) == rows(sys.argv[2]) and len(rows(sys.argv[1])) == 28 else 1)"
  ${WORK}/sweep_full.csv ${WORK}/sweep_merged.csv RESULT_VARIABLE rc)
execute_process(COMMAND ${PYTHON} -c "
import csv, sys
keep = ['config', 'theta', 'phi', 'exact', 'found', 'missed', 'false_contacts', 'pcs', 'candidates', 'layers']
rows = lambda p: sorted(tuple(r[k] for k in keep) for r in csv.DictReader(open(p)))
sys.exit(0 if rows(sys.argv[1]) == rows(sys.argv[2]) else 1)"
  ${WORK}/sweep_full.csv ${WORK}/sweep_halves.csv RESULT_VARIABLE rc2)
if(NOT rc EQUAL 0 OR NOT rc2 EQUAL 0)
  message(SEND_ERROR "sweep merge: the merged shards differ from the full sweep (3 shards: ${rc}, 2 shards: ${rc2})")
endif()
expect("sweep merge: overlapping shards" 2 "is in both" sweep merge ${WORK}/sweep_s1.csv ${WORK}/sweep_s1.csv
       ${WORK}/sweep_s2.csv ${WORK}/sweep_s3.csv --csv ${WORK}/sweep_bad.csv)
# A merge that would be partial, or of different sweeps (scene, view steps, configurations), is refused.
expect("sweep merge: a shard missing" 2 "shard\\(s\\) 2 of 3 missing" sweep merge ${WORK}/sweep_s1.csv ${WORK}/sweep_s3.csv
       --csv ${WORK}/sweep_bad.csv)
expect("sweep merge: shards of 2 and of 3" 2 "is a shard of 2" sweep merge ${WORK}/sweep_s1.csv ${WORK}/sweep_h2.csv
       ${WORK}/sweep_s3.csv --csv ${WORK}/sweep_bad.csv)
expect("sweep: another scene's shard" 0 "" sweep ${FIXTURES}/golden/boxes_touching_ties/case.json --res 32 --ids unique
       --mode full,paper --theta-step 90 --phi-step 45 --shard 2/3 --csv ${WORK}/sweep_other2.csv)
expect("sweep merge: different sweeps" 2 "CSVs of different sweeps" sweep merge ${WORK}/sweep_s1.csv ${WORK}/sweep_other2.csv
       ${WORK}/sweep_s3.csv --csv ${WORK}/sweep_bad.csv)
if(EXISTS ${WORK}/sweep_bad.csv)
  message(SEND_ERROR "a refused sweep merge wrote its --csv")
endif()
expect("sweep: bad shard" 2 "expected K/N with 1 <= K <= N" sweep ${sweep_args} --shard 4/3)
expect("golden compare: a shard" 0 "shard 2/5: 5 of 22 cases" golden compare --shard 2/5)
# Progress is for terminals only: with stderr a pipe (as here), nothing but messages.
execute_process(COMMAND ${PEELCD} golden compare --shard 1/6 OUTPUT_VARIABLE out ERROR_VARIABLE err)
execute_process(COMMAND ${PEELCD} detect ${scene} --quiet OUTPUT_VARIABLE out2 ERROR_VARIABLE err2)
# (The sanitizer build prints its own report to stderr: look for progress, not for silence.)
if("${err}${err2}" MATCHES "\r|\\[#|cases|loading the meshes|running the frame")
  message(SEND_ERROR "progress: printed to a stderr that is not a terminal:\n${err}${err2}")
else()
  message(STATUS "ok: no progress output when stderr is not a terminal")
endif()

# Crowded scenes: a cap on the ROIs a dump writes, and one pair by name.
set(crowd ${FIXTURES}/golden/crowded_conservative_16/case.json)
expect("dump: above --max-rois" 2 "20 overlapping pairs \\(ROIs\\), above --max-rois 5" dump ${crowd} --max-rois 5 --out ${WORK}/dump_crowd)
if(EXISTS ${WORK}/dump_crowd OR EXISTS ${WORK}/dump_crowd.partial)
  message(SEND_ERROR "dump: a refused dump left ${WORK}/dump_crowd behind")
endif()
expect("dump: --pair" 0 "1 ROIs, 1 views" dump ${crowd} --pair ball4,ball1 --out ${WORK}/dump_pair)
file(READ ${WORK}/dump_pair/meta.json pair_meta)
if(NOT pair_meta MATCHES "\"object_a\": 1" OR NOT pair_meta MATCHES "\"object_b\": 4" OR NOT pair_meta MATCHES "pair0_ball1_ball4")
  message(SEND_ERROR "dump --pair: meta.json does not keep the scene's object indices\n${pair_meta}")
endif()
expect("dump: --pair unknown" 2 "no object named \"ball99\"" dump ${crowd} --pair ball1,ball99 --out ${WORK}/dump_pair2)
expect("dump: --pair malformed" 2 "expected two object names" dump ${crowd} --pair ball1 --out ${WORK}/dump_pair3)
expect("golden: compare-dumps help" 0 "exit 0 when" golden compare-dumps --help)
expect("golden: skipped stack" 77 "skipped: the renderer is" golden compare boxes_crossing --require-renderer no-such-gpu)
expect("golden: unknown case" 2 "unknown case \"nonesuch\"" golden compare nonesuch)
expect("golden: bad tier" 2 "unknown tier" golden compare boxes_crossing --tier fuzzy)

# Dynamic scenes: a few frames of each; the exit status is non-zero on any false contact.
expect("simulate help" 0 "test1, test2, crowd" simulate --help)
expect("simulate crowd" 0 "crowd: 2 frames.*false contacts over all frames: 0" simulate crowd --objects 12 --frames 2)
expect("simulate crowd, bad count" 2 "objects" simulate crowd --objects 1)
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
expect("bench" 0 "threads: 1 for every method.*World, stage auto.*exact CPU path.*CGAL, cropped.*FCL 0.7, deforming refit.*FCL 0.7, deforming rebuilt.*floor" bench ${scene} --frames 1 --res 64 --threads 1)
expect("bench spheres" 0 "spheres .1680 triangles each., 2 frames, 2 objects.*World, stage auto. +[0-9.]+ +[0-9.]+ +0.00%" bench spheres --stacks 21 --frames 2 --short)
expect("bench spheres-wave" 0 "World, stage auto. +[0-9.]+ +[0-9.]+ +0.00% +0 .*FCL 0.7, deforming refit" bench spheres-wave --stacks 21 --frames 2 --short)
expect("bench crowd" 0 "crowd, 1 frames, 8 objects.*CGAL, cropped" bench crowd --objects 8 --frames 1)
expect("bench --scaling" 0 "peelcd default, 2 threads +[0-9.]+ +[0-9.]+ +0.00% +0 .*scaling: the default World with 2 threads / with 1, the two alone after the side-by-side frames, alternating frame by frame: [0-9.]+ \\(medians [0-9.]+ / [0-9.]+ ms\\); side by side with the others \\(the table\\): [0-9.]+.*scaling by the work's balance alone: 0\\.[0-9]+ \\(median; the default World planned for 2 lanes"
       bench spheres-wave --stacks 21 --frames 2 --short --threads 1 --scaling 2)
# The World's timed routes forced on (OSMesa with the GPU's resolve: the resident route, batched):
# the default rows warmed until they chose, every frame exact. The image route is some 50x the
# exact path's frame here, so the choice is the routed path and no timed frame is on the image
# route (without the warm-up to a choice, the comparison's image frames would be among the timed
# ones: 2 of 3); without the flag the routes are not timed here at all.
expect("bench --time-routes" 0
       "on the image route in 0 of 3 timed frames.*peelcd default .World, stage auto. +[0-9.]+ +[0-9.]+ +0.00% +0 .*pairs only .stage auto. +[0-9.]+ +[0-9.]+ +0.00% +0 "
       bench crowd --objects 12 --frames 3 --short --resolve gpu --time-routes --threads 1)
expect("bench: routes not timed on a software renderer" 0 "on the image route in 0 of 2 timed frames"
       bench crowd --objects 12 --frames 2 --short --resolve gpu --threads 1)
expect("bench --scaling: not for the queries" 2 "--scaling times the World rows of the pair and self scenes, not volume" bench volume --scaling 2)
expect("bench cloth-crumpled --scaling" 0
       "scaling: peelcd World .default., 2 threads / 1 thread, the two alone, alternating frame by frame: [0-9.]+ .medians [0-9.]+ / [0-9.]+ ms; missed 0 / 0.*scaling: peelcd frame API, exact path, 2 threads / 1 thread, [^)]*missed 0 / 0"
       bench cloth-crumpled --cloth 20 --frames 2 --scaling 2)
expect("calibrate help" 0 "cost models" calibrate --help)
expect("calibrate: large meshes" 0 "large meshes.*stacks +triangles.*\n +10 +720 .*\n +16 +1920 .*ratio: measured / predicted" calibrate --backend cpu --repeat 1 --budgets 16 --large 10 16)
# The coverage compared on the GL stage (OSMesa here): the frame API's one-pair scenes and the
# World's frames, raster and compute in turns; the World's choice written into the cost file.
expect("calibrate: the coverage on the World's frames" 0
       "World: 200-ball pile +[0-9.]+ +[0-9.]+ .*World: waving spheres 2x82k +[0-9.]+ +[0-9.]+ .*coverage: compute / raster [0-9.]+ on the World's frames \\(geometric mean over 2 scenes; [0-9.]+ over the frame API's 15 one-pair scenes\\): (raster|compute) .*cost models written"
       calibrate --backend osmesa --repeat 1 --budgets 32 --large 0 --write-costs ${WORK}/costs_coverage.json)
file(READ ${WORK}/costs_coverage.json costs_coverage)
if(NOT costs_coverage MATCHES "\"coverage\": \"(raster|compute)\"")
  message(SEND_ERROR "calibrate --write-costs: no coverage in the file\n${costs_coverage}")
endif()
expect("bench: bad peeler" 2 "--peeler: unknown value \"magic\"" detect ${scene} --peeler magic)

# peelcd explain (docs/debugging.md): one pair's walk and verdict; detect --explain-misses.
expect("explain: separated under the paper's configuration" 0
       "exact: the triangles intersect.*view 0: .*texel .*verdict: missed: separated by a layer of the same object"
       explain ${scene} --paper --pair bunny:351,dragon:1283 --out ${WORK}/explain_page --json ${WORK}/explain.json)
foreach(f index.html view0.png explain.json)
  if(NOT EXISTS ${WORK}/explain_page/${f})
    message(SEND_ERROR "explain --out: ${f} missing")
  endif()
endforeach()
file(READ ${WORK}/explain.json explained)
string(JSON verdict GET "${explained}" verdict)
string(JSON intersect GET "${explained}" exact intersect)
string(JSON nviews LENGTH "${explained}" views)
if(NOT verdict STREQUAL "separated" OR NOT intersect OR NOT nviews EQUAL 1)
  message(SEND_ERROR "explain --json: verdict ${verdict}, intersect ${intersect}, views ${nviews}")
endif()
expect("explain: the default finds it (exact CPU path on llvmpipe)" 0 "verdict: found by the exact CPU path"
       explain ${scene} --pair bunny:351,dragon:1283 --json ${WORK}/explain_exact.json)
expect("explain: the image stage forced finds it" 0 "verdict: found in view 0 at texel"
       explain ${scene} --stage image --pair dragon:1283,bunny:351 --json ${WORK}/explain_found.json)
expect("explain: a pair that does not intersect" 0 "verdict: no contact"
       explain ${scene} --paper --views 3 --pair bunny:1,dragon:2 --json ${WORK}/explain_none.json)
validate("explain --json" explain.schema.json ${WORK}/explain.json ${WORK}/explain_page/explain.json
         ${WORK}/explain_exact.json ${WORK}/explain_found.json ${WORK}/explain_none.json)
expect("explain: JSON on stdout" 0 "\"schema\": \"peelcd.explain/1\"" explain ${scene} --pair 0:351,1:1283 --json - --quiet)
expect("explain: unknown object" 2 "--pair 'cat:1,dragon:2': no object named 'cat'" explain ${scene} --pair cat:1,dragon:2)
expect("explain: triangle out of range" 2 "triangle 99999 is out of range" explain ${scene} --pair bunny:99999,dragon:2)
expect("explain: same object, no self" 2 "which does not ask for self-collision" explain ${scene} --pair bunny:1,bunny:2)
expect("explain: a triangle with itself" 2 "a triangle with itself is not a pair" explain ${scene} --pair bunny:1,bunny:1)
expect("explain: a self pair" 0 "verdict:" explain ${scene} --self --pair bunny:1,bunny:200)
expect("explain: --pair required" 2 "--pair is required" explain ${scene})
expect("explain: page folder not empty" 2 "not an empty folder"
       explain ${scene} --paper --pair bunny:351,dragon:1283 --out ${WORK}/explain_page)
expect("detect --explain-misses" 3 "explain: the first 3 missed pair.*bunny:[0-9]+,dragon:[0-9]+: missed: "
       detect ${scene} --paper --check --max-miss 1 --explain-misses 3)
expect("explain-misses needs check" 2 "requires --check" detect ${scene} --explain-misses 3)
# Outputs never overwrite inputs or peelcd's own data (bench and simulate like detect and sweep),
# and a device or a FIFO is no mesh: each refused before any work, the files untouched.
file(MAKE_DIRECTORY ${WORK}/own/meshes ${WORK}/own/scenes)
file(COPY ${FIXTURES}/meshes/bunny_3k.obj ${FIXTURES}/meshes/dragon_3k.obj DESTINATION ${WORK}/own/meshes)
file(COPY ${scene} DESTINATION ${WORK}/own/scenes)
file(SHA256 ${WORK}/own/scenes/bunny_dragon.json scene_sum)
file(SHA256 ${WORK}/own/meshes/bunny_3k.obj mesh_sum)
expect("bench --csv onto its scene" 2 "it is the input" bench ${WORK}/own/scenes/bunny_dragon.json --frames 1
       --csv ${WORK}/own/scenes/bunny_dragon.json)
expect("bench --csv onto a mesh it uses" 2 "it is the input" bench ${WORK}/own/scenes/bunny_dragon.json --frames 1
       --csv ${WORK}/own/meshes/bunny_3k.obj)
file(SHA256 ${WORK}/own/scenes/bunny_dragon.json scene_after)
file(SHA256 ${WORK}/own/meshes/bunny_3k.obj mesh_after)
if(NOT scene_after STREQUAL scene_sum OR NOT mesh_after STREQUAL mesh_sum)
  message(SEND_ERROR "bench --csv changed its input")
endif()
file(SHA256 ${FIXTURES}/meshes/velociraptor.obj raptor_sum)
expect("simulate --csv onto the built-in fixture" 2 "inside peelcd's own data" simulate test1 --frames 1
       --csv ${FIXTURES}/meshes/velociraptor.obj)
expect("bench --csv onto the built-in fixture" 2 "inside peelcd's own data" bench test1 --frames 1
       --csv ${FIXTURES}/meshes/velociraptor.obj)
file(SHA256 ${FIXTURES}/meshes/velociraptor.obj raptor_after)
if(NOT raptor_after STREQUAL raptor_sum)
  message(SEND_ERROR "simulate/bench --csv changed the built-in fixture")
endif()
expect("a device as a mesh" 2 "'/dev/zero': not a regular file" detect ${FIXTURES}/meshes/torus.obj /dev/zero)
execute_process(COMMAND mkfifo ${WORK}/pipe.obj)
expect("a FIFO as a mesh" 2 "pipe.obj': not a regular file" detect ${FIXTURES}/meshes/torus.obj ${WORK}/pipe.obj)
# Report folders: refused before any work when they are a file, hold a dump, or lie inside what
# is under test; a reused one holds only the new report.
file(WRITE ${WORK}/report_is_a_file "x")
set(g ${FIXTURES}/golden)
expect("golden compare --report onto a file" 2 "exists and is not a folder"
       golden compare boxes_crossing --backend cpu --report ${WORK}/report_is_a_file)
expect("golden compare --report inside the goldens" 2 "which is under test"
       golden compare boxes_crossing --backend cpu --report ${g}/boxes_crossing/report)
expect("compare-dumps --report onto a dump" 2 "holds a dump"
       golden compare-dumps ${g}/boxes_crossing/expected ${g}/boxes_touching_ties/expected --report ${g}/boxes_crossing/expected)
file(MAKE_DIRECTORY ${WORK}/reused)
file(WRITE ${WORK}/reused/stale_layer00_error.png "an earlier run's picture")
expect("compare-dumps into a reused report folder" 1 "DIFFERENT"
       golden compare-dumps ${g}/boxes_crossing/expected ${g}/boxes_touching_ties/expected --report ${WORK}/reused)
if(EXISTS ${WORK}/reused/stale_layer00_error.png OR NOT EXISTS ${WORK}/reused/report.txt)
  message(SEND_ERROR "a reused report folder kept an earlier run's files, or lacks the new report")
endif()
# Output that says what happened: a write that fails is an error; an unknown class is refused;
# a random binary .obj is said to be binary; one object alone points at --self; the conservative
# mode prints no epsilon.
execute_process(COMMAND sh -c "'${PEELCD}' detect '${scene}' --list > /dev/full" RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "writing the standard output failed")
  message(SEND_ERROR "detect --list > /dev/full: exit ${rc}, expected 2 and a message: ${err}")
endif()
expect("classes --class unknown" 2 "no class named \"bogus\"" classes --class bogus)
string(ASCII 1 2 3 binary_bytes)
file(WRITE ${WORK}/binary.obj "v 0 0 0\n${binary_bytes}garbage")
expect("binary obj" 2 "binary.obj': cannot read: binary data at byte" detect ${WORK}/binary.obj ${FIXTURES}/meshes/torus.obj)
file(WRITE ${WORK}/one.json "{\"objects\": [{\"mesh\": \"${FIXTURES}/meshes/torus.obj\"}]}")
expect("one object" 0 "one object, no pair: --self tests it against itself" detect ${WORK}/one.json)
execute_process(COMMAND ${PEELCD} detect ${scene} --stage image OUTPUT_VARIABLE out)
if(out MATCHES "eps ")
  message(SEND_ERROR "conservative detect printed an epsilon: ${out}")
endif()
# A golden folder copied elsewhere still compares (its meshes read from peelcd's own data, said);
# a mesh that is nowhere names the case's scene and object.
file(REMOVE_RECURSE ${WORK}/copied_golden)
file(COPY ${FIXTURES}/golden/boxes_crossing DESTINATION ${WORK}/copied_golden)
expect("golden compare: a copied golden folder" 0 "not beside the goldens: read from.*boxes_crossing, production path.*match"
       golden compare boxes_crossing --golden-dir ${WORK}/copied_golden)
file(READ ${WORK}/copied_golden/boxes_crossing/case.json case_json)
string(REPLACE "box_unit.obj" "nowhere.obj" case_json "${case_json}")
file(WRITE ${WORK}/copied_golden/boxes_crossing/case.json "${case_json}")
expect("golden compare: a mesh that is nowhere" 2 "nowhere.obj': no such file \\(referenced by '.*boxes_crossing/case.json': objects\\[0\\]"
       golden compare boxes_crossing --golden-dir ${WORK}/copied_golden)
expect("calibrate --write-costs onto a fixture mesh" 2 "inside peelcd's own data" calibrate --backend cpu
       --write-costs ${FIXTURES}/meshes/bunny_3k.obj)
