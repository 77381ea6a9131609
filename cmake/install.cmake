# Install rules and the Debian package (cpack -G DEB, scripts/package):
#   bin/                     every polarslam program, and polarslam-lcm-spy
#   share/polarslam/config/  robots, worlds, process groups, parameter files (found by the
#                            programs from their own folder: processes/common/program_info)
#   share/polarslam/logs/    the simulated default log
#   share/polarslam/web/     polarslam-bridge's built-in map page (found like config/: program_info)
#   share/polarslam/java/    the type jar for lcm-spy
#   share/doc/polarslam/     README, LICENSE, docs/
include(GNUInstallDirs)
set(polarslam_share ${CMAKE_INSTALL_DATADIR}/polarslam)

get_property(polarslam_programs GLOBAL PROPERTY POLARSLAM_PROGRAMS)
install(TARGETS ${polarslam_programs} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(PROGRAMS ${CMAKE_SOURCE_DIR}/scripts/lcm-spy DESTINATION ${CMAKE_INSTALL_BINDIR} RENAME polarslam-lcm-spy)
install(DIRECTORY ${CMAKE_SOURCE_DIR}/config/ DESTINATION ${polarslam_share}/config)
install(DIRECTORY ${CMAKE_SOURCE_DIR}/processes/polarslam-bridge/web/ DESTINATION ${polarslam_share}/web)
install(FILES ${CMAKE_SOURCE_DIR}/logs/office.lcmlog ${CMAKE_SOURCE_DIR}/logs/README.md
        DESTINATION ${polarslam_share}/logs)
if(POLARSLAM_JAR)
  install(FILES ${POLARSLAM_JAR} DESTINATION ${polarslam_share}/java)
endif()
install(FILES ${CMAKE_SOURCE_DIR}/README.md ${CMAKE_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DOCDIR})
if(EXISTS ${CMAKE_SOURCE_DIR}/docs)
  install(DIRECTORY ${CMAKE_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR})
endif()

set(CPACK_PACKAGE_NAME polarslam)
set(CPACK_PACKAGE_VENDOR "polarslam authors")
set(CPACK_PACKAGE_CONTACT "polarslam authors <polarslam@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "2D SLAM with a laser range finder, advanced sonar and odometry over LCM")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_RESOURCE_FILE_LICENSE ${CMAKE_SOURCE_DIR}/LICENSE)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)  # the shared libraries' packages, found by dpkg-shlibdeps
# lcm-logger / lcm-logplayer for recording and replay groups; Java for polarslam-lcm-spy.
set(CPACK_DEBIAN_PACKAGE_DEPENDS "liblcm-bin")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "default-jre, libjchart2d-java, liblcm-java")
include(CPack)
