# Install the libraries, headers and a CMake package: find_package(corrlap CONFIG REQUIRED)
# then link corrlap::corrlap (or one of corrlap::core / estimators / discretizations / backends).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

get_property(_targets GLOBAL PROPERTY CORRLAP_EXPORTED_TARGETS)
# An installed library finds the corrlap libraries it needs beside itself: a consumer links only the
# libraries it calls, and the loader resolves the others through the library's own run path.
foreach(_t IN LISTS _targets)
  get_target_property(_type ${_t} TYPE)
  if(_type STREQUAL "SHARED_LIBRARY")
    set_target_properties(${_t} PROPERTIES INSTALL_RPATH "$ORIGIN")
  endif()
endforeach()
install(TARGETS ${_targets} corrlap EXPORT corrlapTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  INCLUDES DESTINATION include)
set_target_properties(corrlap PROPERTIES EXPORT_NAME corrlap)
install(EXPORT corrlapTargets NAMESPACE corrlap:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/corrlap)

configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/corrlapConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/corrlapConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/corrlap)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/corrlapConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/corrlapConfig.cmake
  ${CMAKE_CURRENT_BINARY_DIR}/corrlapConfigVersion.cmake
  ${CMAKE_CURRENT_LIST_DIR}/FindCHOLMOD.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/corrlap)

# The build tree is a package too: find_package(corrlap CONFIG) with corrlap_DIR=<build dir> uses
# the targets of this build (headers from the source tree, libraries from the build tree).
export(EXPORT corrlapTargets NAMESPACE corrlap:: FILE ${CMAKE_CURRENT_BINARY_DIR}/corrlapTargets.cmake)
configure_file(${CMAKE_CURRENT_LIST_DIR}/FindCHOLMOD.cmake ${CMAKE_CURRENT_BINARY_DIR}/FindCHOLMOD.cmake COPYONLY)
