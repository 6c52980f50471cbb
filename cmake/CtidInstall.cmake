# Installation and the exported package: find_package(ctid) gives ctid::ctid.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

install(TARGETS ${CTID_LAYERS} ctid ctid_compile_options EXPORT ctidTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/ctid DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT ctidTargets NAMESPACE ctid:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/ctid)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/ctidConfig.cmake.in
  ${PROJECT_BINARY_DIR}/ctidConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/ctid)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/ctidConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/ctidConfig.cmake ${PROJECT_BINARY_DIR}/ctidConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/ctid)
