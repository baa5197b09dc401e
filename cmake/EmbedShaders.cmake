# Embeds GLSL files into a C++ source at build time, so the binary needs no shader files at run
# time and a shader edit triggers a rebuild. Usage:
#   peelcd_embed_shaders(OUT <cpp> [HEADER <h>] NAMESPACE <ns> FILES <f1> <f2> ...)
# Each file becomes `extern const char* const <stem>_<ext>` (e.g. peel_frag), declared in HEADER, plus
# `shader_sources_hash`, the first 16 hex digits of the SHA-256 of all sources (goldens record it).
set(_PEELCD_EMBED_SCRIPT ${CMAKE_CURRENT_LIST_DIR}/embed_shaders_run.cmake)

function(peelcd_embed_shaders)
  cmake_parse_arguments(ARG "" "OUT;HEADER;NAMESPACE" "FILES" ${ARGN})
  add_custom_command(
    OUTPUT ${ARG_OUT} ${ARG_HEADER}
    COMMAND ${CMAKE_COMMAND} -DOUT=${ARG_OUT} -DHEADER=${ARG_HEADER} -DNAMESPACE=${ARG_NAMESPACE}
            "-DFILES=${ARG_FILES}" -P ${_PEELCD_EMBED_SCRIPT}
    DEPENDS ${ARG_FILES} ${_PEELCD_EMBED_SCRIPT}
    COMMENT "Embedding shaders into ${ARG_OUT}"
    VERBATIM)
endfunction()
