# Generates C++ headers (and, when a JDK is present, a jar for lcm-spy) from lcmtypes/*.lcm.
# Debian's LCM 1.3.1 ships no CMake package, so lcm-gen is driven by hand.
file(GLOB POLARSLAM_LCM_FILES CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/lcmtypes/*.lcm)
set(LCMGEN_CPP_DIR ${CMAKE_BINARY_DIR}/lcmgen/cpp)
set(LCMGEN_JAVA_DIR ${CMAKE_BINARY_DIR}/lcmgen/java)
set(POLARSLAM_LCM_HEADERS)
foreach(lcm_file ${POLARSLAM_LCM_FILES})
  get_filename_component(type_name ${lcm_file} NAME_WE)
  list(APPEND POLARSLAM_LCM_HEADERS ${LCMGEN_CPP_DIR}/polarslam/${type_name}.hpp)
endforeach()
add_custom_command(
  OUTPUT ${POLARSLAM_LCM_HEADERS}
  COMMAND ${CMAKE_COMMAND} -E make_directory ${LCMGEN_CPP_DIR}
  COMMAND ${LCM_GEN} --cpp --cpp-std c++11 --cpp-hpath ${LCMGEN_CPP_DIR} ${POLARSLAM_LCM_FILES}
  DEPENDS ${POLARSLAM_LCM_FILES}
  COMMENT "lcm-gen: C++ headers for polarslam message types")
add_custom_target(polarslam_lcmtypes_cpp DEPENDS ${POLARSLAM_LCM_HEADERS})
add_library(polarslam_lcmtypes INTERFACE)
add_dependencies(polarslam_lcmtypes polarslam_lcmtypes_cpp)
# SYSTEM: generated headers trip -Wshadow/-Wconversion.
target_include_directories(polarslam_lcmtypes SYSTEM INTERFACE ${LCMGEN_CPP_DIR})
target_link_libraries(polarslam_lcmtypes INTERFACE PkgConfig::LCM)

find_package(Java COMPONENTS Development)
find_file(LCM_JAR lcm.jar PATHS /usr/share/java /usr/local/share/java)
if(Java_FOUND AND LCM_JAR)
  set(POLARSLAM_JAR ${CMAKE_BINARY_DIR}/polarslam_lcmtypes.jar)
  add_custom_command(
    OUTPUT ${POLARSLAM_JAR}
    COMMAND sh ${CMAKE_SOURCE_DIR}/cmake/build-type-jar.sh ${LCM_GEN} ${Java_JAVAC_EXECUTABLE}
            ${Java_JAR_EXECUTABLE} ${LCM_JAR} ${POLARSLAM_JAR} ${LCMGEN_JAVA_DIR} ${POLARSLAM_LCM_FILES}
    DEPENDS ${POLARSLAM_LCM_FILES} ${CMAKE_SOURCE_DIR}/cmake/build-type-jar.sh
    COMMENT "lcm-gen: Java jar of polarslam types for lcm-spy")
  add_custom_target(polarslam_lcmtypes_jar ALL DEPENDS ${POLARSLAM_JAR})
else()
  message(WARNING "No JDK or lcm.jar: the lcm-spy type jar will not be built")
endif()
