# polarslam_process(NAME SOURCES...) builds one program into bin/ (and installs it: cmake/install.cmake).
set(CMAKE_RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bin)
function(polarslam_process name)
  add_executable(${name} ${ARGN})
  target_link_libraries(${name} PRIVATE polarslam_bridge)
  set_property(GLOBAL APPEND PROPERTY POLARSLAM_PROGRAMS ${name})
endfunction()
