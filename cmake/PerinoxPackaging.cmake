# Packaging: perinox:: aliases, the perinoxTargets export set, installed headers, scenes and
# linear-solver presets, and perinoxConfig.cmake / perinoxConfigVersion.cmake, so that other
# projects use perinox through find_package(perinox) (docs/embedding.md).
include(CMakePackageConfigHelpers)
set(PERINOX_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/perinox)

# perinox_export(<target>): a perinox::<target> alias in the build tree, and the target in the
# export set (libraries to lib, programs to bin), so that perinox::<target> means the same thing
# in the build tree and after find_package(perinox).
function(perinox_export target)
  get_target_property(type ${target} TYPE)
  if(type STREQUAL "EXECUTABLE")
    add_executable(perinox::${target} ALIAS ${target})
  else()
    add_library(perinox::${target} ALIAS ${target})
  endif()
  install(TARGETS ${target} EXPORT perinoxTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endfunction()

# perinox_library(<target> INCLUDE <dir> [HEADERS_TO <subdir> HEADERS <files...>]):
# position-independent code; <dir> as the public include directory in the build tree and
# <prefix>/include once installed; <dir>/perinox/** installed to include/perinox/**, or the
# given HEADERS to include/<subdir>; then perinox_export.
function(perinox_library target)
  cmake_parse_arguments(L "" "INCLUDE;HEADERS_TO" "HEADERS" ${ARGN})
  set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${L_INCLUDE}>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  if(L_HEADERS)
    install(FILES ${L_HEADERS} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/${L_HEADERS_TO})
  else()
    install(DIRECTORY ${L_INCLUDE}/perinox DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  endif()
  perinox_export(${target})
endfunction()

# The export set, the package configuration files, and the data an installed driver reads:
# linear-solver presets in share/perinox/xml/solvers, the scenes as examples in share/perinox/xml.
function(perinox_install_package)
  install(EXPORT perinoxTargets NAMESPACE perinox:: FILE perinoxTargets.cmake
    DESTINATION ${PERINOX_INSTALL_CMAKEDIR})
  string(REPLACE ";" " " PERINOX_TRILINOS_COMPONENTS_TEXT "${PERINOX_TRILINOS_COMPONENTS}")
  configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/perinoxConfig.cmake.in
    ${PROJECT_BINARY_DIR}/perinoxConfig.cmake INSTALL_DESTINATION ${PERINOX_INSTALL_CMAKEDIR}
    PATH_VARS CMAKE_INSTALL_DATADIR)
  write_basic_package_version_file(${PROJECT_BINARY_DIR}/perinoxConfigVersion.cmake
    VERSION ${PROJECT_VERSION} COMPATIBILITY SameMajorVersion)
  install(FILES ${PROJECT_BINARY_DIR}/perinoxConfig.cmake ${PROJECT_BINARY_DIR}/perinoxConfigVersion.cmake
    DESTINATION ${PERINOX_INSTALL_CMAKEDIR})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/xml/solvers DESTINATION ${CMAKE_INSTALL_DATADIR}/perinox/xml
    FILES_MATCHING PATTERN "*.xml")
  file(GLOB scenes ${PROJECT_SOURCE_DIR}/xml/*.xml)
  install(FILES ${scenes} DESTINATION ${CMAKE_INSTALL_DATADIR}/perinox/xml)
endfunction()
