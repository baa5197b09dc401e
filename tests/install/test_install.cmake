# Installs the build into a fresh prefix, then builds and runs the standalone examples
# (examples/, find_package(peelcd)) against it, and checks peelcd.pc with pkg-config.
#   -DBUILD=<peelcd build dir> -DSOURCE=<peelcd source dir> -DWORK=<scratch dir>
file(REMOVE_RECURSE ${WORK})
set(prefix ${WORK}/prefix)
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()
run(${CMAKE_COMMAND} --install ${BUILD} --prefix ${prefix})
foreach(f include/peelcd/peelcd.h include/peelcd/version.h include/peelcd/core/image/detector.h
          lib/cmake/peelcd/peelcdConfig.cmake lib/cmake/peelcd/peelcdConfigVersion.cmake
          lib/pkgconfig/peelcd.pc share/doc/peelcd/LICENSE)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
run(${CMAKE_COMMAND} -S ${SOURCE}/examples -B ${WORK}/examples -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build ${WORK}/examples -j 2)
run(${WORK}/examples/two_meshes)
message(STATUS "${last_output}")
run(${WORK}/examples/animation)
message(STATUS "${last_output}")
find_program(PKG_CONFIG pkg-config REQUIRED)
set(ENV{PKG_CONFIG_PATH} ${prefix}/lib/pkgconfig)
run(${PKG_CONFIG} --modversion peelcd)
message(STATUS "pkg-config: peelcd ${last_output}")
run(${PKG_CONFIG} --cflags --libs peelcd)
# The package's own directories are those of this prefix, wherever it is (not CMAKE_INSTALL_PREFIX).
run(${PKG_CONFIG} --variable=includedir peelcd)
string(STRIP "${last_output}" includedir)
run(${PKG_CONFIG} --variable=libdir peelcd)
string(STRIP "${last_output}" libdir)
if(NOT EXISTS "${includedir}/peelcd/peelcd.h" OR NOT EXISTS "${libdir}/libpeelcd_core.a")
  message(FATAL_ERROR "peelcd.pc points elsewhere than the install prefix ${prefix}: includedir=${includedir} libdir=${libdir}")
endif()
run(${PKG_CONFIG} --cflags peelcd)
string(REGEX MATCHALL "-I[^ \n]+" includes "${last_output}")
file(REAL_PATH "${includedir}" real_includedir)
set(at -1)
foreach(i ${includes})
  string(SUBSTRING "${i}" 2 -1 dir)
  file(REAL_PATH "${dir}" real)
  if(real STREQUAL real_includedir)
    set(at 0)
  endif()
endforeach()
if(at EQUAL -1)
  message(FATAL_ERROR "pkg-config --cflags peelcd lacks -I${includedir}: ${last_output}")
endif()
# pkg-config: a consumer that includes only peelcd/peelcd.h, built with the .pc's flags and a
# newer standard than the library's (-std=c++20 must not be overridden), runs a World on OSMesa
# (the .pc's Cflags define PEELCD_HAVE_OSMESA when the OSMesa component is installed).
run(${PKG_CONFIG} --cflags --libs peelcd)
string(STRIP "${last_output}" pc_flags)
separate_arguments(pc_flags UNIX_COMMAND "${pc_flags}")
if(pc_flags MATCHES "-std=")
  message(FATAL_ERROR "pkg-config --cflags peelcd forces a language standard: ${pc_flags}")
endif()
run(c++ -std=c++20 -O1 ${SOURCE}/tests/install/consumer/main.cpp -o ${WORK}/consumer_pc ${pc_flags})
if(EXISTS ${prefix}/include/peelcd/gl_osmesa/osmesa_context.h)
  run(${WORK}/consumer_pc osmesa)
else()
  run(${WORK}/consumer_pc cpu)
endif()
message(STATUS "${last_output}")
# find_package(peelcd COMPONENTS ...) with any subset: the contexts are not needed by the others.
# (Components comma-separated: a list would be split by run()'s ARGN.)
foreach(components core core,io core,io,eval,bench gl,gl_egl oracle)
  string(REPLACE "," "_" tag "${components}")
  run(${CMAKE_COMMAND} -S ${SOURCE}/tests/install/consumer -B ${WORK}/consumer_${tag} -DCMAKE_PREFIX_PATH=${prefix}
      -DPEELCD_COMPONENTS=${components} -DCMAKE_BUILD_TYPE=Release)
endforeach()
run(${CMAKE_COMMAND} -S ${SOURCE}/tests/install/consumer -B ${WORK}/consumer_all -DCMAKE_PREFIX_PATH=${prefix}
    -DPEELCD_COMPONENTS=core,io,gl,gl_egl,gl_osmesa -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build ${WORK}/consumer_all -j 2)
run(${WORK}/consumer_all/consumer cpu)
message(STATUS "${last_output}")
# find_package(peelcd) without COMPONENTS needs neither FCL nor OpenEXR.
run(${CMAKE_COMMAND} -S ${SOURCE}/tests/install/no_components -B ${WORK}/no_components -DCMAKE_PREFIX_PATH=${prefix})

# The installed command line runs without the source tree: its data is under share/peelcd.
foreach(f bin/peelcd share/peelcd/fixtures/meshes/bunny_3k.obj share/peelcd/fixtures/golden/boxes_crossing/case.json
          share/peelcd/scripts/plot_sweep.py)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
run(${prefix}/bin/peelcd calibrate --backend cpu --repeat 1 --budgets 16 --large 12)
run(${prefix}/bin/peelcd golden compare --backend cpu --tier hardware boxes_crossing --report ${WORK}/report)
# ... and reads it there, not in the build's source tree: with a fixture mesh gone from the
# prefix, calibrate fails naming the prefix's file.
file(RENAME ${prefix}/share/peelcd/fixtures/meshes/bunny_3k.obj ${WORK}/bunny_3k.obj)
execute_process(COMMAND ${prefix}/bin/peelcd calibrate --backend cpu --repeat 1 --budgets 16
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
file(RENAME ${WORK}/bunny_3k.obj ${prefix}/share/peelcd/fixtures/meshes/bunny_3k.obj)
if(NOT rc EQUAL 2 OR NOT err MATCHES "share/peelcd/fixtures/meshes/bunny_3k.obj': no such file")
  message(FATAL_ERROR "installed calibrate without its mesh: expected exit 2 naming the installed file, got ${rc}: ${err}")
endif()
# $PEELCD_DATA_DIR overrides; a wrong one is named.
execute_process(COMMAND ${CMAKE_COMMAND} -E env PEELCD_DATA_DIR=${WORK}/nowhere ${prefix}/bin/peelcd golden compare
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "PEELCD_DATA_DIR is set")
  message(FATAL_ERROR "PEELCD_DATA_DIR=nowhere: expected exit 2 naming it, got ${rc}: ${err}")
endif()
