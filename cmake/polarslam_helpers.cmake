# polarslam_process(NAME SOURCES...) builds one LCM process executable into bin/.
set(CMAKE_RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bin)
function(polarslam_process name)
  add_executable(${name} ${ARGN})
  target_link_libraries(${name} PRIVATE polarslam_bridge)
endfunction()
