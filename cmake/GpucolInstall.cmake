# Installs the library, its public headers and a gpucolConfig.cmake, so that another project can
# find_package(gpucol) and link gpucol::gpucol with Bullet's include directories and libraries.
include(CMakePackageConfigHelpers)

install(TARGETS gpucol EXPORT gpucolTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY plugin/include/gpucol DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT gpucolTargets NAMESPACE gpucol:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/gpucol)

configure_package_config_file(cmake/gpucolConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/gpucolConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/gpucol)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/gpucolConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/gpucolConfig.cmake
  ${CMAKE_CURRENT_BINARY_DIR}/gpucolConfigVersion.cmake
  ${CMAKE_CURRENT_LIST_DIR}/GpucolBulletWorldImporter.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/gpucol)
