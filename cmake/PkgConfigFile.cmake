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
# peelcd/backends.h offers "osmesa" where PEELCD_HAVE_OSMESA is defined (as peelcd::gl_osmesa's
# CMake users get it). No -std: peelcd needs C++17 or later, and a consumer's own choice stands.
set(_pc_defines "")
if(TARGET peelcd_gl_egl)
  string(APPEND _pc_defines " -DPEELCD_HAVE_EGL=1")
endif()
if(TARGET peelcd_gl_osmesa)
  string(APPEND _pc_requires " osmesa")
  string(APPEND _pc_defines " -DPEELCD_HAVE_OSMESA=1")
endif()
# The prefix is found from where the .pc file lies (pkg-config's ${pcfiledir}), so the file is
# right wherever the build is installed (cmake --install build --prefix P), not only at
# CMAKE_INSTALL_PREFIX. An absolute CMAKE_INSTALL_LIBDIR is kept as it is.
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(_pc_prefix "${CMAKE_INSTALL_PREFIX}")
  set(_pc_libdir "${CMAKE_INSTALL_LIBDIR}")
else()
  file(RELATIVE_PATH _pc_up "/x/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/x")
  string(REGEX REPLACE "/$" "" _pc_up "${_pc_up}")
  set(_pc_prefix "\${pcfiledir}/${_pc_up}")
  set(_pc_libdir "\${prefix}/${CMAKE_INSTALL_LIBDIR}")
endif()
if(IS_ABSOLUTE "${CMAKE_INSTALL_INCLUDEDIR}")
  set(_pc_includedir "${CMAKE_INSTALL_INCLUDEDIR}")
else()
  set(_pc_includedir "\${prefix}/${CMAKE_INSTALL_INCLUDEDIR}")
endif()
file(WRITE ${PROJECT_BINARY_DIR}/peelcd.pc.in
"prefix=${_pc_prefix}
libdir=${_pc_libdir}
includedir=${_pc_includedir}

Name: peelcd
Description: @PROJECT_DESCRIPTION@
Version: @PROJECT_VERSION@
Requires: ${_pc_requires}
Cflags: -I\${includedir}${_pc_defines}
Libs: -L\${libdir}${_pc_libs} -pthread
")
configure_file(${PROJECT_BINARY_DIR}/peelcd.pc.in ${PROJECT_BINARY_DIR}/peelcd.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/peelcd.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
