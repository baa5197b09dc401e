# peelcd.pc: the core, io, gl and context libraries that were built (static archives, so their
# own dependencies are listed in Libs, not Libs.private).
set(_pc_libs "")
set(_pc_requires "eigen3 gmp mpfr")
foreach(t gl_osmesa gl_egl gl io core)
  if(TARGET peelcd_${t})
    string(APPEND _pc_libs " -lpeelcd_${t}")
  endif()
endforeach()
if(TARGET peelcd_gl)
  string(APPEND _pc_libs " -lpeelcd_glad")
endif()
if(TARGET peelcd_io)
  string(APPEND _pc_requires " assimp nlohmann_json")
endif()
if(TARGET peelcd_gl_egl)
  string(APPEND _pc_requires " egl")
endif()
if(TARGET peelcd_gl_osmesa)
  string(APPEND _pc_requires " osmesa")
endif()
file(WRITE ${PROJECT_BINARY_DIR}/peelcd.pc.in
"prefix=@CMAKE_INSTALL_PREFIX@
libdir=\${prefix}/@CMAKE_INSTALL_LIBDIR@
includedir=\${prefix}/@CMAKE_INSTALL_INCLUDEDIR@

Name: peelcd
Description: @PROJECT_DESCRIPTION@
Version: @PROJECT_VERSION@
Requires: ${_pc_requires}
Cflags: -I\${includedir} -std=c++17
Libs: -L\${libdir}${_pc_libs} -pthread
")
configure_file(${PROJECT_BINARY_DIR}/peelcd.pc.in ${PROJECT_BINARY_DIR}/peelcd.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/peelcd.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
