# page_status(URL STATE TEXT [ARGS...]): opens URL in headless Chromium (the flags in ${flags})
# and sets STATE and TEXT to the status the page's own script sets (data-status and its text).
function(page_status url state_var text_var)
  execute_process(COMMAND ${CHROMIUM} ${flags} --dump-dom "${url}" RESULT_VARIABLE rc OUTPUT_VARIABLE dom
                  ERROR_VARIABLE log TIMEOUT 300)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "viewer: chromium --dump-dom ${url} failed (${rc}): ${log}")
  endif()
  string(REGEX MATCH "data-status=\"([a-z]+)\"[^>]*>([^<]*)" status "${dom}")
  set(${state_var} "${CMAKE_MATCH_1}" PARENT_SCOPE)
  set(${text_var} "${CMAKE_MATCH_2}" PARENT_SCOPE)
  set(page_dom "${dom}" PARENT_SCOPE)  # the whole page, for checks of its contents
endfunction()
