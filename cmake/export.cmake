# The libraries as a package: scanplan::<name> in the tree (ALIAS) and in the installed
# scanplanConfig.cmake (`cmake --install build --prefix P`, then find_package(scanplan)).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# Each library of scanplan_libraries (CMakeLists.txt): the target scanplan_<name>, exported as
# scanplan::<name>, its headers installed to include/scanplan/<name>/.

# Headers that expose a third-party library the target links PRIVATE: used inside the target
# (and by its tests), never installed.
set(scanplan_private_headers collision/fcl_geometry.h)

# scanplan::scanplan: every library above.
add_library(scanplan_umbrella INTERFACE)
set_target_properties(scanplan_umbrella PROPERTIES EXPORT_NAME scanplan)
add_library(scanplan::scanplan ALIAS scanplan_umbrella)

set(scanplan_exported scanplan_umbrella)
foreach(name IN LISTS scanplan_libraries)
  set_target_properties(scanplan_${name} PROPERTIES EXPORT_NAME ${name})
  target_compile_features(scanplan_${name} PUBLIC cxx_std_20)  # its headers are C++20
  add_library(scanplan::${name} ALIAS scanplan_${name})
  target_link_libraries(scanplan_umbrella INTERFACE scanplan_${name})
  list(APPEND scanplan_exported scanplan_${name})

  set(excludes)
  foreach(header IN LISTS scanplan_private_headers)
    get_filename_component(header_dir ${header} DIRECTORY)
    if(header_dir STREQUAL name)
      get_filename_component(header_name ${header} NAME)
      list(APPEND excludes PATTERN ${header_name} EXCLUDE)
    endif()
  endforeach()
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${name}/
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/scanplan/${name}
          FILES_MATCHING PATTERN "*.h" PATTERN detail EXCLUDE ${excludes})
endforeach()

install(TARGETS ${scanplan_exported} EXPORT scanplanTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS scanplan RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

set(scanplan_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/scanplan)
install(EXPORT scanplanTargets NAMESPACE scanplan:: DESTINATION ${scanplan_cmake_dir})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/scanplanConfig.cmake.in
  ${PROJECT_BINARY_DIR}/scanplanConfig.cmake INSTALL_DESTINATION ${scanplan_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/scanplanConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/scanplanConfig.cmake
              ${PROJECT_BINARY_DIR}/scanplanConfigVersion.cmake
        DESTINATION ${scanplan_cmake_dir})
